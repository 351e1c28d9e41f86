"""Integrators: order of accuracy, work-precision, the DPM thesis' implicit-method cases.

Studies (DPM thesis, Samiei 2012, §2.7.6 and §3.9; every reference is analytic except the
hopper's, which is the run at the smallest step):

1. collision: a sphere (glass, 2520 kg/m3, d = 8 mm) hits a plane head-on at 0.5 m/s, no
   damping, no gravity, linear contact k = 250 N/m or Hertz (E = 1e6 Pa, nu = 0.3); errors
   of the restitution, the velocity and the position after the contact, and of the largest
   overlap, against the contact resolution CR = t_contact / dt from 1.2 to 200 (worst of
   three phases of the contact start within a step), with the observed order (slope of
   log error against log CR for CR >= 10) and the CPU time (work-precision).
2. sandwich: the sphere between two planes one diameter apart, 15 % initial overlap
   (x = R + 0.15 R cos(omega t)), 0.45 s at dt = 1e-4, 1e-3, 3.5e-3 s and a sweep; the
   largest error relative to the amplitude.
3. contact detection: the sphere approaches the plane at 0.5 m/s with the contact starting
   at a fraction of a step; largest overlap against that fraction (CR 1.3 and 2) and
   against CR (fraction 0).
4. hopper: a flat hopper (one particle deep) of polydisperse steel spheres (d 8-12 mm,
   7850 kg/m3, k = 1000 N/m, no damping, no friction) discharging under gravity; the
   mass-weighted mean residence time (time to fall below the outlet) against dt, whether
   every particle stayed inside the walls, and the CPU time.

Run ``python benchmarks/integrators.py`` (``--quick`` for a short run; ``--only collision``
etc.); writes benchmarks/results/integrators[_quick].json and .png.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import dpm

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


def _sim(integrator: str, dt: float, law: str, **kw) -> tuple[dpm.Simulation, dpm.Material]:
    sim = dpm.Simulation(dt=dt, integrator=integrator, dt_check="off", max_overlap=2.0, **kw)
    if law == "linear":
        m = dpm.Material("glass", density=RHO)
        sim.contact(m, m, model="linear_spring_dashpot", stiffness=K_LIN, restitution=1.0,
                    friction=0.0)
    else:
        m = dpm.Material("glass", density=RHO, young=E_HERTZ, poisson=NU)
        sim.contact(m, m, model="hertz_mindlin", restitution=1.0, friction=0.0)
    return sim, m


def collision(integrator: str, law: str, cr: float, phase: float) -> dict:
    """One head-on collision with a plane at z = 0; the contact starts ``phase`` x dt after
    t = 0. Errors relative to v0 (velocity), to the largest overlap (position, overlap)."""
    ref = linear_reference() if law == "linear" else hertz_reference()
    tc = ref["tc"]
    dt = tc / cr
    sim, m = _sim(integrator, dt, law)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    t0 = phase * dt
    sim.add_particles("sphere", material=m, radius=R, positions=[[0, 0, R + V0 * t0]],
                      velocities=[[0, 0, -V0]])
    nsteps = int(math.ceil((t0 + tc) / dt)) + 2
    worst = 0.0
    cpu = 0.0
    try:
        for _ in range(nsteps):
            t = time.perf_counter()
            sim.run(steps=1, progress=False)
            cpu += time.perf_counter() - t
            worst = max(worst, R - sim.bodies.position[0, 2])
        ok = True
    except dpm.UnstableRunError:
        ok = False
    t_end = sim.time
    z = sim.bodies.position[0, 2]
    vz = sim.bodies.velocity[0, 2]
    z_exact = R + V0 * (t_end - t0 - tc)
    return dict(ok=ok, e_err=abs(vz / V0 - 1.0) if ok else math.inf,
                v_err=abs(vz - V0) / V0 if ok else math.inf,
                x_err=abs(z - z_exact) / ref["dmax"] if ok else math.inf,
                overlap_err=abs(worst - ref["dmax"]) / ref["dmax"] if ok else math.inf,
                cpu=cpu, steps=nsteps)


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
    out: dict = {}
    for law in ("linear", "hertz"):
        out[law] = {}
        for integ in ALL:
            rows = []
            collision(integ, law, 20, 0.5)  # warm-up (compiles)
            for cr in crs:
                rs = [collision(integ, law, cr, ph) for ph in phases]
                rows.append({k: max(r[k] for r in rs) for k in
                             ("e_err", "v_err", "x_err", "overlap_err")}
                            | dict(cr=cr, cpu=float(np.mean([r["cpu"] for r in rs])),
                                   ok=all(r["ok"] for r in rs)))
            order = {k: observed_order([r["cr"] for r in rows], [r[k] for r in rows])
                     for k in ("e_err", "v_err", "x_err", "overlap_err")}
            out[law][integ] = dict(rows=rows, order=order)
            print(f"collision {law:6s} {integ:16s} order e {order['e_err']:.2f} "
                  f"v {order['v_err']:.2f} x {order['x_err']:.2f}; CR 10: e_err "
                  f"{rows[crs.index(10)]['e_err']:.2e}", flush=True)
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
    try:
        while done < n:
            k = min(chunk, n - done)
            t = time.perf_counter()
            sim.run(steps=k, progress=False)
            cpu += time.perf_counter() - t
            done += k
            exact = R + 0.15 * R * math.cos(w * sim.time)
            err = max(err, abs(sim.bodies.position[0, 2] - exact) / (0.15 * R))
        ok = bool(np.all(np.abs(sim.bodies.position[:, 2] - R) < R))
    except dpm.UnstableRunError:
        ok = False
    return dict(dt=dt, err=err if ok else math.inf, ok=ok, cpu=cpu)


def study_sandwich(quick: bool) -> dict:
    dts = [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 3.5e-3] if not quick else [1e-4, 1e-3, 3.5e-3]
    duration = 0.45 if not quick else 0.1
    out = {}
    for integ in ALL:
        out[integ] = [sandwich(integ, dt, duration) for dt in dts]
        print(f"sandwich {integ:16s} " + " ".join(f"{r['dt']:.0e}:{r['err']:.2e}"
                                                  for r in out[integ]), flush=True)
    return dict(dts=dts, duration=duration, runs=out, contact_time=linear_reference()["tc"])


def approach(integrator: str, cr: float, phase: float) -> float:
    """Largest overlap / analytic largest overlap of a sphere approaching a plane."""
    ref = linear_reference()
    dt = ref["tc"] / cr
    sim, m = _sim(integrator, dt, "linear")
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
    return worst / ref["dmax"]


def study_detection(quick: bool) -> dict:
    phases = list(np.linspace(0.0, 0.95, 20 if not quick else 6))
    crs = [1.3, 1.5, 2, 3, 5, 10, 20] if not quick else [1.3, 2, 5, 10]
    integs = ["position_verlet", "velocity_verlet", "gear4", "newmark_beta", "numerov",
              "backward_euler"]
    out: dict = dict(phases=phases, crs=crs, by_phase={}, by_cr={})
    for integ in integs:
        out["by_phase"][integ] = {str(cr): [approach(integ, cr, p) for p in phases]
                                  for cr in (1.3, 2)}
        out["by_cr"][integ] = [approach(integ, cr, 0.0) for cr in crs]
        print(f"detection {integ:16s} CR 1.3 worst {max(out['by_phase'][integ]['1.3']):.3f} "
              f"CR 2 worst {max(out['by_phase'][integ]['2']):.3f}", flush=True)
    return out


# ------------------------------------------------------------------------------ hopper
def hopper_scene(n: int, seed: int = 1) -> dict:
    """A flat hopper: funnel of two inclined planes (60 deg from horizontal) with an
    outlet of 6 mean diameters, front and back planes 1.1 d_max apart; particles placed
    on a jittered grid above the funnel, radii uniform in [4, 6] mm."""
    tan60 = math.tan(math.radians(60))
    rng = np.random.default_rng(seed)
    dmax = 12e-3
    cols = 20
    rows = int(math.ceil(n / cols))
    pitch = dmax * 1.05
    width = cols * pitch
    x = (np.arange(cols) - (cols - 1) / 2) * pitch
    pos = []
    for r in range(rows):
        for c in range(cols):
            if len(pos) < n:
                pos.append([x[c] + rng.uniform(-0.02, 0.02) * dmax, 0.0,
                            tan60 * (width / 2 - 0.03) + 0.03 + r * pitch])
    radii = rng.uniform(4e-3, 6e-3, n)
    return dict(positions=np.array(pos), radii=radii, width=width, outlet=6 * 10e-3,
                depth=1.1 * dmax)


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
    aux = sim._aux
    if name == "position_verlet":
        aux[idx, 3:6] = np.nan  # != velocity: the kernel restarts the difference
    elif name in ("gear4", "gear5"):
        aux[idx] = 0.0
        aux[idx, 0:3] = sim.gravity
    elif name == "numerov":
        aux[idx, 0:3] = b.position[idx]
        aux[idx, 3:6] = sim.gravity


def hopper(integrator: str, dt: float, scene: dict, duration: float) -> dict:
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, -9.81), integrator=integrator,
                         dt_check="off", max_overlap=1.5)
    steel = dpm.Material("steel", density=7850.0)
    sim.contact(steel, steel, model="linear_spring_dashpot", stiffness=1000.0,
                restitution=1.0, friction=0.0)
    half = scene["outlet"] / 2
    s, c = math.sin(math.radians(60)), math.cos(math.radians(60))
    # inclined planes through (+-half, 0, 0), normals pointing up and inwards
    sim.add_boundary("plane", material=steel, point=(half, 0, 0), normal=(-s, 0, c))
    sim.add_boundary("plane", material=steel, point=(-half, 0, 0), normal=(s, 0, c))
    sim.add_boundary("plane", material=steel, point=(0, -scene["depth"] / 2, 0),
                     normal=(0, 1, 0))
    sim.add_boundary("plane", material=steel, point=(0, scene["depth"] / 2, 0),
                     normal=(0, -1, 0))
    sim.add_particles("sphere", material=steel, radius=scene["radii"],
                      positions=scene["positions"])
    mass = sim.bodies.mass.copy()
    exit_time = np.full(len(mass), np.nan)
    escaped = False
    cpu = 0.0
    n = int(round(duration / dt))
    every = max(1, int(round(2e-3 / dt)))
    done = 0
    status = "ok"
    try:
        while done < n:
            k = min(every, n - done)
            t = time.perf_counter()
            sim.run(steps=k, progress=False)
            cpu += time.perf_counter() - t
            done += k
            p = sim.bodies.position
            out = (p[:, 2] < -0.02) & np.isnan(exit_time)
            exit_time[out] = sim.time
            gone = np.flatnonzero(~np.isnan(exit_time))
            if len(gone):
                park(sim, gone)
            # inside the walls: not behind a funnel plane or the front/back planes by
            # more than a radius while above the outlet
            above = p[:, 2] > 0.0
            d1 = (p[:, 0] - half) * -s + p[:, 2] * c
            d2 = (p[:, 0] + half) * s + p[:, 2] * c
            behind = above & ((d1 < -sim.bodies.radius) | (d2 < -sim.bodies.radius))
            behind |= np.abs(p[:, 1]) > scene["depth"] / 2 + sim.bodies.radius
            if np.any(behind):
                escaped = True
            if np.all(~np.isnan(exit_time)):
                break
    except dpm.UnstableRunError as err:
        status = "unstable: " + str(err).split(":")[1][:80]
    done_frac = float(np.mean(~np.isnan(exit_time)))
    t = np.where(np.isnan(exit_time), sim.time, exit_time)
    tm = float(np.sum(mass * t) / np.sum(mass))
    iters = getattr(sim.integrator, "stats", None)
    return dict(dt=dt, mean_residence=tm, exited=done_frac, escaped=escaped, status=status,
                cpu=cpu, steps=sim.step_count, newton=dict(iters) if iters else None)


def study_hopper(quick: bool) -> dict:
    n = 2000 if not quick else 200
    duration = 6.0 if not quick else 1.5
    scene = hopper_scene(n)
    m = 7850 * 4 / 3 * math.pi * 4e-3**3
    tc = math.pi / math.sqrt(1000.0 / (m / 2))
    crs = [50, 25, 10, 7, 5, 3.2] if not quick else [25, 10, 7, 5]
    integs = ["velocity_verlet", "position_verlet", "gear4", "newmark_beta", "numerov"]
    if quick:
        integs = ["velocity_verlet", "position_verlet", "newmark_beta", "numerov"]
    out: dict = dict(n=n, duration=duration, contact_time=tc, crs=crs, runs={})
    for integ in integs:
        out["runs"][integ] = []
        for cr in crs:
            r = hopper(integ, tc / cr, scene, duration)
            r["cr"] = cr
            out["runs"][integ].append(r)
            print(f"hopper {integ:16s} CR {cr:5.1f} t_m {r['mean_residence']:.4f} s "
                  f"exited {r['exited']:.2f} escaped {r['escaped']} {r['status'][:40]} "
                  f"cpu {r['cpu']:.1f} s", flush=True)
    return out


# ------------------------------------------------------------------------------ plots
def plot(res: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(17, 10))
    colours = dict(zip(ALL, plt.cm.tab10(np.linspace(0, 1, 10)), strict=False))
    style = {i: ("-" if i in EXPLICIT else "--") for i in ALL}
    if "collision" in res:
        for ax, law in zip(axes[0, :2], ("linear", "hertz"), strict=True):
            for integ, d in res["collision"][law].items():
                cr = [r["cr"] for r in d["rows"]]
                ax.loglog(cr, [max(r["v_err"], 1e-16) for r in d["rows"]], style[integ],
                          marker="o", ms=3, color=colours[integ],
                          label=f"{integ} (p={d['order']['v_err']:.1f})")
            ax.set_xlabel("contact resolution t_c / dt")
            ax.set_ylabel("|v_after - v_exact| / v0 (worst of 3 phases)")
            ax.set_title(f"single collision, {law} contact, e = 1")
            ax.legend(fontsize=7)
        ax = axes[0, 2]
        for integ, d in res["collision"]["linear"].items():
            ax.loglog([r["cpu"] for r in d["rows"]],
                      [max(r["x_err"], 1e-16) for r in d["rows"]], style[integ], marker="o",
                      ms=3, color=colours[integ], label=integ)
        ax.set_xlabel("CPU time per collision [s]")
        ax.set_ylabel("position error after contact / largest overlap")
        ax.set_title("work-precision: linear collision (CPU: one run() call per step)")
        ax.legend(fontsize=7)
    if "sandwich" in res:
        ax = axes[1, 0]
        s = res["sandwich"]
        for integ, rows in s["runs"].items():
            ax.loglog([r["dt"] for r in rows], [min(r["err"], 1e3) for r in rows],
                      style[integ], marker="o", ms=3, color=colours[integ], label=integ)
        ax.axvline(s["contact_time"], color="k", lw=0.5)
        ax.set_xlabel("dt [s] (line: contact duration)")
        ax.set_ylabel("largest |x - x_exact| / amplitude (1e3: failed)")
        ax.set_title(f"particle sandwich, {s['duration']} s")
        ax.legend(fontsize=7)
    if "detection" in res:
        ax = axes[1, 1]
        d = res["detection"]
        for integ, by in d["by_phase"].items():
            ax.plot(d["phases"], by["2"], style.get(integ, "-"), marker="o", ms=3,
                    color=colours[integ], label=f"{integ} CR 2")
        ax.axhline(1.0, color="k", lw=0.5)
        ax.set_xlabel("fraction of the step before the contact starts")
        ax.set_ylabel("largest overlap / exact")
        ax.set_title("contact detection inside a step")
        ax.legend(fontsize=7)
    if "hopper" in res:
        ax = axes[1, 2]
        h = res["hopper"]
        for integ, rows in h["runs"].items():
            ax.plot([r["cr"] for r in rows], [r["mean_residence"] for r in rows],
                    style[integ], marker="o", ms=4, color=colours[integ], label=integ)
            bad = [r for r in rows if r["escaped"] or r["status"] != "ok"]
            ax.plot([r["cr"] for r in bad], [r["mean_residence"] for r in bad], "x",
                    color="r", ms=10)
        ax.set_xscale("log")
        ax.set_xlabel("contact resolution t_c / dt (x: a particle left the walls / failed)")
        ax.set_ylabel("mass-weighted mean residence time [s]")
        ax.set_title(f"flat hopper, {h['n']} spheres")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", nargs="*", default=None,
                    choices=["collision", "sandwich", "detection", "hopper"])
    args = ap.parse_args(argv)
    studies = args.only or ["collision", "sandwich", "detection", "hopper"]
    out_dir = Path(__file__).parent / "results"
    out_dir.mkdir(exist_ok=True)
    stem = "integrators_quick" if args.quick else "integrators"
    jpath = out_dir / f"{stem}.json"
    res = json.loads(jpath.read_text()) if jpath.exists() else {}
    fns = dict(collision=study_collision, sandwich=study_sandwich, detection=study_detection,
               hopper=study_hopper)
    for s in studies:
        t = time.perf_counter()
        res[s] = fns[s](args.quick)
        res[s + "_wall_s"] = time.perf_counter() - t
        jpath.write_text(json.dumps(res, indent=1, default=float))
    plot(res, out_dir / f"{stem}.png")
    print(f"wrote {jpath} and {stem}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
