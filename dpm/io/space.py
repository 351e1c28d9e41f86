"""Room on disk before a write: a write that fails half-way inside HDF5 leaves a file the
library can neither finish nor close (h5py only prints the errors of the chunks it writes
when a dataset handle closes, and the process may crash at exit), so the output asks for
the room first and stops cleanly where there is none.

- :func:`reserve` allocates the disk blocks a frame may need past the end of an open file
  without changing its size (Linux ``fallocate`` with ``FALLOC_FL_KEEP_SIZE``): a full
  disk (ENOSPC) or quota (EDQUOT) fails there, before HDF5 writes a byte; HDF5 then writes
  into blocks that are already the file's.
- :func:`check_room` is the same question for a new file (a checkpoint): the free space of
  its file system (``statvfs``).
- Both check the process' file-size limit (``ulimit -f``, RLIMIT_FSIZE), which a write
  past it meets with EFBIG (and SIGXFSZ).

Where the system cannot say (another OS, a file system without ``fallocate``), nothing is
checked and a failing write is still caught, later (:class:`dpm.io.hdf5.Writer`).
"""

from __future__ import annotations

import ctypes
import errno
import os
from pathlib import Path

try:
    import resource
except ImportError:  # (not POSIX)
    resource = None

#: room asked beyond the estimate, for HDF5's own metadata (bytes)
MARGIN = 1 << 20
_FALLOC_FL_KEEP_SIZE = 1
_UNSUPPORTED = {errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL, errno.ENODEV, errno.EBADF}
_libc = None


def _fallocate():
    global _libc
    if _libc is None:
        try:
            _libc = ctypes.CDLL(None, use_errno=True)
            _libc.fallocate.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_longlong,
                                        ctypes.c_longlong]
        except (OSError, AttributeError):
            _libc = False
    return getattr(_libc, "fallocate", None) if _libc else None


def size_limit() -> int | None:
    """The process' file-size limit in bytes (``ulimit -f``), None if there is none."""
    if resource is None:
        return None
    soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return None if soft == resource.RLIM_INFINITY else int(soft)


def _check_limit(end: int) -> None:
    limit = size_limit()
    if limit is not None and end > limit:
        raise OSError(errno.EFBIG, f"File too large: the process' file-size limit (ulimit "
                      f"-f) is {limit} bytes; the next write may reach {end}")


def reserve(fd: int, nbytes: int) -> None:
    """Make sure the file open as ``fd`` can grow by ``nbytes`` (+ :data:`MARGIN`): its
    blocks are allocated now, its size unchanged. Raises OSError (ENOSPC, EDQUOT, EFBIG)
    where it cannot."""
    end = os.fstat(fd).st_size
    length = int(nbytes) + MARGIN
    _check_limit(end + length)
    fallocate = _fallocate()
    if fallocate is None:
        return
    if fallocate(fd, _FALLOC_FL_KEEP_SIZE, end, length) != 0:
        err = ctypes.get_errno()
        if err not in _UNSUPPORTED:
            raise OSError(err, os.strerror(err))


def check_room(path: Path, nbytes: int) -> None:
    """Make sure a new file of about ``nbytes`` (+ :data:`MARGIN`) fits beside ``path``:
    the free space of its file system and the file-size limit. Raises OSError (ENOSPC,
    EFBIG) where it does not."""
    need = int(nbytes) + MARGIN
    _check_limit(need)
    try:
        st = os.statvfs(path.parent)
    except (OSError, AttributeError):
        return
    free = st.f_bavail * st.f_frsize
    if free < need:
        raise OSError(errno.ENOSPC, f"No space left on device: {free} bytes free on the "
                      f"file system of {str(path.parent)!r}, about {need} needed")
