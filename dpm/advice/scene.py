"""What the advisor reads of a scene: bodies, elements, clustered shapes, the material pairs
that can meet with their laws, contact durations and overlaps at the impact speed, and
the time-step limits (:mod:`dpm.timestep`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..material import effective_shear, effective_young
from ..timestep import smallest_pair

#: the built-in models whose parameters a Hertz-Mindlin contact's translate to
#: (restitution, friction, rolling resistance); each with what it keeps of the contact
HERTZ_ALTERNATIVES = ("maw_linear_spring", "hooke")
#: integrators that are not candidates: unstable on undamped contacts (taylor), damping
#: every contact numerically (backward_euler): docs/integrators.md
NOT_CANDIDATES = ("taylor", "backward_euler")
IMPLICIT = ("backward_euler", "newmark_beta", "numerov")


@dataclass
class Pair:
    """One material pair that can meet (two bodies' materials, or a body's and a
    boundary's): its law, m* and R* of its smallest bodies, and the Hertz overlap."""

    label: str
    a: Any
    b: Any
    law: Any
    meff: float
    reff: float
    wall: bool
    #: radius of the smaller body [m]: lengths are measured against it
    radius: float = float("nan")

    @property
    def model(self) -> str:
        return self.law.name

    @property
    def restitution(self) -> float:
        e = self.law.params.get("restitution")
        if e is None:  # hertz_brilliantov given its dissipation: e at the scene's speed
            return float("nan")
        return float(e)

    def hertz_overlap(self, speed: float) -> float:
        """Largest overlap of an elastic Hertz collision at ``speed`` [m]:
        d = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) (Hertz 1882)."""
        if self.a.young is None or self.b.young is None:
            return float("nan")
        es = effective_young(self.a, self.b)
        return (15 * self.meff * speed**2 / (16 * es * math.sqrt(self.reff))) ** 0.4


@dataclass
class ShapeFacts:
    """A clustered shape of the scene: its name, bodies, elements per body, and its
    smallest element over its equal-volume radius."""

    name: str
    bodies: int
    count: float
    r_min_over_r_eq: float


@dataclass
class SceneFacts:
    """The scene as the advisor sees it."""

    bodies: int
    elements: int
    spheres_only: bool
    r_min: float
    impact_speed: float
    rayleigh: float | None
    integrator: str
    dt: float
    skin: float | None
    pairs: list[Pair]
    shapes: list[ShapeFacts] = field(default_factory=list)
    implicit_ok: bool = False
    why_not_implicit: str = ""

    def contact_time(self, pair: Pair, law: Any = None) -> float:
        """Duration of a head-on collision of ``pair`` (its own law, or ``law`` with its
        parameters) at the impact speed [s]."""
        law = pair.law if law is None else law
        return float(law.contact_time(pair.a, pair.b, pair.meff, pair.reff,
                                      self.impact_speed))


def alternative_law(pair: Pair, model: str, speed: float) -> Any:
    """``pair``'s Hertz-Mindlin law written as ``model`` (the same restitution, friction
    and rolling resistance; the Maw spring's impact velocity the scene's)."""
    from ..plugins import registry

    p = {k: v for k, v in pair.law.params.items()
         if k in ("restitution", "friction", "rolling_friction", "rolling_model",
                  "rolling_damping")}
    if model == "maw_linear_spring":
        p["impact_velocity"] = speed
    return registry().lookup("impact_model", model)(**p)


def tangential_ratio(pair: Pair, model: str) -> float:
    """k_t / k_n of ``model`` on ``pair``: Mindlin 8 G* a / (2 E* a) = 4 G*/E*
    (Hertz-Mindlin's tangent stiffness), the linear laws' kappa (2/7 by default)."""
    if model in ("hertz_mindlin", "hertz_brilliantov", "linear_cohesion"):
        return 4 * effective_shear(pair.a, pair.b) / effective_young(pair.a, pair.b)
    return float(pair.law.params.get("tangential_stiffness_ratio", 2 / 7)
                 if pair.law.name == model else 2 / 7)


def scene_facts(sim: Any, impact_speed: float | None = None) -> SceneFacts:
    """Read ``sim`` (bodies added, contacts set; it need not have run)."""
    from ..errors import ParameterError
    from ..timestep import scene_report

    b, e = sim.bodies, sim.elements
    if len(b) == 0:
        raise ParameterError("dpm.advise(): the scene has no bodies (add particles first; "
                             "inlets that fill it later are not read)")
    report = scene_report(sim)
    speed = float(impact_speed) if impact_speed is not None else float(report.impact_speed)
    present = sorted(set(int(m) for m in b.material))
    wall_mats = sorted({sim._material_index(x.material, "") for x in sim.boundaries})
    pairs: list[Pair] = []
    seen = set()
    for ia in present:
        for ib in sorted(set(present) | set(wall_mats)):
            law = sim._contacts.get((ia, ib))
            if law is None:
                continue
            ma, mb = sim.materials[ia], sim.materials[ib]
            if ib in present and (ib, ia) not in seen:
                meff, reff = smallest_pair(sim, ia, ib)
                r = min(float(e.radius[e.material == ia].min()),
                        float(e.radius[e.material == ib].min()))
                pairs.append(Pair(f"{ma.name}-{mb.name}", ma, mb, law, meff, reff, False, r))
                seen.add((ia, ib))
            if ib in wall_mats:
                sel = b.material == ia
                m = float(b.mass[sel].min())
                r = float(e.radius[e.material == ia].min())
                pairs.append(Pair(f"{ma.name}-wall {mb.name}", ma, mb, law, m, r, True, r))
    if not pairs:
        raise ParameterError("dpm.advise(): no material pair of the scene has a contact law "
                             "(sim.contact)")
    counts = np.diff(b.element_start)
    shapes = []
    for k, name in enumerate(sim.shape_names):
        sel = b.shape == k
        if not np.any(sel) or name == "sphere":
            continue
        if np.all(counts[sel] == 1):
            continue
        vol = b.mass[sel] / np.array([sim.materials[int(m)].density for m in b.material[sel]])
        r_eq = float(np.mean((3 * vol / (4 * math.pi)) ** (1 / 3)))
        own = np.repeat(sel, counts)
        shapes.append(ShapeFacts(name, int(np.sum(sel)), float(np.mean(counts[sel])),
                                 float(e.radius[own].min()) / r_eq))
    kinds = {getattr(bd, "name", "") for bd in sim.boundaries}
    why = []
    if shapes:
        why.append("clustered bodies")
    if kinds - {"plane", "box"}:
        why.append("boundaries other than planes and boxes (" + ", ".join(
            sorted(kinds - {"plane", "box"})) + ")")
    if any(bd.motion is not None for bd in sim.boundaries):
        why.append("moving boundaries")
    if sim.inlets or sim.outlets:
        why.append("inlets or outlets")
    if np.any(sim.period[3:] > 0):
        why.append("periodic faces")
    return SceneFacts(
        bodies=len(b), elements=len(e), spheres_only=not shapes,
        r_min=float(e.radius.min()), impact_speed=speed, rayleigh=report.rayleigh,
        integrator=sim.integrator.name, dt=float(sim.dt) if sim.dt == sim.dt else math.nan,
        skin=sim.skin, pairs=pairs, shapes=shapes, implicit_ok=not why,
        why_not_implicit=", ".join(why))
