"""Each MPI rank's modelled cost against its measured time in the step kernels.

The box_settle scene (10,000 spheres by default) on the ranks it is started on, one
thread each: after ``--warmup`` steps, ``--steps`` more are timed, and each rank reports
its owned bodies and ghosts, the touching pairs and boundary contacts in its lists (those
with a ghost apart), its modelled cost (``MpiBackend._owned_cost``, what the cut evens),
and its seconds in the step kernels and waiting for the slower rank. Where the ratio of
two ranks' times differs from the ratio of their costs, the cost model misses something.
Writes benchmarks/results/mpi_rank_costs.json.

    mpiexec --allow-run-as-root -n 2 python benchmarks/mpi_rank_costs.py
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("DPM_KERNELS", "scene")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def main() -> None:
    import numpy as np
    from box_settle import _example

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lattice", type=int, nargs=3, default=[20, 20, 25])
    ap.add_argument("--warmup", type=int, default=1500)
    ap.add_argument("--steps", type=int, default=1500)
    args = ap.parse_args()
    ex = _example()
    sim = ex.build(ex.initial_packing(*args.lattice))
    sim.threads = 1
    sim.run(steps=args.warmup, progress=False)
    be = sim.backend
    be.totals.clear()
    sim.run(steps=args.steps, progress=False)
    loc = be.local
    c, w = loc.contacts, loc.wall_contacts
    no, ne = loc.n_owned, len(loc.elements.owner)
    act = c.active[:c.count] != 0
    row = np.repeat(np.arange(ne), np.diff(c.start[:ne + 1]))
    with_ghost = (row >= no) | (c.key[:c.count] >= no)
    mine = {"rank": be.rank, "owned": int(no), "ghosts": int(loc.bodies.ghosts),
            "listed_pairs": int(c.count), "touching_pairs": int(act.sum()),
            "touching_pairs_with_a_ghost": int((act & with_ghost).sum()),
            "touching_boundary": int(np.count_nonzero(w.active[:w.count])),
            "modelled_cost": float(be._owned_cost().sum()),
            "work_s": float(be.totals["work_s"]), "wait_s": float(be.totals["wait_s"]),
            "recuts": int(be.totals.get("recuts", 0))}
    every = be.comm.gather(mine, root=0)
    if be.rank == 0:
        cost = np.array([r["modelled_cost"] for r in every])
        work = np.array([r["work_s"] for r in every])
        out = {"lattice": args.lattice, "warmup": args.warmup, "steps": args.steps,
               "ranks": every,
               "cost_max_over_mean": float(cost.max() / cost.mean()),
               "work_max_over_mean": float(work.max() / work.mean())}
        for r in every:
            print(json.dumps(r))
        print(f"largest over mean: modelled cost {out['cost_max_over_mean']:.3f}, "
              f"step-kernel time {out['work_max_over_mean']:.3f}")
        (HERE / "results" / "mpi_rank_costs.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
