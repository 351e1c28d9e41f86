"""The bridge from objects to kernels: a step module specialised to the scene.

:func:`step_module` copies :mod:`dpm.kernels.step` with its ``bindings`` block rewritten so
that the scene's contact laws become ``law_0 .. law_k`` and its integrator's
``pre_force_body``/``post_force_body`` are imported. The file goes to the dpm cache
directory under a name that carries a fingerprint of every kernel it depends on: numba's
on-disk cache of a kernel does not notice when a jitted function it calls in another file
changes (numba #1833), so a changed law or kernel gives a new file name and a fresh compile
instead of stale code. The fingerprint is taken from the code objects of the kernels as they
are in memory (not from the files on disk): a process that imported a kernel before its file
was edited compiles the code it holds, and must not store it under the new file's name.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import re
import sys
from pathlib import Path
from types import ModuleType

from numba.core.dispatcher import Dispatcher

from . import kernels

_BEGIN = "# --- bindings begin (dpm.plan rewrites this block) ---"
_END = "# --- bindings end ---"
_LOADED: dict[str, ModuleType] = {}


def cache_dir() -> Path:
    """Directory of generated step modules ($DPM_CACHE_DIR or ~/.cache/dpm)."""
    root = os.environ.get("DPM_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "dpm")
    return Path(root) / "steps"


def _code_bytes(code) -> bytes:
    """Deterministic bytes of a code object (marshal's output depends on reference counts)."""
    consts = [(_code_bytes(c) if hasattr(c, "co_code") else repr(c).encode())
              for c in code.co_consts]
    return b"|".join([code.co_code, *consts, " ".join(code.co_names).encode(),
                      " ".join(code.co_varnames).encode()])


def _fingerprint(module: ModuleType) -> bytes:
    """Bytes that change when any jitted function or scalar constant of ``module`` does, as
    the module is in memory."""
    parts = [module.__name__.encode()]
    for name in sorted(vars(module)):
        obj = vars(module)[name]
        if isinstance(obj, Dispatcher) and getattr(obj.py_func, "__module__", None) == \
                module.__name__:
            parts.append(name.encode() + _code_bytes(obj.py_func.__code__))
        elif isinstance(obj, bool | int | float) and not name.startswith("_"):
            parts.append(f"{name}={obj!r}".encode())
    return b"\0".join(parts)


def _kind_imports(kinds: list[int]) -> list[str]:
    """Import lines of the geometry functions of these kinds (registry of
    :mod:`dpm.boundaries.primitives`): the built-ins by name from ``boundary_geometry``,
    a plugin's as ``_kind_<code>``."""
    from .boundaries.primitives import BUILTIN_MODULE, primitive_kind

    builtin = [primitive_kind(k).function[1] for k in kinds
               if primitive_kind(k).function[0] == BUILTIN_MODULE]
    lines = [f"from .boundary_geometry import {', '.join(builtin)}"] if builtin else []
    for k in kinds:
        mod, fn = primitive_kind(k).function
        if mod != BUILTIN_MODULE:
            lines.append(f"from {mod} import {fn} as {_kind_alias(k)}")
    return lines


def _kind_alias(k: int) -> str:
    from .boundaries.primitives import BUILTIN_MODULE, primitive_kind

    mod, fn = primitive_kind(k).function
    return fn if mod == BUILTIN_MODULE else f"_kind_{k}"


def _closest_lines(kinds: list[int], periodic: bool, fused: bool) -> list[str]:
    """A ``closest`` dispatching over the boundary kinds of the scene only; the scene's
    constants (meshes present, joinable kinds present, periodic axes, which force pass).
    What each kind's geometry function is and returns comes from the registry
    (:mod:`dpm.boundaries.primitives`)."""
    from .boundaries.primitives import primitive_kind
    from .kernels.boundary_geometry import PLANE, TRIANGLE

    kinds = sorted(set(kinds)) or [PLANE]
    joints = any(primitive_kind(k).joinable for k in kinds)
    lines = [*_kind_imports(kinds), "",
             f"HAS_TRIANGLES = {TRIANGLE in kinds}", f"HAS_JOINTS = {joints}",
             f"PERIODIC = {bool(periodic)}", f"FUSED = {bool(fused)}", "", "",
             "@inline_jit",
             "def closest(kind, p, x, y, z, r):",
             '    """Contact geometry of the boundary kinds of this scene."""']
    for n, k in enumerate(kinds):
        spec = primitive_kind(k)
        pad = "    "
        if n < len(kinds) - 1:
            lines.append(f"    if kind == {k}:")
            pad = "        "
        extra = ", r" if spec.takes_radius else ""
        call = f"{_kind_alias(k)}(p, x, y, z{extra})"
        if spec.returns_feature:
            lines.append(f"{pad}return {call}")
            continue
        lines.append(f"{pad}d, nx, ny, nz = {call}")
        lines.append(f"{pad}return d, nx, ny, nz, 0")
    return lines


def render(laws: list[tuple[str, str]], integrator_module: str,
           kinds: list[int] | None = None, periodic: bool = False,
           fused: bool = False) -> str:
    """Source of the step module for these (module, function) laws, integrator, boundary
    kinds, periodic axes and force pass (``fused``: every body a single sphere)."""
    template = (Path(kernels.__file__).parent / "step.py").read_text()
    lines = [_BEGIN]
    for k, (mod, fn) in enumerate(laws):
        lines.append(f"from {mod} import {fn} as law_{k}")
    if hasattr(importlib.import_module(integrator_module), "pre_force_sphere"):
        lines.append(f"from {integrator_module} import pre_force_body, pre_force_sphere, "
                     "post_force_body")
    else:  # (optional: the pre-force part of a sphere whose orientation is not tracked)
        lines.append(f"from {integrator_module} import pre_force_body, post_force_body")
        lines.append("pre_force_sphere = pre_force_body")
    lines += _closest_lines(kinds or [], periodic, fused)
    lines += ["", "", "@inline_jit",
              "def pair_force(model, p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, "
              "dt, hist, k):",
              '    """Dispatch to the contact law ``model`` of this scene."""']
    args = "p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k"
    for k in range(len(laws) - 1):
        lines.append(f"    if model == {k}:")
        lines.append(f"        return law_{k}({args})")
    lines.append(f"    return law_{len(laws) - 1}({args})")
    lines.append(_END)
    head, rest = template.split(_BEGIN)
    _, tail = rest.split(_END)
    src = head + "\n".join(lines) + tail
    src = re.sub(r"^from \.", "from dpm.kernels.", src, flags=re.M)
    return "# Generated by dpm.plan from dpm/kernels/step.py; do not edit.\n" + src


def step_module(laws: list[tuple[str, str]], integrator_module: str,
                kinds: list[int] | None = None, periodic: bool = False,
                fused: bool = False) -> ModuleType:
    """Import (generating if needed) the step module for these laws, integrator, boundary
    kinds, periodic axes and force pass."""
    if not laws:
        laws = [("dpm.kernels.law_linear", "linear_spring_dashpot")]
    src = render(laws, integrator_module, kinds, periodic, fused)
    h = hashlib.sha256(src.encode())
    from .boundaries.primitives import primitive_kind

    # the modules the bindings import: laws, integrator, plugin geometry functions
    bound = {m for m, _ in laws} | {integrator_module} | {
        primitive_kind(k).function[0] for k in set(kinds or [])}
    for mod in sorted(bound):
        importlib.import_module(mod)
    kdir = Path(kernels.__file__).parent
    for f in sorted(kdir.glob("*.py")):  # every kernel module the step may reach
        importlib.import_module(f"dpm.kernels.{f.stem}")
    for mod in sorted(m for m in sys.modules if m.startswith("dpm.kernels.") or m in bound):
        h.update(_fingerprint(sys.modules[mod]))
    name = f"dpm_step_{h.hexdigest()[:20]}"
    if name in _LOADED:
        return _LOADED[name]
    d = cache_dir()
    d.mkdir(parents=True, exist_ok=True)
    path = d / f"{name}.py"
    if not path.exists() or path.read_text() != src:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(src)
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[name] = module
    return module


def clear_cache() -> list[Path]:
    """Delete generated step modules and numba's cache of dpm's kernels; return what went."""
    removed: list[Path] = []
    d = cache_dir()
    if d.exists():
        for f in d.rglob("*"):
            if f.is_file():
                f.unlink()
                removed.append(f)
    kdir = Path(kernels.__file__).parent / "__pycache__"
    if kdir.exists():
        for f in list(kdir.glob("*.nbi")) + list(kdir.glob("*.nbc")):
            f.unlink()
            removed.append(f)
    return removed


class ScenePlan:
    """What the scene needs from the kernels, resolved once per scene (:func:`plan_scene`):
    the contact laws in use and the material-pair tables (``pair_model[a, b]`` picks the
    law, ``pair_params[a, b, :]`` its constants), the history width per contact, the
    integrator's kernel module, the boundary kinds present, whether axes are periodic,
    whether a boundary moves and whether every body is a single sphere at its centre."""

    def __init__(self, laws: list[tuple[str, str]], pair_model, pair_params,
                 history_width: int, integrator_module: str, kinds: list[int],
                 periodic: bool, moving: bool, spheres_only: bool) -> None:
        self.laws = laws
        self.pair_model = pair_model
        self.pair_params = pair_params
        self.history_width = history_width
        self.integrator_module = integrator_module
        self.kinds = kinds
        self.periodic = periodic
        self.moving = moving
        self.spheres_only = spheres_only

    def module(self, fused: bool) -> ModuleType:
        """The generated step module of this scene for one force form."""
        return step_module(self.laws, self.integrator_module, self.kinds, self.periodic,
                           fused=fused)


def pair_tables(materials, contacts, context) -> tuple[list, object, object, int]:
    """(laws, pair_model, pair_params, history width) of the material pairs.

    ``contacts``: {(a, b): ImpactModel}; ``context(a, b)``: the
    :class:`dpm.impact.base.PairContext` of the pair. One law index per distinct kernel;
    the history width is the widest the laws declare (3-5 more for a rolling spring)."""
    import numpy as np

    nm = len(materials)
    laws: list[tuple[str, str]] = []
    pair_model = np.zeros((nm, nm), np.int64)
    pair_params = np.zeros((nm, nm, 8))
    for (ia, ib), law in contacts.items():
        if law.kernel not in laws:
            laws.append(law.kernel)
        pair_model[ia, ib] = laws.index(law.kernel)
        pair_params[ia, ib] = law.pair_row(materials[ia], materials[ib], context(ia, ib))
    width = max([law.history_slots for law in contacts.values()] + [3])
    if np.any(pair_params[:, :, 6] != 0.0):
        width = max(width, 6)
    return laws, pair_model, pair_params, width
