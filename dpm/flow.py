"""Inlets and outlets: particles entering and leaving a running simulation.

Both act at events every ``every`` seconds of simulated time (the run's kernel calls end
at these events). An :class:`Outlet` removes the bodies whose centre lies inside (or
outside) its region and records id, time, mass, residence time (time since insertion),
position and velocity; with output on, the records go to ``/removed`` of the HDF5 file.
An :class:`Inlet` inserts bodies drawn from a size distribution and shape mix at a number
or mass rate into its region, at random places where they overlap neither other bodies
(bounding spheres) nor boundaries; what it cannot place is carried to the next event and
counted in ``missed`` when the inlet stops.

Plugins see both through the hooks ``dpm_on_particles_inserted`` and
``dpm_on_particles_removed``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import ParameterError
from .material import Material
from .regions import Region

RECORD_FIELDS = ("id", "time", "mass", "residence_time", "position", "velocity")


class Outlet:
    """Removes bodies whose centre is ``remove="inside"`` (default) or ``"outside"`` the
    ``region``, checked every ``every`` seconds."""

    def __init__(self, region: Region, remove: str = "inside", every: float = 1e-3,
                 name: str = "") -> None:
        if not isinstance(region, Region):
            raise ParameterError(f"Outlet(): region={region!r} must be a dpm region "
                                 "(dpm.BoxRegion, dpm.CylinderRegion)")
        if remove not in ("inside", "outside"):
            raise ParameterError(f"Outlet(): remove={remove!r}; allowed: inside, outside")
        if not every > 0:
            raise ParameterError(f"Outlet(): every={every!r} must be > 0 s")
        self.region = region
        self.remove = remove
        self.every = float(every)
        self.name = name
        self._records: dict[str, list[np.ndarray]] = {k: [] for k in RECORD_FIELDS}

    def select(self, position: np.ndarray) -> np.ndarray:
        inside = self.region.contains(position)
        return inside if self.remove == "inside" else ~inside

    def record(self, records: Mapping[str, np.ndarray]) -> None:
        for k in RECORD_FIELDS:
            self._records[k].append(np.asarray(records[k]))

    @property
    def records(self) -> dict[str, np.ndarray]:
        """All removals so far: id, time, mass, residence_time (n,), position, velocity
        (n, 3)."""
        out = {}
        for k in RECORD_FIELDS:
            parts = self._records[k]
            width = (3,) if k in ("position", "velocity") else ()
            out[k] = np.concatenate(parts) if parts else np.zeros((0, *width))
        return out

    @property
    def removed_mass(self) -> float:
        return float(sum(float(np.sum(m)) for m in self._records["mass"]))

    @property
    def count(self) -> int:
        return int(sum(len(m) for m in self._records["mass"]))


class Inlet:
    """Inserts bodies of ``material`` into ``region`` at ``rate`` bodies/s or
    ``mass_rate`` kg/s from ``start`` to ``stop`` [s], every ``every`` seconds.

    ``shapes`` is the mix: a list of dicts ``{"shape": name, "fraction": f, **params}``
    (number fractions, normalised); a parameter given as a pair ``(low, high)`` is drawn
    uniformly per body (e.g. ``"radius": (4e-3, 6e-3)``). Without ``shapes``, ``shape``
    and the remaining keyword arguments give a single kind. New bodies start with
    ``velocity`` and random orientation (``random_orientation=True``, the default).
    ``seed`` makes the insertion reproducible.
    """

    def __init__(self, region: Region, material: Material, rate: float | None = None,
                 mass_rate: float | None = None, shapes: Sequence[Mapping] | None = None,
                 shape: str = "sphere", velocity: Sequence[float] = (0.0, 0.0, 0.0),
                 start: float = 0.0, stop: float = math.inf, every: float = 1e-3,
                 seed: int = 0, random_orientation: bool = True, max_attempts: int = 30,
                 **shape_params: Any) -> None:
        call = "Inlet()"
        if not isinstance(region, Region):
            raise ParameterError(f"{call}: region={region!r} must be a dpm region")
        if not isinstance(material, Material):
            raise ParameterError(f"{call}: material={material!r} must be a dpm.Material")
        if (rate is None) == (mass_rate is None):
            raise ParameterError(f"{call}: give exactly one of rate (1/s) or mass_rate (kg/s)")
        value = rate if rate is not None else mass_rate
        if not value > 0:
            raise ParameterError(f"{call}: {'rate' if rate is not None else 'mass_rate'}="
                                 f"{value!r} must be > 0")
        if not every > 0 or not stop > start:
            raise ParameterError(f"{call}: every={every!r} must be > 0 and stop={stop!r} "
                                 f"after start={start!r}")
        if shapes is None:
            shapes = [{"shape": shape, "fraction": 1.0, **shape_params}]
        elif shape_params:
            raise ParameterError(f"{call}: give shape parameters inside shapes=[...] "
                                 f"(got also {sorted(shape_params)})")
        fr = np.array([float(s.get("fraction", 1.0)) for s in shapes])
        if len(shapes) == 0 or np.any(fr < 0) or fr.sum() <= 0:
            raise ParameterError(f"{call}: shapes={shapes!r} needs fractions >= 0 with a "
                                 "positive sum")
        self.shapes = [dict(s) for s in shapes]
        self.fractions = fr / fr.sum()
        self.region = region
        self.material = material
        self.rate = rate
        self.mass_rate = mass_rate
        self.velocity = np.asarray(velocity, float).reshape(3)
        self.start = float(start)
        self.stop = float(stop)
        self.every = float(every)
        self.random_orientation = random_orientation
        self.max_attempts = int(max_attempts)
        self.rng = np.random.default_rng(seed)
        self._due = 0.0  # bodies (or kg) owed
        self._last = None
        self.inserted = 0
        self.inserted_mass = 0.0
        self.ids: list[np.ndarray] = []

    def owed(self, t: float) -> float:
        """Add what is due up to time t; return the bodies (or kg) owed."""
        t0 = self.start if self._last is None else max(self._last, self.start)
        t1 = min(t, self.stop)
        if t1 > t0:
            self._due += (self.rate or self.mass_rate) * (t1 - t0)
        self._last = max(t, self._last or t)
        return self._due

    def settle(self, owed: float) -> None:
        """What stays owed after an insertion event (bodies, or kg for ``mass_rate``)."""
        self._due = float(owed)

    def draw(self) -> tuple[str, dict[str, float]]:
        """One body's shape name and parameters."""
        k = int(self.rng.choice(len(self.shapes), p=self.fractions))
        spec = self.shapes[k]
        params = {}
        for key, v in spec.items():
            if key in ("shape", "fraction"):
                continue
            if isinstance(v, tuple | list) and len(v) == 2 and not isinstance(v[0], str):
                lo, hi = float(v[0]), float(v[1])
                params[key] = lo + (hi - lo) * float(self.rng.random())
            else:
                params[key] = v
        return spec.get("shape", "sphere"), params


def random_quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform random unit quaternions (Shoemake 1992)."""
    u1, u2, u3 = rng.random((3, n))
    a, b = np.sqrt(1 - u1), np.sqrt(u1)
    return np.stack([a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2),
                     b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)], axis=1)
