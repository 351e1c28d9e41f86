"""Where the box_settle step's time goes as the packing settles, and what each form of the
step costs there, 1 and 2 threads, in one process.

Runs the 10,000-sphere box_settle scene (examples/box_settle.py: sphere orientation not
integrated, as LIGGGHTS' nve/sphere) in stages of 5,000 steps. After each stage it times,
on the same state, 3 x 100 steps of each variant in turn and prints the median wall time
per step (microseconds):

- ``fused``: the scene's step (fused force pass, no sphere orientation);
- ``+orient``: the same with the sphere orientation integrated;
- ``two-pass``: the two-pass force sum that clustered bodies use;

and, for 2 threads, ``fused`` and ``two-pass`` again. The per-step figures of
benchmarks/NOTES.md rows 13-16 come from it.

    python benchmarks/profile_box_settle.py
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numba

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
import os

import box_settle  # noqa: E402

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module


def per_step(sim, threads: int, two_pass: bool, orient: bool, steps: int = 100) -> float:
    """Wall time per step [us] of ``steps`` steps in this variant (state carries on)."""
    sim.threads = threads
    sim.backend.force_pass = "two_pass" if two_pass else "auto"
    sim.sphere_orientation = orient
    t = time.perf_counter()
    sim.run(steps=steps, progress=False)
    return (time.perf_counter() - t) / steps * 1e6


def main() -> None:
    sim = box_settle.build(box_settle.initial_packing(20, 20, 25))
    variants = {"fused": (1, False, False), "+orient": (1, False, True),
                "two-pass": (1, True, False)}
    if numba.config.NUMBA_NUM_THREADS >= 2:
        variants.update({"fused 2 threads": (2, False, False),
                         "two-pass 2 threads": (2, True, False)})
    for v in variants.values():  # compile every variant before timing
        per_step(sim, *v, steps=2)
    for _ in range(4):
        sim.threads = 1
        sim.backend.force_pass = "auto"
        sim.sphere_orientation = False
        t0 = time.perf_counter()
        r0 = sim.rebuild_count
        sim.run(steps=5000, progress=False)
        wall = time.perf_counter() - t0
        line = (f"steps {sim.step_count}: stage {wall / 5000 * 1e6:.0f} us/step, rebuilds "
                f"{sim.rebuild_count - r0}, pairs {sim.contacts.count}, touching "
                f"{sim.contact_count()} |")
        times = {k: [] for k in variants}
        for _ in range(3):
            for k, v in variants.items():
                times[k].append(per_step(sim, *v))
        for k, ts in times.items():
            line += f" {k} {statistics.median(ts):.0f}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
