"""Large arrays straight from the operating system and straight back (glibc).

glibc serves a block of 128 KB or more by ``mmap`` and unmaps it on free, but each time
such a block is freed it raises that threshold to the block's size (up to 32 MB), so the
many temporaries of a scene's set-up and a neighbour-list rebuild (a few to a few tens
of MB each at 1e6 spheres) then come from the heap, where freed pages stay resident
wherever a live block sits above them. At 1e6 spheres that kept about 200 MB resident
after ``add_particles`` and raised the peak of the first rebuild by as much
(``benchmarks/NOTES.md`` row 23). A fixed threshold of 1 MB (``mallopt``; setting it turns
the adjustment off) gives every large array its own mapping, returned on free.

The cost is a fresh mapping, and its page faults, for each large allocation: the step
loop allocates only in a rebuild (its scratch), a few ms per rebuild at 1e6 spheres.
``DPM_MALLOC_TUNING=0`` in the environment leaves malloc as it is; other C libraries
(macOS, Windows, musl) are left alone.
"""

from __future__ import annotations

import ctypes
import os
import sys

#: glibc's mallopt parameter number of the mmap threshold
M_MMAP_THRESHOLD = -3
#: blocks of this many bytes or more get their own mapping
MMAP_THRESHOLD = 1 << 20


def tune_malloc() -> bool:
    """Fix glibc's mmap threshold at ``MMAP_THRESHOLD``; True if it was set."""
    if os.environ.get("DPM_MALLOC_TUNING", "1") == "0" or not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):  # not glibc
        return False
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD))
