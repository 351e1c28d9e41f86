"""Integrators: order of accuracy, work-precision, the DPM thesis' implicit-method cases.

Studies (DPM thesis, Samiei 2012, §2.7.6 and §3.9; every reference is analytic except the
hopper's, which is the run at the smallest step):

1. collision: a sphere (glass, 2520 kg/m3, d = 8 mm) hits a plane head-on at 0.5 m/s, no
   damping, no gravity, linear contact k = 250 N/m or Hertz (E = 1e6 Pa, nu = 0.3); errors
   of the rebound velocity (= restitution) and position after the contact, and of the
   largest overlap, against the contact resolution CR = t_c / dt from 1.2 to 200 (worst of
   three phases of the contact start within a step), with the observed order (slope of
   log error against log CR for CR >= 10) and the CPU time per collision: 2000 identical
   independent collisions advanced by one ``run(steps=N)`` call (work-precision).
2. sandwich: the sphere between two planes one diameter apart, 15 % initial overlap
   (x = R + 0.15 R cos(omega t)), 0.45 s at dt = 1e-4, 1e-3, 3.5e-3 s and a sweep; the
   largest error relative to the amplitude.
3. contact detection: the sphere approaches the plane at 0.5 m/s with the contact starting
   at a fraction of a step; largest overlap against that fraction (CR 1.3, 2, 3) and
   against CR (fraction 0).
4. hopper: a flat hopper (one particle deep, walls at 30 deg, 6 cm outlet) of 400
   polydisperse steel spheres (d 8-12 mm, 7850 kg/m3, k = 1000 N/m, no damping, no
   friction), settled with the outlet closed, then discharging under gravity for 1.5 s;
   the mass-weighted mean residence time against dt, whether every particle stayed inside
   the walls, the largest speed, and the CPU time.

The engine's tunnelling guard (a run stops when a body moves more than half its radius in
a step) is recorded separately: where it fires, the measurement is repeated with the
guard off on that instance, so that the integrator's own error or stability is reported.

Run ``python benchmarks/integrators.py`` (``--quick`` for a short run; ``--only collision``
etc.); writes benchmarks/results/integrators[_quick].json and .png.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import harness
import numpy as np

import dpm

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

EXPLICIT = ["symplectic_euler", "taylor", "position_verlet", "velocity_verlet", "gear4", "gear5"]
IMPLICIT = ["backward_euler", "newmark_beta", "numerov"]
ALL = EXPLICIT + IMPLICIT

R = 4e-3
RHO = 2520.0
K_LIN = 250.0
E_HERTZ = 1e6
NU = 0.3
V0 = 0.5
MASS = 4.0 / 3.0 * math.pi * R**3 * RHO


def linear_reference() -> dict:
    w = math.sqrt(K_LIN / MASS)
    return dict(tc=math.pi / w, dmax=V0 / w)


def hertz_reference() -> dict:
    """Elastic Hertz sphere-plane impact (Johnson 1985 §11.4), plane of the same material."""
    es = 1.0 / (2.0 * (1.0 - NU**2) / E_HERTZ)
    k = 4.0 / 3.0 * es * math.sqrt(R)
    dmax = (5.0 * MASS * V0**2 / (4.0 * k)) ** 0.4
    # t_c = 2.9432 dmax / v (integral of the Hertz collision)
    return dict(tc=2.943214 * dmax / V0, dmax=dmax)


def _sim(integrator: str, dt: float, law: str, guard: bool = True,
         **kw) -> tuple[dpm.Simulation, dpm.Material]:
    """A scene without bodies. ``guard=False`` switches off the engine's tunnelling guard
    (``Simulation.speed_guard``: a run stops when a body moves more than half its radius
    in a step) on this instance only, so that an integrator's own error can be measured
    where the guard would stop the run; the guarded runs record whether it fires."""
    sim = dpm.Simulation(dt=dt, integrator=integrator, dt_check="off", max_overlap=2.0,
                         threads=1, **kw)
    if not guard:
        sim.speed_guard = False
    if law == "linear":
        m = dpm.Material("glass", density=RHO)
        sim.contact(m, m, model="linear_spring_dashpot", stiffness=K_LIN, restitution=1.0,
                    friction=0.0)
    else:
        m = dpm.Material("glass", density=RHO, young=E_HERTZ, poisson=NU)
        sim.contact(m, m, model="hertz_mindlin", restitution=1.0, friction=0.0)
    return sim, m


def _impacts(integrator: str, law: str, dt: float, t0: float, n: int,
             guard: bool) -> dpm.Simulation:
    """``n`` identical spheres on a square grid 5 R apart (they never touch), each moving
    at -v0 towards its own spot of the plane z = 0, reached at t0; forces primed."""
    sim, m = _sim(integrator, dt, law, guard)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    side = int(math.ceil(math.sqrt(n)))
    ij = np.array([(i % side, i // side) for i in range(n)], float) * 5 * R
    pos = np.c_[ij, np.full(n, R + V0 * t0)]
    sim.add_particles("sphere", material=m, radius=R, positions=pos,
                      velocities=np.tile([0.0, 0.0, -V0], (n, 1)))
    sim.run(steps=0, progress=False)  # initial forces, integrator start (untimed)
    return sim


def _guard_fires(integrator: str, law: str, dt: float, t0: float, nsteps: int) -> bool:
    try:
        _impacts(integrator, law, dt, t0, 1, guard=True).run(steps=nsteps, progress=False)
    except dpm.UnstableRunError:
        return True
    return False


def collision(integrator: str, law: str, cr: float, phase: float, n: int,
              reps: int) -> dict:
    """Head-on collisions with a plane at z = 0; the contact starts ``phase`` x dt after
    t = 0. Velocity error |v_after - v0| / v0 (= restitution error), position error
    |z - z_exact| / largest overlap after the run, both the worst over the ``n`` spheres
    of one ``run(steps=N)`` call covering the whole contact; largest overlap error from a
    one-sphere run stepped one step per call; CPU time (process time, one thread) of the
    ``run(steps=N)`` call divided by ``n``, the least of ``reps`` repetitions; all with
    the tunnelling guard off, ``guard`` = whether it would have stopped the run."""
    ref = linear_reference() if law == "linear" else hertz_reference()
    tc = ref["tc"]
    dt = tc / cr
    t0 = phase * dt
    nsteps = int(math.ceil((t0 + tc) / dt)) + 2
    cpu = math.inf
    ok = True
    for _ in range(reps):
        sim = _impacts(integrator, law, dt, t0, n, guard=False)
        c = time.process_time()
        try:
            sim.run(steps=nsteps, progress=False)
        except dpm.UnstableRunError:
            ok = False
        cpu = min(cpu, time.process_time() - c)
        if not ok:
            break
    b = sim.bodies
    ok = ok and bool(np.all(np.isfinite(b.position)))
    t_end = sim.time
    z_exact = R + V0 * (t_end - t0 - tc)
    v_err = float(np.max(np.abs(b.velocity[:, 2] - V0))) / V0 if ok else math.inf
    x_err = float(np.max(np.abs(b.position[:, 2] - z_exact))) / ref["dmax"] if ok else math.inf
    one = _impacts(integrator, law, dt, t0, 1, guard=False)
    worst = 0.0
    for _ in range(nsteps):
        try:
            one.run(steps=1, progress=False)
        except dpm.UnstableRunError:
            worst = math.inf
            break
        worst = max(worst, R - one.bodies.position[0, 2])
    ov_err = abs(worst - ref["dmax"]) / ref["dmax"] if np.isfinite(worst) else math.inf
    return dict(ok=ok, v_err=v_err, x_err=x_err, overlap_err=ov_err, cpu=cpu / n,
                steps=nsteps, guard=_guard_fires(integrator, law, dt, t0, nsteps))


def observed_order(cr: list[float], err: list[float], low: float = 10.0) -> float:
    """Slope of log(error) against log(CR) over CR >= low (finite, non-zero errors)."""
    pts = [(math.log(c), math.log(e)) for c, e in zip(cr, err, strict=True)
           if c >= low and 0 < e < math.inf]
    if len(pts) < 2:
        return float("nan")
    x, y = np.array(pts).T
    return float(-np.polyfit(x, y, 1)[0])


def study_collision(quick: bool) -> dict:
    crs = [1.2, 2, 3, 5, 10, 20, 50, 100, 200] if not quick else [1.2, 2, 5, 10, 20, 50]
    phases = [0.13, 0.47, 0.81] if not quick else [0.13, 0.81]
    n = 2000 if not quick else 400
    reps = 3 if not quick else 2
    keys = ("v_err", "x_err", "overlap_err")
    out: dict = dict(crs=crs, phases=phases, spheres_per_run=n, reps=reps)
    for law in ("linear", "hertz"):
        out[law] = {}
        for integ in ALL:
            rows = []
            collision(integ, law, 20, 0.5, 50, 1)  # warm-up: compiles every kernel used
            for cr in crs:
                rs = [collision(integ, law, cr, ph, n, reps) for ph in phases]
                rows.append({k: max(r[k] for r in rs) for k in keys}
                            | dict(cr=cr, cpu=float(np.mean([r["cpu"] for r in rs])),
                                   steps=max(r["steps"] for r in rs),
                                   ok=all(r["ok"] for r in rs),
                                   guard=any(r["guard"] for r in rs)))
            order = {k: observed_order([r["cr"] for r in rows], [r[k] for r in rows])
                     for k in keys}
            out[law][integ] = dict(rows=rows, order=order)
            r10 = rows[crs.index(10)]
            print(f"collision {law:6s} {integ:16s} order v {order['v_err']:.2f} "
                  f"x {order['x_err']:.2f}; CR 10: v_err {r10['v_err']:.2e} "
                  f"cpu/collision {r10['cpu'] * 1e6:.2f} us; guard at CR "
                  f"{[r['cr'] for r in rows if r['guard']]}", flush=True)
    return out


def sandwich(integrator: str, dt: float, duration: float = 0.45) -> dict:
    """Largest |x - x_exact| / (0.15 R) over the run (inf if the run failed)."""
    sim, m = _sim(integrator, dt, "linear", overlap_tolerance=0.2)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_boundary("plane", material=m, point=(0, 0, 2 * R), normal=(0, 0, -1))
    sim.add_particles("sphere", material=m, radius=R, positions=[[0, 0, 1.15 * R]])
    w = math.sqrt(K_LIN / MASS)
    n = int(round(duration / dt))
    err = 0.0
    cpu = 0.0
    chunk = max(1, n // 200)
    done = 0
    status = "ok"
    try:
        while done < n:
            k = min(chunk, n - done)
            t = time.process_time()
            sim.run(steps=k, progress=False)
            cpu += time.process_time() - t
            done += k
            exact = R + 0.15 * R * math.cos(w * sim.time)
            err = max(err, abs(sim.bodies.position[0, 2] - exact) / (0.15 * R))
        ok = bool(np.all(np.abs(sim.bodies.position[:, 2] - R) < R))
        if not ok:
            status = "left the gap"
    except dpm.UnstableRunError as e:
        ok = False
        status = f"stopped at t = {sim.time:.4g} s: " + str(e).split(": ", 1)[1][:90]
    return dict(dt=dt, err=err if ok else math.inf, ok=ok, cpu=cpu, status=status)


def study_sandwich(quick: bool) -> dict:
    dts = [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 3.5e-3] if not quick else [1e-4, 1e-3, 3.5e-3]
    duration = 0.45 if not quick else 0.1
    out = {}
    for integ in ALL:
        out[integ] = [sandwich(integ, dt, duration) for dt in dts]
        print(f"sandwich {integ:16s} " + " ".join(f"{r['dt']:.0e}:{r['err']:.2e}"
                                                  for r in out[integ]), flush=True)
    return dict(dts=dts, duration=duration, runs=out, contact_time=linear_reference()["tc"])


def approach(integrator: str, cr: float, phase: float, guard: bool) -> float:
    """Largest overlap / analytic largest overlap of a sphere approaching a plane (inf:
    the run stopped; with ``guard`` on that is the tunnelling guard or a NaN)."""
    ref = linear_reference()
    dt = ref["tc"] / cr
    sim, m = _sim(integrator, dt, "linear", guard)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    # two free steps, then the contact starts phase x dt into the third
    t0 = (2.0 + phase) * dt
    sim.add_particles("sphere", material=m, radius=R, positions=[[0, 0, R + V0 * t0]],
                      velocities=[[0, 0, -V0]])
    worst = 0.0
    try:
        for _ in range(int(math.ceil((t0 + ref["tc"]) / dt)) + 2):
            sim.run(steps=1, progress=False)
            worst = max(worst, R - sim.bodies.position[0, 2])
    except dpm.UnstableRunError:
        return math.inf
    return worst / ref["dmax"] if np.isfinite(worst) else math.inf


def study_detection(quick: bool) -> dict:
    phases = [float(p) for p in np.linspace(0.0, 0.95, 20 if not quick else 6)]
    crs = [1.3, 1.5, 2, 3, 5, 10, 20] if not quick else [1.3, 2, 5, 10]
    integs = ["symplectic_euler", "position_verlet", "velocity_verlet", "gear4", "gear5",
              "newmark_beta", "numerov", "backward_euler"]
    out: dict = dict(phases=phases, crs=crs, by_phase={}, by_cr={}, guard_by_phase={},
                     guard_by_cr={})
    for integ in integs:
        out["by_phase"][integ] = {str(cr): [approach(integ, cr, p, False) for p in phases]
                                  for cr in (1.3, 2, 3)}
        out["guard_by_phase"][integ] = {
            str(cr): [not math.isfinite(approach(integ, cr, p, True)) for p in phases]
            for cr in (1.3, 2, 3)}
        out["by_cr"][integ] = [approach(integ, cr, 0.0, False) for cr in crs]
        out["guard_by_cr"][integ] = [not math.isfinite(approach(integ, cr, 0.0, True))
                                     for cr in crs]
        bp, gp = out["by_phase"][integ], out["guard_by_phase"][integ]
        print(f"detection {integ:16s} " + " ".join(
            f"CR {c}: {min(bp[c]):.3f}-{max(bp[c]):.3f} (guard {sum(gp[c])}/{len(phases)})"
            for c in bp), flush=True)
    return out


# ------------------------------------------------------------------------------ hopper
#: inclination of the hopper walls from horizontal [deg] (60 makes a 0.7 m column of 2000
#: spheres: at k = 1000 N/m its weight alone drives overlaps beyond 1.5 r)
ANGLE = 30.0
HOPPER_K = 1000.0
STEEL = 7850.0


def hopper_scene(n: int, outlet: float, seed: int = 1, angle: float | None = None,
                 settle: float = 0.6) -> dict:
    """A flat hopper: a V of two planes at ``angle`` deg from horizontal meeting an outlet of
    width ``outlet`` at z = 0, front and back planes 1.1 d_max apart (one particle deep).
    The V is filled from just above the outlet on a square grid of pitch 1.05 d_max
    (x jittered by +-2 % d_max), every site at least 1.05 r_max inside the inclined walls,
    so that particles start at most a few mm apart; radii uniform in [4, 6] mm."""
    rng = np.random.default_rng(seed)
    dmax = 12e-3
    pitch = 1.05 * dmax
    half = outlet / 2
    angle = ANGLE if angle is None else angle
    s, c = math.sin(math.radians(angle)), math.cos(math.radians(angle))
    pos: list[list[float]] = []
    z = 0.6 * dmax
    while len(pos) < n:
        # inside both walls by 1.05 r_max: |x| <= half + (z c - 1.05 r_max) / s
        xmax = half + (z * c - 1.05 * dmax / 2) / s
        k = int(math.floor(xmax / pitch))
        xs = np.arange(-k, k + 1) * pitch if xmax > 0 else np.zeros(0)
        for x in xs:
            if len(pos) < n:
                pos.append([x + rng.uniform(-0.02, 0.02) * dmax, 0.0, z])
        z += pitch
    radii = rng.uniform(4e-3, 6e-3, n)
    scene = dict(positions=np.array(pos), radii=radii, outlet=outlet, depth=1.1 * dmax,
                 height=float(z), angle=angle)
    if settle > 0:
        scene["positions"] = _settle(scene, settle)
    return scene


def _walls(sim: dpm.Simulation, steel: dpm.Material, scene: dict) -> None:
    half = scene["outlet"] / 2
    s, c = math.sin(math.radians(scene["angle"])), math.cos(math.radians(scene["angle"]))
    # inclined planes through (+-half, 0, 0), normals pointing up and inwards
    sim.add_boundary("plane", material=steel, point=(half, 0, 0), normal=(-s, 0, c))
    sim.add_boundary("plane", material=steel, point=(-half, 0, 0), normal=(s, 0, c))
    sim.add_boundary("plane", material=steel, point=(0, -scene["depth"] / 2, 0),
                     normal=(0, 1, 0))
    sim.add_boundary("plane", material=steel, point=(0, scene["depth"] / 2, 0),
                     normal=(0, -1, 0))


def _settle(scene: dict, duration: float) -> np.ndarray:
    """Let the grid settle for ``duration`` s with the outlet closed (a plane at z = 0)
    and damped contacts (e = 0.3, velocity Verlet, 25 steps per contact): a grid of
    undamped spheres released at once collapses into a granular gas whose shocks drive
    overlaps beyond 1.5 r at k = 1000 N/m. Returns the settled positions (the discharge
    starts from them at rest)."""
    m = STEEL * 4 / 3 * math.pi * 4e-3**3
    tc = math.pi / math.sqrt(HOPPER_K / (m / 2))
    sim = dpm.Simulation(dt=tc / 25, gravity=(0, 0, -9.81), dt_check="off", threads=1,
                         max_overlap=1.5)
    steel = dpm.Material("steel", density=STEEL)
    sim.contact(steel, steel, model="linear_spring_dashpot", stiffness=HOPPER_K,
                restitution=0.3, friction=0.0)
    _walls(sim, steel, scene)
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=steel, radius=scene["radii"],
                      positions=scene["positions"])
    sim.run(steps=int(round(duration / sim.dt)), progress=False)
    v = np.linalg.norm(sim.bodies.velocity, axis=1)
    scene["settle_max_speed"] = float(v.max())
    return sim.bodies.position.copy()


def park(sim: dpm.Simulation, idx: np.ndarray) -> None:
    """Move particles that left through the outlet far away, at rest and apart (planes are
    infinite: below the outlet the funnel planes go on and would catch them), and reset
    the integrator's per-body history of those particles."""
    b = sim.bodies
    b.position[idx] = np.c_[10.0 + 0.05 * idx, np.zeros(len(idx)), np.full(len(idx), -10.0)]
    b.velocity[idx] = 0.0
    b.angular_velocity[idx] = 0.0
    b.force[idx] = b.mass[idx, None] * sim.gravity
    b.torque[idx] = 0.0
    name = sim.integrator.name
    aux = sim.backend.aux
    if name == "position_verlet":
        aux[idx, 3:6] = np.nan  # != velocity: the kernel restarts the difference
    elif name in ("gear4", "gear5"):
        aux[idx] = 0.0
        aux[idx, 0:3] = sim.gravity
    elif name == "numerov":
        aux[idx, 0:3] = b.position[idx]
        aux[idx, 3:6] = sim.gravity


def hopper(integrator: str, dt: float, scene: dict, duration: float,
           guard: bool = True) -> dict:
    """Discharge for ``duration`` s (or until every particle left). Exit time: first
    sample (every 2 ms) with the centre below the outlet level z = 0 (the particle is
    then parked far away). ``escaped``: a particle
    was ever found behind an inclined wall or the front/back planes by more than its
    radius while above the outlet (sampled every 2 ms). ``max_speed``: the largest
    speed at those samples (the guard limit is 0.5 r / dt)."""
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, -9.81), integrator=integrator,
                         dt_check="off", max_overlap=1.5, overlap_tolerance=1.0, threads=1)
    if not guard:
        sim.speed_guard = False
    # (the particles that left are parked far away on purpose, :func:`park`: the escape
    # guard must not remove them, the arrays keep one row per particle)
    sim.guards.escape = "off"
    steel = dpm.Material("steel", density=STEEL)
    sim.contact(steel, steel, model="linear_spring_dashpot", stiffness=HOPPER_K,
                restitution=1.0, friction=0.0)
    half = scene["outlet"] / 2
    s, c = math.sin(math.radians(scene["angle"])), math.cos(math.radians(scene["angle"]))
    _walls(sim, steel, scene)
    sim.add_particles("sphere", material=steel, radius=scene["radii"],
                      positions=scene["positions"])
    sim.run(steps=0, progress=False)
    mass = sim.bodies.mass.copy()
    exit_time = np.full(len(mass), np.nan)
    escaped = 0.0
    cpu = 0.0
    vmax = 0.0
    n = int(round(duration / dt))
    every = max(1, int(round(2e-3 / dt)))
    done = 0
    status = "ok"
    try:
        while done < n:
            k = min(every, n - done)
            t = time.process_time()
            sim.run(steps=k, progress=False)
            cpu += time.process_time() - t
            done += k
            p = sim.bodies.position
            inside = np.isnan(exit_time)
            if not np.all(np.isfinite(p[inside])):
                status = "NaN"
                break
            vmax = max(vmax, float(np.max(np.linalg.norm(sim.bodies.velocity[inside], axis=1))))
            # the inclined planes are infinite and close the V below z = 0 (implicit
            # schemes take planes only): the outlet is a sink at z = 0 (6 cm wide)
            out = (p[:, 2] < 0.0) & inside
            exit_time[out] = sim.time
            gone = np.flatnonzero(~np.isnan(exit_time))
            if len(gone):
                park(sim, gone)
            above = (p[:, 2] > 0.0) & np.isnan(exit_time)
            d1 = (p[:, 0] - half) * -s + p[:, 2] * c
            d2 = (p[:, 0] + half) * s + p[:, 2] * c
            r = sim.bodies.radius
            behind = above & ((d1 < -r) | (d2 < -r))
            behind |= np.isnan(exit_time) & (np.abs(p[:, 1]) > scene["depth"] / 2 + r)
            if np.any(behind) and not escaped:
                escaped = sim.time
            if np.all(~np.isnan(exit_time)):
                break
    except dpm.UnstableRunError as err:
        status = f"stopped at t = {sim.time:.3f} s: " + str(err).split(": ", 1)[1][:100]
    done_frac = float(np.mean(~np.isnan(exit_time)))
    t_end = np.where(np.isnan(exit_time), sim.time, exit_time)
    tm = float(np.sum(mass * t_end) / np.sum(mass))
    iters = getattr(sim.integrator, "stats", None)
    return dict(dt=dt, mean_residence=tm, exited=done_frac, escaped=bool(escaped),
                escaped_at=escaped, status=status, cpu=cpu, steps=sim.step_count,
                t_end=sim.time, max_speed=vmax, guard_limit_speed=0.5 * 4e-3 / dt,
                newton=dict(iters) if iters else None)


HOPPER_PLAN = dict(
    # (integrator, [contact resolutions]); the reference is velocity_verlet at CR 50
    full=[("velocity_verlet", [50, 25, 10, 5, 3.2, 2.7]),
          ("symplectic_euler", [25, 10, 5, 3.2]),
          ("gear5", [25, 10, 5, 3.2]),
          ("newmark_beta", [25, 10, 5, 3.2, 2.7]),
          ("numerov", [25, 10, 5, 3.2, 2.7])],
    quick=[("velocity_verlet", [25, 10, 5]), ("newmark_beta", [25, 10, 5])])


def study_hopper(quick: bool, n: int | None = None, duration: float | None = None,
                 outlet: float | None = None) -> dict:
    # 400 spheres, 1.5 s: what fitted the time of the run reported in docs/integrators.md
    n = n or (400 if not quick else 150)
    duration = duration or (1.5 if not quick else 0.5)
    outlet = outlet or 6 * 10e-3
    scene = hopper_scene(n, outlet, settle=0.4)
    m = STEEL * 4 / 3 * math.pi * 4e-3**3
    tc = math.pi / math.sqrt(HOPPER_K / (m / 2))
    plan = HOPPER_PLAN["quick" if quick else "full"]
    out: dict = dict(n=n, duration=duration, outlet=outlet, height=scene["height"],
                     angle=scene["angle"], settle=0.4,
                     settle_max_speed=scene.get("settle_max_speed"),
                     contact_time=tc, plan=plan, runs={})
    for integ, crs in plan:
        out["runs"][integ] = []
        hopper(integ, tc / crs[0], scene, 0.004)  # warm-up: compiles the step kernels
        for cr in crs:
            r = hopper(integ, tc / cr, scene, duration)
            r["cr"] = cr
            if r["status"] != "ok" or r["escaped"]:
                # the same run without the tunnelling guard: do particles leave the walls?
                r["unguarded"] = hopper(integ, tc / cr, scene, duration, guard=False)
            out["runs"][integ].append(r)
            u = r.get("unguarded")
            print(f"hopper {integ:16s} CR {cr:5.1f} t_m {r['mean_residence']:.4f} s "
                  f"exited {r['exited']:.3f} escaped {r['escaped']} vmax {r['max_speed']:.2f} "
                  f"{r['status'][:60]} cpu {r['cpu']:.1f} s"
                  + (f" | unguarded: t_m {u['mean_residence']:.4f} escaped {u['escaped']} "
                     f"{u['status'][:30]}" if u else ""), flush=True)
    return out


# ------------------------------------------------------------------------------ plots
def _fin(xs: list, ys: list) -> tuple[list, list]:
    pts = [(x, y) for x, y in zip(xs, ys, strict=True)
           if x is not None and y is not None and 0 < y < math.inf and 0 < x < math.inf]
    return [p[0] for p in pts], [p[1] for p in pts]


def plot(res: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(3, 3, figsize=(18, 16))
    colours = dict(zip(ALL, plt.cm.tab10(np.linspace(0, 1, 10)), strict=False))
    style = {i: ("-" if i in EXPLICIT else "--") for i in ALL}
    marker = {i: ("o" if i in EXPLICIT else "s") for i in ALL}

    def line(ax, integ, x, y, **kw):
        x, y = _fin(x, y)
        ax.plot(x, y, style[integ], marker=marker[integ], ms=4, color=colours[integ],
                label=integ, **kw)

    if "collision" in res:
        c = res["collision"]
        for j, law in enumerate(("linear", "hertz")):
            ax = axes[0, j]
            for integ, d in c[law].items():
                line(ax, integ, [r["cr"] for r in d["rows"]], [r["v_err"] for r in d["rows"]])
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("contact resolution CR = t_c / dt")
            ax.set_ylabel("|v_after - v0| / v0  (worst of 3 phases)")
            ax.set_title(f"single collision, {law} contact, e = 1: rebound velocity error")
            ax.grid(True, which="major", alpha=0.3)
            ax = axes[1, j]
            for integ, d in c[law].items():
                line(ax, integ, [r["cpu"] * 1e6 for r in d["rows"]],
                     [r["v_err"] for r in d["rows"]])
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(f"CPU time per collision [us] (one run() call, "
                          f"{c.get('spheres_per_run', 0)} collisions, 1 thread)")
            ax.set_ylabel("|v_after - v0| / v0")
            ax.set_title(f"work-precision, {law} collision (points: CR 1.2 ... 200)")
            ax.grid(True, which="major", alpha=0.3)
        ax = axes[0, 2]
        for integ, d in c["linear"].items():
            line(ax, integ, [r["cr"] for r in d["rows"]],
                 [r["overlap_err"] for r in d["rows"]])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("contact resolution CR = t_c / dt")
        ax.set_ylabel("|largest overlap - exact| / exact")
        ax.set_title("single collision, linear contact: largest-overlap error")
        ax.grid(True, which="major", alpha=0.3)
    if "sandwich" in res:
        ax = axes[1, 2]
        s = res["sandwich"]
        for integ, rows in s["runs"].items():
            line(ax, integ, [r["dt"] for r in rows], [r["err"] for r in rows])
        ax.axvline(s["contact_time"], color="k", lw=0.5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("dt [s] (vertical line: contact duration t_c)")
        ax.set_ylabel("largest |x - x_exact| / amplitude (missing: run stopped)")
        ax.set_title(f"particle sandwich, {s['duration']} s, linear, e = 1")
        ax.grid(True, which="major", alpha=0.3)
    if "detection" in res:
        ax = axes[2, 0]
        d = res["detection"]
        for integ, by in d["by_phase"].items():
            line(ax, integ, d["phases"], by["2"])
        ax.axhline(1.0, color="k", lw=0.5)
        ax.set_yscale("log")
        ax.set_xlabel("fraction of the step at which the contact starts")
        ax.set_ylabel("largest overlap / exact")
        ax.set_title("contact detection inside a step, CR 2 (guard off)")
        ax.grid(True, which="major", alpha=0.3)
    if "hopper" in res:
        h = res["hopper"]
        ax = axes[2, 1]
        for integ, rows in h["runs"].items():
            # a run the tunnelling guard stopped is shown by its unguarded rerun (red x)
            tm = [r.get("unguarded", r)["mean_residence"] for r in rows]
            line(ax, integ, [r["cr"] for r in rows], tm)
            bad = [(r["cr"], t) for r, t in zip(rows, tm, strict=True)
                   if r["escaped"] or r["status"] != "ok"]
            ax.plot([b[0] for b in bad], [b[1] for b in bad], "x", color="r", ms=12, mew=2)
        ax.set_xscale("log")
        crs = sorted({r["cr"] for rows in h["runs"].values() for r in rows})
        ax.set_xticks(crs)
        ax.set_xticklabels([f"{c:g}" for c in crs])
        ax.minorticks_off()
        ax.set_xlabel("contact resolution t_c / dt (red x: guard stopped it; value of "
                      "the rerun without the guard)")
        ax.set_ylabel(f"mass-weighted mean residence time [s] (cut at {h['duration']} s)")
        ax.set_title(f"flat hopper, {h['n']} steel spheres, {h['duration']} s discharge")
        ax.grid(True, which="major", alpha=0.3)
        ax = axes[2, 2]
        ref = h["runs"]["velocity_verlet"][0]["mean_residence"]
        for integ, rows in h["runs"].items():
            ok = [r for r in rows if r["status"] == "ok" and not r["escaped"]
                  and r is not h["runs"]["velocity_verlet"][0]]
            line(ax, integ, [r["cpu"] for r in ok],
                 [abs(r["mean_residence"] - ref) / ref for r in ok])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("CPU time of the run [s] (1 thread)")
        ax.set_ylabel("|t_m - t_m(velocity_verlet, CR 50)| / t_m")
        ax.set_title("work-precision, hopper (guarded runs that completed)")
        ax.grid(True, which="major", alpha=0.3)
    handles, labels = [], []
    for ax in axes.flat:
        for hd, lb in zip(*ax.get_legend_handles_labels(), strict=True):
            if lb not in labels:
                handles.append(hd)
                labels.append(lb)
    order = [labels.index(i) for i in ALL if i in labels]
    fig.legend([handles[k] for k in order], [labels[k] for k in order], loc="upper center",
               ncol=9, fontsize=11, title="explicit: solid, circles; implicit: dashed, squares")
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path, dpi=90)


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "fewer step sizes and phases, smaller hopper")
    ap.add_argument("--only", nargs="*", default=None,
                    choices=["collision", "sandwich", "detection", "hopper"])
    args = ap.parse_args(argv)
    studies = args.only or ["collision", "sandwich", "detection", "hopper"]
    out_dir = harness.RESULTS
    stem = "integrators_quick" if args.quick else "integrators"
    jpath = out_dir / f"{stem}.json"
    res = json.loads(jpath.read_text()) if jpath.exists() else {}
    fns = dict(collision=study_collision, sandwich=study_sandwich, detection=study_detection,
               hopper=study_hopper)
    for s in studies:
        t = time.perf_counter()
        res[s] = fns[s](args.quick)
        res[s + "_wall_s"] = time.perf_counter() - t
        res.pop("run", None)
        jpath = harness.write("integrators", res, args.quick, default=float)
    harness.png(plot, res, path=out_dir / f"{stem}.png")
    print(f"wrote {jpath} and {stem}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
