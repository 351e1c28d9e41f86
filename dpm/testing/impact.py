"""Contract checks of an impact model (a registered name or an :class:`dpm.ImpactModel`
subclass, with its parameters).

References:

* **no force without overlap** -- the law alone (:func:`dpm.plan.law_module`, the code the
  step runs) at overlap 0 and 1e-9 R* with zero rate gives no force, relative to its force
  at the overlap 1e-2 R* (which must be repulsive: the check is not vacuous); and in a
  real two-sphere run, while the spheres do not touch (their pair already in the
  neighbour list, closer than the skin), force and torque are exactly zero;
* **momentum** -- Newton's third law: in an oblique two-sphere impact with spin and a
  common drift (sphere radii R and 0.8 R), the total linear momentum after every step
  equals the initial one to round-off: |P_k - P_0| <= 4 eps k sum_i m_i |v_i| (the
  worst-case rounding of two half kicks per step; a force applied unequally to the two
  bodies breaks it at order one);
* **restitution** -- the head-on collision of two equal spheres measured by
  :func:`dpm.impact.measure.collide` (the scene's own step kernel, step = contact time /
  ``steps``): -(v_rel after)/(v_rel before) equals the model's stated restitution within
  ``tolerance`` (absolute).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from .errors import ContractError

#: the overlap (times R*) at which the reference force of the no-force check is taken
REFERENCE_OVERLAP = 1e-2
#: the small overlap (times R*) at which the force must already have vanished
SMALL_OVERLAP = 1e-9
#: |F(small)| <= SMALL_FORCE |F(reference)| and |F(0)| <= ZERO_FORCE |F(reference)|
SMALL_FORCE = 1e-6
ZERO_FORCE = 1e-9


def _model(model: str | type, params: dict[str, Any]):
    from ..plugins import registry

    cls = registry().lookup("impact_model", model, "dpm.testing")
    return cls(call=f"dpm.testing({getattr(cls, 'name', '') or cls.__name__})", **params)


def _material(density: float, young: float | None, poisson: float | None):
    from ..material import Material

    return Material("contract", density=density, young=young, poisson=poisson)


def _reduced(radius: float, density: float) -> tuple[float, float]:
    """(m*, R*) of two equal spheres."""
    m = 4.0 / 3.0 * math.pi * radius**3 * density
    return 0.5 * m, 0.5 * radius


def contact_time(model: str | type, params: dict[str, Any], *, density: float = 2500.0,
                 young: float | None = 1e7, poisson: float | None = 0.3,
                 radius: float = 1e-3, speed: float = 0.5) -> float:
    """The model's own head-on contact duration [s] of two equal spheres at ``speed``."""
    inst = _model(model, params)
    mat = _material(density, young, poisson)
    meff, reff = _reduced(radius, density)
    t = float(inst.contact_time(mat, mat, meff, reff, speed))
    if not (math.isfinite(t) and t > 0.0):
        raise ContractError(f"{_label(model)}: contact_time() gave {t!r} for two spheres of "
                            f"radius {radius:g} m at {speed:g} m/s; it must be finite and > 0")
    return t


def _label(model: str | type) -> str:
    return model if isinstance(model, str) else model.__name__


def law_force(model: str | type, params: dict[str, Any], delta: float, ddelta: float = 0.0,
              *, density: float = 2500.0, young: float | None = 1e7,
              poisson: float | None = 0.3, radius: float = 1e-3, speed: float = 0.5,
              dt: float | None = None) -> tuple[float, ...]:
    """(F_n, F_t x, y, z, T_roll x, y, z) of the model's law, as the step composes it, for
    two equal spheres at overlap ``delta`` [m] and overlap rate ``ddelta`` [m/s], normal
    along x, no tangential or relative angular velocity, fresh history."""
    from ..impact.base import PairContext
    from ..impact.parts import pack_tables
    from ..plan import law_module

    inst = _model(model, params)
    mat = _material(density, young, poisson)
    meff, reff = _reduced(radius, density)
    laws, _, pp, width = pack_tables({(0, 0): inst}, [mat],
                                     lambda a, b: PairContext(speed, meff, reff))
    mod = law_module(laws)
    p = tuple(float(x) for x in pp[0, 0])
    hist = np.zeros((1, max(int(width), 1)))
    if dt is None:
        dt = contact_time(model, params, density=density, young=young, poisson=poisson,
                          radius=radius, speed=speed) / 400.0
    return tuple(float(x) for x in mod.pair_force(0, p, float(delta), float(ddelta), 0.0, 0.0,
                                                  0.0, 1.0, 0.0, 0.0, meff, reff, 0.0, 0.0,
                                                  0.0, float(dt), hist, 0))


def check_no_force_without_overlap(model: str | type, params: dict[str, Any], *,
                                   density: float = 2500.0, young: float | None = 1e7,
                                   poisson: float | None = 0.3, radius: float = 1e-3,
                                   speed: float = 0.5) -> dict[str, float]:
    """The law gives no force at zero overlap and a vanishing one at 1e-9 R* (zero rate),
    relative to its force at 1e-2 R*; return the three normal forces."""
    kw = dict(density=density, young=young, poisson=poisson, radius=radius, speed=speed)
    _, reff = _reduced(radius, density)
    ref = law_force(model, params, REFERENCE_OVERLAP * reff, **kw)
    small = law_force(model, params, SMALL_OVERLAP * reff, **kw)
    zero = law_force(model, params, 0.0, **kw)
    name = _label(model)
    if not all(math.isfinite(x) for x in ref + small + zero):
        raise ContractError(f"{name}: the law gave a non-finite force: at overlap "
                            f"{REFERENCE_OVERLAP:g} R* {ref}, at {SMALL_OVERLAP:g} R* {small}, "
                            f"at 0 {zero}")
    fref = ref[0]
    if not fref > 0.0:
        raise ContractError(f"{name}: normal force {fref!r} N at overlap {REFERENCE_OVERLAP:g} "
                            "R* with zero rate; a contact law must repel there")
    for what, f, tol in (("0", zero, ZERO_FORCE), (f"{SMALL_OVERLAP:g} R*", small, SMALL_FORCE)):
        size = math.sqrt(sum(x * x for x in f[:4]))
        if size > tol * fref:
            raise ContractError(
                f"{name}: force {size:.6g} N at overlap {what} with zero rate (normal "
                f"{f[0]:.6g} N); allowed at most {tol:g} x the force at {REFERENCE_OVERLAP:g} R* "
                f"({fref:.6g} N): no force without overlap")
    return {"reference": fref, "small": small[0], "zero": zero[0]}


def _one_thread():
    import numba

    class _Ctx:
        def __enter__(self):
            self.n = numba.get_num_threads()
            numba.set_num_threads(1)  # two bodies: a parallel launch per step only costs

        def __exit__(self, *exc):
            numba.set_num_threads(self.n)

    return _Ctx()


def check_momentum(model: str | type, params: dict[str, Any], *, density: float = 2500.0,
                   young: float | None = 1e7, poisson: float | None = 0.3,
                   radius: float = 1e-3, speed: float = 0.5, steps_per_contact: int = 100,
                   bind_models: Sequence[str] = (), max_steps: int = 20000) -> dict[str, Any]:
    """Oblique impact of spheres R and 0.8 R (impact parameter 0.2 (R1 + R2), spins, a
    common drift): no force before they touch, momentum conserved to round-off at every
    step. Return the step count, the largest momentum error and its bound."""
    from ..impact.measure import bind
    from ..simulation import Simulation

    dt = contact_time(model, params, density=density, young=young, poisson=poisson,
                      radius=radius, speed=speed) / steps_per_contact
    sim = Simulation(dt=dt, gravity=(0, 0, 0), dt_check="off", max_overlap=1.0)
    bind(sim, bind_models)
    mat = _material(density, young, poisson)
    sim.contact(mat, mat, model=model, **params)
    r1, r2 = radius, 0.8 * radius
    m1 = 4.0 / 3.0 * math.pi * r1**3 * density
    m2 = 4.0 / 3.0 * math.pi * r2**3 * density
    gap, b = 0.02 * r1, 0.2 * (r1 + r2)
    drift = speed * np.array([0.1, 0.2, -0.1])
    v1 = drift + [speed * m2 / (m1 + m2), 0.0, 0.0]
    v2 = drift - [speed * m1 / (m1 + m2), 0.0, 0.0]
    sim.add_particles("sphere", material=mat, radius=[r1, r2],
                      positions=[[-r1 - 0.5 * gap, -0.5 * b, 0.0], [r2 + 0.5 * gap, 0.5 * b, 0.0]],
                      velocities=[v1, v2],
                      angular_velocities=[[0.0, 0.0, 0.3 * speed / r1],
                                          [0.2 * speed / r2, 0.0, 0.0]])
    p0 = sim.momentum()
    scale = m1 * float(np.linalg.norm(v1)) + m2 * float(np.linalg.norm(v2))
    eps = float(np.finfo(float).eps)
    name = _label(model)
    touched = False
    worst, bound = 0.0, 0.0
    with _one_thread():
        for k in range(1, max_steps + 1):
            sim.run(steps=1, progress=False)
            bd = sim.bodies
            dist = float(np.linalg.norm(bd.position[1] - bd.position[0]))
            loaded = bool(np.any(bd.force != 0.0) or np.any(bd.torque != 0.0))
            if dist >= r1 + r2 and loaded:
                raise ContractError(f"{name}: force {bd.force[0]} N on a sphere at step {k} "
                                    f"while the spheres are {dist - r1 - r2:.3g} m apart: no "
                                    "force without overlap")
            err = float(np.linalg.norm(sim.momentum() - p0))
            bound = 4.0 * eps * k * scale
            worst = max(worst, err)
            if err > bound:
                raise ContractError(f"{name}: total momentum changed by {err:.3g} kg m/s after "
                                    f"{k} steps (round-off bound {bound:.3g}; initial "
                                    f"{p0}): momentum is not conserved")
            if loaded:
                touched = True
            elif touched and dist > r1 + r2:
                break
        else:
            raise ContractError(f"{name}: the spheres were still in contact after {max_steps} "
                                "steps")
    if not touched:
        raise ContractError(f"{name}: the spheres never touched (no force in {k} steps)")
    return {"steps": k, "error": worst, "bound": bound}


def check_restitution(model: str | type, params: dict[str, Any], restitution: float,
                      tolerance: float = 0.01, *, density: float = 2500.0,
                      young: float | None = 1e7, poisson: float | None = 0.3,
                      radius: float = 1e-3, speed: float = 0.5, steps_per_contact: int = 400,
                      bind_models: Sequence[str] = ()) -> float:
    """Head-on collision of two equal spheres in a real run: the measured restitution is
    ``restitution`` within ``tolerance``; return the measured value."""
    from ..impact.measure import collide

    dt = contact_time(model, params, density=density, young=young, poisson=poisson,
                      radius=radius, speed=speed) / steps_per_contact
    with _one_thread():
        c = collide(model, params, speed=speed, dt=dt, geometry="pair", radii=(radius, radius),
                    density=density, young=young, poisson=poisson,
                    max_steps=200 * steps_per_contact, bind_models=bind_models)
    e = c.restitution
    if not (math.isfinite(e) and abs(e - restitution) <= tolerance):
        raise ContractError(f"{_label(model)}: head-on restitution measured {e:.6g} at "
                            f"{speed:g} m/s ({c.steps} steps of contact), stated "
                            f"{restitution:g}; allowed difference {tolerance:g}")
    return e


class ImpactModelContract:
    """Subclass as ``class TestMine(ImpactModelContract)`` and set ``model`` and
    ``params``; pytest then runs the checks on it.

    ``restitution`` is the restitution the model states for these parameters (default
    ``params["restitution"]``; None skips that check, e.g. for a model whose restitution
    depends on speed), ``restitution_tolerance`` the allowed absolute difference.
    ``bind_models``: laws to compile with it (:func:`dpm.impact.measure.bind`), so that
    the runs share a step module with other tests.
    """

    model: ClassVar[str | type] = ""
    params: ClassVar[dict[str, Any]] = {}
    restitution: ClassVar[float | None] = None
    restitution_tolerance: ClassVar[float] = 0.01
    density: ClassVar[float] = 2500.0
    young: ClassVar[float | None] = 1e7
    poisson: ClassVar[float | None] = 0.3
    radius: ClassVar[float] = 1e-3
    speed: ClassVar[float] = 0.5
    steps_per_contact: ClassVar[int] = 400
    bind_models: ClassVar[Sequence[str]] = ()

    def _kw(self) -> dict[str, Any]:
        return dict(density=self.density, young=self.young, poisson=self.poisson,
                    radius=self.radius, speed=self.speed)

    def stated_restitution(self) -> float | None:
        e = self.restitution
        return self.params.get("restitution") if e is None else e

    def test_no_force_without_overlap(self) -> None:
        check_no_force_without_overlap(self.model, dict(self.params), **self._kw())

    def test_engine_momentum_conserved(self) -> None:
        check_momentum(self.model, dict(self.params), bind_models=self.bind_models,
                       **self._kw())

    def test_engine_head_on_restitution(self) -> None:
        e = self.stated_restitution()
        if e is None:
            import pytest

            pytest.skip("the model states no restitution for these parameters")
        check_restitution(self.model, dict(self.params), float(e), self.restitution_tolerance,
                          steps_per_contact=self.steps_per_contact,
                          bind_models=self.bind_models, **self._kw())
