"""The contact lists' sort by row then key: ``np.lexsort`` against the O(n) counting sort
of :mod:`dpm.kernels.entry_order`, in one process, on entries shaped like a settled bed's
list (each row a few keys above it, ~6 touching pairs a sphere as box_settle's bed).

Two orders of the same entries: as a migration's pool gives them (rows mostly in order,
a rank's kept rows first, then the received ones) and shuffled. Median of 7 timings
each; writes ``results/entry_order.json``.

    python benchmarks/entry_order.py                   # 100,000 and 1,000,000 rows
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from dpm.kernels.entry_order import row_key_order

HERE = Path(__file__).resolve().parent


def entries(n_rows: int, per_row: int, rng: np.random.Generator):
    """Pairs (i, j > i): ``per_row`` partners a row at most, some rows shorter."""
    counts = rng.integers(per_row // 2, per_row + 1, n_rows)
    i = np.repeat(np.arange(n_rows), counts)
    j = np.minimum(i + 1 + rng.integers(0, 60, len(i)), n_rows - 1)
    return i, j


def best(f, repeat: int = 7) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--per-row", type=int, default=6)
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    row_key_order(np.zeros(1, np.int64), np.zeros(1, np.int64), 1)  # (compile or load)
    out = []
    for n in args.rows:
        i, j = entries(n, args.per_row, rng)
        # a migration's pool: the kept 97 % of the rows in order, then 3 % received
        moved = rng.random(n) < 0.03
        pool = np.concatenate([np.flatnonzero(~moved[i]), np.flatnonzero(moved[i])])
        for name, o in (("pool order", pool), ("shuffled", rng.permutation(len(i)))):
            a, b = i[o], j[o]
            assert np.array_equal(row_key_order(a, b, n), np.lexsort((b, a)))
            t_lex = best(lambda a=a, b=b: np.lexsort((b, a)))
            t_cnt = best(lambda a=a, b=b, n=n: row_key_order(a, b, n))
            row = {"rows": n, "entries": len(i), "order": name, "lexsort_ms": 1e3 * t_lex,
                   "counting_sort_ms": 1e3 * t_cnt, "speed_up": t_lex / t_cnt}
            out.append(row)
            print(f"{n:>9,} rows, {len(i):>9,} entries, {name:10s}: lexsort "
                  f"{row['lexsort_ms']:7.2f} ms, counting sort {row['counting_sort_ms']:6.2f}"
                  f" ms ({row['speed_up']:.1f}x)", flush=True)
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "entry_order.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
