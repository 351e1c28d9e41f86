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
_PLACEMENT: dict[tuple[int, ...], ModuleType] = {}


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


#: a scene of at most this many boundary kinds inlines its ``closest`` (the dispatch over
#: its kinds' geometry) at every call; past it only the contact loop of the step inlines
#: it, and the list searches, the initial-overlap check and the pipe-joint hand-over call
#: one compiled ``closest_call``. numba inlines at the level of its IR and types each copy
#: anew, so the copies of a many-kind dispatch made most of a module's compile: a box
#: scene with far boundaries of the six built-in kinds reached its first steps from an
#: empty cache in 206 s, 91 s with the calls. The price is a
#: call per search candidate in scenes of 3+ kinds (their search pass 1.0-1.3x slower).
INLINE_SEARCH_KINDS = 2


def _closest_lines(kinds: list[int], periodic: bool, fused: bool,
                   inline: bool = True) -> list[str]:
    """A ``closest`` dispatching over the boundary kinds of the scene only; the scene's
    constants (meshes present, joinable kinds present, periodic axes, which force pass).
    What each kind's geometry function is and returns comes from the registry
    (:mod:`dpm.boundaries.primitives`). ``closest`` is inlined where the step calls it
    unless ``inline`` is False; ``closest_call`` is ``closest``, or a compiled function
    calling it past :data:`INLINE_SEARCH_KINDS` kinds."""
    from .boundaries.primitives import primitive_kind
    from .kernels.boundary_geometry import PLANE, TRIANGLE

    kinds = sorted(set(kinds)) or [PLANE]
    joints = any(primitive_kind(k).joinable for k in kinds)
    lines = [*_kind_imports(kinds), "",
             f"HAS_TRIANGLES = {TRIANGLE in kinds}", f"HAS_JOINTS = {joints}",
             f"PERIODIC = {bool(periodic)}", f"FUSED = {bool(fused)}", "", "",
             "@inline_jit" if inline else "@jit",
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
    if len(kinds) <= INLINE_SEARCH_KINDS or not inline:
        return [*lines, "", "", "closest_call = closest"]
    return [*lines, "", "", "@jit", "def closest_call(kind, p, x, y, z, r):",
            '    """closest, called (not inlined) by the list searches and checks."""',
            "    return closest(kind, p, x, y, z, r)"]


def _resolve(law):
    """A law as the plan writes it: a composed :class:`~dpm.impact.parts.LawSpec`, or a
    monolithic (module, function). A (module, name) that names no function but the
    ``kernel`` of a registered composed model stands for that model's law."""
    from .impact.parts import LawSpec

    if isinstance(law, LawSpec):
        return law
    mod, fn = law
    if hasattr(importlib.import_module(mod), fn):
        return tuple(law)
    from .plugins import registry

    for name in registry().names("impact_model"):
        cls = registry().lookup("impact_model", name)
        if tuple(cls.kernel) == tuple(law) and cls.normal is not None:
            return LawSpec(mod, fn, tuple(p for p in (cls.normal, cls.tangential,
                                                      cls.adhesion) if p is not None))
    raise ImportError(f"contact law {fn!r}: not in {mod} and no model's kernel")


def _law_modules(laws) -> set[str]:
    """Every module the laws' code lives in (for the fingerprint)."""
    mods = set()
    for law in map(_resolve, laws):
        if hasattr(law, "parts"):
            mods |= {p.target()[0] for p in law.parts}
            mods |= {t[0] for p in law.parts
                     if (t := getattr(p, "attached_target", lambda: None)()) is not None}
        else:
            mods.add(law[0])
    return mods


_LAW_ARGS = "p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt, hist, k"
_NORMAL_ARGS = "p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k"


def _wrap(head: str, args: str, pad: str = "    ") -> list[str]:
    """``head(args)`` as lines of at most 100 characters (continuations indented)."""
    out = [f"{pad}{head}("]
    for a in args.split(", "):
        piece = a + ", "
        if len(out[-1]) + len(piece) > 99:
            out[-1] = out[-1].rstrip()
            out.append(pad + "        ")
        out[-1] += piece
    out[-1] = out[-1].rstrip(", ") + ")"
    return out


def _composed(k: int, spec) -> tuple[list[str], list[str]]:
    """Imports and functions of composed law ``k``: ``law_k`` (forces and rolling torque)
    and ``normal_law_k`` (the normal force alone, for the implicit Jacobian)."""
    lay = spec.layout
    parts = {p.kind: p for p in spec.parts}
    imports = []
    for kind, part in parts.items():
        mod, fn = part.target()
        imports.append(f"from {mod} import {fn} as {kind}_{k}")

    def q(part):
        idx = lay.indices(part)
        if len(idx) == 1:
            return f"(p[{idx[0]}],)"
        return "(" + ", ".join(f"p[{i}]" for i in idx) + ")"

    def h(kind):
        return str(lay.offset.get(kind, 0))

    normal = _wrap(f"fn, kn = normal_{k}", ", ".join(
        [q(parts["normal"]), "delta, ddelta, meff, reff, dt, hist, k", h("normal")]))
    adhesion = []
    if "adhesion" in parts:
        adhesion = _wrap(f"fn = fn - adhesion_{k}", ", ".join(
            [q(parts["adhesion"]), "delta, ddelta, meff, reff, dt, hist, k", h("adhesion")]))
    names = " x ".join(type(p).__name__ for p in spec.parts)
    body = ["", "", "@inline_jit", *_wrap(f"def law_{k}", _LAW_ARGS, "")]
    body[-1] += ":"
    body += [f'    """{spec[1]}: {names}."""', *normal]
    if "tangential" in parts:
        body += _wrap(f"ftx, fty, ftz = tangential_{k}", ", ".join(
            [q(parts["tangential"]), "fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, "
             "hist, k", h("tangential")]))
    else:
        body.append("    ftx, fty, ftz = 0.0, 0.0, 0.0")
    body += adhesion
    if "rolling" in parts:
        body += _wrap(f"rx, ry, rz = rolling_{k}", ", ".join(
            [q(parts["rolling"]), "fn, reff, meff, wx, wy, wz, dt, hist, k", h("rolling")]))
        body.append("    return fn, ftx, fty, ftz, rx, ry, rz")
    else:
        body.append("    return fn, ftx, fty, ftz, 0.0, 0.0, 0.0")
    body += ["", "", "@inline_jit", f"def normal_law_{k}({_NORMAL_ARGS}):", *normal, *adhesion,
             "    return fn"]
    return imports, body


def _monolithic(k: int, law) -> tuple[list[str], list[str]]:
    """A monolithic law (fixed 8-slot row, rolling model in slot 6) wrapped to the
    composed laws' interface."""
    mod, fn = law
    body = ["", "", "@inline_jit", *_wrap(f"def law_{k}", _LAW_ARGS, "")]
    body[-1] += ":"
    body += [f"    fn, ftx, fty, ftz = kernel_{k}(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, "
             "meff, reff,", "                                   dt, hist, k)",
             "    rx = 0.0", "    ry = 0.0", "    rz = 0.0",
             "    if p[6] != 0.0:",
             "        rx, ry, rz = rolling_torque(p, fn, reff, meff, wx, wy, wz, dt, hist, k)",
             "    return fn, ftx, fty, ftz, rx, ry, rz", "", "",
             "@inline_jit", f"def normal_law_{k}({_NORMAL_ARGS}):",
             f"    return kernel_{k}(p, delta, ddelta, 0.0, 0.0, 0.0, nx, ny, nz, meff, reff, "
             "dt, hist,", "                    k)[0]"]
    return [f"from {mod} import {fn} as kernel_{k}"], body


def _laws(laws) -> tuple[list[str], list[str]]:
    """(imports, definitions) of the contact laws of a scene, generated from their parts:
    ``law_0 ..`` and the dispatches ``pair_force(model, ...)`` -> (F_n, F_t x, y, z,
    T_roll x, y, z) and ``pair_normal(model, ...)`` -> F_n; ``pair_row`` as wide as the
    laws' rows (``pair_row16`` past 8 slots); ``ROLLING``: whether any law has rolling
    resistance (a constant of the scene)."""
    laws = [_resolve(law) for law in laws]
    width = max([0] + [law.layout.width for law in laws if hasattr(law, "layout")])
    rolling = any(not hasattr(law, "parts") or any(p.kind == "rolling" for p in law.parts)
                  for law in laws)
    imports = ["from .config import pair_row16 as pair_row" if width > 8 else
               "from .config import pair_row"]
    if any(not hasattr(law, "parts") for law in laws):
        imports.append("from .rolling import rolling_torque")
    body = ["", f"ROLLING = {rolling}"]
    attached: dict[int, str] = {}  # law -> its pair_attached call
    for k, law in enumerate(laws):
        i, b = _composed(k, law) if hasattr(law, "parts") else _monolithic(k, law)
        imports += i
        body += b
        normal = next((p for p in getattr(law, "parts", ()) if p.kind == "normal"), None)
        target = normal.attached_target() if normal is not None else None
        if target is not None:
            imports.append(f"from {target[0]} import {target[1]} as attached_{k}")
            idx = law.layout.indices(normal)
            q = "(" + ", ".join(f"p[{i}]" for i in idx) + ("," if len(idx) == 1 else "") + ")"
            attached[k] = (f"attached_{k}({q}, delta, reff, hist, k, "
                           f"{law.layout.offset.get('normal', 0)})")
    body += attached_lines(attached, len(laws))
    for name, args, doc in (("pair_force", _LAW_ARGS, "F_n, F_t, rolling torque"),
                            ("pair_normal", _NORMAL_ARGS, "the normal force F_n")):
        call = "law" if name == "pair_force" else "normal_law"
        body += ["", "", "@inline_jit", *_wrap(f"def {name}", f"model, {args}", "")]
        body[-1] += ":"
        body.append(f'    """{doc[0].upper() + doc[1:]} of the contact law ``model`` of this '
                    'scene."""')
        for k in range(len(laws) - 1):
            body.append(f"    if model == {k}:")
            body += _wrap(f"return {call}_{k}", args, "        ")
        body += _wrap(f"return {call}_{len(laws) - 1}", args)
    return imports, body


def attached_lines(attached: dict[int, str], nlaws: int) -> list[str]:
    """``RANGED`` (whether a law keeps contacts at a separation) and
    ``pair_attached(model, p, delta, reff, hist, k)``: whether a listed pair at negative
    overlap is in contact (the normal part's ``attached`` call; False for the others)."""
    body = ["", f"RANGED = {bool(attached)}", "", "", "@inline_jit",
            "def pair_attached(model, p, delta, reff, hist, k):",
            '    """Whether a pair at negative overlap ``delta`` is in contact (laws with an '
            'interaction range)."""']
    for k, call in attached.items():
        if len(attached) == nlaws and k == max(attached):
            body.append(f"    return {call}")
            return body
        body.append(f"    if model == {k}:")
        body.append(f"        return {call}")
    body.append("    return False")
    return body


def law_lines(laws) -> list[str]:
    """The bindings lines of the contact laws (see :func:`_laws`)."""
    imports, body = _laws(laws)
    return imports + body


def _splice(template: str, lines: list[str]) -> str:
    """``template`` (a file of dpm/kernels) with its bindings block replaced; its imports
    of :data:`CACHED_LIBRARIES` name their cached copies (:func:`library_module`)."""
    text = (Path(kernels.__file__).parent / template).read_text()
    head, rest = text.split(_BEGIN)
    _, tail = rest.split(_END)
    src = head + "\n".join([_BEGIN, *lines, _END]) + tail
    for stem in CACHED_LIBRARIES:
        if re.search(rf"^from \.{stem} import ", src, flags=re.M):
            name = library_module(stem).__name__
            src = re.sub(rf"^from \.{stem} import ", f"from {name} import ", src, flags=re.M)
    src = re.sub(r"^from \.", "from dpm.kernels.", src, flags=re.M)
    return f"# Generated by dpm.plan from dpm/kernels/{template}; do not edit.\n" + src


#: kernel files that every step module calls but that do not depend on the scene (the
#: neighbour-list build: four parallel loops, ~21 s of a scene's ~85 s cold compile on 2
#: cores). The step modules import them from a generated copy
#: compiled with numba's cache on, named like a step module by every kernel source, so
#: they compile once per machine instead of once per scene kind. (The library files
#: themselves stay uncached: numba's cache of a function does not notice a change in a
#: file it calls, numba #1833; the copy's name does.)
CACHED_LIBRARIES = ("neighbours",)
_LIBRARIES: dict[str, ModuleType] = {}


def library_module(stem: str) -> ModuleType:
    """The cached copy of the kernel file ``dpm/kernels/<stem>.py`` (remembered per
    process): its ``jit``/``pjit`` functions compiled with numba's cache
    (``step_jit``/``step_pjit``), its other imports absolute."""
    if stem not in _LIBRARIES:
        text = (Path(kernels.__file__).parent / f"{stem}.py").read_text()
        imports = re.search(r"^from \.config import (.*)$", text, flags=re.M)
        names = [n.strip() for n in imports.group(1).split(",")]
        cached = {"jit": "step_jit as jit", "pjit": "step_pjit as pjit"}
        src = text.replace(imports.group(0), "from .config import "
                           + ", ".join(cached.get(n, n) for n in names))
        src = re.sub(r"^from \.", "from dpm.kernels.", src, flags=re.M)
        src = (f"# Generated by dpm.plan from dpm/kernels/{stem}.py (numba's cache on); "
               "do not edit.\n" + src)
        _LIBRARIES[stem] = _load(src, set(), f"dpm_lib_{stem}")
    return _LIBRARIES[stem]


def render(laws: list[tuple[str, str]], integrator_module: str,
           kinds: list[int] | None = None, periodic: bool = False,
           fused: bool = False, one_thread: bool = False) -> str:
    """Source of the step module for these laws (composed :class:`LawSpec` s or monolithic
    (module, function)), integrator, boundary kinds, periodic axes and force pass
    (``fused``: every body a single sphere); ``one_thread``: its one-thread form."""
    lines, body = _laws(laws)
    lines += integrator_lines(integrator_module)
    lines += _closest_lines(kinds or [], periodic, fused)
    src = _splice("step.py", lines + body)
    return one_thread_form(src) if one_thread else src


#: appended to the one-thread form (run at its import, before any function compiles):
#: numba notes that ``parallel=True`` found no parallel loop to transform, which is the
#: point of this form
_ONE_THREAD_TAIL = """\
import warnings as _warnings

from numba.core.errors import NumbaPerformanceWarning as _NumbaPerformanceWarning

_warnings.filterwarnings("ignore", category=_NumbaPerformanceWarning,
                         message="(?s).*'parallel=True' was specified but no transformation")
"""


def one_thread_form(src: str) -> str:
    """The one-thread form of a generated step module's source: every ``prange`` loop a
    plain ``range`` loop, the functions still compiled with ``parallel=True``.

    A ``prange`` loop launches a parallel region even on one thread (~0.9 us each, three
    per step: most of a tiny scene's step; a 1-sphere step 4.78 -> 1.91 us), while
    the plain loop inside a ``parallel=True`` function is compiled as fast as the body of
    a parallel loop (as plain ``@jit`` functions the same loops ran 4-5x slower: the
    docstring of :func:`dpm.kernels.step.fused_pass`). Each loop's iterations
    run in the same order as one chunk of the parallel form, so both forms give the same
    bits (tests/kernels/test_backend_contract.py runs 1 and 2 threads)."""
    return src.replace("prange(", "range(") + "\n\n" + _ONE_THREAD_TAIL


def integrator_lines(integrator_module: str) -> list[str]:
    """The bindings lines importing an integrator's per-body parts."""
    if hasattr(importlib.import_module(integrator_module), "pre_force_sphere"):
        return [f"from {integrator_module} import pre_force_body, pre_force_sphere, "
                "post_force_body"]
    # (optional: the pre-force part of a sphere whose orientation is not tracked)
    return [f"from {integrator_module} import pre_force_body, post_force_body",
            "pre_force_sphere = pre_force_body"]


def render_implicit(laws) -> str:
    """Source of the implicit integrators' kernels (dpm/kernels/implicit.py) for these
    laws."""
    return _splice("implicit.py", law_lines(laws))


def law_module(laws) -> ModuleType:
    """A module holding only these composed laws (``law_0 ..``, ``pair_force``,
    ``pair_normal``), to call a law alone (benchmarks/impact_models.py times them)."""
    imports, body = _laws(laws)
    src = "\n".join(["# Generated by dpm.plan: contact laws alone; do not edit.",
                     "from dpm.kernels.config import inline_jit", *imports, *body, ""])
    src = re.sub(r"^from \.", "from dpm.kernels.", src, flags=re.M)
    return _load(src, _law_modules(laws), "dpm_laws")


def implicit_module(laws) -> ModuleType:
    """Import (generating if needed) the implicit kernels for these laws."""
    if not laws:
        laws = [("dpm.kernels.law_linear", "linear_spring_dashpot")]
    return _load(render_implicit(laws), _law_modules(laws), "dpm_implicit")


def step_module(laws: list[tuple[str, str]], integrator_module: str,
                kinds: list[int] | None = None, periodic: bool = False,
                fused: bool = False, one_thread: bool = False) -> ModuleType:
    """Import (generating if needed) the step module for these laws, integrator, boundary
    kinds, periodic axes and force pass, in its one-thread form if ``one_thread``."""
    if not laws:
        laws = [("dpm.kernels.law_linear", "linear_spring_dashpot")]
    src = render(laws, integrator_module, kinds, periodic, fused, one_thread)
    from .boundaries.primitives import primitive_kind

    # the modules the bindings import: laws, integrator, plugin geometry functions
    geometry = {primitive_kind(k).function[0] for k in set(kinds or [])}
    return _load(src, _law_modules(laws) | {integrator_module} | geometry, "dpm_step")


def placement_module(kinds: list[int]) -> ModuleType:
    """Import (generating if needed) the inlets' placement test
    (:mod:`dpm.kernels.placement`) for these boundary kinds (remembered per process: an
    inlet asks at every flow event)."""
    from .boundaries.primitives import primitive_kind

    key = tuple(sorted(set(kinds)))
    if key not in _PLACEMENT:
        src = _splice("placement.py", _closest_lines(list(key), False, False))
        geometry = {primitive_kind(k).function[0] for k in key}
        _PLACEMENT[key] = _load(src, geometry, "dpm_place")
    return _PLACEMENT[key]


def _load(src: str, modules: set[str], prefix: str) -> ModuleType:
    """Write (if needed) and import the generated module ``src``, named by its text and
    the fingerprint of every kernel module and of ``modules``."""
    h = hashlib.sha256(src.encode())
    for mod in sorted(modules):
        importlib.import_module(mod)
    kdir = Path(kernels.__file__).parent
    for f in sorted(kdir.glob("*.py")):  # every kernel module the step may reach
        importlib.import_module(f"dpm.kernels.{f.stem}")
    for mod in sorted(m for m in sys.modules if m.startswith("dpm.kernels.")
                      or m in modules):
        h.update(_fingerprint(sys.modules[mod]))
    name = f"{prefix}_{h.hexdigest()[:20]}"
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


from .impact.parts import history_flips  # noqa: E402  (the plan reads the parts' layouts)


class ScenePlan:
    """What the scene needs from the kernels, resolved once per scene (:func:`plan_scene`):
    the contact laws in use and the material-pair tables (``pair_model[a, b]`` picks the
    law, ``pair_params[a, b, :]`` its constants), the history width per contact, the
    integrator's kernel module, the boundary kinds present, whether axes are periodic,
    whether a boundary moves, whether every body is a single sphere at its centre, and the
    interaction range of laws that act at a separation."""

    def __init__(self, laws: list[tuple[str, str]], pair_model, pair_params,
                 history_width: int, integrator_module: str, kinds: list[int],
                 periodic: bool, moving: bool, spheres_only: bool, reach: float = 0.0) -> None:
        self.laws = laws
        self.pair_model = pair_model
        self.pair_params = pair_params
        self.history_width = history_width
        self.integrator_module = integrator_module
        self.kinds = kinds
        self.periodic = periodic
        self.moving = moving
        self.spheres_only = spheres_only
        #: how far beyond touching [m] a law keeps contacts (the largest
        #: :meth:`dpm.impact.parts.NormalPart.reach`; 0: touching only)
        self.reach = float(reach)
        #: (laws, history width) bool: history floats negated when a pair swaps
        self.history_flips = history_flips(laws, history_width)

    def module(self, fused: bool, one_thread: bool = False) -> ModuleType:
        """The generated step module of this scene for one force form (and in its
        one-thread form if ``one_thread``: :func:`one_thread_form`)."""
        return step_module(self.laws, self.integrator_module, self.kinds, self.periodic,
                           fused=fused, one_thread=one_thread)
