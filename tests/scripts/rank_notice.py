"""Under mpiexec: ``dpm.notice`` prints once and ``dpm.is_root`` lets one rank write.

    mpiexec -n 3 python tests/scripts/rank_notice.py OUT_DIR
"""

import sys
from pathlib import Path

import dpm

out = Path(sys.argv[1])
dpm.notice("notice from", "the script", sep=" | ")
print(f"print from rank {dpm.parallel.rank()}")
if dpm.is_root():
    with open(out / "summary.txt", "a") as fh:  # (appends: a second writer would show)
        fh.write(f"written by rank {dpm.parallel.rank()}\n")
