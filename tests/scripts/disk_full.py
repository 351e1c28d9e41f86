"""A run that meets a full disk, for tests/io/test_disk_full.py: the small box scene of
tests/small_scene.py writes frames every 10 steps and checkpoints every 50; after
200 steps the file-size limit of the process (RLIMIT_FSIZE, SIGXFSZ ignored: writes past it
fail with EFBIG as they would with ENOSPC on a full disk) is set just above what is on disk.

    python disk_full.py DIR output        the output file meets the limit
    python disk_full.py DIR checkpoint    a checkpoint meets it (no output file)
    python disk_full.py DIR enospc        no limit: the output goes to DIR/full/run.h5, a
                                          small file system the test mounted there

Exits 3 after printing the OutputError's message, 0 if the run ended (it must not).
"""

from __future__ import annotations

import resource
import signal
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from small_scene import small_scene  # noqa: E402

import dpm  # noqa: E402


def main() -> int:
    d, mode = Path(sys.argv[1]), sys.argv[2]
    sim = small_scene()
    if mode != "checkpoint":
        sim.output(d / ("full" if mode == "enospc" else "") / "run.h5", every_steps=10)
    sim.checkpoint_every(d / "run.ckpt.h5", every_steps=50, keep=2)
    sim.run(steps=200, progress=False)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    if mode == "enospc":
        limit = resource.RLIM_INFINITY
    # (the output asks for room for a frame and 1 MiB more: a few frames still fit)
    elif mode == "output":
        limit = (d / "run.h5").stat().st_size + (1 << 20) + 15000
    else:
        limit = 30000
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
    try:
        sim.run(steps=2000, progress=False)
    except dpm.OutputError as exc:
        print(exc, flush=True)
        sim.close()  # (after the failure: quiet)
        return 3
    sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
