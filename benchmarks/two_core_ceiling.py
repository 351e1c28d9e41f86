"""What two threads can give on this machine, measured on loops simpler than a DEM step.

#18 asks two threads to reach 1.8x LIGGGHTS' one core on every scene kind, small ones
included (the meshGran port's 500 spheres, 2,000 spheres on a meshed floor). Before
blaming the step, this script measures the machine's own ceiling: two ``prange`` loops
compiled by numba with dpm's threading layer, each timed on one and on two threads in
turn (``numba.set_num_threads``), in a compiled loop of many calls (no dispatch cost),
at 2e3 to 2e5 elements:

- ``stream``: a half kick and a drift (``v += f dt``, ``x += v dt``) over n x 3 arrays: the
  memory traffic of an integrator's part, ~4 ns an element;
- ``compute``: 20 sines an element, no memory traffic to speak of.

Gain = time on one thread / time on two, the median of ``--rounds`` alternated rounds.
A step whose loops look like ``stream`` at the scene's size cannot gain more than that
row's gain from a second thread here.

    python benchmarks/two_core_ceiling.py            # writes results/two_core_ceiling.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import dpm  # noqa: F401  (its threading-layer choice: OpenMP first)

HERE = Path(__file__).resolve().parent


def kernels():
    from numba import njit, prange

    @njit(parallel=True)
    def stream(x, v, f, dt):
        for i in prange(x.shape[0]):
            for d in range(3):
                v[i, d] += f[i, d] * dt
                x[i, d] += v[i, d] * dt

    @njit(parallel=True)
    def compute(x, v, f, dt):
        for i in prange(x.shape[0]):
            s = 0.0
            for k in range(20):
                s += np.sin(x[i, 0] + k)
            v[i, 0] = s

    @njit
    def repeat(k, fn, x, v, f, dt):
        for _ in range(k):
            fn(x, v, f, dt)

    return {"stream": stream, "compute": compute}, repeat


def main() -> None:
    import numba

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[2000, 20000, 200000])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--tag", default="two_core_ceiling")
    a = ap.parse_args()
    fns, repeat = kernels()
    rows = []
    for name, fn in fns.items():
        for n in a.sizes:
            rng = np.random.default_rng(0)
            x, v, f = rng.random((n, 3)), np.zeros((n, 3)), rng.random((n, 3))
            k = max(10, (4_000_000 if name == "stream" else 200_000) // n)
            repeat(1, fn, x, v, f, 1e-9)
            us: dict[int, list[float]] = {1: [], 2: []}
            for _ in range(a.rounds):
                for th in (1, 2):
                    numba.set_num_threads(th)
                    t = time.perf_counter()
                    repeat(k, fn, x, v, f, 1e-9)
                    us[th].append((time.perf_counter() - t) / k * 1e6)
            gains = [u1 / u2 for u1, u2 in zip(us[1], us[2], strict=True)]
            rows.append({"loop": name, "elements": n, "us_1_thread": us[1],
                         "us_2_threads": us[2], "gain_median": statistics.median(gains),
                         "gain_rounds": gains})
            print(f"{name:8s} n={n:7d}: 1 thread {statistics.median(us[1]):9.1f} us, "
                  f"2 threads {statistics.median(us[2]):9.1f} us, gain "
                  f"{statistics.median(gains):.2f} (rounds "
                  f"{', '.join(f'{g:.2f}' for g in gains)})", flush=True)
    out = {"machine": platform.machine(), "cores": os.cpu_count(),
           "threading_layer": numba.threading_layer(), "rounds": a.rounds, "rows": rows}
    path = HERE / "results" / f"{a.tag}.json"
    path.write_text(json.dumps(out, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
