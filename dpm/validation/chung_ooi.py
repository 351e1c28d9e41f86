"""The eight impact benchmarks of Chung & Ooi (2011), Granular Matter 13, 643-656.

Set-ups (materials, radii, speeds, friction, restitution) are those of the published
implementations of the tests (Yade's scripts of Tests 1-4, PySPH's examples of Tests 5, 7
and 8); the paper's own tables and reference curves were not available, so each test is
compared with a closed form (``references.py``): Hertz's elastic impact, the set
restitution, rigid-body Coulomb sliding, and conservation laws. ``docs/validation.md``
lists each test's set-up, its reference and what is not reproduced.

Every test runs its impacts side by side in one scene per (material, model), all scenes on
one compiled step (``impacts.BIND``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from . import Case, Row, compare, register
from .impacts import Impact, Species, run_group
from .references import (
    effective_shear,
    effective_young,
    hertz_impact,
    mindlin_no_slip,
    rigid_sliding,
    sphere_mass,
)

#: (name, density [kg/m3], Young's modulus [Pa], Poisson's ratio)
GLASS = ("glass", 2800.0, 4.8e10, 0.20)
LIMESTONE = ("limestone", 2500.0, 2.0e10, 0.25)
AL_ALLOY_T2 = ("aluminium alloy", 2699.0, 7.0e10, 0.30)
MG_ALLOY = ("magnesium alloy", 1800.0, 4.0e10, 0.35)
ALUMINA = ("alumina", 4000.0, 3.8e11, 0.23)
CAST_IRON = ("cast iron", 7000.0, 1.0e11, 0.25)
AL_ALLOY = ("aluminium alloy", 2700.0, 7.0e10, 0.33)
STEEL = ("steel", 7850.0, 2.08e11, 0.30)
POLYETHYLENE = ("polyethylene", 1400.0, 1.0e9, 0.40)
COPPER = ("copper", 8900.0, 1.2e11, 0.35)
NYLON = ("nylon", 1000.0, 2.5e9, 0.40)

ELASTIC_MODELS = ("hertz_mindlin", "hertz_brilliantov", "maw_linear_spring")
ALL_MODELS = ("hertz_mindlin", "hertz_brilliantov", "hooke", "linear_spring_dashpot",
              "maw_linear_spring", "walton_braun")

HERTZ = "Hertz (1882) closed form"
SET_E = "the set restitution"
SLIDING = "rigid-body Coulomb sliding (Maw et al. 1976, large-angle limit)"
BALANCE = "rigid sphere: change of surface speed = 5/2 change of tangential velocity"
MOMENTUM = "conservation (value after - before, scaled)"
STICK = ("linear springs, k_t = 2/7 k_n, e = 1: equal normal and tangential periods, "
         "F_t/F_n = 2/7 slip/v_n stays below mu: the slip reverses exactly")
NO_SLIP = ("ODE: Hertz normal force, Mindlin spring F_t = -8 G* sqrt(R d) s that never "
           "slides, rigid sphere, contact point at R - d/2 (scipy)")
PASSIVE = ("a passive tangential contact (spring, dashpot, Coulomb slider): the slip "
           "cannot leave faster than it came, abs(slip after) <= abs(slip before)")
#: the models whose springs are linear with k_t = 2/7 k_n and no dashpot when e = 1
LINEAR = ("hooke", "linear_spring_dashpot", "maw_linear_spring", "walton_braun")

#: tolerances: relative for the normal impact (time step T/steps), normalised for the rest
TOL_HERTZ = 5e-3
TOL_E = 1e-2
TOL_SLIDE = 2e-2
TOL_BALANCE = 2e-3  # plus the lever arm's share, see lever()
TOL_MOMENTUM = 1e-9


def params(model: str, e: float, mu: float, speed: float, estar: float,
           reff: float) -> dict[str, Any]:
    """The law's parameters for restitution ``e`` at the approach speed ``speed``.

    Linear springs (``linear_spring_dashpot``, ``walton_braun`` loading) get Hooke's
    k = 4/3 E* R*; ``maw_linear_spring`` its impact speed; ``hertz_brilliantov`` its
    restitution at ``speed`` (A = 0 when e = 1).
    """
    p: dict[str, Any] = {"friction": mu}
    if model == "hertz_brilliantov":
        if e >= 1.0:
            p["dissipation"] = 0.0
        else:
            p.update(restitution=e, reference_speed=speed)
        return p
    p["restitution"] = e
    if model in ("linear_spring_dashpot", "walton_braun"):
        p["stiffness"] = 4.0 / 3.0 * estar * reff
    elif model == "maw_linear_spring":
        p["impact_velocity"] = speed
    return p


def species(mat: tuple, model: str, e: float, mu: float, speed: float, reff: float,
            pair: bool, tag: str = "", density_factor: float = 1.0) -> Species:
    name, rho, young, nu = mat
    estar = effective_young(young, nu, young, nu) if pair else effective_young(young, nu)
    return Species(f"{name}{tag}", rho * density_factor, young, nu, model,
                   params(model, e, mu, speed, estar, reff))


def lever(meff: float, reff: float, estar: float, radius: float, speed: float) -> float:
    """Largest overlap over the radius: the contact force's lever arm lies between R - d
    and R, so rigid-body spin references hold to d_max/R. d_max is the larger of Hertz's
    and the Hooke spring's (k = 4/3 E* R*) at the approach speed."""
    hertz = hertz_impact(meff, reff, estar, speed).max_overlap
    hooke = speed * math.sqrt(meff / (4.0 / 3.0 * estar * reff))
    return max(hertz, hooke) / radius


def steps(quick: bool) -> int:
    return 100 if quick else 200


# ------------------------------------------------------------------ normal elastic impact


def peak(x: np.ndarray) -> float:
    """Largest sample, refined by the parabola through it and its neighbours."""
    k = int(np.argmax(x))
    if 0 < k < len(x) - 1:
        a, b, c = x[k - 1], x[k], x[k + 1]
        den = a - 2.0 * b + c
        if den < 0:
            return float(b - 0.125 * (c - a) ** 2 / den)
    return float(x[k])


def duration(force: np.ndarray, dt: float) -> float:
    """Time the force is non-zero: it starts at t = 0 (bodies touching), its end is
    extrapolated from the last two samples of F^(2/3) (F ~ d^(3/2) as Hertz's ends)."""
    on = np.nonzero(force > 0.0)[0]
    last = int(on[-1])
    t = dt * (last + 1)
    f1 = force[last - 1] ** (2.0 / 3.0)
    f2 = force[last] ** (2.0 / 3.0)
    return t + (dt * f2 / (f1 - f2) if f1 > f2 else 0.0)


def _normal_elastic(test: str, mats: Sequence[tuple], radius: float, speed: float,
                    pair: bool, quick: bool, models: Sequence[str]) -> list[Row]:
    rows = []
    for mat in mats:
        name, rho, young, nu = mat
        m = sphere_mass(radius, rho)
        meff, reff = (m / 2.0, radius / 2.0) if pair else (m, radius)
        estar = effective_young(young, nu, young, nu) if pair else effective_young(young, nu)
        ref = hertz_impact(meff, reff, estar, speed)
        for model in models:
            sp = species(mat, model, 1.0, 0.0, speed, reff, pair)
            imp = (Impact("pair", radius, speed / 2.0, radius2=radius, vn2=speed / 2.0)
                   if pair else Impact("wall", radius, speed))
            o = run_group([sp], [imp], steps_per_contact=2 * steps(quick), record=True)[0]
            t = f"{test} {name}"
            rows.append(compare(t, model, "largest overlap [m]", [(peak(o.overlap),
                                ref.max_overlap)], TOL_HERTZ, HERTZ))
            if model != "maw_linear_spring":  # a linear spring: Hertz's overlap only
                rows.append(compare(t, model, "largest force [N]",
                                    [(peak(o.force), ref.max_force)], TOL_HERTZ, HERTZ))
                rows.append(compare(t, model, "contact duration [s]",
                                    [(duration(o.force, o.dt), ref.duration)], TOL_HERTZ,
                                    HERTZ))
            rows.append(compare(t, model, "restitution", [(o.restitution, 1.0)], TOL_E,
                                "elastic: 1"))
    return rows


def co1(quick: bool, models: Sequence[str]) -> list[Row]:
    """Elastic normal impact of two identical spheres: R = 0.01 m, +-10 m/s."""
    return _normal_elastic("CO1", [GLASS, LIMESTONE], 0.010, 20.0, True, quick, models)


def co2(quick: bool, models: Sequence[str]) -> list[Row]:
    """Elastic normal impact of a sphere with a rigid plane: R = 0.1 m, 0.2 m/s."""
    return _normal_elastic("CO2", [AL_ALLOY_T2, MG_ALLOY], 0.10, 0.2, False, quick, models)


# ------------------------------------------------------------------ restitution


def co3(quick: bool, models: Sequence[str]) -> list[Row]:
    """Normal impact with a rigid plane at restitution 0.2 ... 1: R = 2.5 mm, 3.9 m/s."""
    radius, speed = 0.0025, 3.9
    es = (0.2, 0.6, 1.0) if quick else (0.2, 0.4, 0.6, 0.8, 1.0)
    rows = []
    for mat in (ALUMINA, CAST_IRON):
        for model in models:
            sps = [species(mat, model, e, 0.0, speed, radius, False, f" e={e}") for e in es]
            imps = [Impact("wall", radius, speed, species1=k) for k in range(len(es))]
            out = run_group(sps, imps, steps_per_contact=steps(quick))
            rows.append(compare(f"CO3 {mat[0]}", model, f"restitution e = {es[0]}..{es[-1]}",
                                [(o.restitution, e) for o, e in zip(out, es, strict=True)],
                                TOL_E, SET_E))
    return rows


# ------------------------------------------------------------------ oblique, sphere-plane


def _wall_oblique(test: str, mat: tuple, model: str, radius: float, e: float, mu: float,
                  speed: float, impacts: list[Impact], quick: bool) -> list[Row]:
    """Rows of a sweep of sphere-plane impacts: restitution (not for a speed-dependent
    one, Brilliantov's, when v_n varies), sliding regime, sticking regime (linear springs,
    e = 1), the spin-impulse balance."""
    sp = species(mat, model, e, mu, speed, radius, False)
    out = run_group([sp], impacts, steps_per_contact=steps(quick))
    m = sphere_mass(radius, sp.density)
    inertia = 0.4 * m * radius**2
    arm = lever(m, radius, effective_young(sp.young, sp.poisson), radius,
                max(i.vn1 for i in impacts))
    tol_spin = TOL_BALANCE + arm
    t = f"{test} {mat[0]}"
    rows = []
    if model != "hertz_brilliantov" or speed_constant(impacts):
        rows.append(compare(t, model, "restitution", [(o.restitution, e) for o in out],
                            TOL_E, SET_E))
    slide_t, slide_w, balance, stick, passive = [], [], [], [], []
    for imp, o in zip(impacts, out, strict=True):
        unit = mu * (1.0 + o.restitution) * imp.vn1
        slip0 = imp.vt1 - imp.w1 * radius
        ref = rigid_sliding(imp.vn1, slip0, o.restitution, mu, m, radius, inertia)
        if ref.margin >= 1.3:
            slide_t.append(((o.vt1 - imp.vt1) / unit, ref.dv1 / unit))
            slide_w.append(((o.surf1 + imp.w1 * radius) / unit, ref.dsurf1 / unit))
        balance.append(((o.surf1 + imp.w1 * radius) / unit, 2.5 * (o.vt1 - imp.vt1) / unit))
        if slip0 != 0.0:
            passive.append((abs((o.vt1 + o.surf1) / slip0), 1.0))
        if (e == 1.0 and model in LINEAR and slip0 != 0.0
                and abs(slip0) / (mu * imp.vn1) <= 3.4):
            stick.append(((o.vt1 + o.surf1) / slip0, -1.0))
    if stick:
        # the tangential spring's history converges at about first order in dt: 1.1 % at
        # 200 steps per contact, 0.22 % at 800 (steel, hooke); 3/steps passes
        rows.append(compare(t, model, "slip after / slip before, sticking", stick,
                            3.0 / steps(quick) + arm, STICK))
    if slide_t:
        rows.append(compare(t, model, "change of v_t / (mu (1+e) v_n), sliding", slide_t,
                            TOL_SLIDE, SLIDING, scale=1.0))
        rows.append(compare(t, model, "change of R w / (mu (1+e) v_n), sliding", slide_w,
                            tol_spin + TOL_SLIDE, SLIDING, scale=2.5))
    rows.append(compare(t, model, "spin-impulse balance, all impacts", balance, tol_spin,
                        BALANCE, scale=2.5))
    rows.append(_passive(t, model, passive, 3.0 / steps(quick) + arm))
    return rows


def _passive(test: str, model: str, points: list[tuple[float, float]],
             tolerance: float) -> Row:
    """abs(slip after / slip before) <= 1 (the discretisation's share: as the sticking
    row's)."""
    return compare(test, model, "abs(slip after / slip before) <= 1, all impacts", points,
                   tolerance, PASSIVE, scale=1.0, bound=True)


def speed_constant(impacts: Sequence[Impact]) -> bool:
    return len({round(i.vn1, 12) for i in impacts}) == 1


def co4(quick: bool, models: Sequence[str]) -> list[Row]:
    """Oblique sphere-plane impact at 3.9 m/s, incidence 5-85 degrees: R = 2.5 mm,
    mu = 0.092, e = 0.98 (alumina, aluminium alloy)."""
    radius, speed, mu, e = 0.0025, 3.9, 0.092, 0.98
    angles = (10, 30, 50, 70, 85) if quick else tuple(range(5, 90, 5))
    imps = [Impact("wall", radius, speed * math.cos(math.radians(a)),
                   vt1=speed * math.sin(math.radians(a))) for a in angles]
    rows = []
    for mat in (ALUMINA, AL_ALLOY):
        for model in models:
            rows += _wall_oblique("CO4", mat, model, radius, e, mu, speed, imps, quick)
    return rows


def co5(quick: bool, models: Sequence[str]) -> list[Row]:
    """Oblique sphere-plane impact at v_n = 5 m/s, v_t / (mu v_n) = 0.5 ... 30: R = 10 um,
    mu = 0.3, e = 1 (steel, polyethylene)."""
    radius, vn, mu, e = 1e-5, 5.0, 0.3, 1.0
    psis = (1.0, 4.0, 10.0, 20.0) if quick else (0.5, 1, 2, 3, 4, 6, 8, 10, 14, 20, 30)
    imps = [Impact("wall", radius, vn, vt1=p * mu * vn) for p in psis]
    rows = []
    for mat in (STEEL, POLYETHYLENE):
        for model in models:
            rows += _wall_oblique("CO5", mat, model, radius, e, mu, vn, imps, quick)
            if model in ("hertz_mindlin", "hertz_brilliantov"):
                rows.append(_no_slip("CO5", mat, model, radius, vn, quick))
    return rows


def _no_slip(test: str, mat: tuple, model: str, radius: float, vn: float,
             quick: bool) -> Row:
    """The Mindlin spring's no-slip limit (mu = 1e6): slip after / slip before against the
    ODE (``references.mindlin_no_slip``), at 1000 (quick) or 2000 steps per contact: the
    tangential spring's history converges at first order (steel: 37 % off at 20 steps per
    contact, 17 % at 50, 4.7 % at 200, 1.2 % at 800, 0.3 % at 3200); 15/steps passes."""
    name, rho, young, nu = mat
    n = 1000 if quick else 2000
    sp = species(mat, model, 1.0, 1e6, vn, radius, False)
    o = run_group([sp], [Impact("wall", radius, vn, vt1=0.01 * vn)], steps_per_contact=n)[0]
    m = sphere_mass(radius, rho)
    ref = mindlin_no_slip(m, radius, effective_young(young, nu), effective_shear(young, nu),
                          vn)
    return compare(f"{test} {name}", model, f"slip after / before, no-slip limit ({n} steps)",
                   [((o.vt1 + o.surf1) / (0.01 * vn), ref)], 15.0 / n, NO_SLIP)


def co6(quick: bool, models: Sequence[str]) -> list[Row]:
    """Sphere-plane impact at v_n = 0.2 m/s with spin 0.175 ... 21 rad/s: R = 0.1 m,
    mu = 0.4, e = 0.5 (aluminium alloy, nylon)."""
    radius, vn, mu, e = 0.1, 0.2, 0.4, 0.5
    spins = (0.5, 3.0, 10.0, 21.0) if quick else (0.175, 0.5, 1, 2, 3, 4, 5, 7, 10, 14, 21)
    imps = [Impact("wall", radius, vn, w1=w) for w in spins]
    rows = []
    for mat in (AL_ALLOY, NYLON):
        for model in models:
            rows += _wall_oblique("CO6", mat, model, radius, e, mu, vn, imps, quick)
    return rows


# ------------------------------------------------------------------ oblique, two spheres


def _pair_spin(test: str, mat: tuple, model: str, r1: float, r2: float, rho2: float,
               vn1: float, vn2: float, e: float, mu: float, spins: Sequence[float],
               quick: bool) -> list[Row]:
    m1, m2 = sphere_mass(r1, mat[1]), sphere_mass(r2, mat[1] * rho2)
    reff = r1 * r2 / (r1 + r2)
    same = rho2 == 1.0 and r1 == r2
    sps = [species(mat, model, e, mu, vn1 + vn2, reff, True)]
    if not same:
        sps.append(species(mat, model, e, mu, vn1 + vn2, reff, True, " (heavy)", rho2))
    w2 = 1.0 if same else 0.0  # identical spheres spin alike (opposite at the contact)
    imps = [Impact("pair", r1, vn1, w1=w, radius2=r2, vn2=vn2, w2=w2 * w,
                   species2=0 if same else 1) for w in spins]
    out = run_group(sps, imps, steps_per_contact=steps(quick))
    i1, i2 = 0.4 * m1 * r1**2, 0.4 * m2 * r2**2
    arm = lever(m1 * m2 / (m1 + m2), reff, effective_young(mat[2], mat[3], mat[2], mat[3]),
                r1, vn1 + vn2)
    t = f"{test} {mat[0]}"
    rows = [compare(t, model, "restitution", [(o.restitution, e) for o in out], TOL_E, SET_E)]
    slide_v, slide_w, mom, ang, passive = [], [], [], [], []
    for imp, o in zip(imps, out, strict=True):
        un = imp.vn1 + imp.vn2
        slip0 = (imp.vt1 + imp.w1 * r1) - (imp.vt2 - imp.w2 * r2)
        ref = rigid_sliding(un, slip0, o.restitution, mu, m1, r1, i1, m2, r2, i2)
        unit = mu * (1.0 + o.restitution) * un * m1 * m2 / (m1 + m2) / m1
        if ref.margin >= 1.3:
            slide_v.append(((o.vt1 - imp.vt1) / unit, ref.dv1 / unit))
            slide_w.append(((o.surf1 - imp.w1 * r1) / unit, ref.dsurf1 / unit))
        pscale = m1 * unit
        slip1 = (o.vt1 + o.surf1) - (o.vt2 + o.surf2)
        if slip0 != 0.0:
            passive.append((abs(slip1 / slip0), 1.0))
        mom.append(((o.momentum[1] - o.momentum[0]) / pscale, 0.0))
        ang.append(((o.angular[1] - o.angular[0]) / (pscale * (r1 + r2)), 0.0))
    if slide_v:
        rows.append(compare(t, model, "change of v_t1 / (mu (1+e) v_n m*/m1), sliding",
                            slide_v, TOL_SLIDE, SLIDING, scale=1.0))
        rows.append(compare(t, model, "change of R1 w1 / (mu (1+e) v_n m*/m1), sliding",
                            slide_w, TOL_SLIDE + arm, SLIDING, scale=2.5))
    rows.append(compare(t, model, "tangential momentum, all impacts", mom, TOL_MOMENTUM,
                        MOMENTUM, scale=1.0))
    rows.append(compare(t, model, "angular momentum, all impacts", ang, TOL_MOMENTUM,
                        MOMENTUM, scale=1.0))
    rows.append(_passive(t, model, passive, 3.0 / steps(quick) + arm))
    return rows


def co7(quick: bool, models: Sequence[str]) -> list[Row]:
    """Two identical spheres meeting at 0.2 m/s each, both spinning at w = 0.175 ... 22
    rad/s about the same axis (their surfaces slip at 2 w R): R = 0.1 m, mu = 0.4, e = 0.5
    (aluminium alloy, copper)."""
    spins = (0.5, 3.0, 10.0, 22.0) if quick else (0.175, 0.5, 1, 2, 3, 4, 5, 7, 9, 12, 22)
    rows = []
    for mat in (AL_ALLOY, COPPER):
        for model in models:
            rows += _pair_spin("CO7", mat, model, 0.1, 0.1, 1.0, 0.2, 0.2, 0.5, 0.4, spins,
                               quick)
    return rows


def co8(quick: bool, models: Sequence[str]) -> list[Row]:
    """A spinning sphere (R = 0.1 m, 0.2 m/s, w = 0.175 ... 22 rad/s) hits a resting one of
    five times its radius and 1000 times its density: mu = 0.4, e = 0.5 (aluminium alloy,
    nylon; the paper's case with a 1000 times stiffer shear modulus is not reproduced)."""
    spins = (0.5, 3.0, 10.0, 22.0) if quick else (0.175, 0.5, 1, 2, 3, 4, 5, 7, 9, 12, 22)
    rows = []
    for mat in (AL_ALLOY, NYLON):
        for model in models:
            rows += _pair_spin("CO8", mat, model, 0.1, 0.5, 1000.0, 0.2, 0.0, 0.5, 0.4,
                               spins, quick)
    return rows


for _n, _f, _m, _title in [
    ("co1", co1, ELASTIC_MODELS, "elastic normal impact of two identical spheres"),
    ("co2", co2, ELASTIC_MODELS, "elastic normal impact of a sphere with a rigid plane"),
    ("co3", co3, ALL_MODELS, "normal impact with a plane at different restitutions"),
    ("co4", co4, ALL_MODELS, "oblique impact with a plane, constant speed, angles"),
    ("co5", co5, ALL_MODELS, "oblique impact with a plane, constant v_n, tangential speeds"),
    ("co6", co6, ALL_MODELS, "impact with a plane, constant v_n, initial spins"),
    ("co7", co7, ALL_MODELS, "two identical spheres, constant v_n, initial spins"),
    ("co8", co8, ALL_MODELS, "sphere on a large heavy sphere, initial spins"),
]:
    register(Case(_n, _title, _m, _f))
