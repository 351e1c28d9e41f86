"""The registry of boundary primitive kinds: what the step needs to know about each.

A boundary is made of primitives (:class:`dpm.boundaries.Primitives`); each primitive is a
row of ``par`` (``PAR_WIDTH`` = 20 floats) and a kind code. :mod:`dpm.plan` writes the
scene's ``closest`` (the contact geometry of every kind present) from this registry, so a
plugin adds a primitive kind without editing dpm::

    from dpm.boundaries.primitives import PrimitiveKind, register_primitive

    BALL = register_primitive(PrimitiveKind(
        code=100, name="ball", width=4,
        function=("my_package.kernels", "ball_distance")))

``function`` names a numba function decorated with :func:`dpm.kernels.config.inline_jit`,
``f(p, x, y, z)`` (or ``f(p, x, y, z, r)`` with ``takes_radius``) of the primitive's row
``p`` (a tuple of 20 floats: index it) and a sphere centre in the boundary's frame,
returning ``(dist, nx, ny, nz)`` (or, with ``returns_feature``, ``(dist, nx, ny, nz,
feature)``): the signed distance from the centre to the surface (> 0 outside) and the unit
normal from the surface towards the centre. Plugin kinds are two-sided (a sphere touches
when dist < r); only the built-in PLANE is one-sided. Keep the function in a module that
imports only numpy, numba and math: its code is part of the fingerprint of the generated
step module (a changed function gives a new module, not stale cached code).

What a plugin kind does not get (the step's kernels hold these for the built-in kinds):
``closest_any`` (the brute-force list of the tests) knows the built-in kinds only and
treats another kind as absent (the inlets' placement test, :mod:`dpm.kernels.placement`,
is generated per set of kinds like the step and does know them); the hand-over of tangential
history across a joined end (``joinable``) is done for AXI and TORUS only; the mesh rules
for shared edges and vertices are TRIANGLE's.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ParameterError
from ..kernels import boundary_geometry as bg

#: the module of the built-in geometry functions
BUILTIN_MODULE = "dpm.kernels.boundary_geometry"


@dataclass(frozen=True)
class PrimitiveKind:
    """One primitive kind.

    code : int
        The kind code stored in ``Primitives.kind`` (built-ins 0-5; plugins take codes of
        64 and above).
    name : str
        A short name (``plane``, ``slab``, ...).
    width : int
        Columns of ``par`` the kind uses (at most ``PAR_WIDTH``); the rest stay zero.
    function : (module, name)
        The numba geometry function (see the module docstring).
    takes_radius : bool
        The function takes the sphere radius as a fifth argument.
    returns_feature : bool
        The function returns a fifth value, the feature (0 face; ``JOINED`` beyond a joined
        end; triangle edges and vertices 1-6).
    joinable : bool
        Its ends can be joined to another piece's (``JOINED`` feature; the scene compiles
        the joint hand-over, ``HAS_JOINTS``).
    """

    code: int
    name: str
    width: int
    function: tuple[str, str]
    takes_radius: bool = False
    returns_feature: bool = False
    joinable: bool = False


_KINDS: dict[int, PrimitiveKind] = {}


def register_primitive(kind: PrimitiveKind) -> PrimitiveKind:
    """Register ``kind``; return it. Registering the same kind again is a no-op; another
    kind under a code or name already taken is refused."""
    if not isinstance(kind.code, int) or kind.code < 0:
        raise ParameterError(f"register_primitive(): code={kind.code!r} must be an int >= 0")
    if not 1 <= kind.width <= bg.PAR_WIDTH:
        raise ParameterError(f"register_primitive({kind.name!r}): width={kind.width} must "
                             f"be in [1, {bg.PAR_WIDTH}] (the columns of par)")
    if (not isinstance(kind.function, tuple) or len(kind.function) != 2
            or not all(isinstance(s, str) and s for s in kind.function)):
        raise ParameterError(f"register_primitive({kind.name!r}): function="
                             f"{kind.function!r} must be (module, name)")
    known = _KINDS.get(kind.code)
    if known == kind:
        return kind
    if known is not None:
        raise ParameterError(f"register_primitive({kind.name!r}): code {kind.code} is "
                             f"taken by {known.name!r}")
    for other in _KINDS.values():
        if other.name == kind.name:
            raise ParameterError(f"register_primitive(): name {kind.name!r} is taken (code "
                                 f"{other.code})")
    _KINDS[kind.code] = kind
    return kind


def unregister_primitive(code: int) -> None:
    """Remove a plugin kind (tests); the built-ins stay."""
    if code in BUILTIN_CODES:
        raise ParameterError(f"unregister_primitive(): {code} is a built-in kind")
    _KINDS.pop(code, None)


def primitive_kind(code: int) -> PrimitiveKind:
    """The registered kind of ``code``."""
    try:
        return _KINDS[int(code)]
    except KeyError:
        raise ParameterError(f"boundary primitive kind {code} is not registered (known: "
                             + ", ".join(f"{k.code} {k.name}" for k in kinds()) + "; see "
                             "dpm.boundaries.primitives.register_primitive)") from None


def kinds() -> list[PrimitiveKind]:
    """Every registered kind, by code."""
    return [_KINDS[c] for c in sorted(_KINDS)]


PLANE = register_primitive(PrimitiveKind(bg.PLANE, "plane", 6,
                                         (BUILTIN_MODULE, "plane_distance")))
SLAB = register_primitive(PrimitiveKind(bg.SLAB, "slab", 12, (BUILTIN_MODULE, "slab_distance")))
AXI = register_primitive(PrimitiveKind(bg.AXI, "axi", 12, (BUILTIN_MODULE, "axi_distance"),
                                       takes_radius=True, returns_feature=True,
                                       joinable=True))
TORUS = register_primitive(PrimitiveKind(bg.TORUS, "torus", 14,
                                         (BUILTIN_MODULE, "torus_distance"),
                                         returns_feature=True, joinable=True))
TRIANGLE = register_primitive(PrimitiveKind(bg.TRIANGLE, "triangle", 19,
                                            (BUILTIN_MODULE, "triangle_distance"),
                                            returns_feature=True))
SIEVE = register_primitive(PrimitiveKind(bg.SIEVE, "sieve", 17,
                                         (BUILTIN_MODULE, "sieve_distance"),
                                         takes_radius=True))
BUILTIN_CODES = frozenset(_KINDS)
