"""What two threads can gain on this machine, and what the settled clusters bed gains.

The issue's goal for clustered bodies is two threads at least 1.8x one thread in the
settled bed. Whether a machine allows that depends on how its memory serves two cores,
so this script measures, in one process, one thread against two:

- the machine: the cost of one parallel launch (a loop too short to share), a
  compute-bound loop (arithmetic on a small array, no memory traffic), a
  streaming sum over 64 MB, and a random gather over 32 MB (what a contact pass does when
  it reads its partners' rows);
- the settled bed of ``clusters_settle.py`` (2,000 four-sphere clusters from its own
  lattice start, settled on two threads): the whole step as a user runs it (one thread:
  the one-thread form; two threads: the parallel form), and the step's passes one by one
  on the parallel form at one and at two threads: the pre-force part (the rotation of
  every body), the contact pass (every listed pair, a force row each), the sum pass
  (each body's rows, its partners' rows by the transposed index, the integrator's
  post-force part) and one list rebuild; with the rebuilds per step of the timed steps,
  what the whole step spends outside these (its serial remainder and call overheads).

Each figure is the best of ``--reps`` timings, 1 and 2 threads in turn; the ratio is
one-thread time over two-thread time. numba's threading layer is the one a dpm run takes
(OpenMP first: ``dpm/__init__.py``; TBB's parallel launch costs ~30 us on 2 threads of
this machine against OpenMP's ~3: the ``parallel_launch`` probe).
``NUMBA_THREADING_LAYER=tbb python benchmarks/thread_ceiling.py --tag thread_ceiling_tbb``
measures the same on TBB. Writes ``results/<tag>.json``.

    python benchmarks/thread_ceiling.py
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

import dpm  # noqa: F401  (before any parallel launch: it puts OpenMP first, as in a run)

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


@njit(parallel=True, cache=True)
def _compute(x, out, rounds):
    for i in prange(x.shape[0]):
        v = x[i]
        for _ in range(rounds):
            v = 0.5 * v + 1.0 / (1.0 + v * v)
        out[i] = v


@njit(parallel=True, cache=True)
def _launch(a):
    for i in prange(a.shape[0]):
        a[i] += 1.0


@njit(parallel=True, cache=True)
def _stream(a):
    s = 0.0
    for i in prange(a.shape[0]):
        s += a[i]
    return s


@njit(parallel=True, cache=True)
def _gather(a, idx):
    s = 0.0
    for i in prange(idx.shape[0]):
        s += a[idx[i]]
    return s


def best(fn, reps: int) -> float:
    fn()
    ts = []
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return min(ts)


def in_turn(fn, reps: int) -> dict:
    """``fn`` timed at one and two threads (best of ``reps`` each), and their ratio."""
    t = {}
    for k in (1, 2):
        numba.set_num_threads(k)
        t[k] = best(fn, reps)
    return {"one_thread_s": t[1], "two_threads_s": t[2], "speedup": t[1] / t[2]}


def machine(reps: int) -> dict:
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, 4096)
    out = np.empty_like(x)
    big = rng.uniform(0, 1, 8_000_000)  # 64 MB
    table = rng.uniform(0, 1, 4_000_000)  # 32 MB
    idx = rng.integers(0, len(table), 4_000_000)
    small = np.zeros(64)

    def launches():  # (2,000 launches of a loop too short to be worth a thread)
        for _ in range(2000):
            _launch(small)

    launch = in_turn(launches, reps)
    launch["us_per_launch"] = {k: launch[f"{k}_s"] / 2000 * 1e6
                               for k in ("one_thread", "two_threads")}
    return {"parallel_launch": launch, "compute": in_turn(lambda: _compute(x, out, 2000), reps),
            "stream_64MB": in_turn(lambda: _stream(big), reps),
            "random_gather_32MB": in_turn(lambda: _gather(table, idx), reps)}


def clusters(reps: int, steps: int) -> dict:
    import clusters_settle as cs

    geo = cs.geometry(2000, side=0.035)
    sim = cs.scene(cs.own_start(2000, geo), geo)
    sim.threads = 2
    sim.run(steps=geo["settle_steps"], progress=False)

    rebuilds = sim.rebuild_count

    def run(k: int) -> float:
        sim.threads = k
        return best(lambda: sim.run(steps=steps, progress=False), reps) / steps

    whole = {k: run(k) for k in (1, 2)}
    ran = 2 * (reps + 1) * steps
    rebuilds = (sim.rebuild_count - rebuilds) / ran
    # the passes on the parallel form (the one a two-thread run takes), one and two threads
    os.environ["DPM_ONE_THREAD_FORM"] = "0"
    whole["parallel_form_1"] = run(1)  # (like for like with the passes below)
    sim.threads = 2
    sim.run(steps=1, progress=False)
    be, dt = sim.backend, sim.dt
    m = be.module
    ctl, bodies, elems, pairs, walls, bnd = be.records()
    passes = {
        "pre_force": in_turn(lambda: m.pre_force(0.0, ctl, bodies, elems), reps * 20),
        "contact_pass": in_turn(lambda: m.contact_pass(dt, ctl, bodies, elems, pairs, walls,
                                                       bnd), reps * 20),
        "sum_pass": in_turn(lambda: m.sum_pass(0.0, False, ctl, bodies, elems, pairs,
                                               walls), reps * 20),
        # (last: it leaves force rows uncleared; the steps after would not be a run's)
        "rebuild": in_turn(lambda: m.rebuild(ctl, bodies, elems, pairs, walls, bnd,
                                             be.diag), reps * 4),
    }
    per_step = {k: sum(v[f"{k}_s"] for n, v in passes.items() if n != "rebuild")
                + rebuilds * passes["rebuild"][f"{k}_s"]
                for k in ("one_thread", "two_threads")}
    c = sim.contacts
    return {"bodies": len(sim.bodies), "elements": len(sim.elements),
            "listed_pairs": int(c.count), "touching_pairs": int(sim.contact_count()),
            "step": {"one_thread_s": whole[1], "two_threads_s": whole[2],
                     "speedup": whole[1] / whole[2],
                     "what": "sim.run as a user runs it: one-thread form against two threads"},
            "step_parallel_form": {"one_thread_s": whole["parallel_form_1"],
                                   "two_threads_s": whole[2],
                                   "speedup": whole["parallel_form_1"] / whole[2]},
            "passes_parallel_form": passes, "rebuilds_per_step": rebuilds,
            "passes_per_step_s": per_step,
            "rest_of_step_s": {"one_thread": whole["parallel_form_1"]
                               - per_step["one_thread"],
                               "two_threads": whole[2] - per_step["two_threads"]}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--tag", default="thread_ceiling", help="results/<tag>.json")
    a = ap.parse_args()
    os.environ.setdefault("DPM_KERNELS", "scene")
    out = {"cores": os.cpu_count(), "machine": machine(a.reps),
           "threading_layer": numba.threading_layer()}
    print(f"threading layer: {out['threading_layer']}")
    for k, v in out["machine"].items():
        print(f"machine {k}: 2 threads {v['speedup']:.2f}x one", flush=True)
    us = out["machine"]["parallel_launch"]["us_per_launch"]
    print(f"a parallel launch: {us['one_thread']:.1f} us on one thread, "
          f"{us['two_threads']:.1f} us on two")
    out["settled_clusters"] = clusters(a.reps, a.steps)
    cl = out["settled_clusters"]
    print(f"settled clusters, whole step: 2 threads {cl['step']['speedup']:.2f}x one "
          f"(on the parallel form at both: {cl['step_parallel_form']['speedup']:.2f}x)")
    for k, v in cl["passes_parallel_form"].items():
        print(f"  {k}: {v['one_thread_s'] * 1e6:.0f} / {v['two_threads_s'] * 1e6:.0f} us, "
              f"{v['speedup']:.2f}x")
    print(f"  rebuilds per step {cl['rebuilds_per_step']:.4f}; rest of the step (whole less "
          f"the passes and the rebuilds' share): {cl['rest_of_step_s']['one_thread'] * 1e6:.0f}"
          f" / {cl['rest_of_step_s']['two_threads'] * 1e6:.0f} us")
    out["date"] = time.strftime("%Y-%m-%d")
    path = HERE / "results" / f"{a.tag}.json"
    path.write_text(json.dumps(out, indent=1))
    print("->", path)


if __name__ == "__main__":
    main()
