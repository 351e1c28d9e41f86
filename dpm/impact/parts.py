"""Contact parts: an impact model is a named composition of a normal, a tangential, an
adhesion and a rolling part (MercuryDPM's species = normal x friction x adhesion).

A part declares

- ``parameters``: the :class:`~dpm.parameters.Parameter` s it reads (a composed model's
  parameters are the union of its parts', unless the model lists its own);
- ``slots``: the names of its constants in the pair row, in the order its numba function
  reads them (``q[0], q[1], ...``); parts of one model that name the same slot share it
  (and must give it the same value);
- ``history``: how many history floats per contact it keeps, and ``history_flips``:
  whether they are vectors of element i relative to j (a spring), which change sign when
  the pair is stored the other way round (:meth:`dpm.Simulation.permute`, migration
  between ranks); True for tangential and rolling parts, False for normal and adhesion
  parts (scalars such as a plastic overlap);
- ``function``: its numba scalar function, ``("package.module", "name")`` or the
  ``inline_jit`` dispatcher itself;

and :meth:`Part.values` fills its slots for a material pair. The plan lays out, per
composed law, the pair row (slots in the order normal, tangential, adhesion, rolling,
first appearance wins) and the history (tangential, rolling, normal, adhesion), and
generates the law (:func:`dpm.plan.render`)::

    F_n, k_n = normal(q_n, d, d', m*, R*, dt, hist, k, h_n)
    F_t      = tangential(q_t, F_n, k_n, d, v_t, n, m*, R*, dt, hist, k, h_t)
    F_n     -= adhesion(q_a, d, d', m*, R*, dt, hist, k, h_a)
    T_r      = rolling(q_r, F_n, R*, m*, w_rel, dt, hist, k, h_r)

Monolithic laws (``ImpactModel.kernel`` naming one function with the fixed 8-slot row)
keep working: the plan wraps them with the row's rolling slots 5-7.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter

if TYPE_CHECKING:
    from ..material import Material
    from .base import ImpactModel, PairContext

#: the numba signatures of the part kinds (documentation; the plan writes the calls)
SIGNATURES = {
    "normal": "f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)",
    "tangential": "f(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k, h)"
                  " -> (F_t x, y, z)",
    "adhesion": "f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> F_a",
    "rolling": "f(q, fn, reff, meff, wx, wy, wz, dt, hist, k, h) -> (T x, y, z)",
}
#: the order of the parts in the pair row, and in the history
ROW_ORDER = ("normal", "tangential", "adhesion", "rolling")
HISTORY_ORDER = ("tangential", "rolling", "normal", "adhesion")
#: the widest pair row a scene may have (dpm.kernels.config.pair_row16)
MAX_ROW = 16


class Part:
    """One part of a contact law (see the module docstring)."""

    kind: ClassVar[str] = ""
    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = {}
    slots: ClassVar[tuple[str, ...]] = ()
    history: ClassVar[int] = 0
    #: the history floats are vectors of i relative to j (negated when i and j swap)
    history_flips: ClassVar[bool] = False
    function: ClassVar[Any] = ("", "")
    needs_elastic_constants: ClassVar[bool] = False
    #: whether the universal step module (:mod:`dpm.universal_step`) carries this part
    #: (a part whose constants do not fit its region, or that needs detection beyond
    #: touching, compiles a scene's own module instead)
    universal: ClassVar[bool] = True

    def values(self, model: ImpactModel, a: Material, b: Material,
               context: PairContext) -> tuple[float, ...]:
        """The part's slot values for materials ``a``, ``b`` (in the order of ``slots``),
        from the model's validated ``model.params``."""
        raise NotImplementedError

    def target(self) -> tuple[str, str]:
        """(module, name) of the numba function."""
        f = self.function
        if isinstance(f, tuple):
            return f
        py = getattr(f, "py_func", f)
        return py.__module__, py.__name__

    def key(self) -> tuple:
        """What makes two parts compile to the same code."""
        extra = getattr(self, "attached_target", lambda: None)()
        return (self.kind, type(self).__qualname__, self.target(), tuple(self.slots),
                int(self.history)) + ((extra,) if extra else ())

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class NormalPart(Part):
    """Normal force from overlap and rate: ``f(q, delta, ddelta, meff, reff, dt, hist, k,
    h) -> (F_n, k_n)``; F_n > 0 repulsive (cut off at 0 by the part if it wants), k_n the
    stiffness a tangential part may scale with."""

    kind = "normal"
    #: a part that keeps contacts at a separation (an interaction range): its numba
    #: ``f(q, delta, reff, hist, k, h) -> bool``, asked for a listed pair at negative
    #: overlap whether it is still in contact (None: a pair touches only at delta > 0)
    attached: ClassVar[Any] = None

    def reach(self, model: ImpactModel, a: Material, b: Material, rmax: float) -> float:
        """How far beyond touching [m] this part can keep a contact between materials
        ``a`` and ``b`` of elements at most ``rmax`` in radius (0: touching only). The
        neighbour search, the boundary search and the MPI halo extend by the scene's
        largest."""
        return 0.0

    def attached_target(self) -> tuple[str, str] | None:
        """(module, name) of the ``attached`` function, or None."""
        f = self.attached
        if f is None or isinstance(f, tuple):
            return f
        py = getattr(f, "py_func", f)
        return py.__module__, py.__name__

    def contact_time(self, model: ImpactModel, a: Material, b: Material, meff: float,
                     reff: float, speed: float) -> float:
        """Duration [s] of a head-on collision at ``speed`` (for the time-step check)."""
        raise NotImplementedError

    def stiffness(self, model: ImpactModel, a: Material, b: Material,
                  context: PairContext) -> float | None:
        """A representative normal stiffness k_n [N/m] of the pair, which the ``epsd``
        rolling spring scales with; None: that rolling model is not offered."""
        return None


class TangentialPart(Part):
    """Tangential force: ``f(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt,
    hist, k, h) -> (F_t x, y, z)``, fn the repulsive normal force (before adhesion)."""

    kind = "tangential"
    history_flips = True


class AdhesionPart(Part):
    """Attraction: ``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> F_a``, subtracted
    from F_n after the tangential part (so friction is limited by the repulsive force)."""

    kind = "adhesion"


class RollingPart(Part):
    """Rolling resistance torque on i (j gets the opposite): ``f(q, fn, reff, meff, wx, wy,
    wz, dt, hist, k, h) -> (T x, y, z)``, w the relative angular velocity w_i - w_j."""

    kind = "rolling"
    history_flips = True


class ConstantTorque(RollingPart):
    """``T_r = -mu_r F_n R* w_rel/|w_rel|`` (DPM thesis eq. 2.53 with the unit vector; Zhou et
    al. 1999). A rolling sphere decelerates at 5/7 mu_r g."""

    name = "constant_torque"
    slots = ("mu_r",)
    function = ("dpm.kernels.rolling", "constant_torque")

    def values(self, model, a, b, context):
        return (float(model.params["rolling_friction"]),)


class EPSD(RollingPart):
    """Elastic-plastic spring-dashpot, "type C" of Ai, Chen, Rotter & Ooi (2011): k_r =
    2.25 mu_r^2 R*^2 k_n, M <- M - k_r w_rel dt limited to mu_r R* F_n, viscous
    -eta_r 2 sqrt(I_r k_r) w_rel below the limit, I_r = 7/5 m* R*^2. k_n: the normal part's
    :meth:`NormalPart.stiffness`."""

    name = "epsd"
    slots = ("mu_r", "k_roll", "eta_r")
    history = 3
    function = ("dpm.kernels.rolling", "epsd")

    def values(self, model, a, b, context):
        kn = model.normal.stiffness(model, a, b, context)
        if kn is None:
            raise ParameterError(f"{model.call}: rolling_model='epsd' is not offered by "
                                 f"{type(model).__name__}; allowed: constant_torque")
        return (float(model.params["rolling_friction"]), kn if math.isfinite(kn) else 0.0,
                float(model.params.get("rolling_damping", 0.3)))


#: rolling parts by the ``rolling_model`` parameter (extend it to add one)
ROLLING_PARTS: dict[str, RollingPart] = {"constant_torque": ConstantTorque(), "epsd": EPSD()}


class Layout:
    """Where the parts of one composed law keep their constants and their history."""

    def __init__(self, parts: tuple[Part, ...]) -> None:
        by_kind = {p.kind: p for p in parts}
        self.slots: dict[str, int] = {}
        for kind in ROW_ORDER:
            if kind in by_kind:
                for s in by_kind[kind].slots:
                    self.slots.setdefault(s, len(self.slots))
        self.width = len(self.slots)
        if self.width > MAX_ROW:
            raise ParameterError(f"a contact law with {self.width} pair constants; at most "
                                 f"{MAX_ROW}")
        self.offset: dict[str, int] = {}
        #: per history float: negated when the pair's order is reversed
        self.flips: list[bool] = []
        h = 0
        for kind in HISTORY_ORDER:
            if kind in by_kind:
                self.offset[kind] = h
                n = int(by_kind[kind].history)
                h += n
                self.flips += [bool(by_kind[kind].history_flips)] * n
        self.history = h

    def indices(self, part: Part) -> tuple[int, ...]:
        return tuple(self.slots[s] for s in part.slots)


class LawSpec(tuple):
    """A composed law as the step sees it: the tuple (module, name) (equal to a monolithic
    ``kernel`` tuple of that name) with ``parts`` and their ``layout``."""

    parts: tuple[Part, ...]
    layout: Layout

    def __new__(cls, module: str, name: str, parts: tuple[Part, ...]) -> LawSpec:
        obj = super().__new__(cls, (module, name))
        obj.parts = parts
        obj.layout = Layout(parts)
        return obj

    def __getnewargs__(self) -> tuple:  # (stored in checkpoints: a tuple subclass)
        return (self[0], self[1], self.parts)

    def key(self) -> tuple:
        return (tuple(self), tuple(p.key() for p in self.parts))

    def renamed(self, name: str) -> LawSpec:
        return LawSpec(self[0], name, self.parts)


#: monolithic laws: history slots 0-5 are the tangential and rolling springs (vectors),
#: 6-7 the normal law's state (scalars)
MONOLITHIC_FLIPS = (True,) * 6 + (False,) * 2


def history_flips(laws: list, width: int) -> np.ndarray:
    """(laws, width) bool: which history floats of each law's contacts are negated when a
    pair is stored the other way round."""
    out = np.zeros((max(len(laws), 1), width), bool)
    for k, spec in enumerate(laws):
        flips = spec.layout.flips if isinstance(spec, LawSpec) else MONOLITHIC_FLIPS
        n = min(len(flips), width)
        out[k, :n] = flips[:n]
    return out


def pack_tables(contacts: dict, materials: list, context_of) -> tuple:
    """The scene's laws (one per distinct composition), material-pair tables and history
    width: (laws, pair_model, pair_params, history width). ``context_of(ia, ib)`` gives the
    :class:`PairContext` of a pair. The table is 8 wide (``kernels.config.pair_row``), or 16
    where a law needs more (``pair_row16``)."""
    nm = len(materials)
    laws: list = []
    keys: list = []
    widths = [1]
    rows = {}
    pair_model = np.zeros((nm, nm), np.int64)
    for (ia, ib), law in contacts.items():
        spec = law.law_spec()
        key = spec.key() if isinstance(spec, LawSpec) else tuple(spec)
        if key not in keys:
            if isinstance(spec, LawSpec) and spec in laws:  # same name, other parts
                spec = spec.renamed(f"{spec[1]}_{len(laws)}")
            laws.append(spec)
            keys.append(key)
        k = keys.index(key)
        pair_model[ia, ib] = k
        widths.append(law.history_width())
        rows[ia, ib] = law.pair_row(materials[ia], materials[ib], context_of(ia, ib))
    width = 8 if max([0] + [len(r) for r in rows.values()]) <= 8 else MAX_ROW
    pair_params = np.zeros((nm, nm, width))
    for (ia, ib), r in rows.items():
        pair_params[ia, ib, :len(r)] = r
    return laws, pair_model, pair_params, max(widths)


def contact_reach(contacts: dict, materials: list, rmax: float) -> float:
    """The scene's interaction range beyond touching [m]: the largest
    :meth:`NormalPart.reach` of the laws of its material pairs (0 for touching-only laws)."""
    out = 0.0
    for (ia, ib), law in contacts.items():
        normal = getattr(law, "normal", None)
        if normal is not None:
            out = max(out, float(normal.reach(law, materials[ia], materials[ib], rmax)))
    return out
