"""A thermo-style log of a running Simulation, like LIGGGHTS' ``thermo`` command."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..hookspecs import hookimpl
from ..io.hdf5 import THERMO_COLUMNS
from ..parameters import shown

#: column -> (header, format)
_FORMAT = {"time": ("time[s]", "{:12.6g}"), "step": ("step", "{:10.0f}"),
           "particles": ("particles", "{:9.0f}"), "kinetic_energy": ("KE[J]", "{:12.5g}"),
           "contacts": ("contacts", "{:9.0f}"), "max_overlap": ("ovl/r", "{:9.3g}"),
           "inserted": ("inserted", "{:9.0f}"), "removed": ("removed", "{:8.0f}"),
           "work": ("work[J]", "{:11.4g}"), "dissipated": ("dissip[J]", "{:11.4g}")}


def thermo_row(sim: Any) -> dict[str, float]:
    """One row of the log for the current state of ``sim``: time [s], step, particles
    present, kinetic energy [J] (translational + rotational), contacts (touching particle
    pairs and particle-boundary entries of the last force evaluation), max_overlap (the
    largest overlap / radius since the backend's last reset), inserted and removed bodies
    (all inlets, all outlets), work done by the boundaries [J] and the energy dissipated
    [J] (``sim.energy.balance(sim)``)."""
    bal = sim.energy.balance(sim)
    try:
        contacts = float(sim.contact_count())
        overlap = float(sim.backend.max_overlap()[0])
    except (AttributeError, TypeError):  # before the first run: no backend state yet
        contacts = overlap = float("nan")
    return {"time": float(sim.time), "step": float(sim.step_count),
            "particles": float(len(sim.bodies)), "kinetic_energy": float(sim.kinetic_energy()),
            "contacts": contacts, "max_overlap": overlap,
            "inserted": float(sum(i.inserted for i in sim.inlets)),
            "removed": float(sum(o.count for o in sim.outlets)),
            "work": float(bal["work"]), "dissipated": float(bal["dissipated"])}


class Thermo:
    """A log of :func:`thermo_row` during the runs of ``sim``.

    ``Thermo(sim)`` records a row at every output frame (the ``dpm_on_output`` hook, so it
    costs nothing between frames); ``Thermo(sim, every=1e-3)`` records one every ``every``
    seconds of simulated time when the run is driven by :meth:`run` (``thermo.run(
    until=0.5)`` runs ``sim.run`` in pieces of ``every``), and :meth:`record` adds a row at
    any moment (from the user's own loop). Rows go to ``/thermo`` of the simulation's
    output file when one is open (``file=True``), and with ``live=True`` each row is
    printed as it is recorded, under a header (like LIGGGHTS' ``thermo`` output).
    ``print(thermo)`` prints the whole table; ``thermo.rows`` is a list of dicts,
    ``thermo.columns()`` a dict of arrays. :meth:`close` unregisters the hook.

    The hook is a plugin of the process-wide registry (``dpm.registry().manager``); it
    only reacts to its own simulation. A checkpoint does not keep the Thermo object: after
    :func:`dpm.restart` make a new one (the file's ``/thermo`` keeps the rows up to the
    checkpoint).
    """

    def __init__(self, sim: Any, every: float | None = None, live: bool = False,
                 file: bool = True, stream: Any = None) -> None:
        if every is not None and not (isinstance(every, int | float) and every > 0):
            raise ParameterError(f"Thermo(every={shown(every)}): a time > 0 [s] or None (one row "
                                 f"per output frame)")
        self.sim = sim
        self.every = None if every is None else float(every)
        self.live = bool(live)
        self.file = bool(file)
        self.stream = stream
        self.rows: list[dict[str, float]] = []
        self._header_done = False
        self._registered = False
        if self.every is None:
            from ..plugins import registry

            registry().manager.register(self, name=f"dpm-thermo-{id(self)}")
            self._registered = True

    # the hook (only while registered)
    @hookimpl
    def dpm_on_output(self, sim: Any, frame: int, path: Any) -> None:
        if sim is self.sim:
            self.record()

    def record(self) -> dict[str, float]:
        """Add a row for the current state (and write / print it)."""
        row = thermo_row(self.sim)
        self.rows.append(row)
        w = getattr(self.sim, "last_output", None)
        if self.file and w is not None and not w.closed and hasattr(w, "write_thermo"):
            w.write_thermo(row)
        if self.live:
            out = self.stream or sys.stdout
            if not self._header_done:
                print(self.header(), file=out)
                self._header_done = True
            print(self.line(row), file=out, flush=True)
        return row

    def run(self, steps: int | None = None, until: float | None = None, **kw: Any) -> None:
        """Run ``sim`` to ``until`` [s] (or for ``steps`` steps) in pieces of ``every``
        seconds, recording a row at the start and after each piece."""
        sim = self.sim
        if (steps is None) == (until is None):
            raise ParameterError("Thermo.run(): give exactly one of steps or until")
        every = self.every if self.every is not None else float("inf")
        end = until if until is not None else sim.time + steps * sim.dt
        target_step = None if steps is None else sim.step_count + int(steps)
        kw.setdefault("progress", False)
        if not self.rows or self.rows[-1]["step"] != sim.step_count:
            self.record()
        while True:
            if target_step is not None:
                left = target_step - sim.step_count
                if left <= 0:
                    break
                n = min(left, max(1, round(every / sim.dt)) if np.isfinite(every) else left)
                sim.run(steps=n, **kw)
            else:
                if sim.time >= end - 0.5 * sim.dt:
                    break
                sim.run(until=min(end, sim.time + every), **kw)
            if self.every is not None:
                self.record()

    def close(self) -> None:
        """Stop recording at output frames (unregister the hook)."""
        if self._registered:
            from ..plugins import registry

            registry().manager.unregister(self)
            self._registered = False

    def __enter__(self) -> Thermo:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def columns(self) -> dict[str, np.ndarray]:
        return {k: np.array([r[k] for r in self.rows]) for k in THERMO_COLUMNS}

    @staticmethod
    def header() -> str:
        return " ".join(f"{_FORMAT[k][0]:>{len(_FORMAT[k][1].format(0))}}"
                        for k in THERMO_COLUMNS)

    @staticmethod
    def line(row: dict[str, float]) -> str:
        return " ".join(_FORMAT[k][1].format(row.get(k, float("nan")))
                        for k in THERMO_COLUMNS)

    def __len__(self) -> int:
        return len(self.rows)

    def __str__(self) -> str:
        return format_table(self.rows)


def format_table(rows: list[dict[str, float]] | dict[str, np.ndarray]) -> str:
    """The thermo table as text: ``rows`` as a list of dicts, or columns (``run.thermo``)."""
    if isinstance(rows, dict):
        n = min((len(v) for v in rows.values()), default=0)
        rows = [{k: float(v[i]) for k, v in rows.items()} for i in range(n)]
    return "\n".join([Thermo.header()] + [Thermo.line(r) for r in rows])
