"""Hertz-Mindlin impact model."""

from __future__ import annotations

from ..material import Material, effective_shear, effective_young
from .base import ImpactModel, hertz_beta, hertz_contact_time


class HertzMindlin(ImpactModel):
    """Hertz normal force, Mindlin no-slip tangential spring with history, Coulomb limit.

        F_n = max(0, 4/3 E* sqrt(R* d) d + 2 sqrt(5/6) beta sqrt(2 E* sqrt(R* d) m*) d')
        k_t = 8 G* sqrt(R* d),   c_t = 2 sqrt(5/6) beta sqrt(k_t m*)
        beta = -ln e / sqrt(ln^2 e + pi^2)

    E* = 1/((1-nu1^2)/E1 + (1-nu2^2)/E2), G* = 1/(2(2-nu1)(1+nu1)/E1 + 2(2-nu2)(1+nu2)/E2),
    R* = r1 r2/(r1 + r2) (r for a wall), m* likewise.
    Sources: Hertz (1882), Mindlin (1949), Tsuji, Tanaka & Ishida (1992) for the damping,
    with the LIGGGHTS/EDEM factors (Antypov & Elliott 2011 discuss their restitution).
    Elastic contact time 2.868 (m*^2/(R* E*^2 v))^(1/5).
    Requires young and poisson on both materials.
    """

    name = "hertz_mindlin"
    kernel = ("dpm.kernels.law_hertz_mindlin", "hertz_mindlin")
    needs_elastic_constants = True

    def pair_row(self, a: Material, b: Material, context):
        return self._row(effective_young(a, b), effective_shear(a, b),
                         hertz_beta(float(self.params["restitution"])), self.params["friction"])

    def contact_time(self, a, b, meff, reff, speed):
        return hertz_contact_time(meff, reff, effective_young(a, b), speed)
