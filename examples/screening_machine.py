"""Tumbling screening machine (TSM) of M decks: Alkhaldi (2007), ch. 4, as a parametric scene.

The machine of the thesis' first study (sec. 4.4): a sifting unit of ``levels`` = 5 levels
stacked in a vertical barrel of radius R = 0.8 m. The floors of levels 5..2 are square-
mesh sieves of decreasing hole width w = 17, 15, 13, 11 mm with bars as wide as the holes
(w/g = 1); level 1 has a solid floor. The unit moves by :class:`dpm.Tumbling` (main shaft
speed ``rpm``, plate inclinations ``alpha`` and ``beta``, shaft ``eccentricity``, barrel
``free`` = turning with the shaft, ``fixed``, or ``oscillating`` with factor K and period
t_p, eqs. 4.1-4.7). Spheres of five sizes, numbered as the thesis' package of 3,483
particles (1210 x 10 mm, 832 x 12, 611 x 14, 467 x 16, 363 x 18; the thesis writes "radii",
but only diameters let each size pass the holes above its level and stop at its own, so
they are read as diameters), are fed at ``feed_rate`` = 147 particles/s from a nozzle at
the centre of the top deck (``mode="continuous"``), or all placed above the top deck at
t = 0 (``mode="batch"``). Sieves use the hole clearance model 1 (eq. 4.20) with
zeta = 0.8 (the thesis' b = 0.8 w).

Outlets: the barrel wall keeps the particles on their deck except at one opening per
level, a window of ``outlet_width`` degrees in the barrel wall just above the deck, at the
same angle of the unit's frame on every level (the thesis' exits "located around the
machine body"; it gives no size, so the width is a parameter). The run samples every
``sample`` seconds in the unit's own frame: a particle at the wall (centre within 0.6 of
the largest diameter of the wall) inside a level's window has left through that level's
outlet; it is recorded and taken out, as the outlet chute would carry it away. An outlet
below the machine catches anything else that falls out (counted as ``unseen``). A
particle leaving level i is *sorted* (s_i) if level i is its own size's level and
*gangue* (g_i) if it is smaller (it could have passed the sieve below).

Figures, as the thesis defines them:

- machine efficiency c = 100/M sum_i s_i / (s_i + g_i)  (eq. 4.33), with c_1 = 1 as
  eq. 4.34 sets it (no gangue can reach the lowest level); another level with no exits
  yet counts as 0 (:func:`machine_efficiency`),
- screening efficiency of deck i: the fraction of the undersize that reached level i
  (particles that fit its holes) which passed its sieve,
- throughput of each level's outlet and of each deck (particles per second),
- particles remaining in the machine; mass balance fed = exited + remaining + escaped
  (thrown out of the scene: see docs/scenes.md on the sieve model's energy jumps).

    python examples/screening_machine.py --quick           # 0.6 s, the CI check
    python examples/screening_machine.py --until 20        # the thesis' steady state
    python examples/screening_machine.py --set rpm=150 barrel=fixed --json case.json

``examples/screening_study.py`` runs the thesis' parameter sweeps in parallel processes.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import asdict, dataclass, field, fields

import numpy as np

import dpm

#: the thesis' particle package (sec. 4.4): (count, diameter [m])
PACKAGE = ((1210, 10e-3), (832, 12e-3), (611, 14e-3), (467, 16e-3), (363, 18e-3))
#: sieve holes of the decks from the top deck down (level 5 floor .. level 2 floor) [m]
HOLES = (17e-3, 15e-3, 13e-3, 11e-3)


@dataclass
class Case:
    """One machine set-up; the defaults are the thesis' reference case (sec. 4.4.1)."""

    rpm: float = 50.0                  # main shaft speed [1/min]
    alpha: float = 1.0                 # plate inclination alpha [deg]
    beta: float = 0.65                 # plate inclination beta [deg]
    eccentricity: float = 0.025        # shaft eccentricity [m]
    barrel: str = "free"               # free (spins with the shaft), fixed, oscillating
    oscillation_factor: float = 0.7    # K = omega_b / omega (barrel="oscillating")
    oscillation_period: float = 0.02   # t_p [s] (barrel="oscillating")
    feed_rate: float = 147.0           # particles/s (mode="continuous")
    mode: str = "continuous"           # continuous or batch
    particles: int = 3483              # the package size (scaled by number per size)
    wall_friction: float = 0.4         # particle-deck and particle-barrel friction
    friction: float = 0.5              # particle-particle friction
    restitution: float = 0.4
    radius: float = 0.8                # barrel radius R [m]
    level_height: float = 0.12         # distance between decks [m]
    zeta: float = 0.8                  # hole clearance factor (model 1, eq. 4.20)
    outlet_width: float = 90.0         # angular width of each level's wall outlet [deg]
    until: float = 20.0                # simulated time [s]
    sample: float = 0.01               # level sampling interval [s]
    dt: float = 2e-5
    seed: int = 1
    label: str = ""
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_strings(cls, items: list[str], base: Case | None = None) -> Case:
        """``key=value`` words (``rpm=150 barrel=fixed``) applied over ``base``."""
        case = Case(**asdict(base)) if base is not None else Case()
        kinds = {f.name: f.type for f in fields(cls)}
        for item in items:
            key, sep, value = item.partition("=")
            if not sep or key not in kinds or key == "extra":
                allowed = ", ".join(k for k in kinds if k != "extra")
                raise dpm.ParameterError(f"screening_machine --set: {item!r} must be "
                                         f"key=value with key one of: {allowed}")
            kind = kinds[key]
            try:
                setattr(case, key, value if kind == "str" else
                        int(value) if kind == "int" else float(value))
            except ValueError:
                raise dpm.ParameterError(f"screening_machine --set: {key}={value!r} is "
                                         f"not a {kind}") from None
        return case


class Machine:
    """The built scene and the level bookkeeping of one :class:`Case`."""

    def __init__(self, case: Case) -> None:
        self.case = case
        if case.barrel not in ("free", "fixed", "oscillating"):
            raise dpm.ParameterError(f"Case: barrel={case.barrel!r}; allowed: free, fixed, "
                                     "oscillating")
        if case.mode not in ("continuous", "batch"):
            raise dpm.ParameterError(f"Case: mode={case.mode!r}; allowed: continuous, batch")
        self.levels = len(HOLES) + 1
        # square deck plates reaching past the barrel: inside it they are discs of radius R
        self.half = case.radius
        self.deck_z = [k * case.level_height for k in range(self.levels)]  # level k+1 floor
        self.sizes = np.array([d for _, d in PACKAGE])
        counts = np.array([n for n, _ in PACKAGE], float)
        self.fractions = counts / counts.sum()
        sim = dpm.Simulation(dt=case.dt, gravity=(0.0, 0.0, -9.81))
        rock = dpm.Material("rock", density=2650.0, young=5e7, poisson=0.25)
        steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
        sim.contact(rock, rock, model="hertz_mindlin", restitution=case.restitution,
                    friction=case.friction)
        sim.contact(rock, steel, model="hertz_mindlin", restitution=case.restitution,
                    friction=case.wall_friction)
        self.motion = dpm.Tumbling(
            rpm=case.rpm, alpha=math.radians(case.alpha), beta=math.radians(case.beta),
            eccentricity=case.eccentricity, barrel=case.barrel,
            oscillation_factor=case.oscillation_factor,
            oscillation_period=case.oscillation_period)
        top = self.deck_z[-1] + 2.5 * case.level_height
        sim.add_boundary("tube", material=steel, start=(0.0, 0.0, 0.0),
                         axis=(0.0, 0.0, 1.0), length=top, radius=case.radius,
                         motion=self.motion)
        sim.add_boundary("wall", material=steel, center=(0.0, 0.0, 0.0),
                         normal=(0.0, 0.0, 1.0), half_extents=(self.half, self.half),
                         motion=self.motion)
        for k, hole in enumerate(HOLES[::-1]):  # level 2's floor (11 mm) ... level 5's
            sim.add_boundary("sieve", material=steel, center=(0.0, 0.0, self.deck_z[k + 1]),
                             normal=(0.0, 0.0, 1.0), half_extents=(self.half, self.half),
                             hole=hole, bar=hole,
                             clearance_model="radius", zeta=case.zeta, motion=self.motion)
        z_top = self.deck_z[-1]
        shapes = [{"shape": "sphere", "radius": d / 2, "fraction": f}
                  for (_, d), f in zip(PACKAGE, self.fractions, strict=True)]
        if case.mode == "continuous":
            nozzle = dpm.CylinderRegion(start=(0.0, 0.0, z_top + 0.03), axis=(0.0, 0.0, 1.0),
                                        length=0.08, radius=0.1)
            self.feed = sim.add_inlet(nozzle, rock, rate=case.feed_rate, every=0.02,
                                      seed=case.seed, shapes=shapes,
                                      stop=case.particles / case.feed_rate)
        else:
            self.feed = None
            self._batch(sim, rock, z_top)
        # everything that leaves a deck's edge falls out of the barrel's open bottom
        self.exit = sim.add_outlet(dpm.BoxRegion((-5.0, -5.0, -5.0), (5.0, 5.0, -0.3)),
                                   every=0.005)
        self.sim = sim
        self.last_level: dict[int, int] = {}
        self.size_class: dict[int, int] = {}
        self.reached = np.zeros((len(self.sizes), self.levels), np.int64)  # first arrivals
        self.series: list[dict] = []
        self.exited: list[tuple[int, int, int, float]] = []  # id, class, level, t

    def _batch(self, sim: dpm.Simulation, rock: dpm.Material, z_top: float) -> None:
        """The whole package on a jittered lattice in a column above the top deck."""
        case = self.case
        rng = np.random.default_rng(case.seed)
        n = np.rint(self.fractions * case.particles).astype(int)
        diam = np.repeat(self.sizes, n)
        rng.shuffle(diam)
        spacing = 1.15 * self.sizes.max()
        side = int(math.ceil(math.sqrt(len(diam) / 6)))  # about 6 layers
        xyz = dpm.lattice((-0.5 * side * spacing, -0.5 * side * spacing, z_top + 0.03),
                          (0.5 * side * spacing, 0.5 * side * spacing, z_top + 1.0),
                          spacing=spacing, jitter=0.05 * spacing, seed=case.seed)
        xyz = xyz[np.argsort(xyz[:, 2], kind="stable")][: len(diam)]  # lowest layers
        for d in self.sizes:
            sim.add_particles("sphere", material=rock, radius=d / 2, positions=xyz[diam == d])

    def local(self, position: np.ndarray, t: float) -> np.ndarray:
        """Points in the sifting unit's own frame, R^T (x - o)."""
        rot, org = self.motion.pose(np.array([t]))
        return (position - org[0]) @ rot[0]

    def level_of(self, local: np.ndarray) -> np.ndarray:
        """Level (1..M) of each point (unit frame) inside the barrel, over a deck and below
        the next; 0 outside the barrel or below the machine."""
        inside = np.hypot(local[:, 0], local[:, 1]) < self.case.radius
        lev = np.floor(local[:, 2] / self.case.level_height).astype(np.int64) + 1
        return np.where(inside & (local[:, 2] > -0.01) & (lev >= 1),
                        np.minimum(lev, self.levels), 0)

    def at_outlet(self, local: np.ndarray) -> np.ndarray:
        """Points at the barrel wall inside the outlet window (centred on the unit's +x)."""
        r = np.hypot(local[:, 0], local[:, 1])
        phi = np.degrees(np.abs(np.arctan2(local[:, 1], local[:, 0])))
        return ((r > self.case.radius - 0.6 * self.sizes.max())
                & (phi < 0.5 * self.case.outlet_width))

    def own_level(self, diameter: np.ndarray) -> np.ndarray:
        """The level each size belongs to: 1 + the number of sieve floors it cannot pass
        (a sphere passes a square hole of width w under clearance model 1 if d < w)."""
        holes_from_bottom = np.array(HOLES[::-1])      # floors of levels 2, 3, ...
        return 1 + (diameter[:, None] >= holes_from_bottom[None, :]).sum(axis=1)

    def observe(self) -> None:
        """Record the level of every particle present; one at a level's outlet window has
        left through it: it is recorded and taken out (the outlet chute)."""
        sim = self.sim
        ids = sim.bodies.id
        local = self.local(sim.bodies.position, sim.time)
        lev = self.level_of(local)
        out = self.at_outlet(local)
        diam = 2.0 * sim.bodies.radius
        gone = []
        for i, lv, o, d in zip(ids.tolist(), lev.tolist(), out.tolist(), diam.tolist(),
                               strict=True):
            if i not in self.size_class:
                self.size_class[i] = int(np.argmin(np.abs(self.sizes - d)))
            prev = self.last_level.get(i, 0)
            if lv and lv != prev:
                if prev == 0 or lv < prev:
                    self.reached[self.size_class[i], lv - 1] += 1
                self.last_level[i] = lv
            if lv and o:
                gone.append(i)
                self.exited.append((i, self.size_class[i], lv, sim.time))
        if gone:
            sim.remove_particles(gone)

    def exits(self) -> tuple[np.ndarray, np.ndarray]:
        """(class, level) of every particle that left the machine so far (level 0: it
        fell out below before it was seen on a level)."""
        rec = self.exit.records
        cls = [c for _, c, _, _ in self.exited] + [self.size_class.get(int(i), -1)
                                                   for i in rec["id"]]
        lev = [lv for _, _, lv, _ in self.exited] + [0] * len(rec["id"])
        return np.array(cls, np.int64), np.array(lev, np.int64)

    def figures(self) -> dict:
        return figures(self.exits(), self.reached, self.own_level(self.sizes), self.levels)

    def run(self, progress: bool = False) -> dict:
        """Run to ``case.until`` in sampling intervals; returns the case's figures."""
        sim, case = self.sim, self.case
        t0 = time.perf_counter()
        steps0 = sim.step_count
        psteps = 0.0
        while sim.time < case.until - 0.5 * case.dt:
            n_before = len(sim.bodies)
            s_before = sim.step_count
            sim.run(until=min(case.until, sim.time + case.sample), progress=progress)
            psteps += 0.5 * (n_before + len(sim.bodies)) * (sim.step_count - s_before)
            self.observe()
            if len(self.series) == 0 or sim.time - self.series[-1]["t"] >= 0.1 - 1e-9:
                f = self.figures()
                self.series.append({"t": sim.time, "c": f["machine_efficiency"],
                                    "exited": f["exited"], "present": len(sim.bodies)})
        wall = time.perf_counter() - t0
        out = self.figures()
        fed = (sum(len(x) for x in self.feed.ids) if self.feed is not None
               else len(self.size_class))
        out.update({"case": asdict(case), "fed": int(fed), "present": len(sim.bodies),
                    # thrown out of the scene (the escape guard removed them)
                    "escaped": int(sim.escaped.count),
                    "time": sim.time, "steps": sim.step_count - steps0, "wall_s": wall,
                    "particle_steps_per_s": psteps / max(wall, 1e-9), "series": self.series})
        return out


def figures(exits: tuple[np.ndarray, np.ndarray], reached: np.ndarray,
            own: np.ndarray, levels: int) -> dict:
    """The thesis' figures from the exits and the first arrivals on each level.

    ``exits``: (size class, level left from) per exited particle; ``reached[c, l]``:
    particles of class c that arrived on level l + 1; ``own[c]``: the level of class c.
    Sorted s_i: exits from level i of the class whose own level is i; gangue g_i: exits
    from level i of a class whose own level is below i (eq. 4.33).
    """
    cls, lev = exits
    s = np.zeros(levels, np.int64)
    g = np.zeros(levels, np.int64)
    unseen = oversize = 0
    for c, lv in zip(cls.tolist(), lev.tolist(), strict=True):
        if lv <= 0 or c < 0:
            unseen += 1
        elif own[c] == lv:
            s[lv - 1] += 1
        elif own[c] < lv:
            g[lv - 1] += 1
        else:  # below its own level: a sieve let an oversize particle through
            oversize += 1
    ci = level_efficiencies(s, g)
    # screening efficiency of the floor of level l (l >= 2): of the particles that reached
    # level l and fit its floor's holes, the fraction that reached level l - 1
    screen = []
    for lv in range(2, levels + 1):
        fits = [c for c in range(len(own)) if own[c] < lv]
        came = reached[fits, lv - 1].sum()
        passed = reached[fits, lv - 2].sum()
        screen.append(float(passed / came) if came else float("nan"))
    return {"sorted": s.tolist(), "gangue": g.tolist(), "level_efficiency": ci.tolist(),
            "machine_efficiency": machine_efficiency(s, g), "unseen": int(unseen),
            "oversize_through": int(oversize),
            "exited": int(len(cls)), "deck_screening": screen,
            "exits_per_level": (s + g).tolist()}


def level_efficiencies(s: np.ndarray, g: np.ndarray) -> np.ndarray:
    """c_i = s_i / (s_i + g_i) of each level (eq. 4.33); c_1 = 1 (eq. 4.34: nothing
    smaller than the lowest level's own size exists, so g_1 = 0); a higher level with no
    exits yet: 0."""
    s = np.asarray(s, float)
    g = np.asarray(g, float)
    ci = np.where(s + g > 0, s / np.maximum(s + g, 1), 0.0)
    ci[0] = 1.0
    return ci


def machine_efficiency(s: np.ndarray, g: np.ndarray) -> float:
    """c = 100/M sum_i c_i [%] (eqs. 4.33-4.34)."""
    return float(100.0 * level_efficiencies(s, g).mean())


def run_case(case: Case, progress: bool = False) -> dict:
    """Build and run one case (what the study's worker processes call)."""
    return Machine(case).run(progress=progress)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="0.6 s with 300 particles")
    p.add_argument("--until", type=float, default=None, help="simulated time [s]")
    p.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE",
                   help="case parameters, e.g. rpm=150 barrel=fixed mode=batch")
    p.add_argument("--json", default=None, help="write the figures to this JSON file")
    args = p.parse_args(argv)
    base = Case(until=0.6, particles=300) if args.quick else Case()
    case = Case.from_strings(args.set, base)
    if args.until is not None:
        case.until = args.until
    out = run_case(case, progress=not args.quick)
    dpm.notice(f"simulated {out['time']:.2f} s in {out['wall_s']:.1f} s "
               f"({out['particle_steps_per_s']:.3g} particle-steps/s); fed {out['fed']}, "
               f"exited {out['exited']}, in the machine {out['present']}, thrown out of the "
               f"scene {out['escaped']}")
    for lv in range(len(out["sorted"]), 0, -1):
        dpm.notice(f"  level {lv}: sorted {out['sorted'][lv - 1]:5d}  gangue "
                   f"{out['gangue'][lv - 1]:5d}")
    dpm.notice(f"machine efficiency c = {out['machine_efficiency']:.1f} % (eq. 4.33); deck "
               "screening (top down): " + ", ".join(f"{100 * x:.0f} %" if x == x else "-"
                                                    for x in out["deck_screening"][::-1]))
    if args.json and dpm.is_root():  # (rank 0 writes: every rank holds the result)
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
