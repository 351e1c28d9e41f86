"""HDF5 output of a run; the layout is documented in docs/output-format.md.

Per-particle data of all frames are concatenated along the first axis of extendable,
chunked datasets under ``/particles``; frame k holds rows ``start[k] : start[k] + count[k]``
(the particle count may change between frames). The file is written in SWMR mode and
flushed after every frame; ``/frames/time`` is extended last, so a run killed at any moment
leaves a readable file whose frames are the ones fully written.
"""

from __future__ import annotations

import time as _time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._lazy import lazy_module

h5py = lazy_module("h5py")

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
}
#: per-element fields of clustered bodies: name -> (width, dtype)
ELEMENT_FIELDS = {"position": (3, "f8"), "radius": (0, "f8"), "body_id": (0, "i8")}
#: records of removed bodies (outlets): name -> (width, dtype)
REMOVED_FIELDS = {"id": (0, "i8"), "time": (0, "f8"), "mass": (0, "f8"),
                  "residence_time": (0, "f8"), "position": (3, "f8"), "velocity": (3, "f8"),
                  "outlet": (0, "i4")}
XDMF_INTERVAL_S = 5.0


class Writer:
    """Append frames of a :class:`dpm.Simulation` to an HDF5 file (and its XDMF sidecar)."""

    def __init__(self, path: str | Path, sim: Simulation) -> None:
        from .. import __version__

        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.file = h5py.File(self.path, "w", libver="latest")
        f = self.file
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["dpm_version"] = __version__
        f.attrs["dt"] = sim.dt
        f.attrs["gravity"] = sim.gravity
        f.attrs["integrator"] = sim.integrator.name
        f.attrs["materials"] = [m.name for m in sim.materials] or [""]
        f.attrs["boundaries"] = [b.name for b in sim.boundaries] or [""]
        n_guess = max(len(sim.bodies), 1)
        g = f.create_group("particles")
        for name, (width, dtype, _) in FIELDS.items():
            shape = (0, width) if width else (0,)
            maxshape = (None, width) if width else (None,)
            chunk = (min(n_guess, 65536), width) if width else (min(n_guess, 65536),)
            g.create_dataset(name, shape=shape, maxshape=maxshape, dtype=dtype, chunks=chunk)
        # sphere elements of clustered bodies (empty when every body is one sphere)
        self.clusters = not (sim.plan is None or sim.plan.spheres_only)
        m_guess = max(len(sim.elements), 1)
        eg = f.create_group("elements")
        for name, (width, dtype) in ELEMENT_FIELDS.items():
            shape = (0, width) if width else (0,)
            maxshape = (None, width) if width else (None,)
            chunk = (min(m_guess, 65536), width) if width else (min(m_guess, 65536),)
            eg.create_dataset(name, shape=shape, maxshape=maxshape, dtype=dtype, chunks=chunk)
        fr = f.create_group("frames")
        for name, dtype in (("time", "f8"), ("step", "i8"), ("start", "i8"), ("count", "i8"),
                            ("element_start", "i8"), ("element_count", "i8")):
            fr.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(1024,))
        nb = max(len(sim.boundaries), 1)
        bg = f.create_group("boundaries")
        for name in ("force", "torque"):
            bg.create_dataset(name, shape=(0, nb, 3), maxshape=(None, nb, 3), dtype="f8",
                              chunks=(64, nb, 3))
        rg = f.create_group("removed")
        for name, (width, dtype) in REMOVED_FIELDS.items():
            shape = (0, width) if width else (0,)
            maxshape = (None, width) if width else (None,)
            chunk = (1024, width) if width else (1024,)
            rg.create_dataset(name, shape=shape, maxshape=maxshape, dtype=dtype, chunks=chunk)
        f.swmr_mode = True
        self.removed = 0
        self.frames = 0
        self.rows = 0
        self.element_rows = 0
        self._last_xdmf = 0.0

    def write(self, sim: Simulation) -> None:
        """Append the current state as a frame and flush it to disk."""
        b = sim.bodies
        n = len(b)
        g = self.file["particles"]
        for name, (_, _, attr) in FIELDS.items():
            ds = g[name]
            ds.resize(self.rows + n, axis=0)
            ds[self.rows:self.rows + n] = getattr(b, attr)
        bg = self.file["boundaries"]
        nb = bg["force"].shape[1]
        for name in ("force", "torque"):
            ds = bg[name]
            ds.resize(self.frames + 1, axis=0)
            vals = np.zeros((nb, 3))
            for k, bd in enumerate(sim.boundaries):
                vals[k] = getattr(bd, name)
            ds[self.frames] = vals
        m = len(sim.elements) if self.clusters else 0
        if m:
            e = sim.elements
            eg = self.file["elements"]
            values = {"position": e.position, "radius": e.radius, "body_id": b.id[e.owner]}
            for name in ELEMENT_FIELDS:
                ds = eg[name]
                ds.resize(self.element_rows + m, axis=0)
                ds[self.element_rows:self.element_rows + m] = values[name]
        fr = self.file["frames"]
        for name, value in (("step", sim.step_count), ("start", self.rows), ("count", n),
                            ("element_start", self.element_rows), ("element_count", m)):
            fr[name].resize(self.frames + 1, axis=0)
            fr[name][self.frames] = value
        self.rows += n
        self.element_rows += m
        # the frame count is the length of /frames/time: extended last
        fr["time"].resize(self.frames + 1, axis=0)
        fr["time"][self.frames] = sim.time
        self.frames += 1
        self.file.flush()
        now = _time.monotonic()
        if self.frames == 1 or now - self._last_xdmf > XDMF_INTERVAL_S:
            self.write_xdmf()
            self._last_xdmf = now

    def write_removed(self, records: dict[str, np.ndarray], outlet: int) -> None:
        """Append the records of bodies an outlet removed (``id`` extended last)."""
        n = len(records["id"])
        if n == 0:
            return
        rg = self.file["removed"]
        values = dict(records, outlet=np.full(n, outlet))
        for name in [k for k in REMOVED_FIELDS if k != "id"] + ["id"]:
            ds = rg[name]
            ds.resize(self.removed + n, axis=0)
            ds[self.removed:self.removed + n] = values[name]
        self.removed += n
        self.file.flush()

    def write_xdmf(self) -> None:
        from .xdmf import write_xdmf_from_arrays

        fr = self.file["frames"]
        write_xdmf_from_arrays(self.path, fr["time"][:], fr["start"][:], fr["count"][:],
                               self.rows)
        if self.clusters:
            write_xdmf_from_arrays(self.path, fr["time"][:], fr["element_start"][:],
                                   fr["element_count"][:], self.element_rows,
                                   group="elements")

    def flush(self) -> None:
        if self.file.id.valid:
            self.file.flush()
            self.write_xdmf()

    def close(self) -> None:
        if self.file.id.valid:
            self.flush()
            self.file.close()


class Run:
    """A run read back from HDF5 (see :func:`load`).

    ``times``, ``steps`` (n_frames,); ``frame(k)`` a dict of the per-particle arrays of
    frame k; ``field(name)`` the list of one field over all frames; ``attrs`` the file
    attributes; ``boundary_force`` (n_frames, n_boundaries, 3).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        with _open(self.path) as f:
            self.attrs: dict[str, Any] = dict(f.attrs)
            n = len(f["frames/time"])
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
                m = len(f["removed/id"])
                self.removed = {k: f["removed"][k][:m] for k in REMOVED_FIELDS}

    def __len__(self) -> int:
        return len(self.times)

    @property
    def n_frames(self) -> int:
        return len(self.times)

    def frame(self, k: int) -> dict[str, np.ndarray]:
        if not -len(self) <= k < len(self):
            raise IndexError(f"frame {k} out of range for {len(self)} frames")
        k = k % len(self)
        a, n = int(self.start[k]), int(self.count[k])
        with _open(self.path) as f:
            out = {name: f["particles"][name][a:a + n] for name in FIELDS}
        out["time"] = float(self.times[k])
        out["step"] = int(self.steps[k])
        return out

    def elements(self, k: int) -> dict[str, np.ndarray]:
        """Sphere elements of frame k (clustered bodies): position, radius, body_id; empty
        arrays when every body is a single sphere."""
        k = k % len(self)
        with _open(self.path) as f:
            fr = f["frames"]
            a, n = int(fr["element_start"][k]), int(fr["element_count"][k])
            return {name: f["elements"][name][a:a + n] for name in ELEMENT_FIELDS}

    def field(self, name: str) -> list[np.ndarray]:
        if name not in FIELDS:
            raise KeyError(f"unknown field {name!r}; fields: {', '.join(FIELDS)}")
        with _open(self.path) as f:
            ds = f["particles"][name]
            return [ds[int(a):int(a) + int(n)] for a, n in zip(self.start, self.count,
                                                               strict=True)]


def _open(path: Path) -> h5py.File:
    # swmr=True reads a file that a writer still holds open or that a killed run left behind
    return h5py.File(path, "r", libver="latest", swmr=True)


def load(path: str | Path) -> Run:
    """Read a dpm HDF5 run back."""
    return Run(path)
