"""Do freshly copied arrays run a kernel faster than arrays kept for a long run?

NOTES rows 58 and 99 saw an MPI rank's step kernels 5-15 % slower when its arrays were
kept between list rebuilds than when each migration left fresh copies, without a cause.
This asks the machine directly: two sets of the same arrays (positions, velocities,
forces and a neighbour list of ``--n`` points, six partners each, near in index as in a
cell-ordered scene), one kept for the whole run, the other replaced by fresh copies
before every round; a pair-loop kernel (gathers by partner, forces scattered to both
sides, the pattern of the force pass) timed on each in turn, 20 passes a timing, for
``--seconds``. Writes ``results/fresh_arrays.json``: medians of both and of their ratio.

    NUMBA_NUM_THREADS=1 python benchmarks/fresh_arrays.py --n 50000 --seconds 60
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from numba import njit

HERE = Path(__file__).resolve().parent


@njit(cache=True)
def pair_pass(pos, vel, force, nb_start, nb_j):
    for i in range(pos.shape[0]):
        for k in range(nb_start[i], nb_start[i + 1]):
            j = nb_j[k]
            dx = pos[i, 0] - pos[j, 0]
            dy = pos[i, 1] - pos[j, 1]
            dz = pos[i, 2] - pos[j, 2]
            f = (vel[i, 0] - vel[j, 0]) * 1e-3 / (1.0 + dx * dx + dy * dy + dz * dz)
            force[i, 0] += f * dx
            force[i, 1] += f * dy
            force[i, 2] += f * dz
            force[j, 0] -= f * dx
            force[j, 1] -= f * dy
            force[j, 2] -= f * dz


def arrays(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    count = np.full(n, 6)
    start = np.concatenate([[0], np.cumsum(count)])
    j = (np.repeat(np.arange(n), count) + rng.integers(1, 60, int(start[-1]))) % n
    return [rng.random((n, 3)), rng.random((n, 3)), np.zeros((n, 3)), start, j]


def timed(a: list[np.ndarray], passes: int = 20) -> float:
    t = time.perf_counter()
    for _ in range(passes):
        pair_pass(*a)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50000)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--tag", default="fresh_arrays")
    args = ap.parse_args()
    kept = arrays(args.n, np.random.default_rng(0))
    fresh = [a.copy() for a in kept]
    timed(kept, 1)  # (compile)
    t_kept, t_fresh = [], []
    end = time.time() + args.seconds
    while time.time() < end:
        fresh = [np.array(a) for a in fresh]
        for _ in range(3):
            t_kept.append(timed(kept))
            t_fresh.append(timed(fresh))
    k, f = np.array(t_kept), np.array(t_fresh)
    out = {"n": args.n, "timings": len(k), "passes_per_timing": 20,
           "kept_median_s": float(np.median(k)), "fresh_median_s": float(np.median(f)),
           "fresh_over_kept_median": float(np.median(f / k)),
           "fresh_over_kept_quartiles": [float(np.quantile(f / k, q)) for q in (0.25, 0.75)]}
    (HERE / "results" / f"{args.tag}.json").write_text(json.dumps(out, indent=1))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
