"""Materials: density and elastic constants shared by particles and boundaries."""

from __future__ import annotations

import math
from typing import Any

from .parameters import Parameter, declared_repr, validate


class Material:
    """A solid material.

    Parameters
    ----------
    name : str
        Label used in messages and output.
    density : float
        Mass density [kg/m3], > 0.
    young : float, optional
        Young's modulus E [Pa], > 0. Required by the Hertz-type impact models and by the
        Rayleigh time-step estimate; the linear spring models take a stiffness instead.
    poisson : float, optional
        Poisson ratio nu, in (-1, 0.5).

    Example
    -------
    >>> glass = Material("glass", density=2500, young=5e6, poisson=0.45)
    """

    parameters = {
        "density": Parameter(low=0.0, low_open=True, unit="kg/m3", doc="mass density"),
        "young": Parameter(default=None, low=0.0, low_open=True, unit="Pa",
                           doc="Young's modulus"),
        "poisson": Parameter(default=None, low=-1.0, high=0.5, low_open=True,
                             high_open=True, doc="Poisson ratio"),
    }

    def __init__(self, name: str, density: float | None = None, young: float | None = None,
                 poisson: float | None = None, **unknown: Any) -> None:
        # unknown keywords are taken so that a misspelt one is named in a ParameterError
        # with the allowed ones (not Python's TypeError); density is required there too
        v = validate(f"Material({name!r})", self.parameters,
                     {**unknown, "density": density, "young": young, "poisson": poisson})
        self.name = str(name)
        self.density = float(v["density"])
        self.young = None if v["young"] is None else float(v["young"])
        self.poisson = None if v["poisson"] is None else float(v["poisson"])

    @property
    def shear_modulus(self) -> float | None:
        """G = E / (2 (1 + nu)) [Pa], or None without elastic constants."""
        if self.young is None or self.poisson is None:
            return None
        return self.young / (2.0 * (1.0 + self.poisson))

    def rayleigh_time_step(self, radius: float) -> float | None:
        """Rayleigh wave time step [s] for a sphere of this material and ``radius``.

        dt_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766)  (Li, Xu & Thornton 2005).
        """
        g = self.shear_modulus
        if g is None:
            return None
        return math.pi * radius * math.sqrt(self.density / g) / (0.1631 * self.poisson + 0.8766)

    def __repr__(self) -> str:
        """``Material('glass', density=2500, young=5000000, poisson=0.45)`` (the elastic
        constants only where given)."""
        return declared_repr("Material", self.parameters,
                             {k: getattr(self, k, None) for k in self.parameters},
                             leading=[repr(getattr(self, "name", "?"))])


def effective_young(a: Material, b: Material) -> float:
    """E* = 1 / ((1 - nu_a^2)/E_a + (1 - nu_b^2)/E_b)."""
    return 1.0 / ((1 - a.poisson**2) / a.young + (1 - b.poisson**2) / b.young)


def effective_shear(a: Material, b: Material) -> float:
    """G* = 1 / (2 (2 - nu_a)(1 + nu_a)/E_a + 2 (2 - nu_b)(1 + nu_b)/E_b)  (Mindlin)."""
    return 1.0 / (2 * (2 - a.poisson) * (1 + a.poisson) / a.young
                  + 2 * (2 - b.poisson) * (1 + b.poisson) / b.young)
