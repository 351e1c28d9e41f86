"""Exact checkpoints and restart.

A checkpoint holds everything a run needs to go on as if it had never stopped: the
bodies and elements, both contact lists with every contact's history and touching flag,
the integrator's state, the boundaries (their motions are functions of time, their
frames at the last step), the inlets (random generator state, what they owe, their
schedule), the outlets with their records, the output file's position, the event
schedule and plugin state (the ``dpm_on_checkpoint`` hook). :func:`restart` in a new
process continues the trajectory of the uninterrupted run bit for bit (with the same dpm,
numpy and numba; results do not depend on the thread count).

The file is HDF5 (layout in ``docs/reliability.md``) and holds plain data only: the
attributes say what it is (``format``, ``format_version``, ``dpm_version``, ``step``,
``time``, the scene's ``fingerprint`` and ``scene`` description); ``/state`` is the object
graph of the simulation as JSON text (:mod:`dpm.io.state_tree`: containers, numbers, the
classes of its objects by name and their attributes) in which each large numpy array is a
reference to a dataset ``/arrays/aN`` (readable with h5py; arrays shared between
containers stay shared). Loading one runs no code from the file: it builds only objects
of dpm's classes, of registered plugins and of the running script, through ``__new__`` and
their stored attributes; a scene holding anything else (a lambda, an object of another
library) is refused by name at ``sim.checkpoint_every()``. A checkpoint is written to a
temporary file beside the target, flushed to disk (fsync), then renamed onto it: a run
killed at any moment leaves the previous checkpoint intact.

A checkpoint also records where it was written (attribute ``path``) and what identifies
the output file at that moment (attribute ``output``, JSON: the file's scene fingerprint,
frame count, and the step, time and a digest of its last frame). :func:`restart`
continues that output file only when the checkpoint is restarted where it was written (or
when asked, ``output="continue"``), and only if the file is still that run's file.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._lazy import lazy_module
from .errors import DpmError, OutputError, ParameterError
from .io import space, state_tree
from .operations import Operation
from .plugins import call_hook

h5py = lazy_module("h5py")

if TYPE_CHECKING:
    from .simulation import Simulation

FORMAT = "dpm-checkpoint"
#: 2: plain data (version 1 pickled the simulation, which loading could run code from)
FORMAT_VERSION = 2
#: digits of the step number in the names of periodic checkpoints
STEP_DIGITS = 10


# ----------------------------------------------------------------- scene description
def _plain(value: Any, depth: int = 0) -> Any:
    """A JSON-able rendering of a scene object's parameters (for the fingerprint)."""
    if depth > 6:
        return repr(type(value).__name__)
    if isinstance(value, bool | int | str) or value is None:
        return value
    if isinstance(value, float | np.floating):
        return float(value) if np.isfinite(value) else repr(float(value))
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        if value.size > 64:  # (a mesh: its size and a digest)
            return {"shape": list(value.shape),
                    "sha256": hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()}
        return _plain(value.tolist(), depth + 1)
    if isinstance(value, list | tuple):
        return [_plain(v, depth + 1) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v, depth + 1) for k, v in sorted(value.items(), key=str)}
    params = getattr(value, "params", None)
    out = {"type": f"{type(value).__module__}.{type(value).__qualname__}"}
    if isinstance(params, dict):
        out["params"] = _plain(params, depth + 1)
    return out


def scene_description(sim: Simulation) -> dict[str, Any]:
    """What the scene is made of (not its state): materials, contact laws, boundaries with
    their motions, inlets, outlets, periodic box, integrator, gravity. Two scenes with the
    same description are the same scene."""
    laws = {f"{sim.materials[a].name}-{sim.materials[b].name}": _plain(law)
            for (a, b), law in sorted(sim._contacts.items()) if a <= b}
    return {
        "integrator": sim.integrator.name,
        "gravity": _plain(np.asarray(sim.gravity)),
        "materials": [{"name": m.name, **{k: _plain(v) for k, v in sorted(vars(m).items())
                                          if k != "name"}} for m in sim.materials],
        "contacts": laws,
        "boundaries": [{"kind": bd.name, "material": bd.material.name,
                        "params": _plain(bd.params), "motion": _plain(bd.motion)}
                       for bd in sim.boundaries],
        "inlets": [{"region": _plain(i.region), "material": i.material.name,
                    "shapes": _plain(i.shapes), "rate": _plain(i.rate),
                    "mass_rate": _plain(i.mass_rate), "count": i.count,
                    "mass": _plain(i.mass)}
                   for i in sim.inlets],
        "outlets": [{"region": _plain(o.region), "remove": o.remove} for o in sim.outlets],
        "period": _plain(np.asarray(sim.period)),
    }


def fingerprint(description: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(description, sort_keys=True).encode()).hexdigest()[:16]


def _difference(a: Any, b: Any, where: str = "") -> str:
    """The first place where two descriptions differ, in words."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{where}{k}: only in the {'checkpoint' if k in a else 'scene'}"
            d = _difference(a[k], b[k], f"{where}{k}.")
            if d:
                return d
        return ""
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{where.rstrip('.')}: {len(a)} in the checkpoint, {len(b)} in the scene"
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            d = _difference(x, y, f"{where}{k}.")
            if d:
                return d
        return ""
    return "" if a == b else f"{where.rstrip('.')}: {a!r} in the checkpoint, {b!r} in the scene"


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write(sim: Simulation, path: str | os.PathLike) -> Path:
    """Write a checkpoint of ``sim`` to ``path`` atomically; return the path. An I/O
    error (disk full) raises :class:`OutputError`, the earlier checkpoints intact."""
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"sim.checkpoint(): path={str(path)!r} is a directory")
    # (MPI: the ranks' state into the host first; every rank calls this)
    sim.backend.sync_host()
    if not sim.backend.root:
        return path  # (MPI: every rank holds the whole state; rank 0 writes it)
    path.parent.mkdir(parents=True, exist_ok=True)
    if sim._writer is not None:
        sim._writer.flush()  # the frames the checkpoint counts are on disk
    state: dict[str, Any] = {}
    call_hook(sim._registry, "dpm_on_checkpoint", sim=sim, state=state)
    sim._plugin_state = state
    tree, arrays = state_tree.encode(sim, "sim.checkpoint()")
    text = json.dumps(tree, separators=(",", ":")).encode()
    description = scene_description(sim)
    from .io.hdf5 import _temp_beside, clean_stale_temps

    clean_stale_temps(path.parent)  # (those of a killed run's checkpoints)
    tmp = _temp_beside(path)
    try:
        # (room first: a write failing inside HDF5 leaves a file it cannot close)
        space.check_room(path, sum(a.nbytes for a in arrays.values()) + len(text))
        _write_file(sim, path, tmp, arrays, text, description)
    except (OSError, RuntimeError) as exc:  # (disk full, quota, a removed directory)
        if isinstance(exc, DpmError):
            raise
        raise OutputError(f"writing the checkpoint {str(path)!r} at step {sim.step_count} "
                          f"failed: {exc}; nothing was written in its place (the "
                          "checkpoints written before are intact)") from exc
    finally:
        if tmp.exists():
            tmp.unlink()
    _fsync_dir(path)
    return path


def _write_file(sim: Simulation, path: Path, tmp: Path, arrays: dict[str, np.ndarray],
                text: bytes, description: dict[str, Any]) -> None:
    """The checkpoint into ``tmp``, fsynced and renamed onto ``path``."""
    from . import __version__
    from .io.hdf5 import identity

    with h5py.File(tmp, "w") as f:
        a = f.attrs
        a["format"] = FORMAT
        a["format_version"] = FORMAT_VERSION
        a["dpm_version"] = __version__
        a["numpy_version"] = np.__version__
        a["step"] = sim.step_count
        a["time"] = sim.time
        a["dt"] = sim.dt
        a["bodies"] = len(sim.bodies)
        a["scene"] = json.dumps(description, sort_keys=True)
        a["fingerprint"] = fingerprint(description)
        # where it was written (a copy elsewhere does not continue the run's output)
        # and what identifies the output file (checked when it is resumed)
        a["path"] = os.path.realpath(path)
        a["output"] = json.dumps(identity(sim._writer) if sim._writer is not None
                                 else {}, sort_keys=True)
        g = f.create_group("arrays")
        for name, arr in arrays.items():
            g.create_dataset(name, data=arr)
        f.create_dataset("state", data=np.frombuffer(text, np.uint8))
    with open(tmp, "rb+") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)


# ----------------------------------------------------------------- periodic checkpoints
def numbered(base: Path, step: int) -> Path:
    """The name of the periodic checkpoint of ``step``: the step number before the last
    suffix (``run.ckpt.h5`` -> ``run.ckpt.0000012000.h5``)."""
    return base.with_name(f"{base.stem}.{step:0{STEP_DIGITS}d}{base.suffix}")


def _numbered_name(base: Path) -> re.Pattern:
    """The file names of ``base``'s numbered checkpoints (:func:`numbered`); group 1 the
    step."""
    return re.compile(re.escape(base.stem) + r"\.(\d{" + str(STEP_DIGITS) + "})"
                      + re.escape(base.suffix) + "$")


def numbered_files(base: Path) -> list[tuple[int, Path]]:
    """(step, path) of the periodic checkpoints of ``base`` on disk, oldest first."""
    pat = _numbered_name(base)
    found = []
    if base.parent.is_dir():
        for p in base.parent.iterdir():
            m = pat.match(p.name)
            if m:
                found.append((int(m.group(1)), p))
    return sorted(found)


def check_directory(base: Path, call: str) -> None:
    """Check when checkpoints are asked for that they can be written beside ``base``: its
    directory exists (or is created here, as ``sim.output()`` does) and takes new files.
    Raises ParameterError naming the parameter, its value and what is allowed."""
    from .io.hdf5 import writable_directory

    writable_directory(base, f"{call}: path={str(base)!r}",
                       "allowed: a file name in a directory that exists (or can be created) "
                       "and is writable")


class Schedule(Operation):
    """Periodic checkpoints of a run (:meth:`dpm.Simulation.checkpoint_every`): every
    ``every`` seconds (kept in seconds when dt changes) or ``every_steps`` steps, to
    numbered files beside ``base``, keeping the last ``keep``. An operation of the run
    loop (:mod:`dpm.operations`), after the others due at the same step."""

    order = 50

    def __init__(self, base: Path, every: float | None, every_steps: int | None,
                 keep: int, step: int, dt: float) -> None:
        check_directory(Path(base), "sim.checkpoint_every()")
        self.base = base
        self.every = every
        self.every_steps = every_steps
        self.keep = keep
        #: the step of the next checkpoint
        self.next = step + self.interval(dt)

    def interval(self, dt: float) -> int:
        if self.every_steps is not None:
            return int(self.every_steps)
        return max(1, round(self.every / dt))

    def next_step(self, sim: Simulation) -> int | None:
        return self.next

    def run(self, sim: Simulation) -> None:
        self.write(sim)

    def write(self, sim: Simulation) -> Path:
        self.next = sim.step_count + self.interval(sim.dt)  # (stored as the next one)
        path = write(sim, numbered(self.base, sim.step_count))
        if not sim.backend.root:
            return path
        for _, old in numbered_files(self.base)[:-self.keep]:
            old.unlink(missing_ok=True)
        return path


def restart_advice(sim: Simulation) -> str:
    """What a run stopped by an I/O error (:class:`OutputError`) restarts from: the newest
    periodic checkpoint on disk, or none."""
    ck = sim.operations.checkpoints
    files = numbered_files(Path(ck.base)) if ck is not None else []
    if not files:
        return (". No checkpoint of this run is on disk: make room and run it again "
                "(sim.checkpoint_every(...) makes a run restartable)")
    step, p = files[-1]
    return (f". Make room (free space, raise the quota or the file-size limit) and restart "
            f"from the last checkpoint, step "
            f"{step}: dpm.restart({str(p)!r}) (in the shell: dpm run SCENE --restart "
            f"{str(p)!r}); it continues the output file from that step")


# ----------------------------------------------------------------- restart
def latest(path: str | os.PathLike) -> Path:
    """``path`` itself if it is a file, else the newest periodic checkpoint of it."""
    p = Path(path)
    if p.is_file():
        return p
    files = numbered_files(p)
    if not files:
        raise ParameterError(f"dpm.restart(): no checkpoint at {str(p)!r} (nor numbered "
                             f"ones {numbered(p, 0).name.replace('0' * STEP_DIGITS, 'N' * 4)}"
                             " beside it)")
    return files[-1][1]


def read_attrs(path: str | os.PathLike) -> dict[str, Any]:
    """The attributes of a checkpoint (refusing a file that is not one)."""
    p = Path(path)
    try:
        with h5py.File(p, "r") as f:
            attrs = dict(f.attrs)
    except OSError as exc:
        raise ParameterError(f"dpm.restart(): {str(p)!r} cannot be read as a checkpoint "
                             f"({exc})") from None
    if attrs.get("format") != FORMAT:
        raise ParameterError(f"dpm.restart(): {str(p)!r} is not a dpm checkpoint (format="
                             f"{attrs.get('format')!r}; dpm.load reads output files)")
    return attrs


def restart(path: str | os.PathLike, scene: Simulation | None = None,
            output: str | os.PathLike | None = "auto") -> Simulation:
    """The simulation stored in the checkpoint at ``path`` (or the newest numbered one
    beside it), ready to run on: ``sim.run(...)`` continues the trajectory bit for bit.

    Loading runs no code from the file (:mod:`dpm.io.state_tree`): a checkpoint naming a
    class or function that is not dpm's, a registered plugin's or the running script's is
    refused by name; a script's own classes (a motion, a law) are found in the running
    script, so a scene built from a script restarts from that script.

    A checkpoint of another dpm version or format is refused with the reason. With
    ``scene`` (the same scene built again, by a script or a TOML file) the checkpoint must
    be of that scene: the first difference is named.

    ``output`` says what happens to the output file the run was writing:

    - ``"auto"`` (default): restarted where it was written (the run killed and restarted
      in place), the file is reopened and cut back to the frames the checkpoint had
      written (the restarted run writes the later ones again, identically), and periodic
      checkpoints go on. A checkpoint restarted from anywhere else (a copy, or a moved
      file) never touches the original run's files: the restarted run writes no output
      until ``sim.output(...)`` is called (with a warning), and its periodic checkpoints
      go beside the checkpoint it was restarted from.
    - ``"continue"``: continue the run's output file wherever the checkpoint is.
    - a path: continue that file (a copy of the run's output, e.g. of a copied run
      directory).
    - ``None``: write no output until ``sim.output(...)`` is called.

    A file that is continued must be the one the checkpoint's run wrote (its scene
    fingerprint, frame count and last frame are compared: a file another run replaced is
    refused by name) and must not be written by a live process (refused, naming it).
    """
    from . import __version__

    if not (output is None or isinstance(output, str | os.PathLike)) \
            or isinstance(output, bool) or (isinstance(output, str) and not output.strip()):
        raise ParameterError(f"dpm.restart(): output={output!r}; allowed: 'auto', "
                             "'continue', None or the path of the run's output file")
    p = latest(path)
    attrs = read_attrs(p)
    version = attrs.get("format_version", -1)
    if version != FORMAT_VERSION:
        old = (" (version 1 pickled the simulation, and loading it could run code from the "
               "file: it is not read; run the scene again from its script)"
               if version == 1 else "")
        raise ParameterError(f"dpm.restart(): {str(p)!r} has checkpoint format version "
                             f"{version}; this dpm reads version {FORMAT_VERSION}{old}")
    if attrs.get("dpm_version") != __version__:
        raise ParameterError(f"dpm.restart(): {str(p)!r} was written by dpm "
                             f"{attrs.get('dpm_version')}, this is dpm {__version__}: "
                             "restart it with the version that wrote it")
    if scene is not None:
        mine = scene_description(scene)
        if fingerprint(mine) != attrs["fingerprint"]:
            theirs = json.loads(attrs["scene"])
            raise ParameterError(f"dpm.restart(): {str(p)!r} is a checkpoint of another "
                                 f"scene; first difference: {_difference(theirs, mine)}")
    sim = _load_state(p)
    sim.backend = backend_here(sim.backend)
    _choose_output(sim, p, attrs, output)
    sim._restored(p)
    return sim


#: run settings a scene file may change on restart (they set no state of the scene)
CHANGEABLE = ("dt", "max_overlap", "dt_check", "skin")
#: settings a restart keeps: a change is refused by name
FIXED = ("sphere_orientation", "_overlap_tolerance")


def apply_scene_settings(sim: Simulation, scene: Simulation, source: str) -> list[str]:
    """After ``dpm run SCENE --restart``: the run settings of ``scene`` (the scene file
    built again) that differ from the restored ``sim``'s take effect (dt, max_overlap,
    dt_check, skin, the thread count, the output's interval; a new output path starts a
    new file); returns a line for each. A setting a restart cannot change (orientation
    tracking, the overlap tolerance, the backend, the output's fields in the file being
    continued) is refused by name (ParameterError), before any step. Changes of the scene
    itself (materials, laws, boundaries, gravity, integrator) are refused by
    :func:`restart`'s fingerprint check."""
    call = f"dpm run {source} --restart"
    for name in FIXED:
        a, b = getattr(sim, name), getattr(scene, name)
        if a != b:
            raise ParameterError(f"{call}: [simulation] {name.lstrip('_')}={b!r} in the "
                                 f"scene file, {a!r} in the checkpoint; a restart cannot "
                                 "change it (it changes the state's meaning): set it back")
    if type(scene.backend).__name__ != type(sim.backend).__name__ and not (
            {type(scene.backend).__name__, type(sim.backend).__name__}
            <= {"CpuBackend", "MpiBackend"}):
        raise ParameterError(f"{call}: [simulation] device: {type(scene.backend).__name__} "
                             f"in the scene file, {type(sim.backend).__name__} in the "
                             "checkpoint; a restart goes on with the checkpoint's backend")
    said = []
    for name in CHANGEABLE:
        a, b = getattr(sim, name), getattr(scene, name)
        if name == "skin" and b is None:
            continue  # (not given: the run's own, set at its first step, stays)
        if a != b:
            setattr(sim, name, b)  # (each setter checks, as between runs)
            said.append(f"{name}: {a!r} -> {b!r} (from {source})")
    threads = scene.backend.threads
    if threads != sim.backend.threads:
        said.append(f"threads: {sim.backend.threads!r} -> {threads!r} (from {source})")
        sim.backend.threads = threads
    return said + _apply_output(sim, scene, source)


def _apply_output(sim: Simulation, scene: Simulation, source: str) -> list[str]:
    """The scene file's [output] against the restored run's: the same leaves the output
    as the checkpoint has it (frames at the same steps); another interval takes effect
    from here; another path starts that file (the run's own file is left as it is)."""
    path = scene._output_path
    if path is None:
        return []
    mine, theirs = scene.operations.frames, sim.operations.frames
    every, every_steps = mine.every_s, mine.every
    layout = dict(fields=scene._output_fields, contacts=scene._output_contacts,
                  solids=scene._output_solids)
    same_path = (sim._output_path is not None
                 and os.path.realpath(sim._output_path) == os.path.realpath(path))
    same = (same_path and (every, every_steps if every is None else None)
            == (theirs.every_s, theirs.every if theirs.every_s is None else None)
            and layout == dict(fields=sim._output_fields, contacts=sim._output_contacts,
                               solids=sim._output_solids))
    if same:
        return []
    interval = {"every": every} if every is not None else {"every_steps": every_steps}
    sim.output(path, **interval, overwrite=scene._output_overwrite, **layout)
    what = f"every={every!r} s" if every is not None else f"every_steps={every_steps!r}"
    return [f"output: {path} {what}, {'continued' if same_path else 'a new file'} "
            f"(from {source})"]


def _load_state(p: Path) -> Simulation:
    """The simulation of the checkpoint ``p`` from its plain data (no code of the file)."""
    from .simulation import Simulation

    where = f"dpm.restart({str(p)!r})"
    with h5py.File(p, "r") as f:
        if "state" not in f or "arrays" not in f:
            raise ParameterError(f"{where}: the checkpoint has no /state or /arrays (a "
                                 "damaged or edited file)")
        try:
            tree = json.loads(f["state"][()].tobytes())
        except (ValueError, RecursionError) as exc:
            raise ParameterError(f"{where}: /state is not the JSON text of a state "
                                 f"({type(exc).__name__})") from None
        sim = state_tree.decode(tree, f["arrays"], where)
    if type(sim) is not Simulation:
        raise ParameterError(f"{where}: the stored state is a {type(sim).__name__}, not a "
                             "Simulation")
    return sim


def _text(value: Any) -> str | None:
    if value is None:
        return None
    return value.decode() if isinstance(value, bytes) else str(value)


def _choose_output(sim: Simulation, p: Path, attrs: dict[str, Any],
                   output: str | os.PathLike | None) -> None:
    """Decide which output file the restored ``sim`` goes on writing (see :func:`restart`)
    and put it, with what identifies it, in the state :meth:`Simulation._restored`
    reopens; where none is continued, the run writes no output until ``sim.output()``."""
    written = _text(attrs.get("path"))
    # (a checkpoint without the attribute predates it: restarted as before, in place)
    moved = written is not None and written != os.path.realpath(p)
    ws = sim.__dict__.get("_writer_state")
    text = _text(attrs.get("output"))
    expect = json.loads(text) if text else None
    keyword = output if isinstance(output, str) and output in ("auto", "continue") else None
    if moved and keyword != "continue":
        ck = sim.operations.checkpoints
        if ck is not None:  # periodic checkpoints beside this copy, not the original's
            ck.base = _relocated(Path(ck.base), p)
    if keyword == "continue" or (keyword == "auto" and not moved):
        target = None if ws is None else Path(ws["path"])
    elif output is None or keyword == "auto":
        if ws is not None and keyword == "auto":
            warnings.warn(f"dpm.restart(): {str(p)!r} is not where its run wrote it "
                          f"({written!r}): the run's output {ws['path']!r} is left "
                          f"untouched and the restarted run writes no output until "
                          f"sim.output(...) is called (output='continue' continues that "
                          f"file)", stacklevel=3)
        target = None
    else:
        if ws is None:
            raise ParameterError(f"dpm.restart(): output={str(output)!r}: the run of "
                                 f"{str(p)!r} wrote no output file to continue; call "
                                 f"sim.output(...) after the restart instead")
        target = Path(output)
    if target is None:
        sim.__dict__["_writer_state"] = None
        sim._output_path = None
        return
    sim.__dict__["_writer_state"] = dict(ws, path=str(target), expect=expect)
    sim._output_path = str(target)


def _relocated(base: Path, p: Path) -> Path:
    """The base name of the periodic checkpoints of a run restarted from the checkpoint
    ``p`` that is not where it was written: beside ``p``, with the original base name if
    ``p`` is one of its numbered files, else ``p``'s own name."""
    return p.parent / base.name if _numbered_name(base).match(p.name) else p


def backend_here(backend: Any) -> Any:
    """The backend a restored run takes where it runs now: a checkpoint holds the whole
    scene, not the machine, so a run checkpointed on N ranks goes on on M ranks or on
    one process. A CPU or MPI backend becomes the MPI backend under an MPI launcher with
    several ranks and stays as it was otherwise (the MPI backend on one process is the
    CPU backend); other backends are kept."""
    from .backends.cpu import CpuBackend
    from .parallel import launched_ranks
    from .parallel.backend import MpiBackend

    if launched_ranks() > 1 and type(backend) is CpuBackend:
        mpi = MpiBackend(threads=backend.threads, force_pass=backend.force_pass)
        own = {k: v for k, v in mpi.__dict__.items() if k not in backend.__dict__}
        mpi.__dict__.update(backend.__dict__)  # (its scene, integrator rows, diagnostics)
        mpi.__dict__.update(own)
        return mpi
    if isinstance(backend, MpiBackend):
        backend._reset_local()
    return backend


def resume_output(sim: Simulation, state: dict[str, Any] | None) -> None:
    """Reopen the output file of a restored run at the checkpoint's frame count."""
    if not state:
        return
    from .io.hdf5 import Writer

    path = Path(state["path"])
    if not path.exists():
        warnings.warn(f"dpm.restart(): the output file {str(path)!r} of the run is gone; "
                      "a new one is written from the restart on", stacklevel=3)
        sim._writer = None
        return
    if not sim.backend.root:  # (MPI: rank 0 writes the file)
        from .io.hdf5 import NullWriter

        sim._writer = NullWriter(path, sim)
        sim._writer.frames, sim._writer.removed = int(state["frames"]), int(state["removed"])
        sim.last_output = sim._writer
        return
    sim._writer = Writer.resume(path, sim, int(state["frames"]), int(state["removed"]),
                                expect=state.get("expect"))
    sim.last_output = sim._writer
