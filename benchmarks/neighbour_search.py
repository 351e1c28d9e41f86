"""The neighbour-list rebuild on a packing in cell order and on the same packing mixed.

``dpm.kernels.neighbours.build_neighbour_list`` lists three packings of about k^3 spheres:
the dense box of benchmarks/scaling.py (a cubic lattice, about one sphere per search cell)
numbered in lattice order (``lattice``: box_settle's start) and at random (``mixed``: as a
drum's or a hopper's beads become once they have mixed, in scenes below ``SMALL_SCENE``
elements that are never renumbered), and a face-centred cubic packing of touching spheres
numbered at random (``fcc_mixed``: 2.4 spheres per search cell, as a settled bed's 2-3). Each
rebuild is timed on 1 and 2 threads (the median of ``--reps``), after two untimed calls
(the compile, and a list whose slots are sized by the previous one, as in a run).

With ``--settled NXxNYxNZ`` it also times box_settle's bed of that lattice after 20,000
steps (``mpi_scaling.settled_packing``, built once if missing): ``settled`` rebuilds from
its own list, ``settled_migrated`` from a list that holds only the touching pairs, as an
MPI rank's list after a migration (which carries only the touching entries): the slots
sized by that list are too small for a few elements in a hundred.

With two source trees the script is an A/B: every round runs one process per tree, in
turn, and each figure's ratio B/A (above 1: A faster) is the median over the rounds::

    python benchmarks/neighbour_search.py                       # this tree
    python benchmarks/neighbour_search.py --trees /tmp/before . --rounds 3

Writes benchmarks/results/neighbour_search[_TAG].json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ORDERS = ("lattice", "mixed", "fcc_mixed")


def fcc(n: int, d: float) -> np.ndarray:
    """About ``n`` centres of a face-centred cubic packing of spheres of diameter ``d``
    touching (packing fraction 0.74: 2.4 spheres per search cell, as a settled bed's 2-3)."""
    a = d * np.sqrt(2.0)
    k = int(np.ceil((n / 4) ** (1 / 3)))
    g = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3)
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    return ((g[:, None, :] + basis[None]) * a).reshape(-1, 3)[:n]


def rebuild_times(p: np.ndarray, d: float, reps: int) -> dict:
    """Median rebuild time [us] of the packing ``p`` on 1 and 2 threads, and its pairs."""
    import numba

    from dpm.kernels.neighbours import build_neighbour_list

    n = len(p)
    cap = 16 * n
    args = (np.ascontiguousarray(p), np.full(n, d / 2), np.arange(n, dtype=np.int64), 0.2 * d,
            np.zeros(n + 1, np.int64), np.zeros(cap, np.int32), np.zeros((cap, 3)),
            np.zeros(cap, np.uint8), np.zeros(0, np.int64), np.zeros(0, np.int64),
            np.zeros(6), n)
    out: dict = {}
    for threads in (1, 2):
        numba.set_num_threads(threads)
        build_neighbour_list(*args)
        out["pairs"] = int(build_neighbour_list(*args))
        times = []
        for _ in range(reps):
            t = time.perf_counter()
            build_neighbour_list(*args)
            times.append((time.perf_counter() - t) * 1e6)
        out[str(threads)] = statistics.median(times)
    return out


def settled_times(csv: Path, reps: int) -> dict:
    """Median rebuild time [us] of the settled bed ``csv`` on 1 and 2 threads, from its own
    list (``settled``) and from its touching pairs only (``settled_migrated``)."""
    import numba

    from dpm.kernels.neighbours import SLOT_SLACK, build_neighbour_list

    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    pos, rad = np.ascontiguousarray(data[:, :3]), data[:, 6].copy()
    n = len(pos)
    cap = 16 * n
    start, key = np.zeros(n + 1, np.int64), np.zeros(cap, np.int32)
    args = (pos, rad, np.arange(n, dtype=np.int64), 0.2 * 2 * rad.max(), start, key,
            np.zeros((cap, 3)), np.zeros(cap, np.uint8), np.zeros(0, np.int64),
            np.zeros(0, np.int64), np.zeros(6), n)
    build_neighbour_list(*args)
    pairs = int(build_neighbour_list(*args))
    rows = np.repeat(np.arange(n), np.diff(start))
    partner = key[:pairs].astype(np.int64)
    touch = np.linalg.norm(pos[rows] - pos[partner], axis=1) < rad[rows] + rad[partner]
    thin_start = np.zeros(n + 1, np.int64)
    thin_start[1:] = np.cumsum(np.bincount(rows[touch], minlength=n))
    thin_key = partner[touch].astype(np.int32)
    grew = np.diff(start) > np.diff(thin_start) + SLOT_SLACK
    out: dict = {"elements": n, "pairs": pairs, "touching": int(touch.sum()),
                 "outgrown_after_migration": float(grew.mean())}
    for case in ("settled", "settled_migrated"):
        res: dict = {"pairs": pairs}
        for threads in (1, 2):
            numba.set_num_threads(threads)
            times = []
            for _ in range(reps):
                if case == "settled_migrated":
                    start[:] = thin_start
                    key[:len(thin_key)] = thin_key
                t = time.perf_counter()
                build_neighbour_list(*args)
                times.append((time.perf_counter() - t) * 1e6)
            res[str(threads)] = statistics.median(times)
        out[case] = res
    return out


def worker(k: int, reps: int, settled: str | None = None) -> dict:
    """Rebuild times [us] of this process's dpm, {order: {threads: us, "pairs": n}}."""
    sys.path.insert(0, str(HERE))
    from scaling import D, scene_arrays

    import dpm

    pos, _, _ = scene_arrays(k, "dense")
    n = len(pos)
    out: dict = {"elements": n, "dpm": str(Path(dpm.__file__).parent)}
    for order in ORDERS:
        p = fcc(n, D) if order == "fcc_mixed" else pos
        if order != "lattice":
            p = p[np.random.default_rng(1).permutation(n)]
        out[order] = rebuild_times(p, D, reps)
    if settled:
        out |= settled_times(Path(settled), reps)
    return out


def run_tree(tree: Path, k: int, reps: int, settled: Path | None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree.resolve()))
    cmd = [sys.executable, __file__, "--worker", "--k", str(k), "--reps", str(reps)]
    cmd += ["--settled", str(settled)] if settled else []
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--k", type=int, default=16, help="lattice edge (k^3 spheres)")
    p.add_argument("--reps", type=int, default=40)
    p.add_argument("--trees", nargs=2, type=Path, metavar=("A", "B"))
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--tag", default="")
    p.add_argument("--settled", default=None, metavar="NXxNYxNZ",
                   help="also time box_settle's settled bed of this lattice, from its own "
                        "list and from its touching pairs only (as after a migration)")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.worker:
        print(json.dumps(worker(a.k, a.reps, a.settled)))
        return
    settled = None
    orders = ORDERS
    if a.settled:
        sys.path.insert(0, str(HERE))
        from mpi_scaling import settled_packing

        lat = tuple(int(x) for x in a.settled.split("x"))
        settled = settled_packing(lat, 20000)
        orders = ORDERS + ("settled", "settled_migrated")
    trees = a.trees or [HERE.parent]
    rounds = []
    for r in range(a.rounds if a.trees else 1):
        rounds.append([run_tree(t, a.k, a.reps, settled) for t in trees])
        for t, res in zip(trees, rounds[-1], strict=True):
            print(f"round {r + 1} {t}: " + " | ".join(
                f"{o} {res[o]['pairs']} pairs: 1 thread {res[o]['1']:.0f} us, "
                f"2 threads {res[o]['2']:.0f} us" for o in orders), flush=True)
    result: dict = {"k": a.k, "reps": a.reps, "trees": [str(t) for t in trees],
                    "settled": str(settled) if settled else None, "rounds": rounds}
    if a.trees:
        result["ratio_b_over_a"] = {
            o: {th: statistics.median(r[1][o][th] / r[0][o][th] for r in rounds)
                for th in ("1", "2")} for o in orders}
        for o in orders:
            q = result["ratio_b_over_a"][o]
            print(f"{o}: B/A 1 thread {q['1']:.2f}, 2 threads {q['2']:.2f}")
    name = "neighbour_search" + (f"_{a.tag}" if a.tag else "") + ".json"
    (HERE / "results" / name).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
