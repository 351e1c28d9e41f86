"""A run-time hook that writes its own dataset into the run's HDF5 output.

At every output frame, for the boundaries that an :class:`~dpm_contrib_example.motions.Orbit`
moves, the hook reads the frame the engine stepped them with (``sim.walls.frame``: origin
and origin velocity) and writes it under ``/contrib_example/orbit`` of the output file:
``time`` (frames,), ``origin`` and ``velocity`` (frames, k, 3), attribute ``boundaries``
(their indices in ``sim.boundaries``). Row ``frame`` is written at index ``frame``, so a
run resumed from a checkpoint overwrites the rows after the checkpoint's frames. Scenes
without an orbiting boundary get nothing. The same rows are kept in memory
(:func:`recorded`).

The group is laid out when dpm lays out a new output file (hook ``dpm_output_layout``),
before the file goes to HDF5's single-writer/multiple-reader mode. A file laid out without
it (written before the plugin was installed, then resumed) gets the group at the first
frame, which HDF5 2.0 allows in that mode; where an older HDF5 refuses, the hook warns once
and keeps the rows in memory only.
"""

from __future__ import annotations

import warnings
import weakref
from typing import Any

import numpy as np

from .motions import Orbit

#: where the datasets go in the output file
GROUP = "contrib_example/orbit"

_RECORDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_WARNED: weakref.WeakSet = weakref.WeakSet()


def _layout(f: Any, n: int, ks: list[int]) -> None:
    """The group and its empty extendable datasets."""
    g = f.require_group(GROUP)
    g.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(256,))
    for name in ("origin", "velocity"):
        g.create_dataset(name, shape=(0, n, 3), maxshape=(None, n, 3), dtype="f8",
                         chunks=(256, n, 3))
    g.attrs["boundaries"] = np.asarray(ks, np.int64)
    g["time"].attrs["unit"] = "s"
    g["origin"].attrs["unit"] = "m"
    g["velocity"].attrs["unit"] = "m/s"


def layout(sim: Any, f: Any) -> None:
    """The hook ``dpm_output_layout``: the group of a scene with orbiting boundaries."""
    ks = orbiting(sim)
    if ks and f.get(GROUP) is None:
        _layout(f, len(ks), ks)


def orbiting(sim: Any) -> list[int]:
    """Indices of the boundaries of ``sim`` moved by an Orbit."""
    return [k for k, b in enumerate(sim.boundaries) if isinstance(b.motion, Orbit)]


def recorded(sim: Any) -> dict[str, np.ndarray]:
    """What the hook recorded for ``sim``: frame, time, origin, velocity (arrays)."""
    rows = _RECORDS.get(sim, [])
    if not rows:
        return {"frame": np.zeros(0, np.int64), "time": np.zeros(0),
                "origin": np.zeros((0, 0, 3)), "velocity": np.zeros((0, 0, 3))}
    return {"frame": np.array([r[0] for r in rows]), "time": np.array([r[1] for r in rows]),
            "origin": np.array([r[2] for r in rows]), "velocity": np.array([r[3] for r in rows])}


def on_output(sim: Any, frame: int) -> None:
    ks = orbiting(sim)
    if not ks or getattr(sim, "walls", None) is None:
        return
    fr = np.asarray(sim.walls.frame)
    origin, velocity = fr[ks, 0:3].copy(), fr[ks, 12:15].copy()
    rows = _RECORDS.setdefault(sim, [])
    rows[:] = [r for r in rows if r[0] < frame]  # (a resumed run writes them again)
    rows.append((frame, float(sim.time), origin, velocity))
    f = getattr(sim.last_output, "file", None)
    if f is None:  # no file on this process (an MPI rank other than 0)
        return
    if f.get(GROUP) is None:
        try:
            _layout(f, len(ks), ks)
        except (ValueError, RuntimeError, OSError) as exc:  # HDF5 < 2.0 in SWMR mode
            if sim not in _WARNED:
                _WARNED.add(sim)
                warnings.warn(f"dpm-contrib-example: cannot add {GROUP} to {f.filename} "
                              f"({exc}); the rows are kept in memory only (recorded(sim))",
                              stacklevel=2)
            return
    g = f[GROUP]
    for name, value in (("origin", origin), ("velocity", velocity), ("time", sim.time)):
        ds = g[name]
        ds.resize(frame + 1, axis=0)
        ds[frame] = value
    f.flush()
