"""The per-body cost model that the MPI backend cuts the domain by, fitted to step times.

``MpiBackend`` weighs each body by its modelled cost per step (elements, listed contacts,
touching contacts) when it bisects the domain. This script measures the three costs on
one process and one thread, on the box_settle scene (Hertz-Mindlin, 10,000 spheres):

- the lattice held in place (gravity off: few contacts touch) at two Verlet skins, which
  list different numbers of pairs;
- the settled bed, where most listed pairs touch.

The three step times solve for the cost of an element, a listed pair and a touching
pair's extra.

Each time is the median of ``--rounds`` runs of ``--steps`` steps with no list rebuild
in them (a rebuild is the migration's share, not the step's). Writes
benchmarks/results/mpi_cost_model.json with the weights relative to an element, as
:mod:`dpm.parallel.backend` uses them (per side: a pair counts for both its bodies).

    python benchmarks/mpi_cost_model.py
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("DPM_KERNELS", "scene")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
RESULTS = HERE / "results"


def _timed(sim, steps: int, rounds: int) -> tuple[float, int, int]:
    """(median seconds per step over rounds without a rebuild, listed, touching)."""
    import numpy as np

    times = []
    while len(times) < rounds:
        r0 = sim.rebuild_count
        t0 = time.perf_counter()
        sim.run(steps=steps, progress=False)
        dt = (time.perf_counter() - t0) / steps
        if sim.rebuild_count == r0:
            times.append(dt)
    c = sim.contacts
    return float(np.median(times)), int(c.count), int(c.active[:c.count].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--settle", type=int, default=12000, help="steps before the bed's fit")
    args = ap.parse_args()
    from box_settle import _example

    ex = _example()
    csv = ex.initial_packing(20, 20, 25)
    rows = {}
    for name, skin_factor in (("lattice", 1.0), ("lattice, skin x2", 2.0)):
        sim = ex.build(csv)
        sim.threads = 1
        sim.gravity = (0.0, 0.0, 0.0)  # (held in place: nothing touches, no rebuild)
        sim.run(steps=5, progress=False)
        sim.skin = sim.skin * skin_factor
        sim.run(steps=5, progress=False)
        rows[name] = _timed(sim, args.steps, args.rounds)
        print(name, rows[name], flush=True)
    sim = ex.build(csv)
    sim.threads = 1
    sim.run(steps=args.settle, progress=False)
    rows["settled"] = _timed(sim, args.steps, args.rounds)
    print("settled", rows["settled"], flush=True)
    n = len(sim.bodies)
    (t1, l1, a1), (t2, l2, a2), (t3, l3, a3) = (rows["lattice"], rows["lattice, skin x2"],
                                                rows["settled"])
    import numpy as np

    element, listed, touching = (float(x) for x in np.linalg.solve(
        np.array([[n, l1, a1], [n, l2, a2], [n, l3, a3]], float), np.array([t1, t2, t3])))
    out = {"bodies": n, "runs": {k: {"s_per_step": t, "listed": l, "touching": a}
                                 for k, (t, l, a) in rows.items()},
           "ns": {"element": element * 1e9, "listed_pair": listed * 1e9,
                  "touching_pair_extra": touching * 1e9},
           "weights_per_side": {"listed": 0.5 * listed / element,
                                "touching": 0.5 * touching / element}}
    print(json.dumps(out["ns"]), json.dumps(out["weights_per_side"]))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "mpi_cost_model.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
