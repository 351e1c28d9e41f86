"""HDF5 output of a run; the layout is documented in docs/output-format.md.

Per-particle data of all frames are concatenated along the first axis of extendable,
chunked datasets under ``/particles``; frame k holds rows ``start[k] : start[k] + count[k]``
(the particle count may change between frames).

Durability: the file is built with its whole layout under a temporary name in the same
directory, fsynced and renamed onto its name (``os.replace``), so a file at the final name
always opens; it is then reopened in SWMR mode and flushed after every frame. Each frame
is flushed in two steps, the particle rows and the frame table first, ``/frames/time``
extended last, so a run killed at any moment leaves a readable file whose frames are the
ones fully written (:func:`load` also drops a frame whose rows are not all there).

One writer per file: a :class:`Writer` holds an exclusive lock on its file for its whole
life (a Linux open-file-description lock of a byte far past the end of the file, which
readers and HDF5 never take, so ``dpm.load`` and SWMR readers work while it writes); a
new writer of an existing file (a restart, or a new run with ``overwrite=True``) must take
it first, so it is refused while a live process writes the file, naming that process (the
lock of a dead process is released by the system).
"""

from __future__ import annotations

import errno
import gc
import hashlib
import json
import os
import re
import socket
import sys
import tempfile
import time as _time
import traceback
import warnings
import weakref
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._lazy import lazy_module
from ..errors import DpmError, OutputError, ParameterError
from . import repair, space
from .contacts import CONTACT_FIELDS, PARTICLE_FIELDS
from .solids import SOLID_FRAME_FIELDS, solid_rows

h5py = lazy_module("h5py")

try:
    import fcntl
except ImportError:  # (no file locks here: one writer per file is not enforced)
    fcntl = None

if TYPE_CHECKING:
    from ..simulation import Simulation

FORMAT = "dpm-hdf5"
FORMAT_VERSION = 1
#: per-particle fields: name -> (width, dtype, Bodies attribute)
FIELDS = {
    "id": (0, "i8", "id"),
    "position": (3, "f8", "position"),
    "velocity": (3, "f8", "velocity"),
    "orientation": (4, "f8", "orientation"),
    "angular_velocity": (3, "f8", "angular_velocity"),
    "radius": (0, "f8", "radius"),
    "mass": (0, "f8", "mass"),
    "material": (0, "i4", "material"),
    "shape": (0, "i4", "shape"),
}
#: units of the datasets (the ``unit`` attribute of each; "" dimensionless)
UNITS = {"position": "m", "velocity": "m/s", "orientation": "", "angular_velocity": "rad/s",
         "radius": "m", "mass": "kg", "time": "s", "residence_time": "s", "force": "N",
         "torque": "N m", "kinetic_energy": "J", "work": "J", "dissipated": "J",
         "surface": "m", "pose": "m (origin), 1 (rotation)", "local_vertices": "m",
         "normal_force": "N", "overlap": "m", "point": "m", "ends": "m", "rotation": ""}
#: per-element fields of clustered bodies: name -> (width, dtype)
ELEMENT_FIELDS = {"position": (3, "f8"), "radius": (0, "f8"), "body_id": (0, "i8")}
#: records of removed bodies (outlets): name -> (width, dtype)
REMOVED_FIELDS = {"id": (0, "i8"), "time": (0, "f8"), "mass": (0, "f8"),
                  "residence_time": (0, "f8"), "position": (3, "f8"), "velocity": (3, "f8"),
                  "outlet": (0, "i4")}
#: the frame table, one entry per frame (``time`` extended last)
FRAME_FIELDS = {"time": "f8", "step": "i8", "start": "i8", "count": "i8",
                "element_start": "i8", "element_count": "i8"}
#: the frame table's columns of a file with contact output (``contacts=True``)
CONTACT_FRAME_FIELDS = {"contact_start": "i8", "contact_count": "i8"}
#: the names ``sim.output(fields=...)`` takes (``"all"``: every one)
OUTPUT_FIELDS = tuple(PARTICLE_FIELDS)
#: the thermo log (:class:`dpm.analysis.Thermo`): one float64 column each, ``time``
#: extended last (its length is the number of complete rows)
THERMO_COLUMNS = ("time", "step", "particles", "kinetic_energy", "contacts", "max_overlap",
                  "inserted", "removed", "work", "dissipated")
#: the XDMF sidecar is rewritten after a frame when the last write is older than this [s]
#: (and after the first frame, at every flush and at close)
XDMF_INTERVAL_S = 5.0
#: a scene file's text up to this size [bytes] is stored in every output file; a larger
#: one by its path and SHA-256 (``scene_sha256``)
SCENE_TEXT_MAX = 1 << 20
#: datasets a resume keeps whole (not rows of frames)
_UNCUT = frozenset({"line_nodes"})
#: rows copied at a time when a file is rebuilt (:meth:`Writer.resume`)
_COPY_BLOCK_BYTES = 64 << 20


def _fsync(path: Path, directory: bool = False) -> None:
    try:
        fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # a file system without fsync on directories
    finally:
        os.close(fd)


def _temp_beside(path: Path, suffix: str = ".tmp") -> Path:
    """A new empty file in the directory of ``path`` (hidden, unique name naming this host
    and process, so that :func:`clean_stale_temps` knows a dead writer's), with the mode
    a plain new file would get (mkstemp's is 0600)."""
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{_HOST}.{os.getpid()}.",
                                suffix=suffix)
    try:
        os.fchmod(fd, 0o666 & ~_umask())
    except (AttributeError, OSError):
        pass
    finally:
        os.close(fd)
    return Path(name)


_HOST = socket.gethostname().replace("/", "_") or "host"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True
    return True


def clean_stale_temps(directory: Path) -> list[Path]:
    """Remove the temporary files in ``directory`` that writers of this host left when
    they were killed (:func:`_temp_beside`'s names: the process is gone); returns them.
    Those of live processes and of other hosts (a shared file system) are left."""
    pattern = re.compile(r"^\..+\." + re.escape(_HOST) + r"\.(\d+)\.[^/]*(tmp|probe)$")
    gone = []
    try:
        names = os.listdir(directory)
    except OSError:
        return gone
    for name in names:
        m = pattern.match(name)
        if m and int(m.group(1)) != os.getpid() and not _alive(int(m.group(1))):
            p = Path(directory) / name
            try:
                p.unlink()
                gone.append(p)
            except OSError:
                pass
    return gone


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _publish(tmp: Path, path: Path, overwrite: bool) -> None:
    """Rename the finished ``tmp`` onto ``path``: atomically; without ``overwrite`` never
    over an existing file (a hard link fails when the name exists)."""
    _fsync(tmp)
    if overwrite:
        os.replace(tmp, path)
    else:
        try:
            os.link(tmp, path)
        except FileExistsError:
            tmp.unlink(missing_ok=True)
            raise ParameterError(_exists_message(path)) from None
        except OSError:  # no hard links on this file system: check, then rename
            if path.exists():
                tmp.unlink(missing_ok=True)
                raise ParameterError(_exists_message(path)) from None
            os.replace(tmp, path)
        else:
            tmp.unlink()
    _fsync(path.parent, directory=True)


def _exists_message(path: Path | str) -> str:
    return (f"sim.output(): {str(path)!r} already exists and is kept; pass overwrite=True "
            f"to replace it (and its XDMF sidecars) or choose another name")


# ----------------------------------------------------------------- one writer per file
#: the files this process's writers hold: (device, inode) -> the Writer (weakly)
_HELD: dict[tuple[int, int], Any] = {}
#: the writer's lock: an open-file-description (OFD) write lock of this byte of the file,
#: far past its end (HDF5 and readers never lock it; HDF5's own locks are flock locks,
#: independent of these); the owner's process id is the offset of a second one-byte lock
#: after it (OFD locks carry no process id), found with F_OFD_GETLK
_LOCK_AT = 1 << 62
_PID_SPAN = 1 << 31


def _lock(fd: int, cmd: int, kind: int, start: int, length: int) -> tuple[int, ...]:
    import struct

    fmt = "hhqqi4x"  # struct flock: l_type, l_whence, l_start, l_len, l_pid (Linux)
    out = fcntl.fcntl(fd, cmd, struct.pack(fmt, kind, os.SEEK_SET, start, length, 0))
    return struct.unpack(fmt, out)


class _Claim:
    """An open descriptor of a run file that holds the writer's lock on it (see
    :func:`_claim`). Released by :meth:`release` or when it is collected."""

    def __init__(self, fd: int, key: tuple[int, int]) -> None:
        self.fd, self.key = fd, key

    def release(self) -> None:
        fd, self.fd = self.fd, -1
        if fd >= 0:
            os.close(fd)  # (releases the locks)
            owner = _HELD.get(self.key)
            if owner is not None and getattr(owner(), "_claim", None) in (self, None):
                _HELD.pop(self.key, None)

    def __del__(self) -> None:
        try:
            self.release()
        except Exception:  # noqa: BLE001  (at interpreter exit)
            pass


def _holder(fd: int) -> str:
    """" by process N" for the owner of the writer's lock on the file open at ``fd``; ""
    where it cannot be told."""
    try:
        kind, _, start, _, _ = _lock(fd, fcntl.F_OFD_GETLK, fcntl.F_WRLCK, _LOCK_AT + 1,
                                     _PID_SPAN)
    except (OSError, ValueError):
        return ""
    if kind == fcntl.F_UNLCK:
        return ""
    pid = start - _LOCK_AT - 1
    return f" by process {pid}{' (this process)' if pid == os.getpid() else ''}"


def _claim(path: Path, call: str) -> _Claim | None:
    """Claim the existing file ``path`` for writing, for the writer's whole life: an
    exclusive lock that readers never take, refused with :class:`ParameterError` naming the
    file and the process that holds it when a live writer has it. A lock of this process's
    own writer whose file was closed is released first. The lock of a dead process is
    released by the system. None where the system or the file system takes no such lock
    (then nothing is enforced, as before)."""
    setlk = getattr(fcntl, "F_OFD_SETLK", None)
    if setlk is None:
        return None
    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return None
    st = os.fstat(fd)
    key = (st.st_dev, st.st_ino)
    for attempt in (0, 1):
        try:
            _lock(fd, setlk, fcntl.F_WRLCK, _LOCK_AT, 1)
            break
        except OSError as e:
            if e.errno not in (errno.EAGAIN, errno.EACCES):  # no such locks here
                os.close(fd)
                return None
        ref = _HELD.get(key)
        writer = ref() if ref is not None else None
        if attempt == 0 and writer is not None and writer.closed:
            writer._release()  # (its file was closed without Writer.close())
            continue
        who = (" by another Writer of this process (a Simulation still writing it)"
               if writer is not None else _holder(fd) or " by another process")
        os.close(fd)
        raise ParameterError(
            f"{call}: {str(path)!r} is being written{who}; a run file has one writer. "
            f"Let that run end (or stop it) first, or write to another path")
    try:  # (the owner's process id, for the message of a refused writer)
        _lock(fd, setlk, fcntl.F_RDLCK, _LOCK_AT + 1 + os.getpid(), 1)
    except OSError:
        pass
    return _Claim(fd, key)


def _open_rw(path: Path) -> Any:
    """The run file opened for writing (HDF5's own locks as ever: the writer's lock is
    another kind)."""
    return h5py.File(path, "r+", libver="latest")


def check_not_written(path: str | Path, call: str) -> None:
    """Refuse (ParameterError) an existing file that a live writer holds."""
    path = Path(path)
    if path.is_file():
        claim = _claim(path, call)
        if claim is not None:
            claim.release()


def check_output_path(path: str | Path, overwrite: bool, call: str = "sim.output()") -> None:
    """Check at ``output()`` time that a run file can be created at ``path``: not a
    directory, not an existing file unless ``overwrite``, its directory exists or is
    created here, and a file can be created and removed there. Raises ParameterError
    naming the path and the reason."""
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"{call}: cannot write {str(path)!r}: it is a directory")
    if path.exists() or path.is_symlink():
        if not overwrite:
            raise ParameterError(_exists_message(path))
        check_not_written(path, call)  # (overwrite=True: never a file a live run writes)
    writable_directory(path, f"{call}: cannot write {str(path)!r}")


def writable_directory(path: Path, lead: str, allowed: str = "") -> None:
    """Check that files can be created beside ``path``: its directory exists or is created
    here, and a file can be created and removed there. Raises ParameterError starting with
    ``lead`` (the call and the value) and ending with ``allowed``."""
    tail = f"; {allowed}" if allowed else ""
    parent = path.parent
    above = parent
    while not above.exists() and above != above.parent:
        above = above.parent
    if not above.is_dir():
        raise ParameterError(f"{lead}: {str(above)!r} is a file, not a directory{tail}")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ParameterError(f"{lead}: its directory {str(parent)!r} cannot be created "
                             f"({e.strerror or e}){tail}") from None
    if not parent.is_dir():
        raise ParameterError(f"{lead}: {str(parent)!r} is not a directory{tail}")
    try:
        probe = _temp_beside(path, suffix=".probe")
        probe.unlink()
    except OSError as e:
        raise ParameterError(f"{lead}: no file can be created in {str(parent)!r} "
                             f"({e.strerror or e}){tail}") from None


def check_output_fields(fields: Any, call: str = "sim.output()") -> tuple[str, ...]:
    """The optional per-particle fields named by ``fields`` (a name, ``"all"`` or an
    iterable of names of :data:`OUTPUT_FIELDS`), in that table's order; ParameterError
    naming the value and the allowed names otherwise."""
    allowed = f"allowed: a name or a tuple of names of {', '.join(OUTPUT_FIELDS)}, or 'all'"
    if isinstance(fields, str):
        names = OUTPUT_FIELDS if fields == "all" else (fields,)
    else:
        names = fields
    try:
        names = list(names)
    except TypeError:
        raise ParameterError(f"{call}: fields={fields!r}; {allowed}") from None
    for name in names:
        if not isinstance(name, str) or name not in OUTPUT_FIELDS:
            raise ParameterError(f"{call}: fields={fields!r}: {name!r} is not a field; "
                                 f"{allowed}")
    return tuple(k for k in OUTPUT_FIELDS if k in names)


def sidecars(path: str | Path) -> tuple[Path, Path]:
    """The XDMF sidecars of a run file: ``run.xdmf`` and ``run.elements.xdmf``."""
    path = Path(path)
    return path.with_suffix(".xdmf"), path.with_suffix(".elements.xdmf")


#: the other sidecars a run file may have (removed with a file that is replaced)
OTHER_SIDECARS = (".boundaries.xdmf", ".contacts.xdmf", ".solids.xdmf")


def _scene_attrs(f: Any, sim: Simulation) -> None:
    """The scene in the file: ``scene``, the JSON description a checkpoint stores
    (:func:`dpm.checkpoint.scene_description`), its ``scene_fingerprint``, and for a run of
    a TOML scene file (``dpm run scene.toml``) ``scene_file`` and ``scene_toml`` (its
    text). A stand-in of a Simulation that lacks the scene's parts stores none."""
    from ..checkpoint import fingerprint, scene_description

    try:
        description = scene_description(sim)
    except AttributeError:
        return
    f.attrs["scene"] = json.dumps(description, sort_keys=True)
    f.attrs["scene_fingerprint"] = fingerprint(description)
    source = getattr(sim, "_scene_source", None)
    if source is not None:
        f.attrs["scene_file"] = str(source[0])
        text = str(source[1])
        if len(text.encode()) <= SCENE_TEXT_MAX:
            f.attrs["scene_toml"] = text
        else:  # (a scene file with its data inline: its path and digest, not a copy)
            f.attrs["scene_sha256"] = hashlib.sha256(text.encode()).hexdigest()


def _layout(f: Any, sim: Simulation, fields: tuple[str, ...] = (),
            contacts: bool = False, solids: bool = False) -> None:
    """Attributes and every dataset (empty) of a new run file; ``fields``: the optional
    per-particle fields (:data:`OUTPUT_FIELDS`), ``contacts``: the contact output,
    ``solids``: the solid shapes of clustered bodies (:mod:`dpm.io.solids`)."""
    from .. import __version__

    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["dpm_version"] = __version__
    f.attrs["dt"] = sim.dt
    f.attrs["gravity"] = sim.gravity
    f.attrs["integrator"] = sim.integrator.name
    f.attrs["materials"] = [m.name for m in sim.materials] or [""]
    f.attrs["boundaries"] = [b.name for b in sim.boundaries] or [""]
    f.attrs["shapes"] = list(getattr(sim, "shape_names", [])) or [""]
    f.attrs["units"] = "SI: m, s, kg, N, rad (each dataset's unit attribute)"
    _scene_attrs(f, sim)

    def group(name: str, fields: dict[str, tuple[int, str]], rows: int) -> None:
        g = f.create_group(name)
        for field, (width, dtype) in fields.items():
            shape = (0, width) if width else (0,)
            maxshape = (None, width) if width else (None,)
            chunk = (rows, width) if width else (rows,)
            g.create_dataset(field, shape=shape, maxshape=maxshape, dtype=dtype, chunks=chunk)

    prows = min(max(len(sim.bodies), 1), 65536)
    group("particles", {k: (w, d) for k, (w, d, _) in FIELDS.items()}
          | {k: PARTICLE_FIELDS[k] for k in fields}, prows)
    if contacts:
        g = f.create_group("contacts")
        rows = 4 * prows
        for name, (shape, dtype) in CONTACT_FIELDS.items():
            g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype=dtype,
                             chunks=(rows, *shape))
        # the lines' nodes of a frame of C contacts: rows 0 .. C - 1, [2 k, 2 k + 1]
        # (grown to the largest frame; every frame's topology reads its first C rows)
        g.create_dataset("line_nodes", shape=(0, 2), maxshape=(None, 2), dtype="i8",
                         chunks=(rows, 2))
    # sphere elements of clustered bodies (empty when every body is one sphere)
    group("elements", ELEMENT_FIELDS, min(max(len(sim.elements), 1), 65536))
    group("frames", {k: (0, d) for k, d in FRAME_FIELDS.items()}
          | ({k: (0, d) for k, d in CONTACT_FRAME_FIELDS.items()} if contacts else {})
          | ({k: (0, d) for k, d in SOLID_FRAME_FIELDS.items()} if solids else {}), 1024)
    if solids:
        from .solids import solids_layout

        solids_layout(f, 16 * prows)
    nb = max(len(sim.boundaries), 1)
    bg = f.create_group("boundaries")
    for name in ("force", "torque"):
        bg.create_dataset(name, shape=(0, nb, 3), maxshape=(None, nb, 3), dtype="f8",
                          chunks=(64, nb, 3))
    # the boundaries' surfaces (triangles, dpm.io.surfaces): in their own frames once,
    # then per frame each boundary's pose and the world vertices (for ParaView)
    local, faces, owner, vowner = boundary_surfaces(sim)
    sg = f.create_group("surfaces")
    sg.create_dataset("local_vertices", data=local)
    sg.create_dataset("vertex_boundary", data=vowner)
    sg.create_dataset("faces", data=faces)
    sg.create_dataset("boundary", data=owner)
    nv = max(len(local), 1)
    bg.create_dataset("pose", shape=(0, nb, 12), maxshape=(None, nb, 12), dtype="f8",
                      chunks=(64, nb, 12))
    bg.create_dataset("surface", shape=(0, nv, 3), maxshape=(None, nv, 3), dtype="f8",
                      chunks=(max(1, min(64, (1 << 20) // (24 * nv))), nv, 3))
    group("removed", REMOVED_FIELDS, 1024)
    _thermo_layout(f)
    from ..plugins import call_hook, registry

    # plugins' own datasets, while new ones may still be created (before SWMR mode)
    call_hook(getattr(sim, "_registry", None) or registry(), "dpm_output_layout", sim=sim,
              file=f)
    for g in f.values():
        for name, ds in g.items():
            if name in UNITS:
                ds.attrs["unit"] = UNITS[name]


def boundary_surfaces(sim: Simulation) -> tuple[np.ndarray, ...]:
    """(local vertices (V, 3), faces (T, 3), boundary of each face (T,), boundary of each
    vertex (V,)) of every boundary's surface (:mod:`dpm.io.surfaces`); planes are drawn
    over the particles' bounding box, widened by half."""
    from .surfaces import boundary_surface

    pos = sim.bodies.position
    if len(pos):
        lo, hi = pos.min(axis=0), pos.max(axis=0)
        centre, extent = 0.5 * (lo + hi), 0.75 * float(np.max(hi - lo)) + 1e-3
    else:
        centre, extent = np.zeros(3), 1.0
    verts, faces, owner, vowner, n = [], [], [], [], 0
    for k, bd in enumerate(sim.boundaries):
        v, fc = boundary_surface(bd, extent, centre)
        verts.append(v)
        faces.append(fc + n)
        owner.append(np.full(len(fc), k, np.int32))
        vowner.append(np.full(len(v), k, np.int32))
        n += len(v)
    if not verts:
        return (np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int32),
                np.zeros(0, np.int32))
    return tuple(np.concatenate(a) for a in (verts, faces, owner, vowner))


def _thermo_layout(f: Any) -> None:
    """The empty ``/thermo`` table (created with the file: SWMR allows no new dataset)."""
    g = f.create_group("thermo")
    for name in THERMO_COLUMNS:
        g.create_dataset(name, shape=(0,), maxshape=(None,), dtype="f8", chunks=(1024,))


def complete_frames(f: Any) -> tuple[int, int, int]:
    """``(frames, particle_rows, element_rows)`` of the complete frames of an open run file:
    the length of ``/frames/time``, less any trailing frame whose rows are not all written
    (a file that a killed run left behind)."""
    fr = f["frames"]
    n = min(len(fr[k]) for k in (*FRAME_FIELDS, *CONTACT_FRAME_FIELDS, *SOLID_FRAME_FIELDS)
            if k in fr)
    if "boundaries" in f:
        n = min(n, *(len(f["boundaries"][k]) for k in f["boundaries"]))
    rows = min(len(f["particles"][k]) for k in f["particles"])
    has_el = "elements" in f and "element_start" in fr
    erows = min(len(f["elements"][k]) for k in f["elements"]) if has_el else 0
    if n == 0:
        return 0, 0, 0
    start, count = fr["start"][:n], fr["count"][:n]
    ok = start + count <= rows
    if has_el:
        ok &= fr["element_start"][:n] + fr["element_count"][:n] <= erows
    if "contact_start" in fr:
        ok &= fr["contact_start"][:n] + fr["contact_count"][:n] <= contact_rows(f)
    if "solid_vertex_start" in fr:
        vrows, frows = solid_rows(f)
        ok &= fr["solid_vertex_start"][:n] + fr["solid_vertex_count"][:n] <= vrows
        ok &= fr["solid_face_start"][:n] + fr["solid_face_count"][:n] <= frows
    if not ok.all():
        n = int(np.argmin(ok))
    if n == 0:
        return 0, 0, 0
    k = n - 1
    end = int(start[k] + count[k])
    eend = int(fr["element_start"][k] + fr["element_count"][k]) if has_el else 0
    return n, end, eend


def contact_rows(f: Any) -> int:
    """Rows of ``/contacts`` written in full (0 for a file without contact output)."""
    if "contacts" not in f:
        return 0
    return min(len(f["contacts"][k]) for k in CONTACT_FIELDS)


def complete_removed(f: Any) -> int:
    if "removed" not in f:
        return 0
    return min(len(f["removed"][k]) for k in f["removed"])


def complete_thermo(f: Any) -> int:
    """Complete rows of ``/thermo`` (0 when the file has none: written by an older dpm)."""
    if "thermo" not in f:
        return 0
    return min(len(f["thermo"][k]) for k in f["thermo"])


def _check_format(f: Any, path: Path) -> None:
    fmt = f.attrs.get("format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode()
    if fmt != FORMAT:
        raise ParameterError(f"{str(path)!r} is not a dpm run file (format attribute "
                             f"{fmt!r}, expected {FORMAT!r})")
    version = int(f.attrs.get("format_version", 0))
    if version > FORMAT_VERSION:
        raise ParameterError(f"{str(path)!r} has format_version {version}; this dpm reads "
                             f"up to {FORMAT_VERSION}")


def _start_counts(w: Any, sim: Simulation) -> None:
    """A new file's counts: frames, particle and element rows, removal and thermo rows."""
    w.clusters = not (sim.plan is None or sim.plan.spheres_only)
    w.frames = w.rows = w.element_rows = w.removed = w.thermo_rows = 0
    w.contact_rows = w.line_nodes = 0
    w.solids = None
    w._last_step = None  # (the step of the last complete frame)


class Writer:
    """Append frames of a :class:`dpm.Simulation` to an HDF5 file (and its XDMF sidecar).

    ``Writer(path, sim)`` creates the file atomically (see the module docstring); an
    existing file at ``path`` is kept and :class:`ParameterError` raised unless
    ``overwrite=True``, which replaces it and removes its XDMF sidecars.
    :meth:`resume` reopens an existing run file instead, cut back to a checkpoint.

    ``fields`` (optional per-particle fields, :data:`OUTPUT_FIELDS`), ``contacts`` (the
    touching pairs per frame) and ``solids`` (the solid shapes of clustered bodies per
    frame): None takes what ``sim.output()`` stored. The file's layout says what each frame
    holds, so a resumed file goes on with the same fields.
    """

    def __init__(self, path: str | Path, sim: Simulation, overwrite: bool = False,
                 fields: tuple[str, ...] | None = None, contacts: bool | None = None,
                 solids: bool | None = None) -> None:
        if fields is None:
            fields = tuple(getattr(sim, "_output_fields", ()))
        if contacts is None:
            contacts = bool(getattr(sim, "_output_contacts", False))
        if solids is None:
            solids = bool(getattr(sim, "_output_solids", False))
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.is_dir():
            raise ParameterError(f"sim.output(): {str(self.path)!r} is a directory")
        if not overwrite and self.path.exists():
            raise ParameterError(_exists_message(self.path))
        self._claim = None
        clean_stale_temps(self.path.parent)
        # overwrite: the file it replaces must not be one a live process writes (held
        # until the new file is in its place)
        old = _claim(self.path, "sim.output()") if self.path.is_file() else None
        tmp = _temp_beside(self.path)
        claim = None
        try:
            with h5py.File(tmp, "w", libver="latest") as f:
                _layout(f, sim, fields, contacts, solids)
            claim = _claim(tmp, "sim.output()")  # (the new file is ours from its birth)
            _publish(tmp, self.path, overwrite)
        except BaseException:
            tmp.unlink(missing_ok=True)
            if claim is not None:
                claim.release()
            raise
        finally:
            if old is not None:
                old.release()
        for s in (*sidecars(self.path), *(self.path.with_suffix(x) for x in OTHER_SIDECARS)):
            s.unlink(missing_ok=True)  # (those of a replaced file describe other frames)
        self._open(claim)
        _start_counts(self, sim)
        if solids:
            from .solids import Solids

            self.solids = Solids(self.file)

    def _open(self, claim: _Claim | None) -> None:
        """Open the file for SWMR writing, holding ``claim`` (its lock) until close."""
        self._claim = claim
        try:
            self.file = _open_rw(self.path)
            self.file.swmr_mode = True
        except BaseException:
            self._release()
            raise
        if claim is not None:
            _HELD[claim.key] = weakref.ref(self)
        self._last_xdmf = 0.0
        self._local = None  # the surfaces' local vertices (read at the first frame)
        self.failed: str | None = None  # (what stopped the writer: it writes no more)
        # every dataset held open for the writer's life: HDF5 writes a dataset's cached
        # chunks when its last handle closes, and an I/O error there (disk full) is only
        # printed by h5py, never raised; held open, they are written by the explicit
        # flushes, whose errors stop the run before a frame is marked complete
        self._datasets: list[Any] = []
        self.file.visititems(lambda _, obj: self._datasets.append(obj)
                             if isinstance(obj, h5py.Dataset) else None)
        # (group, bytes per row, bytes per chunk) of each: the room a write may need
        self._row_sizes = [(ds.name.split("/")[1],
                            ds.dtype.itemsize * int(np.prod(ds.shape[1:], dtype=np.int64)),
                            ds.chunks[0] if ds.chunks else 0) for ds in self._datasets]

    def _reserve(self, rows: dict[str, int]) -> None:
        """Room on disk for a write that appends ``rows[group]`` rows to the datasets of
        each named group (:func:`dpm.io.space.reserve`: a full disk stops the write before
        HDF5 writes a byte): the rows and a new chunk of each of those datasets."""
        need = 0
        for group, row, chunk in self._row_sizes:
            if group in rows:
                need += row * (rows[group] + chunk)
        space.reserve(self.file.id.get_vfd_handle(), need)

    @contextmanager
    def _checked(self, what: str) -> Iterator[None]:
        """Run a write: an I/O error (disk full, quota, a removed directory) stops the
        writer with :class:`OutputError`, the frames written before complete and readable."""
        if self.failed is not None:
            raise OutputError(f"{self.failed} (nothing more is written to this file)")
        try:
            yield
        except DpmError:
            raise
        except (OSError, RuntimeError, ValueError) as exc:
            self._give_up(what, exc)

    def _give_up(self, what: str, exc: BaseException) -> None:
        n = self.frames
        kept = (f"it keeps {n} complete frame(s), up to step {self._last_step}, readable "
                "with dpm.load" if n else "it holds no complete frame")
        why = " ".join(str(exc).split())  # (h5py's messages span lines)
        self.failed = (f"{what} to {str(self.path)!r} failed: {why}; the output stopped "
                       f"there: {kept}")
        # the file as the last complete frame left it: the frame table cut back (where the
        # disk still takes that), the handles closed without a word from h5py
        hook = sys.unraisablehook
        sys.unraisablehook = lambda _: None
        try:
            # (the failed call's frames hold h5py handles: dropped here, not at exit)
            traceback.clear_frames(exc.__traceback__)
            try:
                fr = self.file["frames"]
                for name in fr:
                    if fr[name].shape[0] > n:
                        fr[name].resize(n, axis=0)
                self.file.flush()
            except (OSError, RuntimeError, ValueError):
                pass
            self._datasets = []
            gc.collect()
            try:
                self.file.close()
            except (OSError, RuntimeError, ValueError):
                pass
            try:  # (the sidecar of the complete frames, where the disk takes it)
                write_xdmf(self.path)
            except (OSError, RuntimeError, ValueError, KeyError):
                pass
        finally:
            sys.unraisablehook = hook
        self._release()
        raise OutputError(self.failed) from None

    def _release(self) -> None:
        """Give the file's lock back (after its HDF5 file is closed)."""
        claim, self._claim = getattr(self, "_claim", None), None
        if claim is not None:
            claim.release()

    @classmethod
    def resume(cls, path: str | Path, sim: Simulation, frames: int, removed: int,
               expect: dict[str, Any] | None = None) -> Writer:
        """Reopen the dpm run file ``path`` for appending, cut back to its first ``frames``
        frames and ``removed`` removal records (a checkpoint's :meth:`state`): every
        ``/particles``, ``/elements``, ``/frames``, ``/boundaries`` and ``/removed`` dataset
        is truncated consistently, and the next :meth:`write` appends frame ``frames``.
        ``/thermo`` keeps its rows up to the time of the last kept frame (a file without
        that table, from an older dpm, gets an empty one).

        The frames after a checkpoint are the ones the restarted run writes again (the
        same states), so dropping them loses nothing. A file that a killed run left open
        (HDF5 refuses to reopen it for writing) is repaired in place
        (:func:`dpm.io.repair.clear_status_flags`, as ``h5clear -s``) and cut back; one
        that cannot be repaired is rebuilt: its kept frames are copied into a new file
        that atomically replaces it.

        One writer per file: a file that a live process writes (or keeps open) is refused
        with :class:`ParameterError` naming it and the process, before anything is
        changed. ``expect`` (what a checkpoint recorded of the file, see
        :func:`identity`: ``fingerprint``, ``frames``, ``last_step``, ``last_time``,
        ``last_digest``) must match the file: a file that another run replaced is refused
        by name, not mixed with this run's frames.
        """
        path = Path(path)
        call = f"Writer.resume({str(path)!r})"
        for name, value in (("frames", frames), ("removed", removed)):
            if (isinstance(value, bool) or not isinstance(value, int | np.integer)
                    or value < 0):
                raise ParameterError(f"{call}: {name}={value!r}; allowed: an integer >= 0")
        frames, removed = int(frames), int(removed)
        if not path.is_file():
            raise ParameterError(f"{call}: no such file")
        claim = _claim(path, call)  # (refuses a file a live process writes)
        clean_stale_temps(path.parent)
        try:
            return cls._resume(path, sim, frames, removed, expect, call, claim)
        except BaseException:
            if claim is not None:
                claim.release()
            raise

    @classmethod
    def _resume(cls, path: Path, sim: Simulation, frames: int, removed: int,
                expect: dict[str, Any] | None, call: str, claim: _Claim | None) -> Writer:
        try:
            f = _open_rw(path)
            rebuild = False
        except OSError as e:
            if "lock" in str(e).lower():
                raise ParameterError(f"{call}: the file is open in another process (a run "
                                     f"still writing it?): {e}") from None
            f = None
            if claim is not None and repair.clear_status_flags(path):
                # left open by a killed run (we hold its lock: no live writer): repaired
                # in place, as h5clear -s does, instead of copied
                try:
                    f = _open_rw(path)
                    rebuild = False
                except OSError:
                    f = None
        if f is None:
            try:  # left open for SWMR writing by a killed run, or not HDF5 at all
                f = _open(path)
            except OSError as e2:
                raise ParameterError(f"{call}: not a dpm run file ({e2})") from None
            rebuild = True
        try:
            _check_format(f, path)
            n, _, _ = complete_frames(f)
            if frames > n:
                raise ParameterError(f"{call}: the file has {n} complete frame(s); cannot "
                                     f"resume after frame {frames}")
            if expect:
                _check_identity(f, path, frames, expect, call)
            n_removed = complete_removed(f)
            if removed > n_removed:
                raise ParameterError(f"{call}: the file has {n_removed} removal record(s); "
                                     f"cannot keep {removed}")
            nb = f["boundaries/force"].shape[1]
            if max(len(sim.boundaries), 1) != nb:
                raise ParameterError(f"{call}: the file has {nb} boundary column(s), the "
                                     f"simulation {len(sim.boundaries)} boundaries")
            rows = erows = crows = vrows = frows = 0
            if frames:
                fr, k = f["frames"], frames - 1
                rows = int(fr["start"][k] + fr["count"][k])
                erows = int(fr["element_start"][k] + fr["element_count"][k])
                if "contact_start" in fr:
                    crows = int(fr["contact_start"][k] + fr["contact_count"][k])
                if "solid_vertex_start" in fr:  # (frames may share face rows)
                    vrows = int(fr["solid_vertex_start"][k] + fr["solid_vertex_count"][k])
                    frows = int(np.max(fr["solid_face_start"][:frames]
                                       + fr["solid_face_count"][:frames]))
            has_thermo = "thermo" in f
            thermo = 0
            if has_thermo and frames:
                times = f["thermo/time"][:complete_thermo(f)]
                thermo = int(np.searchsorted(times, f["frames/time"][frames - 1],
                                             side="right"))
            sizes = {"frames": frames, "boundaries": frames, "particles": rows,
                     "elements": erows, "removed": removed, "thermo": thermo,
                     "contacts": crows, "solids": frows, "solids/vertices": vrows}
            if not rebuild:
                _truncate(f, sizes)
        finally:
            f.close()
        if rebuild:
            new = _rebuild(path, sizes, call)  # (the new file is claimed before it is
            if claim is not None:              # renamed onto the name)
                claim.release()
            claim = new
        if not has_thermo:
            with _open_rw(path) as f:
                _thermo_layout(f)
        w = cls.__new__(cls)
        w.path = path
        w._open(claim)
        w._last_step = int(w.file["frames/step"][frames - 1]) if frames else None
        w.clusters = (erows > 0 if sim.plan is None else not sim.plan.spheres_only)
        w.frames, w.rows, w.element_rows, w.removed = frames, rows, erows, removed
        w.thermo_rows = thermo
        w.contact_rows = crows
        w.line_nodes = len(w.file["contacts/line_nodes"]) if "contacts" in w.file else 0
        w.solids = None
        if "solids" in w.file:
            from .solids import Solids

            w.solids = Solids(w.file)
            w.solids.resume(vrows, frows)
        w.write_xdmf()
        return w

    def state(self) -> dict[str, Any]:
        """What a checkpoint stores to :meth:`resume` this file: frames, removed, path."""
        return {"frames": self.frames, "removed": self.removed, "path": str(self.path)}

    def write(self, sim: Simulation) -> None:
        """Append the current state as a frame and flush it to disk (an I/O error raises
        :class:`OutputError`, and the frame is not counted)."""
        with self._checked(f"writing frame {self.frames} (step {sim.step_count})"):
            self._write(sim)
        self._last_step = sim.step_count

    def _write(self, sim: Simulation) -> None:
        if sim.plan is not None:
            self.clusters = not sim.plan.spheres_only
        b = sim.bodies
        n = len(b)
        m = len(sim.elements) if self.clusters else 0
        self._reserve({"particles": n, "elements": m, "frames": 1, "boundaries": 1,
                       "contacts": 8 * n, "solids": 64 * m})
        g = self.file["particles"]
        for name, (_, _, attr) in FIELDS.items():
            ds = g[name]
            ds.resize(self.rows + n, axis=0)
            value = getattr(b, attr, None)  # (a stand-in state may lack the shape)
            ds[self.rows:self.rows + n] = 0 if value is None else value
        extra = [k for k in PARTICLE_FIELDS if k in g]
        if extra or "contacts" in self.file:
            from .contacts import particle_values

            sim.backend.to_host()  # (the contact lists of a device backend)
        for name in extra:
            ds = g[name]
            ds.resize(self.rows + n, axis=0)
            ds[self.rows:self.rows + n] = particle_values(sim, name)
        bg = self.file["boundaries"]
        nb = bg["force"].shape[1]
        for name in ("force", "torque"):
            ds = bg[name]
            ds.resize(self.frames + 1, axis=0)
            vals = np.zeros((nb, 3))
            for k, bd in enumerate(sim.boundaries):
                vals[k] = getattr(bd, name)
            ds[self.frames] = vals
        if "pose" in bg:
            self._write_surfaces(sim, bg, nb)
        if m:
            e = sim.elements
            eg = self.file["elements"]
            values = {"position": e.position, "radius": e.radius, "body_id": b.id[e.owner]}
            for name in ELEMENT_FIELDS:
                ds = eg[name]
                ds.resize(self.element_rows + m, axis=0)
                ds[self.element_rows:self.element_rows + m] = values[name]
        fr = self.file["frames"]
        columns = [("step", sim.step_count), ("start", self.rows), ("count", n),
                   ("element_start", self.element_rows), ("element_count", m)]
        nc = 0
        if "contacts" in self.file:
            nc = self._write_contacts(sim)
            columns += [("contact_start", self.contact_rows), ("contact_count", nc)]
        if self.solids is not None:
            s = self.solids
            placed = (s.write(sim) if self.clusters else (s.vertex_rows, 0, s.face_rows, 0))
            columns += list(zip(SOLID_FRAME_FIELDS, placed, strict=True))
        for name, value in columns:
            fr[name].resize(self.frames + 1, axis=0)
            fr[name][self.frames] = value
        # the frame count is the length of /frames/time: extended last, after a flush of
        # everything else, so that no frame is ever on disk before its rows
        self.file.flush()
        fr["time"].resize(self.frames + 1, axis=0)
        fr["time"][self.frames] = sim.time
        self.file.flush()
        self.rows += n
        self.element_rows += m
        self.contact_rows += nc
        self.frames += 1
        now = _time.monotonic()
        if self.frames == 1 or now - self._last_xdmf > XDMF_INTERVAL_S:
            self._write_xdmf()
            self._last_xdmf = now

    def _write_contacts(self, sim: Simulation) -> int:
        """This frame's touching pairs (:func:`dpm.io.contacts.contact_rows`) appended to
        ``/contacts``; ``line_nodes`` grown to this frame's count. Returns the count."""
        from .contacts import contact_rows

        rows = contact_rows(sim)
        g = self.file["contacts"]
        k, nc = self.contact_rows, len(rows["id"])
        for name in CONTACT_FIELDS:
            ds = g[name]
            ds.resize(k + nc, axis=0)
            ds[k:k + nc] = rows[name]
        if nc > self.line_nodes:
            ds = g["line_nodes"]
            ds.resize(nc, axis=0)
            ds[self.line_nodes:nc] = 2 * np.arange(self.line_nodes, nc)[:, None] + [0, 1]
            self.line_nodes = nc
        return nc

    def _write_surfaces(self, sim: Simulation, bg: Any, nb: int) -> None:
        """This frame's pose of every boundary and the world vertices of its surface."""
        from ..motion import frames as motion_frames
        from .surfaces import world

        pose = np.zeros((nb, 12))
        pose[:, 3:12] = np.eye(3).ravel()
        for k, bd in enumerate(sim.boundaries):
            pose[k] = motion_frames(getattr(bd, "motion", None), np.array([sim.time]))[0, :12]
        if self._local is None:
            sg = self.file["surfaces"]
            self._local = (sg["local_vertices"][:], sg["vertex_boundary"][:])
        local, owner = self._local
        xyz = np.zeros(bg["surface"].shape[1:])
        for k in range(len(sim.boundaries)):
            sel = owner == k
            xyz[:len(local)][sel] = world(local[sel], pose[k])
        for name, value in (("pose", pose), ("surface", xyz)):
            ds = bg[name]
            ds.resize(self.frames + 1, axis=0)
            ds[self.frames] = value

    def write_removed(self, records: dict[str, np.ndarray], outlet: int) -> None:
        """Append the records of bodies an outlet removed (``id`` extended last)."""
        if len(records["id"]):
            with self._checked(f"writing {len(records['id'])} removal record(s)"):
                self._write_removed(records, outlet)

    def _write_removed(self, records: dict[str, np.ndarray], outlet: int) -> None:
        n = len(records["id"])
        self._reserve({"removed": n})
        rg = self.file["removed"]
        values = dict(records, outlet=np.full(n, outlet))
        for name in [k for k in REMOVED_FIELDS if k != "id"] + ["id"]:
            if name == "id":
                self.file.flush()
            ds = rg[name]
            ds.resize(self.removed + n, axis=0)
            ds[self.removed:self.removed + n] = values[name]
        self.removed += n
        self.file.flush()

    def write_thermo(self, row: dict[str, float]) -> None:
        """Append one row to ``/thermo`` (columns :data:`THERMO_COLUMNS`; a column the row
        lacks is NaN) and flush; ``time`` is extended last, so a row is complete on disk
        once its time is there."""
        unknown = set(row) - set(THERMO_COLUMNS)
        if unknown:
            raise ParameterError(f"Writer.write_thermo(): unknown column(s) "
                                 f"{', '.join(sorted(unknown))}; columns: "
                                 f"{', '.join(THERMO_COLUMNS)}")
        with self._checked("writing a thermo row"):
            self._write_thermo(row)

    def _write_thermo(self, row: dict[str, float]) -> None:
        self._reserve({"thermo": 1})
        g = self.file["thermo"]
        k = self.thermo_rows
        for name in THERMO_COLUMNS[1:] + THERMO_COLUMNS[:1]:
            if name == "time":
                self.file.flush()
            ds = g[name]
            ds.resize(k + 1, axis=0)
            ds[k] = float(row.get(name, np.nan))
        self.thermo_rows = k + 1
        self.file.flush()

    def write_xdmf(self) -> None:
        """Rewrite the XDMF sidecar(s) for the frames written so far (atomically)."""
        with self._checked("writing the XDMF sidecar"):
            self._write_xdmf()

    def _write_xdmf(self) -> None:
        from .xdmf import write_xdmf_from_arrays

        fr = self.file["frames"]
        k = self.frames
        write_xdmf_from_arrays(self.path, fr["time"][:k], fr["start"][:k], fr["count"][:k],
                               self.rows, fields=set(self.file["particles"]))
        if "surfaces" in self.file and len(self.file["surfaces/faces"]):
            from .xdmf import write_boundaries_xdmf

            write_boundaries_xdmf(self.path, fr["time"][:k],
                                  self.file["boundaries/surface"].shape[1],
                                  len(self.file["surfaces/faces"]))
        if self.clusters:
            write_xdmf_from_arrays(self.path, fr["time"][:k], fr["element_start"][:k],
                                   fr["element_count"][:k], self.element_rows,
                                   group="elements")
        if "contacts" in self.file:
            from .xdmf import write_contacts_xdmf

            write_contacts_xdmf(self.path, fr["time"][:k], fr["contact_start"][:k],
                                fr["contact_count"][:k], self.contact_rows, self.line_nodes)
        if self.solids is not None:
            from .xdmf import write_solids_xdmf

            write_solids_xdmf(self.path, *(fr[c][:k] for c in (("time",)
                                                               + tuple(SOLID_FRAME_FIELDS))),
                              self.solids.vertex_rows, self.solids.face_rows)

    @property
    def closed(self) -> bool:
        return not self.file.id.valid

    def flush(self) -> None:
        """Flush the file and rewrite its XDMF sidecar (nothing after a failure: the run
        stopped with it)."""
        if self.failed is None and self.file.id.valid:
            with self._checked("flushing"):
                self.file.flush()
                self._write_xdmf()
            self._last_xdmf = _time.monotonic()

    def close(self) -> None:
        if self.failed is None and self.file.id.valid:
            self.flush()
            self._datasets = []
            with self._checked("closing"):
                self.file.close()
        self._release()


class NullWriter:
    """What an MPI rank other than 0 keeps in place of a :class:`Writer`: the same frame
    and record counts (so that output and checkpoints fall on the same steps and a
    checkpoint names the same file), no file. Rank 0 writes the whole scene, which every
    rank holds between kernel calls (:mod:`dpm.parallel`)."""

    def __init__(self, path: str | Path, sim: Simulation) -> None:
        self.path = Path(path)
        _start_counts(self, sim)

    def state(self) -> dict[str, Any]:
        return {"frames": self.frames, "removed": self.removed, "path": str(self.path)}

    def write(self, sim: Simulation) -> None:
        self.frames += 1

    def write_removed(self, records: dict[str, np.ndarray], outlet: int) -> None:
        self.removed += len(records["id"])

    def write_thermo(self, row: dict[str, float]) -> None:
        self.thermo_rows += 1

    def write_xdmf(self) -> None:
        """No file here."""

    closed = False

    def flush(self) -> None:
        """No file here."""

    def close(self) -> None:
        """No file here."""


def _truncate(f: Any, sizes: dict[str, int]) -> None:
    """Cut every dataset of the groups in ``sizes`` to that many rows, in place: the frame
    count (``/frames/time``) and removal count (``/removed/id``) first."""
    for group in ("frames", "removed", "thermo", "boundaries", "particles", "elements",
                  "contacts", "solids"):
        if group not in f:
            continue
        g = f[group]
        names = sorted(g, key=lambda k: k not in ("time", "id") or group == "particles")
        for name in names:
            size = sizes.get(f"{group}/{name}", sizes[group])
            if name not in _UNCUT and g[name].shape[0] > size:
                g[name].resize(size, axis=0)
    f.flush()


def _frame_digest(f: Any, k: int) -> str:
    """A digest of frame ``k``'s particle ids and positions (what tells two runs apart)."""
    fr = f["frames"]
    a, n = int(fr["start"][k]), int(fr["count"][k])
    h = hashlib.sha256(np.ascontiguousarray(f["particles/id"][a:a + n]).tobytes())
    h.update(np.ascontiguousarray(f["particles/position"][a:a + n]).tobytes())
    return h.hexdigest()[:16]


def identity(writer: Any) -> dict[str, Any]:
    """What identifies the file ``writer`` writes, at its current frame count (stored in
    a checkpoint, checked by :meth:`Writer.resume`): the file's ``scene_fingerprint``,
    ``frames``, and the step, time and a digest of the ids and positions of the last
    frame. Empty for a writer without an open file."""
    f = getattr(writer, "file", None)
    if f is None or not f.id.valid:
        return {}
    out: dict[str, Any] = {"frames": int(writer.frames),
                           "fingerprint": _text(f.attrs.get("scene_fingerprint")) or ""}
    if writer.frames:
        k = int(writer.frames) - 1
        out["last_step"] = int(f["frames/step"][k])
        out["last_time"] = float(f["frames/time"][k])
        out["last_digest"] = _frame_digest(f, k)
    return out


def _check_identity(f: Any, path: Path, frames: int, expect: dict[str, Any],
                    call: str) -> None:
    """Refuse (ParameterError, by name) a file that is not the one ``expect`` describes."""
    why = ""
    mine, theirs = _text(f.attrs.get("scene_fingerprint")) or "", expect.get("fingerprint")
    if mine and theirs and mine != theirs:
        why = (f"its scene fingerprint is {mine}, the checkpoint's run wrote {theirs} (the "
               f"file of another scene)")
    elif frames and "last_step" in expect:
        k = frames - 1
        step, time = int(f["frames/step"][k]), float(f["frames/time"][k])
        if (step, time) != (int(expect["last_step"]), float(expect["last_time"])):
            why = (f"its frame {k} is at step {step} (t = {time:g} s), the checkpoint's "
                   f"run wrote it at step {expect['last_step']} (t = "
                   f"{float(expect['last_time']):g} s)")
        elif expect.get("last_digest") and _frame_digest(f, k) != expect["last_digest"]:
            why = (f"its frame {k} holds other particles or positions than the "
                   f"checkpoint's run wrote")
    if why:
        raise ParameterError(f"{call}: the file is not the output of the checkpoint's run: "
                             f"{why}. Another run replaced it? It is left as it is; restart "
                             f"with dpm.restart(..., output=None) and write a new file with "
                             f"sim.output(...)")


def _rebuild(path: Path, sizes: dict[str, int], call: str = "Writer.resume()") -> _Claim | None:
    """Copy the file with each group cut to ``sizes`` rows into a new file that atomically
    replaces it (same attributes, datasets, dtypes, chunks); returns the claim of the new
    file (taken before it replaces the old one)."""
    tmp = _temp_beside(path)
    claim = None
    try:
        with _open(path) as src, h5py.File(tmp, "w", libver="latest") as dst:
            dst.attrs.update(src.attrs)
            for gname, g in src.items():
                out = dst.create_group(gname)
                out.attrs.update(g.attrs)
                for name, ds in g.items():
                    rows = ds.shape[0]
                    if name not in _UNCUT:
                        rows = min(rows, sizes.get(f"{gname}/{name}",
                                                   sizes.get(gname, rows)))
                    new = out.create_dataset(name, shape=(rows,) + ds.shape[1:],
                                             # (a contiguous dataset stays contiguous)
                                             maxshape=ds.maxshape if ds.chunks else None,
                                             dtype=ds.dtype,
                                             chunks=ds.chunks, compression=ds.compression,
                                             compression_opts=ds.compression_opts)
                    new.attrs.update(ds.attrs)
                    row_bytes = max(ds.dtype.itemsize * int(np.prod(ds.shape[1:])), 1)
                    block = max(_COPY_BLOCK_BYTES // row_bytes, 1)
                    for a in range(0, rows, block):
                        new[a:min(a + block, rows)] = ds[a:min(a + block, rows)]
        claim = _claim(tmp, call)
        _publish(tmp, path, overwrite=True)
    except BaseException:
        tmp.unlink(missing_ok=True)
        if claim is not None:
            claim.release()
        raise
    return claim


class Run:
    """A run read back from HDF5 (see :func:`load`).

    ``times``, ``steps`` (n_frames,); ``frame(k)`` a dict of the per-particle arrays of
    frame k; ``field(name)`` the list of one field over all frames; ``attrs`` the file
    attributes; ``boundary_force`` (n_frames, n_boundaries, 3). A file with no frame yet
    (a run killed right after it started) has ``n_frames == 0``.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        with _open_run(self.path) as f:
            self.attrs: dict[str, Any] = dict(f.attrs)
            n, self._rows, self._element_rows = complete_frames(f)
            self._contacts = "contacts" in f
            self._solids = "solids" in f
            self.times = f["frames/time"][:n]
            self.steps = f["frames/step"][:n]
            self.start = f["frames/start"][:n]
            self.count = f["frames/count"][:n]
            self.boundary_force = f["boundaries/force"][:n]
            self.boundary_torque = f["boundaries/torque"][:n]
            #: bodies removed by outlets: id, time, mass, residence_time, position,
            #: velocity, outlet (index in sim.outlets)
            self.removed: dict[str, np.ndarray] = {}
            if "removed" in f:
                m = complete_removed(f)
                self.removed = {k: f["removed"][k][:m] for k in REMOVED_FIELDS}
            #: the thermo log (:class:`dpm.analysis.Thermo`): column -> (rows,) array;
            #: empty for a file without one (written by an older dpm)
            self.thermo: dict[str, np.ndarray] = {}
            if "thermo" in f:
                m = complete_thermo(f)
                self.thermo = {k: f["thermo"][k][:m] for k in f["thermo"]}

    def __len__(self) -> int:
        return len(self.times)

    @property
    def n_frames(self) -> int:
        return len(self.times)

    def _index(self, k: int) -> int:
        if not -len(self) <= k < len(self):
            raise IndexError(f"frame {k} out of range: {self.path} has {len(self)} "
                             f"complete frame(s)")
        return k % len(self)

    def frame(self, k: int) -> dict[str, np.ndarray]:
        """The per-particle arrays of frame k (with the optional fields the file has:
        force, torque, contact_count, rotation), its time and step."""
        k = self._index(k)
        a, n = int(self.start[k]), int(self.count[k])
        with _open(self.path) as f:
            out = {name: f["particles"][name][a:a + n] for name in (*FIELDS, *PARTICLE_FIELDS)
                   if name in f["particles"]}  # (a file before "shape" lacks it)
        out["time"] = float(self.times[k])
        out["step"] = int(self.steps[k])
        return out

    def to_dataframe(self, k: int = -1) -> Any:
        """Frame k's per-particle fields as a pandas DataFrame, one row per particle (by
        id), every vector split into scalar columns: ``id``, ``position_x``,
        ``position_y``, ``position_z``, ``velocity_x`` .., ``orientation_w``,
        ``orientation_x``, ``orientation_y``, ``orientation_z``, ``angular_velocity_x``
        .., ``radius``, ``mass``, ``material``, ``shape``, and the optional fields the
        file has (``force_x`` .., ``torque_x`` .., ``contact_count``, ``rotation_xx``,
        ``rotation_xy`` .. ``rotation_zz``: row, column of the rotation matrix). The
        frame's ``time``, ``step`` and the file's ``materials`` and ``shapes`` names are
        in ``df.attrs``. Needs pandas (the ``pandas`` extra)."""
        try:
            import pandas
        except ImportError:
            raise DpmError("Run.to_dataframe() needs pandas: pip install "
                           "'dpm-granular[pandas]' (or pip install pandas)") from None
        f = self.frame(k)
        xyz = "xyz"
        names = {3: tuple(xyz), 4: ("w", "x", "y", "z"),
                 # (rotation: 9 components column after column, VTK's tensor order)
                 9: tuple(xyz[i] + xyz[j] for j in range(3) for i in range(3))}
        columns: dict[str, np.ndarray] = {}
        for name, value in f.items():
            if name in ("time", "step"):
                continue
            a = np.asarray(value)
            if a.ndim == 1:
                columns[name] = a
                continue
            a = a.reshape(len(a), -1)
            parts = names.get(a.shape[1], tuple(str(c) for c in range(a.shape[1])))
            for c, part in enumerate(parts):
                columns[f"{name}_{part}"] = a[:, c]
        df = pandas.DataFrame(columns)
        df.attrs.update(time=f["time"], step=f["step"], path=str(self.path),
                        materials=[_text(m) for m in self.attrs.get("materials", [])],
                        shapes=[_text(s) for s in self.attrs.get("shapes", [])])
        return df

    def elements(self, k: int) -> dict[str, np.ndarray]:
        """Sphere elements of frame k (clustered bodies): position, radius, body_id; empty
        arrays when every body is a single sphere."""
        k = self._index(k)
        with _open(self.path) as f:
            fr = f["frames"]
            a, n = int(fr["element_start"][k]), int(fr["element_count"][k])
            return {name: f["elements"][name][a:a + n] for name in ELEMENT_FIELDS}

    def contacts(self, k: int) -> dict[str, np.ndarray]:
        """The touching pairs of frame k (a file written with ``contacts=True``): ``id``
        (C, 2) body ids, ``ends`` (C, 2, 3) the two body centres, ``point``, ``force`` on
        the first body (C, 3), ``normal_force``, ``overlap`` (C,). Raises KeyError for a
        file without contact output."""
        k = self._index(k)
        with _open(self.path) as f:
            if "contacts" not in f:
                raise KeyError(f"{self.path} has no contact output (sim.output(..., "
                               f"contacts=True) writes it)")
            fr = f["frames"]
            a, n = int(fr["contact_start"][k]), int(fr["contact_count"][k])
            return {name: f["contacts"][name][a:a + n] for name in CONTACT_FIELDS}

    def solids(self, k: int) -> dict[str, np.ndarray]:
        """The solid shapes of the clustered bodies of frame k (a file written with
        ``solids=True``): ``vertices`` (W, 3) world positions, ``faces`` (U, 3) triangles
        (rows of ``vertices``), ``body_id`` and ``shape`` (U,) of each triangle. Raises
        KeyError for a file without solids."""
        k = self._index(k)
        with _open(self.path) as f:
            if "solids" not in f:
                raise KeyError(f"{self.path} has no solids (sim.output(..., solids=True) "
                               f"writes them)")
            fr, g = f["frames"], f["solids"]
            a, n = int(fr["solid_vertex_start"][k]), int(fr["solid_vertex_count"][k])
            b, m = int(fr["solid_face_start"][k]), int(fr["solid_face_count"][k])
            out = {"vertices": g["vertices"][a:a + n]}
            out.update({name: g[name][b:b + m] for name in ("faces", "body_id", "shape")})
            return out

    @property
    def solid_shapes(self) -> list[dict[str, Any]]:
        """The meshes of the clustered shapes of a file with solids (empty otherwise): per
        mesh ``name``, ``description``, ``shape`` (its index in the frames' ``shape``
        field; a shape added after the file was created is past the end of
        ``attrs["shapes"]``), ``volume`` (the ideal solid's),
        ``mesh_volume`` (what the mesh encloses; NaN when it is not closed), ``vertices``
        (V, 3) in the body's principal frame and ``faces`` (T, 3)."""
        from .solids import MESH_FIELDS

        with _open(self.path) as f:
            if "solid_shapes" not in f:
                return []
            g = f["solid_shapes"]
            n = min(len(g[k]) for k in MESH_FIELDS)
            out = []
            for k in range(n):
                a, v = int(g["vertex_start"][k]), int(g["vertex_count"][k])
                b, t = int(g["face_start"][k]), int(g["face_count"][k])
                out.append({"name": g["name"][k].decode(),
                            "description": g["description"][k].decode(),
                            "shape": int(g["shape"][k]), "volume": float(g["volume"][k]),
                            "mesh_volume": float(g["mesh_volume"][k]),
                            "vertices": g["vertices"][a:a + v], "faces": g["faces"][b:b + t]})
            return out

    @property
    def scene(self) -> dict[str, Any] | None:
        """The scene's description stored at the file's creation (the one a checkpoint
        stores: materials, contact laws, boundaries, inlets, outlets, ...); None for a
        file written before dpm stored it."""
        text = _text(self.attrs.get("scene"))
        return None if text is None else json.loads(text)

    @property
    def scene_toml(self) -> str | None:
        """The text of the TOML scene file of the run (``dpm run scene.toml``); None for a
        scene built in Python, a file written before dpm stored it, or a scene file over
        :data:`SCENE_TEXT_MAX` bytes (stored by path and its SHA-256, attribute
        ``scene_sha256``)."""
        return _text(self.attrs.get("scene_toml"))

    @property
    def scene_file(self) -> str | None:
        """The path of the TOML scene file the run came from (None: see :attr:`scene_toml`)."""
        return _text(self.attrs.get("scene_file"))

    def field(self, name: str) -> list[np.ndarray]:
        """One per-particle field over all frames (a list of arrays)."""
        with _open(self.path) as f:
            if name not in FIELDS and name not in f["particles"]:
                raise KeyError(f"unknown field {name!r}; fields: "
                               f"{', '.join(k for k in f['particles'])}")
            ds = f["particles"][name]
            return [ds[int(a):int(a) + int(n)] for a, n in zip(self.start, self.count,
                                                               strict=True)]

    def write_xdmf(self) -> Path:
        """Rewrite the XDMF sidecar(s) beside the file; returns the particles' one."""
        return write_xdmf(self.path)


def _text(value: Any) -> str | None:
    """An HDF5 string attribute as str (None when absent)."""
    if value is None:
        return None
    return value.decode() if isinstance(value, bytes) else str(value)


#: metadata read attempts of a SWMR reader. HDF5's default is 100, each failed checksum
#: followed by a sleep that starts at 1 ns and doubles (H5C__load_entry), so a block that
#: a killed writer left half-written made a read sleep for ever (seen once in
#: tests/io/test_output_safety.py); 30 attempts give a writer racing the reader about a
#: second in all, then the read fails with an error
READ_ATTEMPTS = 30


def _swmr_read_fapl() -> Any:
    """A file access property list for SWMR reads with :data:`READ_ATTEMPTS` (set through
    the HDF5 library h5py loaded: h5py does not wrap ``H5Pset_metadata_read_attempts``);
    None if that library cannot be reached (the default attempts then apply)."""
    global _FAPL
    if _FAPL is None:
        import ctypes
        import glob

        fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
        fapl.set_libver_bounds(h5py.h5f.LIBVER_LATEST, h5py.h5f.LIBVER_LATEST)
        _FAPL = False
        here = os.path.dirname(h5py.__file__)
        for lib in sorted(glob.glob(os.path.join(here, "..", "h5py.libs", "libhdf5-*.so*"))
                          + [h5py.h5.__file__]):
            try:
                fn = ctypes.CDLL(lib).H5Pset_metadata_read_attempts
            except (OSError, AttributeError):
                continue
            fn.argtypes = [ctypes.c_int64, ctypes.c_uint]
            if fn(fapl.id, READ_ATTEMPTS) >= 0:
                _FAPL = fapl
                break
    return _FAPL or None


_FAPL: Any = None


def _open_run(path: Path, call: str = "dpm.load") -> h5py.File:
    """A dpm run file opened for reading; ParameterError naming it when it is missing, not
    HDF5, or another kind of HDF5 file (a checkpoint)."""
    if not path.is_file():
        raise ParameterError(f"{call}({str(path)!r}): "
                             f"{'not a file' if path.exists() else 'no such file'}")
    try:
        f = _open(path)
    except OSError as exc:
        raise ParameterError(f"{call}({str(path)!r}): not an HDF5 file that can be read "
                             f"({' '.join(str(exc).split())})") from None
    fmt = f.attrs.get("format")
    fmt = fmt.decode() if isinstance(fmt, bytes) else fmt
    if fmt == "dpm-checkpoint" or fmt != FORMAT or "frames" not in f:
        f.close()
        what = ("a dpm checkpoint: dpm.restart() continues it" if fmt == "dpm-checkpoint"
                else f"an HDF5 file of another kind (format attribute {fmt!r})")
        raise ParameterError(f"{call}({str(path)!r}): the file is {what}; {call} reads the "
                             "output of sim.output() (a run file)")
    return f


def _open(path: Path) -> h5py.File:
    # swmr=True reads a file that a writer still holds open or that a killed run left behind
    fapl = _swmr_read_fapl()
    if fapl is None:
        return h5py.File(path, "r", libver="latest", swmr=True)
    fid = h5py.h5f.open(os.fsencode(path), h5py.h5f.ACC_RDONLY | h5py.h5f.ACC_SWMR_READ,
                        fapl=fapl)
    return h5py.File(fid)


def write_xdmf(path: str | Path) -> Path:
    """(Re)write the XDMF sidecar(s) of the dpm run file ``path`` for its complete frames
    (``run.xdmf``, and ``run.elements.xdmf`` for clustered bodies); returns the first."""
    from .xdmf import write_xdmf as _write

    return _write(path)


def _xdmf_frames(path: Path) -> int | None:
    """Frames the XDMF sidecar ``path`` lists (None when there is none or it is unreadable)."""
    try:
        return path.read_text().count('GridType="Uniform"')
    except (OSError, UnicodeDecodeError):
        return None


def check_xdmf(run: Run) -> None:
    """Rewrite the sidecar(s) of ``run`` (with a warning) when one lists another number of
    frames than the HDF5 file has (a killed run, or a file cut back by a resume)."""
    particles, elements = sidecars(run.path)
    contacts = run.path.with_suffix(".contacts.xdmf")
    solids = run.path.with_suffix(".solids.xdmf")
    stale = []
    for side, needed in ((particles, True), (elements, run._element_rows > 0),
                         (contacts, run._contacts), (solids, run._solids)):
        if not needed:
            continue
        listed = _xdmf_frames(side)
        if listed is None and not side.exists() and run.n_frames == 0:
            continue
        if listed != run.n_frames:
            stale.append(f"{side.name} lists {'no' if listed is None else listed} frame(s)")
    if not stale:
        return
    what = f"dpm.load({str(run.path)!r}): {' and '.join(stale)}, the file has {run.n_frames}"
    writable = (os.access(run.path, os.W_OK) and os.access(run.path.parent, os.W_OK)
                and all(not s.exists() or os.access(s, os.W_OK) for s in (particles,
                                                                            elements,
                                                                            contacts,
                                                                            solids)))
    if not writable:
        warnings.warn(f"{what}; the file is read-only, the sidecar is not rewritten",
                      stacklevel=3)
        return
    try:
        run.write_xdmf()
    except OSError as e:
        warnings.warn(f"{what}; rewriting the sidecar failed: {e}", stacklevel=3)
        return
    warnings.warn(f"{what}; rewrote the sidecar (a killed run?)", stacklevel=3)


def load(path: str | Path, repair_xdmf: bool = True) -> Run:
    """Read a dpm HDF5 run back. With ``repair_xdmf`` a sidecar that lists another number
    of frames than the file has is rewritten (with a warning), unless the file is
    read-only."""
    run = Run(path)
    if repair_xdmf:
        check_xdmf(run)
    return run
