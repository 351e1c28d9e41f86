"""Progress bar of a run: simulated time, steps per second and ETA (tqdm)."""

from __future__ import annotations

import sys

from tqdm import tqdm


class Progress:
    """A tqdm bar over steps, shown on a terminal (or when ``enabled`` is True)."""

    def __init__(self, nsteps: int, dt: float, t0: float, enabled: bool | None = None) -> None:
        if enabled is None:
            enabled = sys.stderr.isatty()
        self.bar = None
        if enabled and nsteps > 0:
            self.bar = tqdm(total=nsteps, unit="step", dynamic_ncols=True, file=sys.stderr,
                            bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} steps "
                                       "[{elapsed}<{remaining}, {rate_fmt}{postfix}]")
            self.bar.set_postfix_str(f"t={t0:.4g} s")

    def update(self, steps: int, time: float) -> None:
        if self.bar is not None:
            self.bar.update(steps)
            self.bar.set_postfix_str(f"t={time:.4g} s", refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
