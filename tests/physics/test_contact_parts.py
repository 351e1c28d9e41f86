"""Contact laws composed from parts (dpm.impact.parts).

A model is built here, without editing dpm, from dpm's Hertz normal part with Tsuji damping
and a viscous tangential part defined in this file, registered with ``dpm.register``, and
run on an explicit (velocity Verlet) and an implicit (Newmark-beta) integrator:

* head-on: the restitution measured is the one set (the Hertz part's damping is solved for
  it with the attractive force cut off);
* oblique: the contact-point tangential velocity after the impact matches an independent
  solution of the rigid-body equations of a sphere hitting a wall with the same force laws
  (scipy's solve_ivp), in the viscous regime (Coulomb limit only near the edges of the
  contact) and in the sliding regime (where rigid-body impulse theory gives
  1 - 7/2 mu (1 + e) v_n / v_t).

Both integrators run the same scene type, so one step module and one implicit module are
compiled for them; the implicit rolling-resistance test compiles one more of each. The rest
(layouts, generated source, refusals) compiles nothing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dpm
from dpm.impact import HertzTsujiNormal, LinearCohesion, TangentialPart
from dpm.impact.collision import tsuji_beta_for_restitution
from dpm.impact.measure import collide
from dpm.impact.parts import Layout
from dpm.kernels.config import inline_jit
from dpm.material import Material, effective_young
from dpm.parameters import Parameter


@inline_jit
def viscous_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k,
                       h):
    """F_t = -min(c_t |v_t|, mu F_n) v_t / |v_t|; q = (c_t, mu); no history."""
    vt = math.sqrt(vtx * vtx + vty * vty + vtz * vtz)
    if vt == 0.0:
        return 0.0, 0.0, 0.0
    ft = min(q[0] * vt, q[1] * max(fn, 0.0))
    return -ft * vtx / vt, -ft * vty / vt, -ft * vtz / vt


class ViscousTangential(TangentialPart):
    """A purely viscous tangential force with a constant coefficient c_t [N s/m] and a
    Coulomb limit: F_t = -min(c_t |v_t|, mu F_n) v_t / |v_t|."""

    name = "viscous"
    slots = ("c_t", "mu")
    function = viscous_tangential
    parameters = {
        "tangential_viscosity": Parameter(low=0.0, unit="N s/m", doc="c_t"),
        "friction": Parameter(default=0.5, low=0.0, doc="Coulomb friction coefficient"),
    }

    def values(self, model, a, b, context):
        return float(model.params["tangential_viscosity"]), float(model.params["friction"])


class HertzViscous(dpm.ImpactModel):
    """Hertz with Tsuji damping x a viscous tangential force."""

    name = "hertz_viscous"
    normal = HertzTsujiNormal()
    tangential = ViscousTangential()


dpm.register("impact_model", "hertz_viscous", HertzViscous)

R = 1e-3
RHO = 2500.0
YOUNG = 1e7
NU = 0.3
V = 0.3
MASS = 4.0 / 3.0 * math.pi * R**3 * RHO
INTEGRATORS = ["velocity_verlet", "newmark_beta"]


def estar() -> float:
    m = Material("m", density=RHO, young=YOUNG, poisson=NU)
    return effective_young(m, m)


def contact_time() -> float:
    """Elastic Hertz duration at V (Johnson 1985), to choose the step."""
    return 2.868265699194 * (MASS**2 / (R * estar() ** 2 * V)) ** 0.2


def reference(e: float, ct: float, mu: float, vt: float) -> float:
    """Contact-point tangential velocity after / before of a sphere (radius R, mass MASS)
    hitting a wall at V normal and vt tangential speed, by solve_ivp of the rigid-body
    equations with the same laws: Hertz-Tsuji normal force cut off at zero, F_t = -min(c_t
    |u|, mu F_n) sign(u) at the contact point (lever arm a = R - d/2, as the engine's),
    u = v_x - w_y a; the sphere leaves when the normal force returns to zero."""
    es = estar()
    beta = tsuji_beta_for_restitution(e)
    inertia = 0.4 * MASS * R * R

    def force(y):
        d, dd = -y[0], -y[1]  # overlap (z measured from touching), its rate
        if d <= 0.0:
            return 0.0, -1.0
        a = math.sqrt(R * d)
        f = 4.0 / 3.0 * es * a * d + 2.0 * math.sqrt(5.0 / 6.0) * beta * math.sqrt(
            2.0 * es * a * MASS) * dd
        return max(f, 0.0), f

    def rhs(t, y):
        fn, _ = force(y)
        lever = R + 0.5 * y[0]
        u = y[2] - y[3] * lever
        ft = -math.copysign(min(ct * abs(u), mu * fn), u)
        return [y[1], fn / MASS, ft / MASS, -lever * ft / inertia]

    def ends(t, y):
        return force(y)[1] if t > 1e-3 * contact_time() else 1.0

    ends.terminal = True
    ends.direction = -1
    sol = solve_ivp(rhs, (0.0, 10 * contact_time()), [0.0, -V, vt, 0.0], events=ends,
                    rtol=1e-11, atol=1e-14, max_step=contact_time() / 200)
    y = sol.y[:, -1]
    return (y[2] - y[3] * R) / vt


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_composed_model_head_on_restitution(integrator):
    """The Hertz-Tsuji part of the composed model rebounds with the set restitution."""
    c = collide("hertz_viscous", {"restitution": 0.6, "tangential_viscosity": 1e-3},
                speed=V, dt=contact_time() / 1000, integrator=integrator, end_exponent=1.5)
    assert c.restitution == pytest.approx(0.6, rel=2e-3)
    assert c.spin == 0.0


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("ct, mu, vt", [(5e-3, 0.5, 0.2), (1.0, 0.1, 1.0)],
                         ids=["viscous", "sliding"])
def test_composed_model_viscous_tangential_part(integrator, ct, mu, vt):
    """Oblique impact: the new tangential part's effect matches the rigid-body solution
    (and, sliding, impulse theory)."""
    e = 0.6
    c = collide("hertz_viscous", {"restitution": e, "tangential_viscosity": ct,
                                  "friction": mu},
                speed=V, tangential_speed=vt, dt=contact_time() / 1000, integrator=integrator,
                end_exponent=1.5)
    ref = reference(e, ct, mu, vt)
    assert 0.05 < 1.0 - ref < 0.8  # the part changes the motion markedly
    assert c.tangential_restitution == pytest.approx(ref, abs=2e-3 * (1.0 - ref))
    if ct == 1.0:  # sliding all through the contact
        assert ref == pytest.approx(1.0 - 3.5 * mu * (1.0 + e) * V / vt, rel=2e-3)


def test_implicit_rolling_resistance_of_a_composed_model():
    """Newmark-beta with the composed model plus the constant-torque rolling part (the
    implicit integrators used to refuse rolling resistance): a sphere rolling on a plane
    decelerates at 5/7 mu_r g (DPM thesis eq. 2.53; the viscous tangential part keeps the
    slip constant once its transient, rate 7 c_t / (2 m), has died out)."""
    mu_r, g, v0 = 0.05, 9.81, 0.05
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -g), integrator="newmark_beta")
    m = Material("m", density=RHO, young=YOUNG, poisson=NU)
    sim.contact(m, m, model="hertz_viscous", restitution=0.6, tangential_viscosity=1e-3,
                friction=1.0, rolling_friction=mu_r)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    k = 4.0 / 3.0 * estar() * math.sqrt(R)
    d0 = (MASS * g / k) ** (2.0 / 3.0)  # resting Hertz overlap
    sim.add_particles("sphere", material=m, radius=R, positions=[[0, 0, R - d0]],
                      velocities=[[v0, 0, 0]], angular_velocities=[[0, v0 / R, 0]])
    sim.run(steps=2000, progress=False)  # the slip's transient: exp(-6.7)
    v1, t1 = sim.bodies.velocity[0, 0], sim.time
    sim.run(steps=2000, progress=False)
    decel = (v1 - sim.bodies.velocity[0, 0]) / (sim.time - t1)
    assert decel == pytest.approx(5.0 / 7.0 * mu_r * g, rel=2e-3)


# ------------------------------------------------------------------ no compilation below


def test_parameters_and_flags_come_from_the_parts():
    assert set(HertzViscous.parameters) == {"restitution", "tangential_viscosity", "friction",
                                            "rolling_friction", "rolling_model",
                                            "rolling_damping"}
    assert HertzViscous.needs_elastic_constants
    assert HertzViscous.kernel == (__name__, "hertz_viscous")
    with pytest.raises(dpm.ParameterError, match="tangential_viscosity"):
        HertzViscous(tangential_viscosity=-1.0)


def test_row_and_history_layout_follow_the_parts():
    m = HertzViscous(tangential_viscosity=2e-3, friction=0.4)
    spec = m.law_spec()
    assert spec == (__name__, "hertz_viscous")
    assert spec.layout.slots == {"E*": 0, "beta": 1, "c_t": 2, "mu": 3}
    assert spec.layout.history == 0
    mat = Material("m", density=RHO, young=YOUNG, poisson=NU)
    row = m.pair_row(mat, mat, dpm.impact.PairContext())
    assert row.tolist() == [estar(), tsuji_beta_for_restitution(0.5), 2e-3, 0.4]
    # with rolling resistance the rolling part gets slots and history after the others
    m = HertzViscous(tangential_viscosity=2e-3, rolling_friction=0.1, rolling_model="epsd")
    lay = m.law_spec().layout
    assert m.law_spec()[1] == "hertz_viscous_epsd"
    assert list(lay.slots) == ["E*", "beta", "c_t", "mu", "mu_r", "k_roll", "eta_r"]
    assert lay.offset == {"tangential": 0, "rolling": 0, "normal": 3} and lay.history == 3
    # Hertz-Mindlin and its cohesion share the slot beta between normal and tangential part
    lay = LinearCohesion(cohesion_energy_density=1.0).law_spec().layout
    assert list(lay.slots) == ["E*", "beta", "G*", "mu", "k_c"]
    assert lay.offset == {"tangential": 0, "normal": 3, "adhesion": 3} and lay.history == 3


def test_generated_law_calls_the_parts_with_their_slots():
    spec = HertzViscous(tangential_viscosity=1.0).law_spec()
    src = dpm.plan.render([spec], "dpm.kernels.integrate_velocity_verlet")
    assert f"from {__name__} import viscous_tangential as tangential_0" in src
    assert "tangential_0((p[2], p[3]), fn, kn," in src
    assert "normal_0((p[0], p[1]), delta," in src
    assert "ROLLING = False" in src
    src = dpm.plan.render_implicit([spec])
    assert "viscous_tangential as tangential_0" in src and "def implicit_steps" in src


def test_parts_must_agree_on_a_shared_slot():
    class OtherBeta(ViscousTangential):
        slots = ("c_t", "beta")

    class Clash(dpm.ImpactModel):
        name = "clash"
        normal = HertzTsujiNormal()
        tangential = OtherBeta()

    mat = Material("m", density=RHO, young=YOUNG, poisson=NU)
    with pytest.raises(dpm.ParameterError, match="shared slot 'beta'"):
        Clash(tangential_viscosity=1.0).pair_row(mat, mat, dpm.impact.PairContext())


def test_layout_refuses_too_many_slots():
    class Wide(ViscousTangential):
        slots = tuple(f"s{k}" for k in range(16))

    with pytest.raises(dpm.ParameterError, match="at most 16"):
        Layout((HertzTsujiNormal(), Wide()))


def test_epsd_needs_a_normal_stiffness():
    class NoStiffness(HertzTsujiNormal):
        def stiffness(self, model, a, b, context):
            return None

    class Model(dpm.ImpactModel):
        name = "no_stiffness"
        normal = NoStiffness()

    mat = Material("m", density=RHO, young=YOUNG, poisson=NU)
    law = Model(rolling_friction=0.1, rolling_model="epsd")
    with pytest.raises(dpm.ParameterError, match="not offered"):
        law.pair_row(mat, mat, dpm.impact.PairContext())
    assert np.isfinite(Model(rolling_friction=0.1).pair_row(mat, mat,
                                                            dpm.impact.PairContext())).all()
