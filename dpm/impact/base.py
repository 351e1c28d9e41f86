"""Base class of impact models."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..errors import ParameterError
from ..kernels.config import N_HISTORY, N_PAIR_PARAMS
from ..material import Material
from ..parameters import Parameter, validate
from .parts import ROLLING_PARTS, AdhesionPart, LawSpec, NormalPart, Part, TangentialPart

#: rolling resistance models of monolithic laws -> id in their pair row's slot 6 (see
#: dpm.kernels.rolling; composed models take theirs from ROLLING_PARTS)
ROLLING_MODELS = {"constant_torque": 1, "epsd": 2}
#: rolling models that read a normal stiffness from slot 5 and eta_r from slot 6
_ROLLING_WITH_SPRING = {"epsd"}

COMMON = {
    "restitution": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                             doc="normal coefficient of restitution"),
    "friction": Parameter(default=0.5, low=0.0, doc="Coulomb friction coefficient"),
    "rolling_friction": Parameter(default=0.0, low=0.0,
                                  doc="rolling friction coefficient mu_r (torque mu_r F_n R*)"),
    "rolling_model": Parameter(default="constant_torque", kind="str",
                               doc="rolling resistance model: " + ", ".join(ROLLING_MODELS)),
    "rolling_damping": Parameter(default=0.3, low=0.0, high=1.0, high_open=True,
                                 doc="rolling_model='epsd': viscous damping ratio eta_r of the "
                                     "rolling spring (Ai et al. 2011 advise 0.3)"),
}
#: the parameters every composed model has (its rolling part is chosen by them)
ROLLING = {k: v for k, v in COMMON.items() if k.startswith("rolling_")}


@dataclass(frozen=True)
class PairContext:
    """What the scene tells a model about a material pair when the tables are packed.

    impact_speed: characteristic impact speed [m/s] (largest initial speed or free-fall
    speed over the scene's height); meff, reff: effective mass [kg] and radius [m] of the
    smallest bodies of the pair (a wall counts as infinite).
    """

    impact_speed: float = 1.0
    meff: float = 1.0
    reff: float = 1.0


class ImpactModel:
    """A contact force law for one material pair.

    **Composed** (every built-in model): set the parts ``normal`` (required),
    ``tangential`` and ``adhesion`` (optional) to :class:`~dpm.impact.parts.Part`
    instances; the rolling part comes from ``rolling_model`` when ``rolling_friction`` > 0
    (``rolling_parts``). ``parameters`` (default: the rolling ones plus the parts'),
    ``needs_elastic_constants`` (default: any part's) and ``kernel`` (the law's module
    and name in the generated step; default: the class's module and ``name``) follow from
    the parts; the pair row, the history layout and the contact time
    (:meth:`NormalPart.contact_time`) too. See docs/impact-models.md.

    **Monolithic** (no ``normal``): name one numba kernel in ``kernel`` as
    ``("package.module", "function")`` with the signature
    ``law(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k) -> (F_n,
    F_t x, y, z)``, declare ``parameters`` and fill the pair constants in :meth:`pair_row`
    with :meth:`_row` (slots 6 and 7 carry the rolling resistance model and coefficient;
    slots 0..5 are the law's own, except that the ``epsd`` rolling model takes slot 5 for
    the normal stiffness its spring scales with: a law that offers it fills at most slots
    0..4 and passes ``stiffness=`` to ``_row``). History: ``hist[k, 0:history_slots]``
    (0-2 tangential spring by convention, 3-5 the rolling spring, 6-7 free).
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = dict(COMMON)
    kernel: ClassVar[tuple[str, str]] = ("", "")
    needs_elastic_constants: ClassVar[bool] = False
    #: the parts of a composed model (None: a monolithic ``kernel``)
    normal: ClassVar[NormalPart | None] = None
    tangential: ClassVar[TangentialPart | None] = None
    adhesion: ClassVar[AdhesionPart | None] = None
    #: rolling parts by ``rolling_model``
    rolling_parts: ClassVar[dict[str, Part]] = ROLLING_PARTS
    #: history floats per contact the kernel reads and writes, ``hist[k, 0:history_slots]``
    #: (0-2: the tangential spring by convention; 6-7 free for the normal law). Slots 3-5
    #: belong to the rolling spring and are added when a pair has rolling resistance. Each
    #: scene allocates the widest its laws declare: a narrow history row is less memory
    #: and less traffic per contact. The default, N_HISTORY, suits any law.
    history_slots: ClassVar[int] = N_HISTORY

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        parts = [p for p in (cls.normal, cls.tangential, cls.adhesion) if p is not None]
        if cls.normal is None:
            if parts:
                raise TypeError(f"{cls.__name__}: a composed model needs a normal part")
            return
        for p in parts:
            if not isinstance(p, Part):
                raise TypeError(f"{cls.__name__}: {p!r} is not a Part instance")
        if "parameters" not in cls.__dict__:
            params = dict(ROLLING)
            for p in parts:
                params.update(p.parameters)
            cls.parameters = params
        if "needs_elastic_constants" not in cls.__dict__:
            cls.needs_elastic_constants = any(p.needs_elastic_constants for p in parts)
        if "kernel" not in cls.__dict__:
            cls.kernel = (cls.__module__, cls.name or cls.__name__.lower())

    def __init__(self, call: str | None = None, **params: Any) -> None:
        self.call = call or f"{type(self).__name__}()"
        self.params = validate(self.call, self.parameters, params)
        rm = self.params.get("rolling_model", "constant_torque")
        allowed = (self._rolling_choices() if self.normal is not None
                   else list(ROLLING_MODELS))
        if rm not in allowed:
            raise ParameterError(f"{self.call}: rolling_model={rm!r}; allowed: "
                                 f"{', '.join(allowed)}")

    # ------------------------------------------------------------------ composition
    def rolling(self) -> Part | None:
        """The rolling part of this instance (None without rolling resistance)."""
        if float(self.params.get("rolling_friction", 0.0) or 0.0) > 0.0:
            rm = self.params.get("rolling_model", "constant_torque")
            if rm in self.rolling_parts:
                return self.rolling_parts[rm]
            from ..plugins import registry

            return registry().lookup("rolling_model", rm, self.call)()  # a plugin's
        return None

    def _rolling_choices(self) -> list[str]:
        """Rolling models a composed law takes: its own, and those plugins register."""
        from ..plugins import registry

        return sorted(set(self.rolling_parts) | set(registry().names("rolling_model")))

    def parts(self) -> tuple[Part, ...]:
        """The parts of this instance: normal, tangential, adhesion, rolling (those set)."""
        return tuple(p for p in (self.normal, self.tangential, self.adhesion, self.rolling())
                     if p is not None)

    def law_spec(self) -> tuple:
        """What the step compiles for this instance: a :class:`LawSpec` (composed; the
        rolling part in the name when there is one) or the monolithic ``kernel``."""
        if self.normal is None:
            return tuple(self.kernel)
        roll = self.rolling()
        name = self.kernel[1] + (f"_{roll.name}" if roll is not None else "")
        return LawSpec(self.kernel[0], name, self.parts())

    def history_width(self) -> int:
        """History floats per contact this instance needs."""
        if self.normal is None:
            roll = float(self.params.get("rolling_friction", 0.0) or 0.0) > 0.0
            return max(self.history_slots, 6 if roll else 3)
        return self.law_spec().layout.history

    def pair_row(self, a: Material, b: Material, context: PairContext) -> np.ndarray:
        """Constants of the law for materials ``a`` and ``b``: composed, the parts' slot
        values at the places the layout gives them; monolithic: length N_PAIR_PARAMS."""
        if self.normal is None:
            raise NotImplementedError
        spec = self.law_spec()
        row = np.zeros(spec.layout.width)
        given: dict[str, float] = {}
        for part in spec.parts:
            vals = tuple(float(v) for v in part.values(self, a, b, context))
            if len(vals) != len(part.slots):
                raise ParameterError(f"{self.call}: part {part!r} gave {len(vals)} values for "
                                     f"its {len(part.slots)} slots {part.slots}")
            for s, v in zip(part.slots, vals, strict=True):
                if s in given and not (given[s] == v or (v != v and given[s] != given[s])):
                    raise ParameterError(f"{self.call}: parts disagree on the shared slot "
                                         f"{s!r} ({given[s]!r} and {v!r})")
                given[s] = v
                row[spec.layout.slots[s]] = v
        return row

    def contact_time(self, a: Material, b: Material, meff: float, reff: float,
                     speed: float) -> float:
        """Duration [s] of a head-on collision at ``speed`` (for the time-step check)."""
        if self.normal is None:
            raise NotImplementedError
        return self.normal.contact_time(self, a, b, meff, reff, speed)

    def _row(self, *values: float, stiffness: float | None = None) -> np.ndarray:
        """Pack the law's constants; add the rolling model's (slots 6, 7 and for ``epsd`` 5).

        ``stiffness``: a representative normal stiffness k_n [N/m] of the pair, which the
        ``epsd`` rolling spring scales with (k_r = 2.25 mu_r^2 R*^2 k_n).
        """
        row = np.zeros(N_PAIR_PARAMS)
        row[: len(values)] = values
        mu_r = float(self.params.get("rolling_friction", 0.0))
        if mu_r > 0.0:
            rm = self.params.get("rolling_model", "constant_torque")
            row[6] = ROLLING_MODELS[rm]
            row[7] = mu_r
            if rm in _ROLLING_WITH_SPRING:
                if len(values) > 5 or stiffness is None:
                    raise ParameterError(f"{self.call}: rolling_model={rm!r} is not offered by "
                                         f"{type(self).__name__}; allowed: constant_torque")
                row[5] = stiffness if math.isfinite(stiffness) else 0.0
                row[6] += float(self.params.get("rolling_damping", 0.3))
        return row


def hertz_equivalent_stiffness(meff: float, reff: float, estar: float, speed: float) -> float:
    """Maw's linear stiffness that stores the strain energy of a Hertz contact at ``speed``:
    k = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5) (DPM thesis eq. 2.29)."""
    speed = max(speed, 1e-12)
    h = 16.0 / 15.0 * math.sqrt(reff) * estar
    return h * (meff * speed * speed / h) ** 0.2


def hertz_beta(restitution: float) -> float:
    """beta = -ln e / sqrt(ln^2 e + pi^2) (0 for e = 1)."""
    le = math.log(restitution)
    return -le / math.sqrt(le * le + math.pi**2)
