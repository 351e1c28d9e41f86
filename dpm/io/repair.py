"""Repair in place of a run file that a killed writer left open.

HDF5 marks a file open for (SWMR) writing in its superblock's consistency flags and
refuses to open it for writing again until they are cleared (its ``h5clear -s`` tool).
A file that a killed dpm run left behind is otherwise whole as of its last flush (the
SWMR writer keeps the file consistent at every flush, and the frame count is extended
last), so :func:`clear_status_flags` clears the flags in place, as ``h5clear -s`` does,
with the end-of-file address raised to the file's size where it lags (as ``h5clear
--increment`` does, so that nothing written past the last flush is reused), and the
superblock's checksum recomputed (Jenkins' lookup3, as HDF5's
``H5_checksum_metadata``). A restart then reopens the file and cuts it back without
copying it.

Only superblock versions 2 and 3 (files written with ``libver="latest"``, as dpm writes
them) are repaired; anything else is left to the caller's fallback (a copy).
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

SIGNATURE = b"\x89HDF\r\n\x1a\n"
_M = 0xFFFFFFFF


def _rot(x: int, k: int) -> int:
    return ((x << k) | (x >> (32 - k))) & _M


def lookup3(data: bytes, initval: int = 0) -> int:
    """Bob Jenkins' lookup3 ``hashlittle`` of ``data`` (HDF5's metadata checksum)."""
    length = len(data)
    a = b = c = (0xDEADBEEF + length + initval) & _M
    i = 0
    while length > 12:
        a = (a + int.from_bytes(data[i:i + 4], "little")) & _M
        b = (b + int.from_bytes(data[i + 4:i + 8], "little")) & _M
        c = (c + int.from_bytes(data[i + 8:i + 12], "little")) & _M
        a = (a - c) & _M
        a ^= _rot(c, 4)
        c = (c + b) & _M
        b = (b - a) & _M
        b ^= _rot(a, 6)
        a = (a + c) & _M
        c = (c - b) & _M
        c ^= _rot(b, 8)
        b = (b + a) & _M
        a = (a - c) & _M
        a ^= _rot(c, 16)
        c = (c + b) & _M
        b = (b - a) & _M
        b ^= _rot(a, 19)
        a = (a + c) & _M
        c = (c - b) & _M
        c ^= _rot(b, 4)
        b = (b + a) & _M
        length -= 12
        i += 12
    if length == 0:
        return c
    tail = data[i:i + length] + bytes(12 - length)
    a = (a + int.from_bytes(tail[0:4], "little")) & _M
    b = (b + int.from_bytes(tail[4:8], "little")) & _M
    c = (c + int.from_bytes(tail[8:12], "little")) & _M
    c = ((c ^ b) - _rot(b, 14)) & _M
    a = ((a ^ c) - _rot(c, 11)) & _M
    b = ((b ^ a) - _rot(a, 25)) & _M
    c = ((c ^ b) - _rot(b, 16)) & _M
    a = ((a ^ c) - _rot(c, 4)) & _M
    b = ((b ^ a) - _rot(a, 14)) & _M
    c = ((c ^ b) - _rot(b, 24)) & _M
    return c


def clear_status_flags(path: str | Path) -> bool:
    """Clear the "open for writing" flags of the HDF5 file ``path`` in place (see the
    module docstring); True when the file was repaired, False when it is not one this
    can repair (no HDF5 signature at 0, a superblock version below 2, 4-byte offsets, a
    checksum that does not match before the change). The file must not be open in a
    live writer (the caller holds the writer's lock)."""
    try:
        fh = open(path, "r+b")  # noqa: SIM115 (closed below)
    except OSError:
        return False
    with fh:
        head = fh.read(12)
        if len(head) < 12 or head[:8] != SIGNATURE or head[8] not in (2, 3) \
                or head[9] != 8:
            return False
        size = 12 + 4 * 8 + 4  # flags, 4 addresses, checksum
        fh.seek(0)
        block = bytearray(fh.read(size))
        if len(block) < size or lookup3(bytes(block[:-4])) != struct.unpack(
                "<I", block[-4:])[0]:
            return False
        block[11] = 0
        eof_at = 12 + 2 * 8
        eof = struct.unpack("<Q", block[eof_at:eof_at + 8])[0]
        actual = os.fstat(fh.fileno()).st_size
        if eof < actual:
            block[eof_at:eof_at + 8] = struct.pack("<Q", actual)
        block[-4:] = struct.pack("<I", lookup3(bytes(block[:-4])))
        fh.seek(0)
        fh.write(block)
        fh.flush()
        os.fsync(fh.fileno())
    return True
