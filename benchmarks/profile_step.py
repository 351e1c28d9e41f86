"""Where one step's time goes: the passes of the step kernel timed one by one, 1 thread.

Builds the dilute or dense box of benchmarks/scaling.py (k^3 spheres), runs 50 steps, then
times (microseconds per step) the whole step and its parts: ``begin`` (integrator pre-force
part and element displacements), ``contact`` (contact pass of the two-pass form), ``sum``
(its per-body sums and integrator post-force part), and one neighbour-list ``rebuild``.
The whole step is the scene's own (the fused pass: every body is a sphere). Writes
benchmarks/results/profile_step[_quick].json.

    python benchmarks/profile_step.py 22 dense
    python benchmarks/profile_step.py --quick     # 10^3 spheres
"""

from __future__ import annotations

import os
import time

import harness
import numba
from shared_scenes import CASES, D, scene_arrays

import dpm
from dpm.backends.records import PairList

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module


def timed(fn, reps: int) -> float:
    fn()
    t = time.perf_counter()
    for _ in range(reps):
        fn()
    return (time.perf_counter() - t) / reps * 1e6


def main() -> None:
    p = harness.parser(__doc__, "a 10^3 lattice")
    p.add_argument("k", type=int, nargs="?", default=None,
                   help="lattice edge (k^3 spheres; 22)")
    p.add_argument("case", nargs="?", default="dense", choices=list(CASES))
    a = p.parse_args()
    a.k = a.k or (10 if a.quick else 22)
    numba.set_num_threads(1)
    pos, vel, box = scene_arrays(a.k, a.case)
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, CASES[a.case][2]), threads=1)
    g = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(g, g, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=g, lower=(0, 0, 0), upper=box, open="+z")
    sim.add_particles("sphere", material=g, radius=D / 2, positions=pos, velocities=vel)
    sim.run(steps=50, progress=False)
    be, dt = sim.backend, sim.dt
    m = be.module
    b, c = sim.bodies, sim.contacts
    n = len(b)
    table = sim._frame_table(100, sim.step_count)
    step = timed(lambda: m.run_steps(100, dt, *be.records(), be.diag, table), 5) / 100
    ctl, bodies, elems, _, walls, bnd = be.records()
    begin = timed(lambda: m.pre_force(0.0, ctl, bodies, elems), 200)
    # the two-pass form's passes need the force rows and the transposed index, which the
    # one-thread fused step of this scene does without
    c.use_rows(True)
    pairs = PairList(c.start, c.key, c.history, c.active, c.force, c.t_start, c.t_pair)
    contact = timed(lambda: m.contact_pass(0.0, ctl, bodies, elems, pairs, walls, bnd), 200)
    summed = timed(lambda: m.sum_pass(0.0, False, ctl, bodies, elems, pairs, walls), 200)
    rebuild = timed(lambda: m.rebuild(ctl, bodies, elems, pairs, walls, bnd, be.diag), 10)
    print(f"{a.case} box, {n} spheres, {c.count} listed pairs, {sim.contact_count()} touching; "
          f"us per step: step {step:.0f} | begin {begin:.0f} ({begin / n * 1e3:.0f} ns per "
          f"body) | contact {contact:.0f} | sum {summed:.0f} | one rebuild {rebuild:.0f}")
    harness.write("profile_step", {
        "case": a.case, "k": a.k, "spheres": n, "listed_pairs": int(c.count),
        "touching": int(sim.contact_count()), "threads": 1,
        "us_per_step": {"step": step, "begin": begin, "contact": contact, "sum": summed,
                        "one_rebuild": rebuild}}, a.quick)


if __name__ == "__main__":
    main()
