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
steps (``shared_scenes.settled_packing``, built once if missing): ``settled`` rebuilds from
its own list, ``settled_migrated`` from a list that holds only the touching pairs, as an
MPI rank's list after a migration (which carries only the touching entries): the slots
sized by that list are too small for a few elements in a hundred.

With two source trees the script is an A/B: every round runs one process per tree, in
turn, and each figure's ratio B/A (above 1: A faster) is the median over the rounds::

    python benchmarks/neighbour_search.py                       # this tree
    python benchmarks/neighbour_search.py --trees /tmp/before . --rounds 3
    python benchmarks/neighbour_search.py --trees /tmp/before . --same-process

(``--same-process``: one process of tree A times A's rebuild and B's, alternated call by
call; separate processes meet different memory placements and moments of a shared machine,
which on small packings can differ by more than a change's effect.)

Writes benchmarks/results/neighbour_search[_quick | _TAG].json (``--quick``: k = 10, 5 rebuilds).
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

import harness
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


def builds(other: str | None) -> list:
    """The rebuild functions to time: this process's dpm's, and with ``other`` (a source
    tree) that tree's ``dpm/kernels/neighbours.py`` loaded beside it (its imports resolve
    to this process's dpm: the two must share ``kernels/config.py`` and the helpers)."""
    import importlib.util

    from dpm.kernels.neighbours import build_neighbour_list

    out = [build_neighbour_list]
    if other:
        name = "dpm.kernels._neighbours_other"
        spec = importlib.util.spec_from_file_location(
            name, Path(other) / "dpm" / "kernels" / "neighbours.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
        out.append(mod.build_neighbour_list)
    return out


def _timed(fns: list, argsets: list, reps: int, before=None) -> list[float]:
    """Median seconds x 1e6 of each function on its own arguments, the functions
    alternated rep by rep (``before(m)``: untimed, before function m's call)."""
    times: list[list[float]] = [[] for _ in fns]
    for rep in range(reps):
        turn = range(len(fns)) if rep % 2 == 0 else range(len(fns) - 1, -1, -1)
        for m in turn:  # (the order flips rep by rep: neither goes first always)
            if before:
                before(m)
            t = time.perf_counter()
            fns[m](*argsets[m])
            times[m].append((time.perf_counter() - t) * 1e6)
    return [statistics.median(x) for x in times]


def rebuild_args(pos: np.ndarray, rad: np.ndarray, skin: float) -> tuple:
    """The arguments of ``build_neighbour_list`` for one list of its own (empty, capacity
    16 pairs an element; no transposed index, no ghosts, not periodic)."""
    n = len(pos)
    cap = 16 * n
    return (pos, rad, np.arange(n, dtype=np.int64), skin, np.zeros(n + 1, np.int64),
            np.zeros(cap, np.int32), np.zeros((cap, 3)), np.zeros(cap, np.uint8),
            np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(6), n)


def rebuild_times(p: np.ndarray, d: float, reps: int, fns: list) -> list[dict]:
    """Median rebuild time [us] of the packing ``p`` on 1 and 2 threads, and its pairs,
    for each rebuild function of ``fns`` (alternated)."""
    import numba

    argsets = [rebuild_args(np.ascontiguousarray(p), np.full(len(p), d / 2), 0.2 * d)
               for _ in fns]
    outs: list[dict] = [{} for _ in fns]
    for threads in (1, 2):
        numba.set_num_threads(threads)
        for fn, args, out in zip(fns, argsets, outs, strict=True):
            fn(*args)
            out["pairs"] = int(fn(*args))
        for out, us in zip(outs, _timed(fns, argsets, reps), strict=True):
            out[str(threads)] = us
    return outs


def settled_times(csv: Path, reps: int, fns: list) -> list[dict]:
    """Median rebuild time [us] of the settled bed ``csv`` on 1 and 2 threads, from its own
    list (``settled``) and from its touching pairs only (``settled_migrated``), for each
    rebuild function of ``fns`` (alternated)."""
    import numba

    from dpm.kernels.neighbours import SLOT_SLACK

    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    pos, rad = np.ascontiguousarray(data[:, :3]), data[:, 6].copy()
    n = len(pos)
    argsets = [rebuild_args(pos, rad, 0.2 * 2 * rad.max()) for _ in fns]
    found = set()
    for fn, args in zip(fns, argsets, strict=True):
        fn(*args)
        found.add(int(fn(*args)))
    if len(found) != 1:
        raise RuntimeError(f"the trees list different pairs on the settled bed: {found}")
    pairs = found.pop()
    start, key = argsets[0][4], argsets[0][5]
    rows = np.repeat(np.arange(n), np.diff(start))
    partner = key[:pairs].astype(np.int64)
    touch = np.linalg.norm(pos[rows] - pos[partner], axis=1) < rad[rows] + rad[partner]
    thin_start = np.zeros(n + 1, np.int64)
    thin_start[1:] = np.cumsum(np.bincount(rows[touch], minlength=n))
    thin_key = partner[touch].astype(np.int32)
    grew = np.diff(start) > np.diff(thin_start) + SLOT_SLACK
    head = {"elements": n, "pairs": pairs, "touching": int(touch.sum()),
            "outgrown_after_migration": float(grew.mean())}
    outs = [{"settled_bed": dict(head)} for _ in fns]

    def thin(m: int) -> None:  # (as a rank's list after a migration: touching pairs only)
        argsets[m][4][:] = thin_start
        argsets[m][5][:len(thin_key)] = thin_key

    for case in ("settled", "settled_migrated"):
        res: list[dict] = [{"pairs": pairs} for _ in fns]
        for threads in (1, 2):
            numba.set_num_threads(threads)
            us = _timed(fns, argsets, reps, thin if case == "settled_migrated" else None)
            for r, u in zip(res, us, strict=True):
                r[str(threads)] = u
        for out, r in zip(outs, res, strict=True):
            out[case] = r
    return outs


def worker(k: int, reps: int, settled: str | None = None, other: str | None = None
           ) -> list[dict]:
    """Rebuild times [us] of this process's dpm (and of ``other``'s rebuild, alternated in
    this process), each {order: {threads: us, "pairs": n}}."""
    from shared_scenes import D, scene_arrays

    import dpm

    fns = builds(other)
    pos, _, _ = scene_arrays(k, "dense")
    n = len(pos)
    outs: list[dict] = [{"elements": n, "dpm": str(Path(dpm.__file__).parent)}]
    outs += [{"elements": n, "dpm": str(other)}] if other else []
    for order in ORDERS:
        p = fcc(n, D) if order == "fcc_mixed" else pos
        if order != "lattice":
            p = p[np.random.default_rng(1).permutation(n)]
        for out, res in zip(outs, rebuild_times(p, D, reps, fns), strict=True):
            out[order] = res
    if settled:
        for out, res in zip(outs, settled_times(Path(settled), reps, fns), strict=True):
            out |= res
    return outs


def run_tree(tree: Path, k: int, reps: int, settled: Path | None,
             other: Path | None = None) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=str(tree.resolve()))
    cmd = [sys.executable, __file__, "--worker", "--k", str(k), "--reps", str(reps)]
    cmd += ["--settled", str(settled)] if settled else []
    cmd += ["--other", str(other.resolve())] if other else []
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    p = harness.parser(__doc__, "a 10^3 lattice, 5 rebuilds a figure")
    p.add_argument("--k", type=int, default=None, help="lattice edge (k^3 spheres; 16)")
    p.add_argument("--reps", type=int, default=None, help="rebuilds a figure (40)")
    p.add_argument("--trees", nargs=2, type=Path, metavar=("A", "B"))
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--tag", default="")
    p.add_argument("--settled", default=None, metavar="NXxNYxNZ",
                   help="also time box_settle's settled bed of this lattice, from its own "
                        "list and from its touching pairs only (as after a migration)")
    p.add_argument("--same-process", action="store_true",
                   help="with --trees A B: one process of tree A times A's rebuild and B's "
                        "(B's neighbours.py loaded beside A's dpm), alternated call by call, "
                        "so that the two meet the same memory and the same moment")
    p.add_argument("--other", default=None, help=argparse.SUPPRESS)
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    a.k = a.k or (10 if a.quick else 16)
    a.reps = a.reps or (5 if a.quick else 40)
    if a.worker:
        print(json.dumps(worker(a.k, a.reps, a.settled, a.other)))
        return
    settled = None
    orders = ORDERS
    if a.settled:
        from shared_scenes import settled_packing

        lat = tuple(int(x) for x in a.settled.split("x"))
        settled = settled_packing(lat, 20000)
        orders = ORDERS + ("settled", "settled_migrated")
    trees = a.trees or [HERE.parent]
    rounds = []
    for r in range(a.rounds if a.trees else 1):
        if a.same_process and a.trees:
            rounds.append(run_tree(trees[0], a.k, a.reps, settled, other=trees[1]))
        else:
            rounds.append([run_tree(t, a.k, a.reps, settled)[0] for t in trees])
        for t, res in zip(trees, rounds[-1], strict=True):
            print(f"round {r + 1} {t}: " + " | ".join(
                f"{o} {res[o]['pairs']} pairs: 1 thread {res[o]['1']:.0f} us, "
                f"2 threads {res[o]['2']:.0f} us" for o in orders), flush=True)
    result: dict = {"k": a.k, "reps": a.reps, "trees": [str(t) for t in trees],
                    "same_process": bool(a.same_process and a.trees),
                    "settled": str(settled) if settled else None, "rounds": rounds}
    if a.trees:
        result["ratio_b_over_a"] = {
            o: {th: statistics.median(r[1][o][th] / r[0][o][th] for r in rounds)
                for th in ("1", "2")} for o in orders}
        for o in orders:
            q = result["ratio_b_over_a"][o]
            print(f"{o}: B/A 1 thread {q['1']:.2f}, 2 threads {q['2']:.2f}")
    harness.write("neighbour_search", result, a.quick,
                  tag=f"neighbour_search_{a.tag}" if a.tag else None)


if __name__ == "__main__":
    main()
