"""What the analysis functions share: frames from a run, a simulation or plain arrays, and
a time series result."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown

#: per-particle keys of a frame dict (those of :meth:`dpm.io.hdf5.Run.frame`)
FRAME_KEYS = ("id", "position", "velocity", "orientation", "angular_velocity", "radius",
              "mass", "material")


@dataclass
class Series:
    """A quantity against time: ``time`` (n,) [s] and ``value`` (n,) (or (n, k))."""

    time: np.ndarray
    value: np.ndarray
    unit: str = ""

    def __len__(self) -> int:
        return len(self.time)

    def __str__(self) -> str:
        head = f"{'time [s]':>12}  value [{self.unit}]" if self.unit else f"{'time [s]':>12}"
        lines = [head]
        for t, v in zip(self.time, self.value, strict=True):
            lines.append(f"{t:12.6g}  {np.array2string(np.asarray(v), precision=6)}")
        return "\n".join(lines)


def is_run(obj: Any) -> bool:
    return hasattr(obj, "frame") and hasattr(obj, "times")


def is_sim(obj: Any) -> bool:
    return hasattr(obj, "bodies") and hasattr(obj, "step_count")


def sim_frame(sim: Any) -> dict[str, Any]:
    """The current state of a :class:`dpm.Simulation` as a frame dict (copies)."""
    b = sim.bodies
    out = {k: np.array(getattr(b, k)) for k in FRAME_KEYS}
    out["inertia"] = np.array(b.inertia)
    out["time"] = float(sim.time)
    out["step"] = int(sim.step_count)
    return out


def frame_index(run: Any, frame: Any) -> int:
    """``frame`` as an index into ``run``'s frames (negative: from the end), or a
    ParameterError naming the run's frame count (not an IndexError)."""
    n = len(run.times)
    try:
        k = int(frame)
        whole = k == frame
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole or isinstance(frame, bool | np.bool_):
        raise ParameterError(f"frame={shown(frame)} is not an integer (a frame index: 0 is "
                             "the first, -1 the last)")
    if not -n <= k < n:
        where = getattr(run, "path", "the run")
        allowed = (f"allowed: 0 .. {n - 1}, or -1 .. -{n} from the end" if n
                   else "it has none to choose from")
        raise ParameterError(f"frame={k}: {where} has {n} frame(s); {allowed}")
    return k % n


def as_frame(obj: Any, frame: int = -1) -> dict[str, Any]:
    """One frame dict from a frame dict, a :class:`~dpm.io.hdf5.Run` (frame ``frame``) or a
    :class:`dpm.Simulation` (its current state)."""
    if isinstance(obj, dict):
        if "position" not in obj:
            raise ParameterError("a frame dict needs at least 'position' (n, 3)")
        return obj
    if is_run(obj):
        return obj.frame(frame_index(obj, frame))
    if is_sim(obj):
        return sim_frame(obj)
    raise ParameterError(f"expected a frame dict, a run (dpm.load) or a Simulation, got "
                         f"{type(obj).__name__}")


def frames_of(source: Any, frames: int | Iterable[int] | slice | None = None
              ) -> Iterator[dict[str, Any]]:
    """Frame dicts of ``source``: a Run (``frames``: an index, indices, a slice, or None
    for all), a Simulation (its current state), a frame dict, or a list of frame dicts."""
    if isinstance(source, dict) or is_sim(source):
        yield as_frame(source)
        return
    if is_run(source):
        n = len(source.times)
        if frames is None:
            idx: Sequence[int] = range(n)
        elif isinstance(frames, slice):
            idx = range(n)[frames]
        elif isinstance(frames, int | np.integer):
            idx = [frame_index(source, frames)]
        else:
            idx = [frame_index(source, k) for k in frames]
        for k in idx:
            yield source.frame(k)
        return
    if isinstance(source, list | tuple):
        seq = source
        if frames is not None:
            seq = [source[k] for k in (range(len(source))[frames] if isinstance(frames, slice)
                                       else np.atleast_1d(frames))]
        for f in seq:
            yield as_frame(f)
        return
    raise ParameterError(f"expected a run (dpm.load), a Simulation, a frame dict or a list "
                         f"of them, got {type(source).__name__}")


def radius_of(f: dict[str, Any], n: int) -> np.ndarray:
    r = f.get("radius")
    if r is None:
        raise ParameterError("the frame has no 'radius'")
    return np.broadcast_to(np.asarray(r, float), (n,))


def mass_of(f: dict[str, Any], n: int) -> np.ndarray:
    m = f.get("mass")
    if m is None:  # unit density
        return 4.0 / 3.0 * np.pi * radius_of(f, n) ** 3
    return np.broadcast_to(np.asarray(m, float), (n,))


def unit(v: Any, name: str) -> np.ndarray:
    v = np.asarray(v, float).reshape(3)
    n = float(np.linalg.norm(v))
    if not n > 0:
        raise ParameterError(f"{name}={shown(v)} must be a non-zero vector")
    return v / n


AXES = {"x": 0, "y": 1, "z": 2}


def axis_index(axis: str | int) -> int:
    if isinstance(axis, str):
        if axis not in AXES:
            raise ParameterError(f"axis={axis!r}; allowed: 'x', 'y', 'z'")
        return AXES[axis]
    if axis not in (0, 1, 2):
        raise ParameterError(f"axis={axis!r}; allowed: 0, 1, 2 or 'x', 'y', 'z'")
    return int(axis)
