"""Rotary kiln: the transverse bed motion of a rotating cylinder swept across Froude numbers.

A horizontal drum (radius R = 40 mm, a ``tube`` about the y axis) is filled to 30 % of its
cross-section with 3 mm glass beads (Hertz-Mindlin, e = 0.5, mu = 0.5, rolling friction
0.02 (EPSD); shell mu = 0.7). Only a slice of 4 bead diameters along the axis is simulated,
periodic in y (``sim.set_periodic``): the tube and the ribs run past both periodic faces,
so every image of the slice sees the same wall. 16 low ribs (``wall`` boundaries one bead
diameter high, turning with the shell) stand for the shell's roughness: on the bare smooth
tube the beads roll on the wall and the bed slips instead of being lifted (sliding regime).

The bed is set as in Oleena (2018, Int. J. Eng. Sci. Math. 7(2), "Discrete element
simulation of granular particles and their numerical simulation in a rotating cylinder",
sec. 9.1): beads on an orthogonal grid with random velocities fall and settle in the
resting drum; then the drum turns (after 0.3 s, reached over 0.2 s) at the angular speed
w of the Froude number Fr = w^2 R / g. For each speed, from samples of the steady part of
the run (which starts at full speed once the drum has turned by 0.6 rad, the bed being
flat at rest, or after 2 revolutions (at most 1 s), whichever is later):

* **regime**, by the first criterion that holds:

  - *centrifuging*: the bed turns with the shell: at least 90 % of the beads move within
    0.1 w R of the shell's rigid rotation (mean over the samples, and at least 80 % in
    every sample), and at least 25 % of them are above the axis (the resting bed is below);
  - *cataracting*: at least 5 % of the beads are in free flight (mean over the samples):
    no other bead within 2 % of contact and not touching the shell;
  - *slumping*: the bed rests on the shell between avalanches: in at least 20 % of the
    samples fewer than 1 % of the beads flow (move faster than 0.1 sqrt(g d) relative to
    the shell's rotation);
  - *cascading*: a curved (kidney, S-shaped) surface: the angles of the three thirds of the
    time-averaged surface profile (``dpm.analysis.drum_surface``, fraction method) differ
    by more than 10 deg;
  - *rolling* otherwise: a flat surface that flows steadily.

* **dynamic angle of repose**: ``dpm.analysis.drum_surface`` (fraction method, 12 columns over
  the middle 60 % of the diameter), mean and standard deviation over the samples;
* **drive torque and power**: the sum over shell and ribs of ``bd.torque`` about the axis
  (mean over the samples), the power from the work the drive did (``bd.work``, integrated
  in the step) over the steady part, against the sampled -T w; the torque is checked
  against the gravity torque of the bed M g x_cm (x_cm: the horizontal offset of the bed's
  centre of mass from the axis), which balances it when the bed's angular momentum is
  steady; and the change of mechanical energy, so that input = dissipation in steady state;
* **mixing**: the beads left (x < 0) and right of the vertical mid-plane when the drum
  starts are two species; Lacey's index (``dpm.analysis.lacey``, cells of R/5 x slice x R/5)
  against revolutions.

The regimes are placed on the Froude ranges of Mellmann (2001, Powder Technol. 118,
251-270, Table 1 / Fig. 10): slumping ~1e-5 < Fr < 1e-3, rolling 1e-4 < Fr < 1e-2,
cascading 1e-3 < Fr < 1e-1, cataracting 0.1 < Fr < 1, centrifuging Fr >= 1; approximate
ranges that depend on the fill degree, the wall friction and the particles.

    python examples/rotary_kiln.py            # 9 speeds, 793 beads: ~15 min (2 shared cores)
    python examples/rotary_kiln.py --quick    # 2 speeds, 334 beads: ~25 s once compiled
    python examples/rotary_kiln.py --output results/ --fr 0.01 0.1

Writes per speed ``kiln_Fr<...>.h5`` + ``.xdmf``, and ``rotary_kiln.json`` (the figures'
data) and ``rotary_kiln.png`` into ``--output``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import dpm
from dpm import analysis as an

G = 9.81
R_BEAD = 1.5e-3
FILL = 0.3
SETTLE = 0.3   # s at rest before the drum turns
RAMP = 0.2     # s to reach the speed
RIBS = 16

# Mellmann (2001), Table 1: approximate Froude ranges of the transverse regimes
MELLMANN = {"slumping": (1e-5, 1e-3), "rolling": (1e-4, 1e-2), "cascading": (1e-3, 1e-1),
            "cataracting": (1e-1, 1.0), "centrifuging": (1.0, 10.0)}
REGIMES = list(MELLMANN)

FULL = {"radius": 0.04, "depth": 0.012,
        "fr": [1e-4, 1e-3, 1e-2, 0.1, 0.3, 0.6, 1.0, 1.5, 3.0]}
QUICK = {"radius": 0.03, "depth": 0.009, "fr": [0.01, 3.0]}


class DelayedRotation(dpm.Rotation):
    """``dpm.Rotation`` that starts after ``delay`` seconds (the bed settles first)."""

    def __init__(self, delay: float, **params) -> None:
        super().__init__(**params)
        self.delay = float(delay)

    def angle(self, t):
        return super().angle(np.asarray(t, float) - self.delay)

    def speed(self, t):
        return super().speed(np.asarray(t, float) - self.delay)


def omega_of(fr: float, radius: float) -> float:
    return math.sqrt(fr * G / radius)


def build(fr: float, radius: float, depth: float, dt: float = 2.5e-5,
          seed: int = 0) -> dpm.Simulation:
    """The drum slice at Froude number ``fr``; ``sim.walls_turning`` lists shell + ribs."""
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, -G))
    glass = dpm.Material("glass", density=2500.0, young=1e7, poisson=0.3)
    steel = dpm.Material("steel", density=7800.0, young=1e7, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.02, rolling_model="epsd")
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.5, friction=0.7,
                rolling_friction=0.02, rolling_model="epsd")
    sim.set_periodic("y", 0.0, depth)
    motion = DelayedRotation(SETTLE, axis=(0.0, 1.0, 0.0), omega=omega_of(fr, radius),
                             center=(0.0, 0.0, 0.0), ramp=RAMP)
    # shell and ribs reach one period past both periodic faces
    walls = [sim.add_boundary("tube", material=steel, start=(0.0, -depth, 0.0),
                              axis=(0.0, 1.0, 0.0), length=3 * depth, radius=radius,
                              motion=motion)]
    h = 2 * R_BEAD
    for k in range(RIBS):
        th = 2 * math.pi * k / RIBS
        c = (radius - h / 2) * math.cos(th), depth / 2, (radius - h / 2) * math.sin(th)
        walls.append(sim.add_boundary(
            "wall", material=steel, center=c, normal=(-math.sin(th), 0.0, math.cos(th)),
            u=(0.0, 1.0, 0.0), half_extents=(1.5 * depth, h / 2), motion=motion))
    sim.walls_turning = walls
    # Oleena sec. 9.1: an orthogonal grid of the bead diameter (here 2.1 r), random
    # velocities, the lowest sites up to the fill (packing ~0.62 once settled)
    pos = dpm.lattice((-radius, 0.0, -radius), (radius, depth, radius), 2.1 * R_BEAD)
    pos = pos[np.hypot(pos[:, 0], pos[:, 2]) < radius - h - 1.2 * R_BEAD]
    n = int(FILL * math.pi * radius**2 * depth * 0.62 / (4 / 3 * math.pi * R_BEAD**3))
    pos = pos[np.argsort(pos[:, 2], kind="stable")][:n]
    rng = np.random.default_rng(seed)
    sim.add_particles("sphere", material=glass, radius=R_BEAD, positions=pos,
                      velocities=rng.normal(0.0, 0.01, pos.shape))
    return sim


def free_flight_fraction(pos: np.ndarray, radius: float, depth: float,
                         tol: float = 0.02) -> float:
    """Fraction of beads with no other bead within (2 r)(1 + tol) (periodic in y) and not
    touching the shell."""
    shift = pos + np.array([2 * radius, 0.0, 2 * radius])
    shift[:, 1] %= depth
    tree = cKDTree(shift, boxsize=(8 * radius, depth, 8 * radius))
    pairs = tree.query_pairs(2 * R_BEAD * (1 + tol), output_type="ndarray")
    touched = np.zeros(len(pos), bool)
    touched[pairs.ravel()] = True
    touched |= np.hypot(pos[:, 0], pos[:, 2]) > radius - R_BEAD * (1 + tol)
    return float(np.mean(~touched))


def third_angles(across: np.ndarray, height: np.ndarray) -> list[float]:
    """Surface angles [deg] of the three thirds of a surface profile (line fits)."""
    good = np.isfinite(height)
    a, h = across[good], height[good]
    out = []
    for part in np.array_split(np.arange(len(a)), 3):
        if len(part) >= 2:
            out.append(math.degrees(math.atan(np.polyfit(a[part], h[part], 1)[0])))
    return out


def run_speed(fr: float, radius: float, depth: float, steady: float, out: Path,
              frames: int = 60) -> dict:
    """Run one speed; sample the steady part; return the measures (see the docstring)."""
    w = omega_of(fr, radius)
    t_rev = 2 * math.pi / w
    sim = build(fr, radius, depth)
    walls = sim.walls_turning
    # steady part: after the bed has turned by 0.6 rad (it starts flat) and 2 revolutions
    # (at most 1 s) have passed at full speed
    start = SETTLE + RAMP + max(0.6 / w, min(2 * t_rev, 1.0))
    end = start + steady
    every = min(steady / frames, t_rev / 24, 0.1)
    h5 = out / f"kiln_Fr{fr:g}.h5"
    sim.output(str(h5), every=every, overwrite=True)
    sim.run(until=SETTLE)
    b = sim.bodies
    ids = np.asarray(b.id).copy()
    left = set(ids[b.position[:, 0] < 0.0].tolist())      # species A: the left half
    cell = (radius / 5, depth, radius / 5)
    box = dict(lower=(-radius, 0.0, -radius), upper=(radius, depth, radius))
    mass = float(np.sum(b.mass))
    v_flow = 0.1 * math.sqrt(G * 2 * R_BEAD)

    def frame_dict():
        return {"id": np.asarray(b.id), "position": b.position, "velocity": b.velocity,
                "radius": b.radius, "mass": b.mass, "time": sim.time}

    lacey_t, lacey_m = [SETTLE], [an.lacey(frame_dict(), left, cell, **box)["M"]]
    s = {k: [] for k in ("t", "corot", "above", "flowing", "free", "angle", "torque",
                         "power", "gravity_torque")}
    heights = []
    t0 = time.perf_counter()
    w_start = e_start = None
    while sim.time < end - 1e-12:
        sim.run(until=min(end, sim.time + every))
        if sim.time > SETTLE + RAMP:
            lacey_t.append(sim.time)
            lacey_m.append(an.lacey(frame_dict(), left, cell, **box)["M"])
        if sim.time < start - 1e-12:
            continue
        if w_start is None:
            w_start = sum(bd.work for bd in walls)
            e_start = an.energy_balance(sim)
        p, v = b.position, b.velocity
        wy = float(walls[0].angular_velocity[1])
        rigid = np.stack([wy * p[:, 2], np.zeros(len(p)), -wy * p[:, 0]], axis=1)
        rel = np.linalg.norm(v - rigid, axis=1)
        surf = an.drum_surface(frame_dict(), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), radius,
                               bins=12, span=0.6, method="fraction")
        heights.append(surf.height)
        torque = sum(float(bd.torque[1]) for bd in walls)
        s["t"].append(sim.time)
        s["corot"].append(float(np.mean(rel < 0.1 * w * radius)))
        s["above"].append(float(np.mean(p[:, 2] > 0.0)))
        s["flowing"].append(float(np.mean(rel > v_flow)))
        s["free"].append(free_flight_fraction(p, radius, depth))
        s["angle"].append(abs(surf.angle))
        s["torque"].append(torque)
        s["power"].append(sum(bd.power() for bd in walls))
        s["gravity_torque"].append(G * float(np.sum(b.mass * p[:, 0])))
    wall = time.perf_counter() - t0
    e_end = an.energy_balance(sim)
    work = sum(bd.work for bd in walls) - w_start
    # (the first sample is taken at `start`: work and energies are counted from there)
    span_t = sim.time - s["t"][0] if len(s["t"]) else float("nan")
    steps, nb = sim.step_count, len(b)
    sim.close()
    mean_h = np.nanmean(np.array(heights), axis=0)
    across = surf.across
    thirds = third_angles(across, mean_h)
    a = {k: np.asarray(val) for k, val in s.items()}
    rest_share = float(np.mean(a["flowing"] < 0.01))
    lt = np.asarray(lacey_t)
    rev = np.maximum(drum_angle(lt, w), 0.0) / (2 * math.pi)
    res = {
        "Fr": fr, "omega": w, "rpm": w * 30 / math.pi, "revolution_s": t_rev,
        "beads": nb, "bed_mass": mass, "steady_s": span_t, "samples": len(a["t"]),
        "criteria": {"corotating_mean": float(a["corot"].mean()),
                     "corotating_min": float(a["corot"].min()),
                     "above_axis_mean": float(a["above"].mean()),
                     "free_flight_mean": float(a["free"].mean()),
                     "resting_share": rest_share,
                     "flowing_mean": float(a["flowing"].mean()),
                     "third_angles_deg": thirds},
        "angle_deg": float(a["angle"].mean()), "angle_std_deg": float(a["angle"].std()),
        "torque_Nm": float(a["torque"].mean()),
        "gravity_torque_Nm": float(a["gravity_torque"].mean()),
        "power_W": work / span_t,
        "power_sampled_W": float(a["power"].mean()),
        "torque_omega_W": float(-a["torque"].mean() * w),
        "energy_change_W": (e_end["current"] - e_start["current"]) / span_t,
        "dissipation_W": (e_end["dissipated"] - e_start["dissipated"]) / span_t,
        "lacey_revolutions": rev.tolist(), "lacey": [float(m) for m in lacey_m],
        "surface": {"across": across.tolist(),
                    "height": [None if not np.isfinite(x) else float(x) for x in mean_h]},
        "snapshot": {"x": p[:, 0].tolist(), "z": p[:, 2].tolist(),
                     "left": [int(i in left) for i in np.asarray(b.id).tolist()]},
        "radius": radius, "h5": h5.name, "wall_s": wall, "steps": steps,
    }
    res["regime"] = classify(res["criteria"])
    return res


def classify(c: dict) -> str:
    """The regime from the measured criteria (the thresholds of the module docstring)."""
    if c["corotating_mean"] >= 0.9 and c["corotating_min"] >= 0.8 \
            and c["above_axis_mean"] >= 0.25:
        return "centrifuging"
    if c["free_flight_mean"] >= 0.05:
        return "cataracting"
    if c["resting_share"] >= 0.2:
        return "slumping"
    th = c["third_angles_deg"]
    if len(th) == 3 and max(th) - min(th) > 10.0:
        return "cascading"
    return "rolling"


def drum_angle(t: np.ndarray, w: float) -> np.ndarray:
    """Drum angle [rad] at times t (the motion of :func:`build`)."""
    return DelayedRotation(SETTLE, axis=(0, 1, 0), omega=w, ramp=RAMP).angle(t)


def steady_time(fr: float, radius: float, quick: bool) -> float:
    """Simulated time of the sampled part: 3 revolutions, within [1.5, 10] s (quick:
    within [0.5, 1] s); 5 revolutions at Fr = 0.1 for the mixing curve."""
    t_rev = 2 * math.pi / omega_of(fr, radius)
    if quick:
        return min(max(2 * t_rev, 0.5), 1.0)
    n = 5.0 if abs(fr - 0.1) < 1e-9 else 3.0
    return min(max(n * t_rev, 1.5), 10.0)


def picture(results: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 8.4))
    gs = fig.add_gridspec(2, 2, top=0.73, bottom=0.07, left=0.08, right=0.94,
                          hspace=0.35, wspace=0.3)
    wk = 0.96 / len(results)
    for k, r in enumerate(results):
        ax = fig.add_axes((0.02 + k * wk, 0.78, 0.92 * wk, 0.17))
        sn = r["snapshot"]
        col = np.where(np.asarray(sn["left"]) > 0, "tab:blue", "tab:orange")
        ax.scatter(sn["x"], sn["z"], s=0.8, c=col, linewidths=0)
        ax.add_patch(plt.Circle((0, 0), r["radius"], fill=False, lw=0.8))
        lim = 1.05 * r["radius"]
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_axis_off()
        ax.set_title(f"Fr {r['Fr']:g}\n{r['regime']}", fontsize=8)
    fr = np.array([r["Fr"] for r in results])
    ax = fig.add_subplot(gs[0, 0])
    for k, (lo, hi) in enumerate(MELLMANN.values()):
        ax.barh(k, hi - lo, left=lo, height=0.5, color="0.85", edgecolor="0.6")
    ax.scatter(fr, [REGIMES.index(r["regime"]) for r in results], color="tab:red",
               zorder=3, label="this run")
    ax.set_xscale("log")
    ax.set_xlim(5e-6, 2e1)
    ax.set_yticks(range(len(REGIMES)), REGIMES)
    ax.set_xlabel("Froude number w^2 R / g")
    ax.set_title("regime (grey: Mellmann 2001 ranges)", fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    ax = fig.add_subplot(gs[0, 1])
    sel = np.array([r["regime"] != "centrifuging" for r in results])
    ax.errorbar(fr[sel], [r["angle_deg"] for r in results if r["regime"] != "centrifuging"],
                yerr=[r["angle_std_deg"] for r in results if r["regime"] != "centrifuging"],
                marker="o", capsize=3)
    ax.set_xscale("log")
    ax.set_xlabel("Froude number")
    ax.set_ylabel("dynamic angle of repose [deg]")
    ax.set_title("surface angle (fraction method, mean +- std)", fontsize=9)
    ax = fig.add_subplot(gs[1, 0])
    ax.plot(fr, [r["torque_Nm"] * 1e3 for r in results], "o-", label="drive torque")
    ax.plot(fr, [r["gravity_torque_Nm"] * 1e3 for r in results], "x--",
            label="M g x_cm of the bed")
    ax.set_xscale("log")
    ax.set_xlabel("Froude number")
    ax.set_ylabel("torque about the axis [mN m]")
    ax2 = ax.twinx()
    ax2.plot(fr, [r["power_W"] * 1e3 for r in results], "s-", color="tab:green",
             label="power (drive work / time)")
    ax2.set_ylabel("power [mW]", color="tab:green")
    ax.legend(fontsize=8, loc="upper left")
    ax2.legend(fontsize=8, loc="center left")
    ax.set_title("drive torque and power (per slice)", fontsize=9)
    ax = fig.add_subplot(gs[1, 1])
    for r in results:
        if r["lacey_revolutions"][-1] >= 0.2 and r["regime"] != "centrifuging":
            ax.plot(r["lacey_revolutions"], r["lacey"], label=f"Fr {r['Fr']:g}")
    ax.set_xlabel("revolutions")
    ax.set_ylabel("Lacey index")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=8)
    ax.set_title("mixing of the left and right halves", fontsize=9)
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv: list[str] | None = None) -> list[dict]:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help="2 speeds, a smaller drum, ~1 s each (for CI)")
    p.add_argument("--output", default="rotary_kiln_results", help="output folder")
    p.add_argument("--fr", type=float, nargs="+", help="Froude numbers (default: the set)")
    args = p.parse_args(argv)
    cfg = QUICK if args.quick else FULL
    radius, depth = cfg["radius"], cfg["depth"]
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    t_all = time.perf_counter()
    for fr in args.fr or cfg["fr"]:
        r = run_speed(fr, radius, depth, steady_time(fr, radius, args.quick), out)
        results.append(r)
        c = r["criteria"]
        dpm.notice(f"Fr {fr:<7g} {r['rpm']:6.2f} rpm  {r['regime']:<12s} angle "
                   f"{r['angle_deg']:5.1f} +- {r['angle_std_deg']:4.1f} deg  torque "
                   f"{r['torque_Nm'] * 1e3:7.3f} mN m "
                   f"(M g x_cm {r['gravity_torque_Nm'] * 1e3:7.3f})"
                   f"  power {r['power_W'] * 1e3:7.3f} mW (-T w {r['torque_omega_W'] * 1e3:7.3f},"
                   f" dE/dt {r['energy_change_W'] * 1e3:+.3f})  Lacey {r['lacey'][-1]:.2f} after "
                   f"{r['lacey_revolutions'][-1]:.2f} rev  [corot {c['corotating_mean']:.2f} "
                   f"above {c['above_axis_mean']:.2f} free {c['free_flight_mean']:.3f} rest "
                   f"{c['resting_share']:.2f} thirds "
                   f"{' '.join(f'{x:.0f}' for x in c['third_angles_deg'])}]  "
                   f"{r['wall_s']:.0f} s", flush=True)
    total = time.perf_counter() - t_all
    doc = {"scene": "rotary_kiln", "quick": args.quick, "radius_m": radius,
           "slice_m": depth, "bead_radius_m": R_BEAD, "fill": FILL, "ribs": RIBS,
           "mellmann_2001_ranges": MELLMANN, "wall_s": total, "speeds": results}
    if dpm.is_root():  # (rank 0 writes: every rank holds the result)
        (out / "rotary_kiln.json").write_text(json.dumps(doc, indent=1))
        try:
            picture(results, out / "rotary_kiln.png")
        except ImportError:
            print("matplotlib is missing: no picture (pip install 'dpm-granular[plot]')")
    dpm.notice(f"{len(results)} speeds in {total:.0f} s; output in {out}/ (open the .xdmf files "
               f"in ParaView)")
    return results


if __name__ == "__main__":
    main()
