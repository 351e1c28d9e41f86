"""Critical time steps of a scene: Rayleigh wave step and shortest contact duration."""

from __future__ import annotations

from dataclasses import dataclass

#: fewer steps per contact than this is refused (explicit schemes go unstable near 2/omega)
MIN_STEPS_PER_CONTACT = 5.0
#: fewer steps per contact than this gives a warning (errors of several per cent in the
#: restitution and the peak force)
WARN_STEPS_PER_CONTACT = 10.0
#: fraction of the Rayleigh step above which a warning is given / the run is refused
WARN_RAYLEIGH_FRACTION = 0.3
MAX_RAYLEIGH_FRACTION = 1.0
#: dt="auto": steps per shortest contact and fraction of the Rayleigh step
AUTO_STEPS_PER_CONTACT = 20.0
AUTO_RAYLEIGH_FRACTION = 0.2


@dataclass
class TimeStepReport:
    """The scene's time-step limits.

    dt: the step in use; rayleigh: smallest Rayleigh step over Hertz-type materials (or
    None); contact_time: shortest head-on contact duration over material pairs at
    ``impact_speed``; ``pair``: the material pair that gives it.
    """

    dt: float
    rayleigh: float | None
    contact_time: float | None
    impact_speed: float
    pair: str = ""
    #: fewest steps per contact the integrator in use accepts
    min_steps: float = MIN_STEPS_PER_CONTACT

    def auto(self) -> float:
        """The step ``Simulation(dt="auto")`` takes: the smaller of 1/20 of the shortest
        contact and 0.2 of the Rayleigh step (1 ms if the scene has neither)."""
        cands = []
        if self.contact_time is not None:
            cands.append(self.contact_time / AUTO_STEPS_PER_CONTACT)
        if self.rayleigh is not None:
            cands.append(AUTO_RAYLEIGH_FRACTION * self.rayleigh)
        return min(cands) if cands else 1e-3

    @property
    def steps_per_contact(self) -> float | None:
        return None if self.contact_time is None else self.contact_time / self.dt

    def problems(self) -> tuple[list[str], list[str]]:
        """(refusals, warnings) as sentences with the numbers."""
        refuse, warn = [], []
        if self.rayleigh is not None:
            f = self.dt / self.rayleigh
            msg = (f"dt={self.dt:g} s is {f:.2f} of the Rayleigh time step {self.rayleigh:.3g} s")
            if f > MAX_RAYLEIGH_FRACTION:
                refuse.append(msg + f" (allowed: <= {MAX_RAYLEIGH_FRACTION:g})")
            elif f > WARN_RAYLEIGH_FRACTION:
                warn.append(msg + f" (advised: <= {WARN_RAYLEIGH_FRACTION:g})")
        spc = self.steps_per_contact
        if spc is not None:
            msg = (f"dt={self.dt:g} s resolves the shortest contact ({self.pair}, "
                   f"{self.contact_time:.3g} s at {self.impact_speed:.3g} m/s) with "
                   f"{spc:.3g} steps")
            if spc < self.min_steps:
                refuse.append(msg + f" (allowed: >= {self.min_steps:g}; "
                              f"critical dt = {self.contact_time / self.min_steps:.3g} s)")
            elif spc < max(WARN_STEPS_PER_CONTACT, self.min_steps):
                warn.append(msg + f" (advised: >= {WARN_STEPS_PER_CONTACT:g})")
        return refuse, warn


def scene_report(sim) -> TimeStepReport:
    """Rayleigh step and shortest contact duration of the scene of ``sim``: over the
    material pairs with a contact law (particle-particle and particle-wall), the smallest
    elements and bodies of each material, at the characteristic speed (largest initial
    speed or the free-fall speed over the scene's height)."""
    import math

    import numpy as np

    b = sim.bodies
    er = sim.elements.radius
    speed = float(np.max(np.linalg.norm(b.velocity, axis=1), initial=0.0))
    g = float(np.linalg.norm(sim.gravity))
    if g > 0 and len(b):
        h = float(np.ptp(b.position @ (sim.gravity / g))) + 2 * float(b.radius.max())
        speed = max(speed, math.sqrt(2 * g * h))
    speed = max(speed, 1e-3)
    rayleigh = None
    tc, pair = None, ""
    present = sorted(set(int(m) for m in b.material))
    wall_mats = sorted({sim._material_index(x.material, "") for x in sim.boundaries})
    for ia in present:
        rmin_a = float(er[sim.elements.material == ia].min())
        mmin_a = float(b.mass[b.material == ia].min())
        for ib in sorted(set(present) | set(wall_mats)):
            law = sim._contacts.get((ia, ib))
            if law is None:
                continue
            ma, mb = sim.materials[ia], sim.materials[ib]
            if ib in present:
                rmin_b = float(er[sim.elements.material == ib].min())
                mmin_b = float(b.mass[b.material == ib].min())
                meff = mmin_a * mmin_b / (mmin_a + mmin_b)
                reff = rmin_a * rmin_b / (rmin_a + rmin_b)
                t = law.contact_time(ma, mb, meff, reff, speed)
                if tc is None or t < tc:
                    tc, pair = t, f"{ma.name}-{mb.name}"
            if ib in wall_mats:
                t = law.contact_time(ma, mb, mmin_a, rmin_a, speed)
                if tc is None or t < tc:
                    tc, pair = t, f"{ma.name}-wall {mb.name}"
            if law.needs_elastic_constants:
                r = ma.rayleigh_time_step(rmin_a)
                if r is not None and (rayleigh is None or r < rayleigh):
                    rayleigh = r
    return TimeStepReport(sim.dt, rayleigh, tc, speed, pair,
                          sim.integrator.min_steps_per_contact)


def smallest_pair(sim, ia: int, ib: int) -> tuple[float, float]:
    """(m*, R*) of the smallest bodies of materials ia and ib (a wall material alone
    counts as an infinitely large, heavy body)."""
    import math

    import numpy as np

    b, e = sim.bodies, sim.elements

    def small(k: int) -> tuple[float, float]:
        sel = b.material == k
        if not np.any(sel):
            return math.inf, math.inf
        return float(b.mass[sel].min()), float(e.radius[e.material == k].min())

    (ma, ra), (mb, rb) = small(ia), small(ib)
    meff = ma if math.isinf(mb) else mb if math.isinf(ma) else ma * mb / (ma + mb)
    reff = ra if math.isinf(rb) else rb if math.isinf(ra) else ra * rb / (ra + rb)
    return meff, reff
