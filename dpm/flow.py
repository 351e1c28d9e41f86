"""Inlets and outlets: particles entering and leaving a running simulation.

Both act at events every ``every`` seconds of simulated time (the run's kernel calls end
at these events). An :class:`Outlet` removes the bodies whose centre lies inside (or
outside) its region and records id, time, mass, residence time (time since insertion),
position and velocity; with output on, the records go to ``/removed`` of the HDF5 file.
An :class:`Inlet` inserts bodies drawn from a size distribution (a range, or
:mod:`dpm.distributions`) and shape mix at a number or mass rate, up to a total count or
mass if given, into its region, at random places where they overlap neither other bodies
(bounding spheres) nor boundaries; what it cannot place is carried to the next event and
counted in ``missed`` when the inlet stops.

An inlet given a planar :class:`~dpm.regions.Face` (rectangle, disc or triangle mesh)
inserts like LIGGGHTS' ``fix insert/stream``: each event places the bodies the coming
interval brings in the slab behind the face that the interval carries through it (depth
r to r + ``|v.n| every``, r the body's bounding radius), and carries them at the velocity's
normal part, free of gravity and contacts (infinite mass), until their centre has crossed
the face; then they are released with ``velocity``.

Plugins see both through the hooks ``dpm_on_particles_inserted`` and
``dpm_on_particles_removed``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .distributions import SizeDistribution, from_table, is_distribution_table
from .errors import ParameterError
from .material import Material
from .parameters import Parameter, numeric_array, validate
from .regions import Face, Region

RECORD_FIELDS = ("id", "time", "mass", "residence_time", "position", "velocity")


class Outlet:
    """Removes bodies whose centre is ``remove="inside"`` (default) or ``"outside"`` the
    ``region``, checked every ``every`` seconds."""

    def __init__(self, region: Region, remove: str = "inside", every: float = 1e-3,
                 name: str = "") -> None:
        if not isinstance(region, Region):
            raise ParameterError(f"Outlet(): region={region!r} must be a dpm region "
                                 "(dpm.BoxRegion, dpm.CylinderRegion)")
        if isinstance(region, Face):
            raise ParameterError(f"Outlet(): region={region!r} is a face, which has no "
                                 "volume to remove from; use dpm.BoxRegion or "
                                 "dpm.CylinderRegion")
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

    ``count`` (bodies) or ``mass`` (kg) is the total the inlet inserts; then it stops
    (``inlet.finished``). With ``rate`` or ``mass_rate`` it sets how fast; alone, everything
    is due at ``start`` (``rate``, or ``mass_rate`` for ``mass``, is then inf: the first event
    inserts all that fits, later events the rest). ``count`` bodies exactly; ``mass``: bodies
    until their mass reaches it (the last one crosses it, as ``mass_rate`` does). Refused by
    name: ``count`` with ``mass``; a ``stop`` before a total in the rate's own unit is due
    (``count`` with ``rate``, ``mass`` with ``mass_rate``); any finite ``stop`` with a total in
    the other unit (``count`` with ``mass_rate``, ``mass`` with ``rate``: the time it takes
    depends on the sizes drawn) or with a total alone.

    ``shapes`` is the mix: a list of dicts ``{"shape": name, "fraction": f, **params}``
    (number fractions, normalised); a parameter given as a pair ``(low, high)`` is drawn
    uniformly per body (e.g. ``"radius": (4e-3, 6e-3)``), one given as a size distribution
    (:class:`dpm.Normal`, :class:`dpm.LogNormal`, :class:`dpm.Sieve`, or the same as a
    one-key dict ``{"normal": {...}}``: :mod:`dpm.distributions`) is drawn from it. Without
    ``shapes``, ``shape`` and the remaining keyword arguments give a single kind. New bodies
    start with ``velocity`` and random orientation (``random_orientation=True``, the
    default). ``seed`` makes the insertion reproducible.

    With a :class:`~dpm.regions.Face` as ``region`` the inlet streams through the face
    (LIGGGHTS' ``insert/stream``; the module docstring): ``velocity`` must cross it
    (normal part at least 1e-3 m/s) and the slab one interval fills, ``|v.n| x every``
    (LIGGGHTS' ``extrude_length``), must be at least the largest body's diameter.
    """

    #: streaming through a face (set per inlet; the default for inlets pickled before)
    stream = False

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
        "count": Parameter(default=None, low=1, kind="int", doc="bodies in all"),
        "mass": Parameter(default=None, low=0.0, low_open=True, unit="kg",
                          doc="mass in all"),
    }
    #: the totals (set per inlet; the defaults for inlets stored before they existed)
    count: int | None = None
    mass: float | None = None

    def __init__(self, region: Region, material: Material, rate: float | None = None,
                 mass_rate: float | None = None, shapes: Sequence[Mapping] | None = None,
                 shape: str = "sphere", velocity: Sequence[float] = (0.0, 0.0, 0.0),
                 start: float = 0.0, stop: float = math.inf, every: float = 1e-3,
                 seed: int = 0, random_orientation: bool = True, max_attempts: int = 30,
                 count: int | None = None, mass: float | None = None,
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
            max_attempts=max_attempts, count=count, mass=mass))
        if rate is not None and mass_rate is not None or (
                rate is None and mass_rate is None and count is None and mass is None):
            raise ParameterError(f"{call}: give exactly one of rate (1/s) or mass_rate (kg/s)"
                                 f", or a total alone (count or mass: all due at start) (got "
                                 f"rate={rate!r}, mass_rate={mass_rate!r})")
        if not stop > start:
            raise ParameterError(f"{call}: stop={stop!r} must be after start={start!r} [s]")
        rate, mass_rate = _totals(call, rate, mass_rate, count, mass, float(start),
                                  float(stop))
        if shapes is None:
            shapes = [{"shape": shape, "fraction": 1.0, **shape_params}]
        elif shape_params:
            raise ParameterError(f"{call}: give shape parameters inside shapes=[...] "
                                 f"(got also {sorted(shape_params)})")
        elif (isinstance(shapes, str | Mapping) or not isinstance(shapes, Sequence)
              or not all(isinstance(sp, Mapping) for sp in shapes)):
            raise ParameterError(f"{call}: shapes={shapes!r} must be a list of dicts "
                                 '{"shape": name, "fraction": f, **parameters}')
        shapes = [_with_distributions(call, k, sp) for k, sp in enumerate(shapes)]
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
        self.count = None if count is None else int(count)
        self.mass = None if mass is None else float(mass)
        self._check_mass_scaling(call)
        self.rng = np.random.default_rng(seed)
        self.inserted = 0
        self.inserted_mass = 0.0
        self.ids: list[np.ndarray] = []
        r = self.smallest_radius()
        if not region.holds(r):
            raise ParameterError(f"{call}: region={region!r} is too small for the smallest "
                                 f"particle it inserts (bounding radius {r:g} m)")
        #: stream insertion through a face: the unit normal along the velocity, the
        #: carrying velocity (the normal part of ``velocity``) and the slab depth [m]
        self.stream = isinstance(region, Face)
        self.direction = np.zeros(3)
        self.carry_velocity = self.velocity
        self.extrude_length = 0.0
        #: bodies being carried: id, position and time at insertion, release time,
        #: mechanical energy booked
        self.transit: dict[str, np.ndarray] = {
            "id": np.zeros(0, np.int64), "x0": np.zeros((0, 3)), "t0": np.zeros(0),
            "release": np.zeros(0), "energy": np.zeros(0)}
        if self.stream:
            self._start_stream(call)

    def _start_stream(self, call: str) -> None:
        n = self.region.normal
        vn = float(self.velocity @ n)
        if abs(vn) < 1e-3:
            raise ParameterError(
                f"{call}: velocity={tuple(float(x) for x in self.velocity)} crosses the face "
                f"{self.region!r} at {abs(vn):.3g} m/s along its normal "
                f"{tuple(float(x) for x in n)}; a stream inlet needs at least 1e-3 m/s "
                "through the face")
        self.direction = n if vn > 0 else -n
        self.carry_velocity = abs(vn) * self.direction
        self.extrude_length = abs(vn) * self.every
        big = self.largest_radius()
        if self.extrude_length < 2.0 * big:
            raise ParameterError(
                f"{call}: the slab one interval carries through the face, |v.n| x every = "
                f"{abs(vn):g} m/s x {self.every:g} s = {self.extrude_length:.3g} m, is "
                f"thinner than the largest body ({2 * big:.3g} m across); raise every to "
                f"at least {2 * big / abs(vn):.3g} s (LIGGGHTS: extrude_length = |v.n| x "
                "insert_every x dt)")

    def _bounding_radii(self) -> list[float]:
        return [float(cls(call="Inlet()", **params).build(1, self.material.density)
                      .bounding_radius[0])
                for (cls, low, high), f in zip(self.resolved, self.fractions, strict=True)
                if f > 0 for params in (low, high)]

    def smallest_radius(self) -> float:
        """The smallest bounding radius [m] of what this inlet inserts: the least over the
        mix's shapes (fraction > 0) built at the low and at the high end of their
        ranges."""
        if self._smallest is None:
            self._smallest = min(self._bounding_radii())
        return self._smallest

    def largest_radius(self) -> float:
        """The largest bounding radius [m] of what this inlet inserts (as
        :meth:`smallest_radius`)."""
        return max(self._bounding_radii())

    def _check_mass_scaling(self, call: str) -> None:
        """A mass-based size distribution (a sieve table, a log-normal on a mass basis)
        honours mass fractions by weighting with size^3: the parameter it is given to must
        scale the whole body. Each shape's body is built at the distribution's two ends
        (the other parameters at their low ends) and refused, naming the parameter, unless
        the masses are in the ratio (high / low)^3 to 1e-4."""
        for k, ((cls, low, _), spec) in enumerate(zip(self.resolved, self.shapes,
                                                      strict=True)):
            for key, v in spec.items():
                if not (isinstance(v, SizeDistribution) and v.by_mass):
                    continue
                m = [float(cls(call=call, **dict(low, **{key: end}))
                           .build(1, self.material.density).mass[0]) for end in (v.low, v.high)]
                want = (v.high / v.low) ** 3
                if not abs(m[1] / m[0] / want - 1.0) <= 1e-4:
                    raise ParameterError(
                        f"{call}: shapes[{k}] {key}={v!r}: a mass-based distribution needs a "
                        f"parameter that scales the whole body (mass ~ size^3), but the "
                        f"{spec.get('shape', 'sphere')!r} body's mass changes by "
                        f"{m[1] / m[0]:.4g} from {key}={v.low:g} to {v.high:g}, not "
                        f"{want:.4g}; give it to a size that scales the body (a sphere's "
                        "radius, a mesh's scale) or use a number distribution")

    @property
    def finished(self) -> bool:
        """Whether the inlet has inserted its ``count`` or ``mass``."""
        return ((self.count is not None and self.inserted >= self.count)
                or (self.mass is not None and self.inserted_mass >= self.mass))

    def candidates(self, radius: float) -> np.ndarray:
        """``max_attempts`` random places for a body of bounding radius ``radius``: in the
        region, or (a face) in the slab behind it at depth radius to radius +
        ``extrude_length``. An inlet that has inserted its ``count`` or ``mass`` offers none
        (the body drawn is not placed: an event ends there, as when the region is full)."""
        if self.finished:
            return np.zeros((0, 3))
        pts = self.region.sample(self.rng, self.max_attempts, radius)
        if not self.stream:
            return pts
        depth = radius + self.rng.random(len(pts)) * self.extrude_length
        return pts - depth[:, None] * self.direction

    def placed(self, sim: Any, ids: np.ndarray) -> None:
        """Bodies ``ids`` were just appended: a stream inlet starts carrying them
        (infinite mass and inertia: no gravity, no contact moves them)."""
        if not self.stream:
            return
        from .guards import mechanical_energy

        b = sim.bodies
        rows = _rows(b.id, ids)
        x0 = b.position[rows].copy()
        depth = (self.region.point - x0) @ self.direction
        speed = float(np.linalg.norm(self.carry_velocity))
        b.invmass[rows] = 0.0
        b.invinertia[rows] = 0.0
        b.angular_velocity[rows] = 0.0
        e = np.array([mechanical_energy(b, sim.gravity, [r]) for r in rows])
        add = {"id": np.asarray(ids, np.int64), "x0": x0, "t0": np.full(len(ids), sim.time),
               "release": sim.time + np.maximum(depth, 0.0) / speed, "energy": e}
        self.transit = {k: np.concatenate([self.transit[k], add[k]]) for k in self.transit}

    def due(self, t: float) -> bool:
        """Whether a carried body's centre has crossed the face by time ``t``."""
        rel = self.transit["release"]
        return bool(len(rel) and rel.min() <= t + 1e-9 * self.every)

    def release(self, sim: Any) -> np.ndarray:
        """Release the carried bodies whose centre has crossed the face by now: they get
        back their mass and inertia and the position and velocity of a release at the
        crossing followed by free flight (``velocity``, gravity) until now. Returns their
        ids. Bodies removed meanwhile are forgotten."""
        from .guards import mechanical_energy

        tr, b, t = self.transit, sim.bodies, sim.time
        present = np.isin(tr["id"], b.id)
        go = present & (tr["release"] <= t + 1e-9 * self.every)
        keep = present & ~go
        ids = tr["id"][go]
        if len(ids):
            rows = _rows(b.id, ids)
            t_rel = tr["release"][go]
            tau = (t - t_rel)[:, None]
            g = np.asarray(sim.gravity, float)
            b.position[rows] = (tr["x0"][go] + (t_rel - tr["t0"][go])[:, None]
                                * self.carry_velocity + self.velocity * tau + 0.5 * g * tau**2)
            b.velocity[rows] = self.velocity + g * tau
            b.angular_velocity[rows] = 0.0
            b.invmass[rows] = 1.0 / b.mass[rows]
            b.invinertia[rows] = 1.0 / b.inertia[rows]
            if sim.energy.started:  # the carrying did work: book it as inserted
                after = np.array([mechanical_energy(b, sim.gravity, [r]) for r in rows])
                sim.energy.inserted += float(np.sum(after - tr["energy"][go]))
        self.transit = {k: v[keep] for k, v in tr.items()}
        return ids

    @property
    def carried(self) -> np.ndarray:
        """Ids of the bodies being carried to the face now."""
        return self.transit["id"].copy()

    def owed(self, t: float) -> float:
        """The bodies (or kg, for ``mass_rate``) due up to time t and not yet inserted.

        The total due is computed from the time since ``start`` in one product, never
        summed interval by interval (a sum of 1000 intervals of 1e-3 s at 500/s ends at
        499.99...: one body short); a count within 1e-9 of a whole number is that number.
        It is at most ``count`` (or ``mass``) in all; nothing once the inlet is
        :attr:`finished`.
        """
        if self.finished:
            return 0.0
        t1 = min(t, self.stop)
        total = 0.0
        if t1 > self.start:
            total = (self.rate or self.mass_rate) * (t1 - self.start)
        if self.mass_rate is not None:
            if self.mass is not None:
                total = min(total, self.mass)
            return total - self.inserted_mass
        if self.count is not None:
            total = min(total, float(self.count))
        if math.isfinite(total):
            whole = round(total)
            if abs(total - whole) <= 1e-9 * max(1.0, total):
                total = float(whole)
        return total - self.inserted

    def draw(self) -> tuple[str, dict[str, float]]:
        """One body's shape name and parameters."""
        k = int(self.rng.choice(len(self.shapes), p=self.fractions))
        spec = self.shapes[k]
        cls = self.resolved[k][0]
        params = {}
        for key, v in spec.items():
            if key in ("shape", "fraction"):
                continue
            if isinstance(v, SizeDistribution):
                params[key] = v.sample(self.rng)
            elif is_range(v, cls, key):
                lo, hi = float(v[0]), float(v[1])
                params[key] = lo + (hi - lo) * float(self.rng.random())
            else:
                params[key] = v
        return spec.get("shape", "sphere"), params


def is_range(v: Any, cls: type | None = None, key: str = "") -> bool:
    """A shape parameter given as a ``(low, high)`` pair of scalars (drawn uniformly per
    body); never a parameter the shape class declares as a list (``kind="any"``, e.g. the
    ``radii`` of a multisphere)."""
    spec = getattr(cls, "parameters", {}).get(key)
    if spec is not None and spec.kind == "any":
        return False
    return (isinstance(v, tuple | list) and len(v) == 2 and not isinstance(v[0], str)
            and np.ndim(v[0]) == 0)


def _totals(call: str, rate: float | None, mass_rate: float | None, count: int | None,
            mass: float | None, start: float, stop: float) -> tuple[float | None, float | None]:
    """(rate, mass_rate) of an inlet with its totals checked: ``count`` or ``mass`` alone
    makes its rate inf (all due at start); the combinations the :class:`Inlet` docstring
    refuses are refused here, by name."""
    if count is not None and mass is not None:
        raise ParameterError(f"{call}: give count (bodies) or mass (kg) in all, not both "
                             f"(got count={count!r}, mass={mass!r})")
    if count is None and mass is None:
        return rate, mass_rate
    total = f"count={count!r}" if count is not None else f"mass={mass!r}"
    if rate is None and mass_rate is None:  # (a total alone: all due at start)
        if math.isfinite(stop):
            raise ParameterError(f"{call}: {total} without a rate is due all at start="
                                 f"{start!r} s; stop={stop!r} has no meaning: leave it out "
                                 "or give rate (1/s) or mass_rate (kg/s)")
        return (math.inf, None) if count is not None else (None, math.inf)
    own = rate if count is not None else mass_rate
    if own is None:  # (a total in the other unit than the rate)
        if math.isfinite(stop):
            other = f"mass_rate={mass_rate!r}" if count is not None else f"rate={rate!r}"
            raise ParameterError(
                f"{call}: {total} with {other}: the time it takes depends on the sizes "
                f"drawn, so stop={stop!r} cannot be checked to leave it room; leave stop "
                f"out (the inlet stops at the total) or give "
                f"{'rate' if count is not None else 'mass_rate'} instead")
        return rate, mass_rate
    goal = float(count if count is not None else mass)  # type: ignore[arg-type]
    need = goal / own
    if own * (stop - start) < goal * (1 - 1e-9):  # (a count within 1e-9 is whole: owed)
        unit = ("bodies", "/s", "s") if count is not None else ("kg", " kg/s", "s")
        raise ParameterError(
            f"{call}: {total} at {'rate' if count is not None else 'mass_rate'}={own!r}"
            f"{unit[1]} takes {need:g} s from start={start!r} s, past stop={stop!r} s (it "
            f"would insert only {own * (stop - start):g} {unit[0]}); leave stop out or set it "
            f"to at least {start + need:g} s")
    return rate, mass_rate


def _with_distributions(call: str, k: int, spec: Mapping) -> dict:
    """Shape ``k`` of a mix with its distribution tables (``{"normal": {...}}``, as a
    scene file writes them) made distribution objects."""
    out = dict(spec)
    for key, v in spec.items():
        if key not in ("shape", "fraction") and is_distribution_table(v):
            out[key] = from_table(f"{call}: shapes[{k}] {key}", v)
    return out


def _rows(ids: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Rows of ``wanted`` ids (all present) in the id column ``ids``."""
    order = np.argsort(ids, kind="stable")
    return order[np.searchsorted(ids[order], wanted)]


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
        if isinstance(v, SizeDistribution):
            ranges.append(f"{key}={v!r}")
            low[key], high[key] = v.low, v.high
        elif is_range(v, cls, key):
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
