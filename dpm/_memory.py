"""Large arrays straight from the operating system and straight back (glibc).

glibc serves a block of 128 KB or more by ``mmap`` and unmaps it on free, but each time
such a block is freed it raises that threshold to the block's size (up to 32 MB), so the
many temporaries of a scene's set-up and a neighbour-list rebuild (a few to a few tens
of MB each at 1e6 spheres) then come from the heap, where freed pages stay resident
wherever a live block sits above them. At 1e6 spheres that kept about 200 MB resident
after ``add_particles`` and raised the peak of the first rebuild by as much. A fixed
threshold of 1 MB (``mallopt``; setting it turns the adjustment off) gives every large
array its own mapping, returned on free.

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


#: bytes of state per body (position, velocity, orientation, forces, mass properties, ids,
#: its share of the neighbour and contact lists) and per sphere element (offset, radius,
#: owner, cell index, neighbour list rows); together 700 B per single-sphere body, the
#: measured peak at 1e6 dense spheres being 631 B
BYTES_PER_BODY = 450
BYTES_PER_ELEMENT = 250


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine (None where the OS does not say)."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_request(call: str, n_bodies: float, n_elements: float) -> None:
    """Refuse, before anything is allocated, a request whose state would not fit in this
    machine's physical memory: ``n_bodies`` bodies with ``n_elements`` sphere elements in
    all need about ``BYTES_PER_BODY`` and ``BYTES_PER_ELEMENT`` bytes each. Raises a
    ParameterError naming the counts, the memory needed and the memory there is."""
    from .errors import ParameterError

    need = float(n_bodies) * BYTES_PER_BODY + float(n_elements) * BYTES_PER_ELEMENT
    have = physical_memory()
    if have is not None and need > have:
        raise ParameterError(
            f"{call}: {float(n_bodies):.4g} bodies ({float(n_elements):.4g} sphere "
            f"elements) would need about {_gb(need)} of memory for their state "
            f"({BYTES_PER_BODY} B per body, {BYTES_PER_ELEMENT} B per element); this "
            f"machine has {_gb(have)}")
