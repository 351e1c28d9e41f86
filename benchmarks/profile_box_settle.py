"""Where the box_settle step's time goes as the packing settles, 1 thread.

Runs the 10,000-sphere box_settle scene (examples/box_settle.py) in stages of 5,000 steps
and after each stage prints the wall time per step of the stage, its neighbour-list
rebuilds, the listed and touching pairs, and the contact pass and sum pass timed alone
(microseconds per step). The per-pass figures of benchmarks/NOTES.md row 12 come from it.

    python benchmarks/profile_box_settle.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numba

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
import box_settle  # noqa: E402


def timed(fn, reps: int) -> float:
    fn()
    t = time.perf_counter()
    for _ in range(reps):
        fn()
    return (time.perf_counter() - t) / reps * 1e6


def pass_times(sim) -> tuple[float, float]:
    """Contact pass and sum pass of the current state, microseconds each."""
    m = sim._module
    b, e, c, wc = sim.bodies, sim.elements, sim.contacts, sim.wall_contacts
    contact = timed(lambda: m.contact_pass(
        0.0, b.position, sim._vf, sim._wf, b.mass, b.invmass, e.owner, e.radius,
        e.material, e.position, c.start, c.key, c.history, c.active, c.force, wc.start,
        wc.key, wc.history, wc.active, wc.force, wc.tag, sim._bnd(), sim._pair_model,
        sim._pair_params, sim._e_worst, sim._e_count), 50)
    summed = timed(lambda: m.sum_pass(
        0.0, False, sim.gravity, b.position, b.velocity, b.orientation,
        b.angular_velocity, b.force, b.torque, b.mass, b.invmass, b.invinertia, sim._aux,
        b.element_start, c.start, c.active, c.force, c.t_start, c.t_pair, wc.start,
        wc.active, wc.force, sim._e_count), 50)
    return contact, summed


def main() -> None:
    numba.set_num_threads(1)
    sim = box_settle.build(box_settle.initial_packing(20, 20, 25))
    sim.threads = 1
    for _ in range(4):
        t0 = time.perf_counter()
        r0 = sim.rebuild_count
        sim.run(steps=5000, progress=False)
        wall = time.perf_counter() - t0
        contact, summed = pass_times(sim)
        print(f"steps {sim.step_count}: {wall / 5000 * 1e6:.0f} us/step (first stage incl. "
              f"compile), rebuilds {sim.rebuild_count - r0}, pairs {sim.contacts.count}, "
              f"touching {int(sim._diag[6])}; contact pass {contact:.0f} us, sum pass "
              f"{summed:.0f} us")


if __name__ == "__main__":
    main()
