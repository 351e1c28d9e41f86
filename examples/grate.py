"""Forward and backward acting grates: residence time of solid fuel on a moving grate.

The cold test grate of Samiei 2012 (DPM thesis, ch. 4; the CUTEC plant of Beckmann et al.
1995): 11 grate bars (Table 3.3: bar length L = 190 mm, bar height h = 30 mm, stroke
A = 30 mm), every other bar moving back and forth at a constant speed with a pause at
each end (``dpm.Reciprocating``). Table 4.1: the forward acting grate is inclined at
13 deg with bars at 7 deg, the backward (reverse) acting grate at 25 deg with bars at
45 deg. Particles are fed at a constant mass rate onto the first bar over an initial bed
and leave past the last bar, where an outlet records their residence times.

**Geometry** (the thesis gives the angles and Table 3.3's sizes, not the drawing; this is
the construction used here). x runs down the grate, z up, y across. Each bar is a
``wall`` slab of length L along its top direction a = (cos b, 0, -sin b) and thickness h;
consecutive bars are offset by the pitch P along the grate line (cos g, 0, -sin g), so the
bar tops form steps of normal height s = P sin|g - b| and overlap like tiles. The plant
is one set of bars, convertible between the two (sec. 4.2), and Table 4.1's angles put the
bars at 20 deg to the grate line in both; we read the forward grate's 7 deg as the bar tops
rising toward their downstream ends (b = -7 deg) and the backward grate's 45 deg as falling
from their upstream ends. Forward (b < g): each bar's downstream end (its nose) rests on
the next bar, the moving bars push downstream. Backward (b > g): each bar's upstream end
(its nose) rests on the bar above, the moving bars push upstream, against the flow. The
step s is one bar height h (the bars then overlap by 108 mm, more than the stroke; the
exposed length is h / tan 20 deg = 82 mm, the pitch 88 mm). Bars 1, 3, ..., 11 (counted
from 1) move, along their own top direction: the first bar, under the feed, moves, so
that the back wall at the feed end and the first bar's stroke carry the fed particles on
(with a fixed first bar the feed piled up there: nothing pushes it over its nose). The back
wall is a vertical sheet standing 2 mm over the first bar's top line (which the bar slides
along), 40 mm from the bar's upstream end, so the stroke never opens a gap under it.

**Width** (sec. 4.3): only a slice of the 1,000 mm grate is simulated, ``--width`` n
particle diameters (largest diameter, + 5 %), between side walls of the particles' own
material (as in the thesis: they stand for the particles left out) or, with
``--periodic``, with periodic side faces. The feed rate is scaled with the width (eq. 4.1:
bed height and residence time are unchanged while the bulk density is).

**Particles and contacts** (Tables 4.2, 4.3): swelling clay (700 kg/m3, d uniform in
12-21 mm), wood (550 kg/m3, 15 mm), ceramic (2200 kg/m3, 12.6 mm) spheres; Maw's linear
spring (``maw_linear_spring``, characteristic impact speed 2 m/s, tangential restitution
= normal, eq. 2.34) with the table's restitution, sliding and rolling friction (constant
torque) for particle/particle and particle/bar; bars of acrylic (E = 3.2 GPa, nu = 0.4).
Position Verlet at dt = 1e-3 s (sec. 4.4) where it gives at least 5 steps per contact
(the table's "collision resolution" 4-7), else halved until it does: Maw's spring with
Table 4.3's constants makes a 12 mm clay sphere's contact with an acrylic bar last 3.2 ms
(3.2 steps at 1e-3 s, where position Verlet ran unstable) and a ceramic sphere's 4.2 ms,
so clay and ceramic run at 5e-4 s, wood at 1e-3 s.

**Bar speed**: 3.5 mm/s as in the experiments (Tables 4.4-4.6), or ``--fast-bars``: 35 mm/s,
the speed-up the thesis used in sec. 3.9.4, with the pause shortened and the feed raised
by the same factor so that the bed height stays about the same (as the thesis argues
there). The pause is not given: 1 s at 3.5 mm/s is assumed (0.1 s with fast bars).

**Outputs**: the residence time distribution of the tracer particles (those fed during
a window after a warm-up, followed until 98 % of their mass has left, as the thesis'
sample), E(t) and F(t) (eqs. 4.11-4.12, ``dpm.analysis.residence_times``), the mass
related mean residence time (eq. 3.58), the bed height along the grate (the highest
particle top above the bar surface, per bar pitch, averaged over the samples), Lacey's
mixing index of the tracers in the bed (``dpm.analysis.lacey``) and the mass balance by
ids (fed = discharged + on the grate).

**Implicit integrators**: the thesis ran sec. 3.9.4's backward grate with its implicit
Numerov scheme. dpm's implicit integrators (``dpm/integrators/implicit.py``) refuse this
scene before the first step: they take fixed planes and boxes only (the bars are moving
``wall`` slabs), a fixed body count (no inlets or outlets) and no periodic faces
(``--integrator numerov`` shows their error).

    python examples/grate.py --quick      # CI: one short run (~13 s once compiled)
    python examples/grate.py              # the four documented sets (~40 min, 2 cores)
    python examples/grate.py --set width  # one of them: validation, mass_flow, width, speed
    python examples/grate.py --grate backward --material wood --mass-flow 40 --fast-bars

Writes ``grate_<set>.json``, ``grate_<set>.png`` (RTDs, bed height, Lacey index) and
``grate_<set>_bed.png`` (the beds at the end, side view) into ``--output`` (default .);
``--replot`` redraws the pictures from the JSON files there. docs/scenes.md gives the
results and the comparison with the thesis.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import dpm
from dpm import analysis as an

G = 9.81
N_BARS = 11
BAR_LENGTH = 0.190   # Table 3.3
BAR_HEIGHT = 0.030   # Table 3.3
STROKE = 0.030       # Table 3.3, moving bar amplitude
GRATE_WIDTH = 1.0    # Table 3.3, bar width (the plant's width the feed is given for)
OVERLAP_MARGIN = 0.020
DT = 1e-3            # sec. 4.4
MAX_OVERLAP = 0.9    # the run stops beyond this overlap / radius (dpm's default: 0.5)
MIN_STEPS = 5.0      # steps per contact at least (dpm's check; the thesis' "resolution")
SLOW_SPEED = 3.5e-3  # Tables 4.4-4.6 [m/s]
SPEED_UP = 10.0      # sec. 3.9.4: 35 mm/s
PAUSE = 1.0          # assumed pause at each end at 3.5 mm/s [s]

#: Table 4.1: (grate inclination, bar top inclination) [deg], positive down the grate. The
#: plant is one set of bars, convertible (sec. 4.2): 20 deg to the grate line in both, the
#: forward grate's bar tops rising 7 deg toward their downstream noses, the backward
#: grate's falling 45 deg from their upstream noses (the sign is our reading of fig. 4.1)
GRATES = {"forward": (13.0, -7.0), "backward": (25.0, 45.0)}

#: Tables 4.2 and 4.3 (particle/particle, particle/bar): density, diameter range, E, nu,
#: restitution, sliding friction, rolling friction
MATERIALS = {
    "clay": dict(density=700.0, d=(0.012, 0.021), young=1e5, poisson=0.4,
                 pp=(0.7, 0.5, 0.002), pb=(0.55, 0.8, 0.002)),
    "wood": dict(density=550.0, d=(0.015, 0.015), young=5e4, poisson=0.3,
                 pp=(0.8, 0.25, 0.0045), pb=(0.65, 0.6, 0.0045)),
    "ceramic": dict(density=2200.0, d=(0.0126, 0.0126), young=2e5, poisson=0.4,
                    pp=(0.94, 0.25, 0.00126), pb=(0.68, 0.2, 0.00126)),
}
ACRYLIC = dict(density=1190.0, young=3.2e9, poisson=0.4)
IMPACT_SPEED = 2.0  # Table 4.3, characteristic impact velocity [m/s]


@dataclass
class Case:
    """One grate run."""

    grate: str = "forward"
    material: str = "clay"
    mass_flow_kg_h: float = 20.0
    fast_bars: bool = False
    width: float = 1.0          # in largest particle diameters
    periodic: bool = False
    bed_height: float = 0.05    # initial bed [m]
    warmup_cycles: float = 15.0
    tracer_cycles: float = 60.0
    max_cycles: float = 250.0
    sample_every: float = 0.5   # of a bar cycle
    seed: int = 1
    integrator: str = "position_verlet"
    label: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def speed(self) -> float:
        return SLOW_SPEED * (SPEED_UP if self.fast_bars else 1.0)

    @property
    def pause(self) -> float:
        return PAUSE / (SPEED_UP if self.fast_bars else 1.0)

    @property
    def cycle(self) -> float:
        return 2 * STROKE / self.speed + 2 * self.pause


class Geometry:
    """The bars' frames (see the module docstring): unit vectors a (bar top, downstream),
    n (bar top normal), the pitch vector d, the noses N_k and centres C_k of the slabs."""

    def __init__(self, grate: str, n_bars: int = N_BARS) -> None:
        g, b = (math.radians(x) for x in GRATES[grate])
        self.grate, self.g, self.b = grate, g, b
        self.a = np.array([math.cos(b), 0.0, -math.sin(b)])
        self.n = np.array([math.sin(b), 0.0, math.cos(b)])
        rel = abs(g - b)
        exposed = BAR_HEIGHT / math.tan(rel)
        if exposed > BAR_LENGTH - STROKE - OVERLAP_MARGIN:
            exposed = BAR_LENGTH - STROKE - OVERLAP_MARGIN
        self.exposed = exposed
        self.step = exposed * math.tan(rel)
        self.pitch = exposed / math.cos(rel)
        self.d = self.pitch * np.array([math.cos(g), 0.0, -math.sin(g)])
        self.forward = grate == "forward"
        k = np.arange(n_bars)[:, None]
        self.nose = k * self.d[None]
        # forward: the nose is the bar's downstream top corner; backward: its upstream one
        half = 0.5 * BAR_LENGTH * self.a
        self.centre = self.nose + (-half if self.forward else half) - 0.5 * BAR_HEIGHT * self.n
        self.top_start = self.centre - half + 0.5 * BAR_HEIGHT * self.n   # upstream top end
        self.top_end = self.centre + half + 0.5 * BAR_HEIGHT * self.n     # downstream top end
        self.moving = np.arange(n_bars) % 2 == 0
        # the moving bars push downstream (forward) or upstream (backward) first
        self.push = self.a if self.forward else -self.a
        self.x_back = float(self.top_start[0, 0])
        self.end = self.top_end[-1] if not self.forward else self.nose[-1]

    def surface(self, x: np.ndarray) -> np.ndarray:
        """Height z of the exposed bar top at x (the highest top line over x), at rest."""
        x = np.asarray(x, float)
        z = np.full(x.shape, -np.inf)
        for s, e in zip(self.top_start, self.top_end, strict=True):
            inside = (x >= s[0]) & (x <= e[0])
            zz = s[2] + (x - s[0]) * (e[2] - s[2]) / (e[0] - s[0])
            z = np.where(inside, np.maximum(z, zz), z)
        return z

    def slab_distance(self, p: np.ndarray) -> np.ndarray:
        """Smallest distance of the points p from the bar slabs at rest (2-D, in x-z)."""
        best = np.full(len(p), np.inf)
        for c in self.centre:
            r = p - c[None]
            s = np.abs(r @ self.a) - 0.5 * BAR_LENGTH
            w = np.abs(r @ self.n) - 0.5 * BAR_HEIGHT
            out = np.hypot(np.maximum(s, 0), np.maximum(w, 0))
            best = np.minimum(best, np.where((s < 0) & (w < 0), 0.0, out))
        return best

    def along(self, p: np.ndarray) -> np.ndarray:
        """Distance of the points down the grate line from the feed end of bar 1 [m]."""
        return (p - self.top_start[0][None]) @ (self.d / self.pitch)

    @property
    def bins(self) -> int:
        """Pitches along the grate from the feed end to the discharge end."""
        return int(math.ceil(float(self.along(self.end[None])[0]) / self.pitch))


def build(case: Case, output: str | None = None) -> tuple[dpm.Simulation, dict]:
    """The scene of ``case``; returns the simulation and what the analysis needs."""
    mat = MATERIALS[case.material]
    geo = Geometry(case.grate)
    dmin, dmax = mat["d"]
    width = case.width * dmax * 1.05
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G), integrator=case.integrator,
                         dt_check="warn", max_overlap=MAX_OVERLAP)
    part = dpm.Material(case.material, density=mat["density"], young=mat["young"],
                        poisson=mat["poisson"])
    bar = dpm.Material("acrylic", **ACRYLIC)
    for other, (e, mu, mur) in ((part, mat["pp"]), (bar, mat["pb"])):
        sim.contact(part, other, model="maw_linear_spring", restitution=e, friction=mu,
                    rolling_friction=mur, impact_velocity=IMPACT_SPEED)
    half_w = 0.5 * width
    bar_half_y = half_w + (2 * dmax if not case.periodic else width)
    for k in range(N_BARS):
        motion = (dpm.Reciprocating(stroke=tuple(STROKE * geo.push), speed=case.speed,
                                    pause=case.pause) if geo.moving[k] else None)
        sim.add_boundary("wall", material=bar, center=tuple(geo.centre[k]),
                         normal=tuple(geo.n), u=tuple(geo.a),
                         half_extents=(0.5 * BAR_LENGTH, bar_half_y),
                         thickness=BAR_HEIGHT, motion=motion)
    # the back wall at the feed end (acrylic): a vertical sheet standing on the first bar's
    # top line (which the bar slides along) with a 2 mm gap, always over the bar
    foot = geo.top_start[0] + (STROKE + 0.01) * geo.a
    sim.add_boundary("wall", material=bar, center=(foot[0], 0.0, foot[2] + 0.002 + 0.15),
                     normal=(1.0, 0.0, 0.0), u=(0.0, 0.0, 1.0),
                     half_extents=(0.15, bar_half_y))
    x_start = float(foot[0])
    if case.periodic:
        if width < 2 * (2 * 0.5 * dmax + 0.1 * dmax) * 1.05:
            raise dpm.ParameterError(
                f"grate: --width {case.width} with --periodic gives a period of "
                f"{width * 1e3:.1f} mm, under two contact cells (2 (d_max + skin)); "
                "use --width >= 3")
        sim.set_periodic("y", -half_w, half_w)
    else:
        for s in (-1, 1):  # side walls of the particles' own material (sec. 4.3)
            sim.add_boundary("plane", material=part, point=(0.0, s * half_w, 0.0),
                             normal=(0.0, -s, 0.0))
    # the initial bed: a lattice over the bars up to bed_height above the exposed top
    x0, x1 = x_start, float(geo.end[0])
    zlo = float(geo.surface(np.array([x1 - 1e-3]))[0])
    zhi = float(geo.top_start[0, 2]) + case.bed_height + dmax
    spacing = 1.05 * dmax
    pts = dpm.lattice((x0, -half_w, zlo), (x1, half_w, zhi), spacing=spacing,
                      jitter=0.02 * dmin, seed=case.seed)
    if len(pts) == 0 or case.width < 1.0:
        raise dpm.ParameterError(f"grate: --width {case.width} must be >= 1 particle "
                                 "diameter")
    if not case.periodic:
        pts = pts[np.abs(pts[:, 1]) <= half_w - 0.5 * dmax]
    surf = geo.surface(pts[:, 0])
    above = pts[:, 2] - surf
    keep = ((above > 0.5 * dmax) & (above < case.bed_height) &
            (geo.slab_distance(pts) > 0.55 * dmax) & (pts[:, 0] > x0 + 0.6 * dmax))
    pts = pts[keep]
    rng = np.random.default_rng(case.seed)
    radii = 0.5 * rng.uniform(dmin, dmax, len(pts)) if dmax > dmin else 0.5 * dmin
    bed_ids = sim.add_particles("sphere", material=part, radius=radii, positions=pts)
    # the time step: the thesis' 1e-3 s (sec. 4.4) where it resolves the shortest contact
    # (the smallest particle on a bar) with MIN_STEPS steps, else halved until it does
    contact = sim.time_step_report().contact_time
    dt = DT
    while contact is not None and contact < MIN_STEPS * dt:
        dt *= 0.5
    sim.dt = dt
    # feed: a constant mass rate, scaled with the width (eq. 4.1), falling onto bar 1
    mass_flow = case.mass_flow_kg_h / 3600.0 * width / GRATE_WIDTH
    if case.fast_bars:
        mass_flow *= SPEED_UP
    f0 = foot + 0.6 * dmax * geo.a
    f1 = f0 + 0.3 * BAR_LENGTH * geo.a
    zf = max(f0[2], f1[2]) + case.bed_height + 1.5 * dmax
    # (the inlet places bodies clear of the side walls itself)
    region = dpm.BoxRegion((min(f0[0], f1[0]), -half_w, zf), (max(f0[0], f1[0]), half_w,
                                                              zf + 1.2 * dmax))
    every = min(0.1 * case.cycle, 1.0)
    shape = dict(radius=(0.5 * dmin, 0.5 * dmax)) if dmax > dmin else dict(radius=0.5 * dmin)
    inlet = sim.add_inlet(region, part, mass_rate=mass_flow, every=every, seed=case.seed,
                          **shape)
    # outlet: past and below the end of the last bar
    e = geo.end
    outlet = sim.add_outlet(dpm.BoxRegion((e[0] + 0.5 * dmin, -1, e[2] - 1.0),
                                          (e[0] + 1.0, 1, e[2] - 0.5 * dmax)), every=0.05)
    if output:
        sim.output(output, every=10 * case.cycle, overwrite=True)
    info = dict(geo=geo, width=width, mass_flow=mass_flow, bed_ids=np.asarray(bed_ids),
                inlet=inlet, outlet=outlet, dmax=dmax, dmin=dmin,
                bed_mass=float(sim.bodies.mass.sum()))
    return sim, info


def bed_profile(sim: dpm.Simulation, geo: Geometry, nbins: int) -> np.ndarray:
    """Bed height per pitch of the grate: the highest particle top above the exposed bar
    surface (at rest) in each bin of one pitch along the grate."""
    b = sim.bodies
    p = b.position
    k = np.floor(geo.along(p) / geo.pitch).astype(int)
    top = p[:, 2] + b.radius - geo.surface(p[:, 0])
    out = np.zeros(nbins)
    for i in range(nbins):
        sel = (k == i) & np.isfinite(top)
        out[i] = top[sel].max() if np.any(sel) else 0.0
    return out


def run_case(case: Case, log: bool = True) -> dict:
    """Run ``case``: warm-up, the tracer window, then on until 98 % of the tracers' mass
    has left (or ``max_cycles``); returns the figures."""
    sim, info = build(case)
    geo, inlet, outlet = info["geo"], info["inlet"], info["outlet"]
    T = case.cycle
    t_warm, t_tracer = case.warmup_cycles * T, (case.warmup_cycles + case.tracer_cycles) * T
    t_max = case.max_cycles * T
    dt_sample = case.sample_every * T
    nbins = geo.bins
    sim.run(steps=1, progress=False)  # compile or load the kernels; the clock starts after
    t0 = time.perf_counter()
    steps0 = sim.step_count
    prof, counts, lacey_t, lacey_m, times = [], [], [], [], []
    particle_steps = 0.0
    worst = 0.0
    tracer_ids = np.zeros(0, np.int64)
    cell = (3 * info["dmax"], 1.0, 2 * info["dmax"])
    while sim.time < t_max - 1e-9:
        n_before = len(sim.bodies)
        sim.run(until=min(sim.time + dt_sample, t_max), progress=False)
        particle_steps += 0.5 * (n_before + len(sim.bodies)) * dt_sample / sim.dt
        times.append(sim.time)
        counts.append(len(sim.bodies))
        worst = max(worst, sim.backend.max_overlap()[0])
        if sim.time >= t_warm:
            prof.append(bed_profile(sim, geo, nbins))
        fed = np.concatenate(inlet.ids) if inlet.ids else np.zeros(0, np.int64)
        born = _birth_of(sim, inlet, fed)
        tracer_ids = fed[(born >= t_warm) & (born < t_tracer)]
        if len(tracer_ids) >= 5 and sim.time > t_tracer:
            frame = {"position": sim.bodies.position, "id": sim.bodies.id,
                     "mass": sim.bodies.mass}
            on = np.isin(sim.bodies.id, tracer_ids)
            if 0 < on.sum() < len(on):
                lacey_t.append(sim.time)
                lacey_m.append(an.lacey(frame, set(tracer_ids.tolist()), cell, min_count=3)["M"])
        if sim.time > t_tracer:
            rec = outlet.records
            out_mass = rec["mass"][np.isin(rec["id"], tracer_ids)].sum()
            tracer_mass = _tracer_mass(sim, outlet, tracer_ids)
            if tracer_mass > 0 and out_mass >= 0.98 * tracer_mass:
                break
    wall = time.perf_counter() - t0
    steps = sim.step_count - steps0
    rec = outlet.records
    sel = np.isin(rec["id"], tracer_ids)
    trec = {k: np.asarray(v)[sel] for k, v in rec.items()}
    rtd = an.residence_times(trec, mass_weighted=True)
    rtd_n = an.residence_times(trec)
    tracer_mass = _tracer_mass(sim, outlet, tracer_ids)
    balance = mass_balance(sim, info)
    prof_arr = np.asarray(prof) if prof else np.zeros((1, nbins))
    result = {
        "case": {k: v for k, v in case.__dict__.items() if k != "extra"},
        "bar_speed_m_s": case.speed, "pause_s": case.pause, "cycle_s": T,
        "width_m": info["width"], "mass_flow_sim_kg_s": info["mass_flow"],
        "pitch_m": geo.pitch, "step_m": geo.step, "exposed_m": geo.exposed,
        "dt_s": sim.dt, "simulated_s": sim.time, "steps": int(steps), "wall_s": wall,
        "particle_steps_per_s": particle_steps / max(wall, 1e-9),
        "bodies_mean": float(np.mean(counts)) if counts else 0.0,
        "tracers": int(len(tracer_ids)), "tracers_out": int(sel.sum()),
        "tracer_mass_out_fraction": float(trec["mass"].sum() / tracer_mass)
        if tracer_mass > 0 else 0.0,
        "mean_residence_s": rtd.mean, "mean_residence_number_s": rtd_n.mean,
        "std_residence_s": float(np.sqrt(rtd.variance)) if len(rtd) else float("nan"),
        "residence_samples": rtd.samples.tolist(), "residence_weights": rtd.weights.tolist(),
        "bed_height_m": prof_arr.mean(axis=0).tolist(),
        # the bed proper: the first 8 pitches (the backward grate's last bar is a bare chute)
        "bed_height_mean_m": float(prof_arr[:, :8].mean()),
        "bodies_t": times, "bodies_n": counts,
        "lacey_t": lacey_t, "lacey_M": lacey_m,
        "mass_balance": balance, "largest_overlap_over_radius": worst,
        "final_bed": np.c_[sim.bodies.position[:, [0, 2]], sim.bodies.radius,
                           np.isin(sim.bodies.id, tracer_ids)].round(5).tolist(),
        "bars": {"centre": geo.centre[:, [0, 2]].tolist(), "a": geo.a[[0, 2]].tolist(),
                 "n": geo.n[[0, 2]].tolist(), "moving": geo.moving.tolist()},
    }
    if log:
        dpm.notice(f"{label_of(case)}: {len(tracer_ids)} tracers, {sel.sum()} out "
                   f"({result['tracer_mass_out_fraction']:.0%} of their mass), t_m = "
                   f"{rtd.mean:.1f} s (std {result['std_residence_s']:.1f} s), bed "
                   f"{result['bed_height_mean_m'] * 1e3:.0f} mm, "
                   f"{result['bodies_mean']:.0f} bodies, "
                   f"{sim.time:.0f} s simulated in "
                   f"{wall:.0f} s; balance {'ok' if balance['exact'] else 'BROKEN'}", flush=True)
    return result


def _birth_of(sim: dpm.Simulation, inlet: dpm.Inlet, ids: np.ndarray) -> np.ndarray:
    """Insertion time of the inlet's bodies ``ids`` (on the grate: their birth; removed:
    removal time - residence time from the outlet and escape records)."""
    t = np.full(len(ids), np.inf)
    b = sim.bodies
    pos = {int(i): k for k, i in enumerate(b.id)}
    for j, i in enumerate(ids):
        k = pos.get(int(i))
        if k is not None:
            t[j] = b.birth[k]
    for rec in [o.records for o in sim.outlets] + [sim.escaped.records]:
        if len(rec.get("id", [])):
            m = {int(i): float(tt - rt) for i, tt, rt in zip(rec["id"], rec["time"],
                                                           rec["residence_time"], strict=True)}
            for j, i in enumerate(ids):
                if int(i) in m:
                    t[j] = m[int(i)]
    return t


def _tracer_mass(sim: dpm.Simulation, outlet: dpm.Outlet, ids: np.ndarray) -> float:
    on = sim.bodies.mass[np.isin(sim.bodies.id, ids)].sum()
    out = outlet.records["mass"][np.isin(outlet.records["id"], ids)].sum()
    esc = sim.escaped.records
    lost = np.asarray(esc["mass"])[np.isin(esc["id"], ids)].sum() if len(esc.get("id", [])) \
        else 0.0
    return float(on + out + lost)


def mass_balance(sim: dpm.Simulation, info: dict) -> dict:
    """Fed (initial bed + inlet) against discharged (outlet; escaped) + on the grate, by
    ids and by mass: ``exact`` when the id sets agree (no body lost or counted twice)."""
    inlet, outlet = info["inlet"], info["outlet"]
    fed = np.concatenate([info["bed_ids"], *inlet.ids]) if inlet.ids else info["bed_ids"]
    out = np.asarray(outlet.records["id"], np.int64)
    esc = np.asarray(sim.escaped.records.get("id", np.zeros(0)), np.int64)
    on = np.asarray(sim.bodies.id, np.int64)
    gone = np.concatenate([out, esc, on])
    exact = bool(len(gone) == len(np.unique(gone)) and
                 np.array_equal(np.sort(fed), np.sort(gone)))
    return {"fed": int(len(fed)), "discharged": int(len(out)), "escaped": int(len(esc)),
            "on_grate": int(len(on)), "exact": exact,
            "fed_mass_kg": float(inlet.inserted_mass + info["bed_mass"]),
            "discharged_mass_kg": float(outlet.records["mass"].sum()),
            "on_grate_mass_kg": float(sim.bodies.mass.sum())}


def label_of(case: Case) -> str:
    return case.label or (f"{case.grate} {case.material} {case.mass_flow_kg_h:g} kg/h "
                          f"{'35' if case.fast_bars else '3.5'} mm/s width {case.width:g}"
                          f"{' periodic' if case.periodic else ''}")


def picture(results: list[dict], path: Path, title: str) -> None:
    """E(t), F(t), mean residence time, bed height and Lacey index of the runs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    ax_e, ax_f, ax_h, ax_m = axes.ravel()
    means = [r["mean_residence_s"] for r in results if r["residence_samples"]]
    # runs whose mean residence times differ by more than 3x: time over each run's t_m
    scaled = len(means) > 1 and max(means) > 3 * min(means)
    for k, r in enumerate(results):
        c = f"C{k % 10}"
        lab = label_of(Case(**{kk: v for kk, v in r["case"].items()}))
        t = np.asarray(r["residence_samples"])
        w = np.asarray(r["residence_weights"])
        if len(t) < 2:
            continue
        unit = r["mean_residence_s"] if scaled else 1.0
        rtd = an.ResidenceTimes(t / unit, w, r["mean_residence_s"] / unit,
                                r["std_residence_s"] ** 2 / unit**2)
        edges, dens = rtd.E(bins=min(20, max(5, len(t) // 8)))
        ax_e.stairs(dens, edges, color=c, label=f"{lab}: t_m {r['mean_residence_s']:.0f} s")
        tt = np.linspace(0, t.max() / unit * 1.05, 400)
        ax_f.plot(tt, rtd.F(tt), color=c, label=lab)
        ax_e.axvline(r["mean_residence_s"] / unit, color=c, ls=":", lw=1)
        h = np.asarray(r["bed_height_m"]) * 1e3
        ax_h.plot(np.arange(len(h)) + 0.5, h, "o-", color=c, ms=3, label=lab)
        if r["lacey_t"]:
            ax_m.plot(np.asarray(r["lacey_t"]) / r["cycle_s"], r["lacey_M"], color=c, label=lab)
    tlabel = "t / t_m (each run's mass mean)" if scaled else "residence time t [s]"
    ax_e.set_xlabel(tlabel)
    ax_e.set_ylabel("E (mass, eq. 4.11)" + ("" if scaled else " [1/s]"))
    ax_e.legend(fontsize=7)
    ax_f.set_xlabel(tlabel)
    ax_f.set_ylabel("F(t) (eq. 4.12)")
    ax_f.set_ylim(0, 1.02)
    ax_h.set_xlabel("position along the grate [bar pitches from the feed]")
    ax_h.set_ylabel("bed height above the bars [mm]")
    ax_m.set_xlabel("time [bar cycles]")
    ax_m.set_ylabel("Lacey index of the tracers in the bed")
    ax_m.set_ylim(-0.1, 1.1)
    for ax in (ax_f, ax_h, ax_m):
        ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    side_views(results, path.with_name(path.stem + "_bed.png"), plt)


def side_views(results: list[dict], path: Path, plt) -> None:
    """The bed at the end of each run, seen from the side (bars at rest; moving bars red,
    tracers filled)."""
    fig, axes = plt.subplots(len(results), 1, figsize=(10, 2.6 * len(results)),
                             squeeze=False)
    for ax, r in zip(axes[:, 0], results, strict=True):
        bars = r["bars"]
        a, n = np.asarray(bars["a"]), np.asarray(bars["n"])
        for c, mv in zip(np.asarray(bars["centre"]), bars["moving"], strict=True):
            q = np.array([c + sa * 0.5 * BAR_LENGTH * a + sb * 0.5 * BAR_HEIGHT * n
                          for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
            ax.fill(q[:, 0], q[:, 1], color="C3" if mv else "0.4", alpha=0.6, lw=0)
        for x, z, rad, tr in r["final_bed"]:
            ax.add_patch(plt.Circle((x, z), rad, fill=bool(tr), color="C0", lw=0.5))
        ax.set_aspect("equal")
        ax.set_title(f"{label_of(Case(**r['case']))}, t = {r['simulated_s']:.0f} s", fontsize=8)
        ax.set_xlabel("x [m]", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


#: the documented sets of runs (``--set NAME``); each a list of Case keyword dicts
SETS = {
    "quick": [dict(grate="backward", material="wood", mass_flow_kg_h=40.0, fast_bars=True,
                   warmup_cycles=2.0, tracer_cycles=10.0, max_cycles=45.0, bed_height=0.03)],
    "validation": [dict(grate="forward", material="clay", mass_flow_kg_h=20.0, fast_bars=True),
                   dict(grate="backward", material="clay", mass_flow_kg_h=20.0, fast_bars=True),
                   dict(grate="backward", material="wood", mass_flow_kg_h=40.0, fast_bars=True),
                   dict(grate="backward", material="ceramic", mass_flow_kg_h=60.0,
                        fast_bars=True)],
    "mass_flow": [dict(grate="backward", material="clay", mass_flow_kg_h=m, fast_bars=True)
                  for m in (20.0, 40.0, 60.0)],
    "width": [dict(grate="forward", material="clay", mass_flow_kg_h=20.0, fast_bars=True,
                   width=w, periodic=p) for w, p in ((1.0, False), (4.0, False), (4.0, True))],
    # the bar speed: the thesis' 10x speed-up (sec. 3.9.4) against the plant's 3.5 mm/s
    "speed": [dict(grate="backward", material="wood", mass_flow_kg_h=40.0, fast_bars=True),
              dict(grate="backward", material="wood", mass_flow_kg_h=40.0, fast_bars=False,
                   warmup_cycles=3.0, tracer_cycles=20.0, max_cycles=130.0)],
}


def compact_json(doc: dict) -> str:
    """JSON of ``doc`` with floats to 6 significant digits, one run per line."""

    def rnd(x):
        if isinstance(x, float):
            return float(f"{x:.6g}")
        if isinstance(x, dict):
            return {k: rnd(v) for k, v in x.items()}
        if isinstance(x, list | tuple):
            return [rnd(v) for v in x]
        return x

    d = rnd(doc)
    runs = ",\n  ".join(json.dumps(r, separators=(",", ":")) for r in d.pop("runs"))
    head = json.dumps(d)[:-1]
    return f'{head}, "runs": [\n  {runs}\n]}}\n'


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one short run (CI)")
    p.add_argument("--set", choices=sorted(SETS), action="append",
                   help="documented set(s) of runs (default: all but quick)")
    p.add_argument("--grate", choices=sorted(GRATES), help="one run of this grate")
    p.add_argument("--material", choices=sorted(MATERIALS), default="clay")
    p.add_argument("--mass-flow", type=float, default=20.0, help="feed [kg/h], whole grate")
    p.add_argument("--fast-bars", action="store_true", help="35 mm/s instead of 3.5 mm/s")
    p.add_argument("--width", type=float, default=1.0, help="in largest diameters")
    p.add_argument("--periodic", action="store_true", help="periodic side faces")
    p.add_argument("--cycles", type=float, default=None, help="max bar cycles of a run")
    p.add_argument("--integrator", default="position_verlet")
    p.add_argument("--output", default=".", help="directory for the files (default .)")
    p.add_argument("--replot", action="store_true",
                   help="redraw the pictures of the grate_*.json in --output, no runs")
    a = p.parse_args(argv)
    out = Path(a.output)
    out.mkdir(parents=True, exist_ok=True)
    if a.replot:
        docs = {}
        for f in sorted(out.glob("grate_*.json")):
            doc = json.loads(f.read_text())
            picture(doc["runs"], f.with_suffix(".png"), f"grate: {doc['set']}")
            docs[doc["set"]] = doc
        return docs
    if a.quick:
        sets = {"quick": SETS["quick"]}
    elif a.grate:
        one = dict(grate=a.grate, material=a.material, mass_flow_kg_h=a.mass_flow,
                   fast_bars=a.fast_bars, width=a.width, periodic=a.periodic,
                   integrator=a.integrator)
        if a.cycles:
            one["max_cycles"] = a.cycles
        sets = {"run": [one]}
    else:
        sets = {name: SETS[name] for name in (a.set or [n for n in SETS if n != "quick"])}
    summary: dict = {}
    done: dict = {}  # a case that two sets share runs once
    for name, cases in sets.items():
        results = []
        for kw in cases:
            key = json.dumps(kw, sort_keys=True)
            if key not in done:
                done[key] = run_case(Case(**kw))
            results.append(done[key])
        doc = {"set": name, "dt": DT, "runs": results}
        if dpm.is_root():  # (rank 0 writes: every rank holds the result)
            (out / f"grate_{name}.json").write_text(compact_json(doc))
            picture(results, out / f"grate_{name}.png", f"grate: {name}")
        summary[name] = doc
    return summary


if __name__ == "__main__":
    main()
