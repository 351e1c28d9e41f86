"""A 2-thread run beside a busy process at normal and at lowest priority (NOTES row 44).

The rotating drum of ``drum_peer.py`` (analytic tube, 3,959 beads) on 2 threads, 8 x 500
steps, alone, then beside a Python busy loop started with ``nice -n 0`` and with
``nice -n 19`` (what dpm's background compile now uses). Prints seconds per 500 steps.

    python benchmarks/busy_neighbour.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

sys.path.insert(0, str(Path(__file__).resolve().parent))

BUSY = "import time\nt = time.time()\nwhile time.time() - t < 120: pass\n"


def timed(sim, rounds: int = 8, steps: int = 500) -> list[float]:
    out = []
    for _ in range(rounds):
        t = time.perf_counter()
        sim.run(steps=steps, progress=False)
        out.append(time.perf_counter() - t)
    return out


def main() -> None:
    import drum_peer as D

    cfg = D.config("full")
    sim = D.scene("tube", D.start(cfg["length"], 1), cfg["length"], None)
    sim.threads = 2
    sim.run(steps=500, progress=False)  # compile or load, first rebuilds
    print("alone:", " ".join(f"{x:.3f}" for x in timed(sim)), flush=True)
    for nice in (0, 19):
        busy = subprocess.Popen(["nice", "-n", str(nice), sys.executable, "-c", BUSY])
        try:
            time.sleep(0.5)
            print(f"beside a busy loop at nice {nice}:",
                  " ".join(f"{x:.3f}" for x in timed(sim)), flush=True)
        finally:
            busy.kill()
            busy.wait()


if __name__ == "__main__":
    main()
