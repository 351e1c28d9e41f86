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
from .parameters import Parameter, numeric_array, validate
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
        validate("Outlet()", {"every": Parameter(low=0.0, low_open=True, unit="s")},
                 {"every": every})
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

    parameters = {
        "rate": Parameter(default=None, low=0.0, low_open=True, unit="1/s"),
        "mass_rate": Parameter(default=None, low=0.0, low_open=True, unit="kg/s"),
        "shape": Parameter(default="sphere", kind="str"),
        "velocity": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m/s"),
        "start": Parameter(default=0.0, unit="s"),
        # inf: the inlet never stops
        "stop": Parameter(default=math.inf, unit="s", allow_inf=True),
        "every": Parameter(default=1e-3, low=0.0, low_open=True, unit="s"),
        "seed": Parameter(default=0, low=0, kind="int"),
        "random_orientation": Parameter(default=True, kind="bool"),
        "max_attempts": Parameter(default=30, low=1, kind="int"),
    }

    def __init__(self, region: Region, material: Material, rate: float | None = None,
                 mass_rate: float | None = None, shapes: Sequence[Mapping] | None = None,
                 shape: str = "sphere", velocity: Sequence[float] = (0.0, 0.0, 0.0),
                 start: float = 0.0, stop: float = math.inf, every: float = 1e-3,
                 seed: int = 0, random_orientation: bool = True, max_attempts: int = 30,
                 **shape_params: Any) -> None:
        call = "Inlet()"
        if not isinstance(region, Region):
            raise ParameterError(f"{call}: region={region!r} must be a dpm region "
                                 "(dpm.BoxRegion, dpm.CylinderRegion)")
        if not isinstance(material, Material):
            raise ParameterError(f"{call}: material={material!r} must be a dpm.Material")
        validate(call, self.parameters, dict(
            rate=rate, mass_rate=mass_rate, shape=shape, velocity=velocity, start=start,
            stop=stop, every=every, seed=seed, random_orientation=random_orientation,
            max_attempts=max_attempts))
        if (rate is None) == (mass_rate is None):
            raise ParameterError(f"{call}: give exactly one of rate (1/s) or mass_rate (kg/s)"
                                 f" (got rate={rate!r}, mass_rate={mass_rate!r})")
        if not stop > start:
            raise ParameterError(f"{call}: stop={stop!r} must be after start={start!r} [s]")
        if shapes is None:
            shapes = [{"shape": shape, "fraction": 1.0, **shape_params}]
        elif shape_params:
            raise ParameterError(f"{call}: give shape parameters inside shapes=[...] "
                                 f"(got also {sorted(shape_params)})")
        elif (isinstance(shapes, str | Mapping) or not isinstance(shapes, Sequence)
              or not all(isinstance(sp, Mapping) for sp in shapes)):
            raise ParameterError(f"{call}: shapes={shapes!r} must be a list of dicts "
                                 '{"shape": name, "fraction": f, **parameters}')
        fraction = Parameter(default=1.0, low=0.0)
        problems = [f"{call}: shapes[{k}] {m}" for k, sp in enumerate(shapes)
                    for m in fraction.problems("fraction", sp.get("fraction", 1.0))]
        if problems:
            raise ParameterError("\n".join(problems))
        fr = np.array([float(sp.get("fraction", 1.0)) for sp in shapes])
        if len(shapes) == 0 or fr.sum() <= 0:
            raise ParameterError(f"{call}: shapes={shapes!r} needs fractions >= 0 with a "
                                 "positive sum")
        #: per shape of the mix: (class, parameters at the low end, at the high end)
        if shape_params:  # a misspelt inlet argument lands among the shape's parameters
            from .plugins import registry

            cls = registry().lookup("shape", shape, call)
            unknown = sorted(set(shape_params) - set(getattr(cls, "parameters", {})))
            if unknown:
                raise ParameterError(
                    f"{call}: unknown parameter(s) "
                    f"{', '.join(f'{k}={shape_params[k]!r}' for k in unknown)}; allowed: "
                    f"{', '.join(['shapes', *sorted(self.parameters)])} and the "
                    f"{shape!r} shape's {', '.join(sorted(cls.parameters)) or 'none'}")
        self.resolved = [resolve_shape(call, k, sp) for k, sp in enumerate(shapes)]
        self._smallest: float | None = None
        self.shapes = [dict(s) for s in shapes]
        self.fractions = fr / fr.sum()
        self.region = region
        self.material = material
        self.rate = rate
        self.mass_rate = mass_rate
        self.velocity = np.asarray(velocity, float).reshape(3)
        self.seed = int(seed)
        self.start = float(start)
        self.stop = float(stop)
        self.every = float(every)
        self.random_orientation = random_orientation
        self.max_attempts = int(max_attempts)
        self.rng = np.random.default_rng(seed)
        self.inserted = 0
        self.inserted_mass = 0.0
        self.ids: list[np.ndarray] = []
        r = self.smallest_radius()
        if not region.holds(r):
            raise ParameterError(f"{call}: region={region!r} is too small for the smallest "
                                 f"particle it inserts (bounding radius {r:g} m)")

    def smallest_radius(self) -> float:
        """The smallest bounding radius [m] of what this inlet inserts: the least over the
        mix's shapes (fraction > 0) built at the low and at the high end of their
        ranges."""
        if self._smallest is None:
            radii = [float(cls(call="Inlet()", **params).build(1, self.material.density)
                           .bounding_radius[0])
                     for (cls, low, high), f in zip(self.resolved, self.fractions, strict=True)
                     if f > 0 for params in (low, high)]
            self._smallest = min(radii)
        return self._smallest

    def owed(self, t: float) -> float:
        """The bodies (or kg, for ``mass_rate``) due up to time t and not yet inserted.

        The total due is computed from the time since ``start`` in one product, never
        summed interval by interval (a sum of 1000 intervals of 1e-3 s at 500/s ends at
        499.99...: one body short); a count within 1e-9 of a whole number is that number.
        """
        t1 = min(t, self.stop)
        total = 0.0
        if t1 > self.start:
            total = (self.rate or self.mass_rate) * (t1 - self.start)
        if self.mass_rate is not None:
            return total - self.inserted_mass
        whole = round(total)
        if abs(total - whole) <= 1e-9 * max(1.0, total):
            total = float(whole)
        return total - self.inserted

    def draw(self) -> tuple[str, dict[str, float]]:
        """One body's shape name and parameters."""
        k = int(self.rng.choice(len(self.shapes), p=self.fractions))
        spec = self.shapes[k]
        params = {}
        for key, v in spec.items():
            if key in ("shape", "fraction"):
                continue
            if is_range(v):
                lo, hi = float(v[0]), float(v[1])
                params[key] = lo + (hi - lo) * float(self.rng.random())
            else:
                params[key] = v
        return spec.get("shape", "sphere"), params


def is_range(v: Any) -> bool:
    """A shape parameter given as a ``(low, high)`` pair (drawn uniformly per body)."""
    return isinstance(v, tuple | list) and len(v) == 2 and not isinstance(v[0], str)


def resolve_shape(call: str, k: int, spec: Mapping) -> tuple[type, dict, dict]:
    """The class of shape ``k`` of an inlet's mix and its parameters at the low and at the
    high end of their ranges, each end built once so that an unknown name, a misspelt or
    missing parameter and a size out of range are refused now, naming the range given."""
    from .plugins import registry

    where = f"{call}: shapes[{k}]"
    name = spec.get("shape", "sphere")
    if not isinstance(name, str):
        raise ParameterError(f"{where} shape={name!r} must be a registered shape name")
    cls = registry().lookup("shape", name, where)
    low: dict[str, Any] = {}
    high: dict[str, Any] = {}
    ranges = []
    for key, v in spec.items():
        if key in ("shape", "fraction"):
            continue
        if is_range(v):
            shown = f"{key}={tuple(v)!r}"
            ranges.append(shown)
            pair = numeric_array(v)
            if pair is None:
                raise ParameterError(f"{where} {shown}: a range (low, high) of two numbers")
            if not pair[0] <= pair[1]:
                raise ParameterError(f"{where} {shown}: the low end {pair[0]:g} exceeds the "
                                     f"high end {pair[1]:g}; allowed: (low, high), low <= high")
            low[key], high[key] = float(pair[0]), float(pair[1])
        else:
            low[key] = high[key] = v
    label = f"{where} {', '.join(ranges)}" if ranges else where
    for end, params in (("low", low), ("high", high)):
        try:
            cls(call=f"{name} at the {end} end" if ranges else name, **params)
        except ParameterError as exc:
            raise ParameterError(f"{label}: {exc}") from None
        except TypeError as exc:  # a shape class without keyword parameters
            raise ParameterError(f"{label}: {exc}") from None
        if not ranges:
            break
    return cls, low, high


def random_quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform random unit quaternions (Shoemake 1992)."""
    u1, u2, u3 = rng.random((3, n))
    a, b = np.sqrt(1 - u1), np.sqrt(u1)
    return np.stack([a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2),
                     b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)], axis=1)
