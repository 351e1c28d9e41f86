"""A contact law's design speed against the impact speeds a scene reaches.

Some laws size their stiffness for one impact speed V (``impact_velocity`` of
``maw_linear_spring``, LIGGGHTS' ``characteristicVelocity``): the spring stores at the
largest compression the energy of a Hertz contact hit at V, so a head-on impact at V
reaches Hertz's largest overlap d_V = V sqrt(m*/k_n) (DPM thesis §2.6.2, eq. 2.29). The
spring is linear, so an impact at speed v reaches (undamped) d = v sqrt(m*/k_n) = d_V v / V:
an impact twice as fast as the design speed overlaps twice as far. A scene whose bodies
fall further than V allows, such as LIGGGHTS' meshGran tutorial (a 1.2 m deep container
under a chute, V = 2 m/s, falls at 4-5 m/s and head-on meetings of a falling and a
rebounding sphere at 6-7 m/s), reaches overlaps of half the radius, where dpm's guard
(``max_overlap``) stops the run.

:func:`design_speed_warnings` says so before the first step; :func:`overlap_hint` adds the
speed an overlap corresponds to when the guard stops a run.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..timestep import smallest_pair

#: a design speed below this fraction of the scene's fall speed gives a warning
WARN_RATIO = 1.2
#: points sampled from each inlet region for its highest point
_SAMPLES = 256


def _design_speed(law: Any) -> float | None:
    """The law's explicit design speed [m/s] (None: none given, or a law without a normal
    part whose stiffness could be asked)."""
    v = law.params.get("impact_velocity")
    return None if v is None or law.normal is None else float(v)


def _stiffness(law: Any, a: Any, b: Any, meff: float, reff: float, v: float) -> float:
    """k_n [N/m] of the law's normal part for m* = meff, R* = reff at design speed v."""
    from .base import PairContext

    return float(law.normal.stiffness(law, a, b, PairContext(v, meff, reff)))


def _reduced(a: float, b: float) -> float:
    """a b / (a + b): a reduced mass or radius (b infinite: a)."""
    return a if math.isinf(b) else a * b / (a + b)


def fall_height(sim: Any) -> float:
    """Height [m] along gravity from the highest place a body starts (bodies present, inlet
    regions) to the lowest place a body can reach that the scene bounds (bodies present,
    triangle-mesh boundaries' vertices); 0 without gravity."""
    g = np.asarray(sim.gravity, float)
    gn = float(np.linalg.norm(g))
    if gn == 0.0:
        return 0.0
    down = g / gn
    starts, ends = [], []
    if len(sim.bodies):
        s = sim.bodies.position @ down
        starts.append(float(s.min()))
        ends.append(float(s.max()))
    rng = np.random.default_rng(0)
    for inlet in sim.inlets:
        pts = np.asarray(inlet.region.sample(rng, _SAMPLES, np.zeros(_SAMPLES)), float)
        starts.append(float((pts @ down).min()))
    from ..boundaries.mesh import Mesh

    for bd in sim.boundaries:
        if isinstance(bd, Mesh) and len(bd.vertices):  # (world vertices)
            ends.append(float((bd.vertices @ down).max()))
    if not starts or not ends:
        return 0.0
    return max(0.0, max(ends) - min(starts))


def design_speed_warnings(sim: Any) -> list[str]:
    """Sentences, one per law whose explicit ``impact_velocity`` lies below the speed of a
    fall over the scene's height (:func:`fall_height`), with the overlap that fall gives."""
    h = fall_height(sim)
    g = float(np.linalg.norm(sim.gravity))
    if h <= 0.0 or g == 0.0 or not len(sim.bodies):
        return []
    v_fall = math.sqrt(2.0 * g * h)
    out = []
    present = sorted(set(int(m) for m in sim.bodies.material))
    for (ia, ib), law in sorted(sim._contacts.items()):
        v = _design_speed(law)
        if v is None or ia not in present or v_fall <= WARN_RATIO * v:
            continue
        a, b = sim.materials[ia], sim.materials[ib]
        meff, reff = smallest_pair(sim, ia, ib)  # (a material of walls only: infinite)
        rmin = float(sim.elements.radius[sim.elements.material == ia].min())
        kn = _stiffness(law, a, b, meff, reff, v)
        d = v_fall * math.sqrt(meff / kn)
        out.append(
            f"{law.name} ({a.name}-{b.name}): impact_velocity={v:g} m/s is below the speed of "
            f"a fall over the scene's height ({h:.3g} m: {v_fall:.3g} m/s). The spring is "
            f"sized for impacts at {v:g} m/s; an impact at {v_fall:.3g} m/s overlaps "
            f"{v_fall / v:.2g} times as far ({d / rmin:.2g} of the smallest radius, "
            "undamped), and a falling body meeting a rebounding one more. Give "
            "impact_velocity the largest impact speed of the scene, or expect runs "
            "stopped by max_overlap="
            f"{sim.max_overlap:g}.")
    return out


def overlap_hint(sim: Any, el: int, overlap: float) -> str:
    """For the guard's message: the approach speed that overlap ``overlap`` (a fraction of
    the radius of element ``el``) corresponds to, where element ``el``'s material has a
    law with a design speed; '' otherwise."""
    e, b = sim.elements, sim.bodies
    if not 0 <= el < len(e):
        return ""
    ia = int(e.material[el])
    r = float(e.radius[el])
    k = int(e.owner[el])
    parts = []
    for (ma, mb), law in sorted(sim._contacts.items()):
        v = _design_speed(law)
        if v is None or ma != ia:
            continue
        # (against the smallest body of the partner material; a wall material: infinite)
        masses, radii = b.mass[b.material == mb], e.radius[e.material == mb]
        meff = _reduced(float(b.mass[k]), float(masses.min()) if len(masses) else math.inf)
        reff = _reduced(r, float(radii.min()) if len(radii) else math.inf)
        kn = _stiffness(law, sim.materials[ma], sim.materials[mb], meff, reff, v)
        speed = overlap * r / math.sqrt(meff / kn)
        if speed > WARN_RATIO * v:
            parts.append(f"{sim.materials[ma].name}-{sim.materials[mb].name}: an overlap of "
                         f"{overlap:.3g} of the radius needs an approach speed of about "
                         f"{speed:.3g} m/s, {speed / v:.2g} times the law's "
                         f"impact_velocity={v:g} m/s")
    if not parts:
        return ""
    return ("; " + "; ".join(parts) + " (the spring is sized for that speed: raise "
            "impact_velocity to the scene's largest impact speed, or max_overlap if "
            "overlaps this large are acceptable)")
