"""Tumbling ball mill with lifters: the 300 mm x 270 mm pilot mill of Hromnik (2013).

Scene: Hromnik, M. 2013, "A GPGPU implementation of the discrete element method applied to
modeling the dynamic particulate environment inside a tumbling mill", MSc thesis,
University of Cape Town (sections 5.2, 6.2, 6.4; figs. 5.15, 5.23, 5.24, 6.7-6.12, 6.16).

- Mill: D = 300 mm, L = 270 mm (fig. 5.15, 5.23), turning about the horizontal y axis,
  the bottom moving towards +x (the charge rises on the +x side; in the x-z picture the
  mill turns anticlockwise). Speeds 60, 70 and 80 % of critical, N_c = 42.3 / sqrt(D) rpm
  (thesis section 6.1) = 77.2 rpm.
- Lifters: the thesis draws the 300 mm mill's profile (fig. 5.15, 259 points) but gives
  no lifter dimensions; its other pilot mill (fig. 5.13) has 12 lifters. Here: 12
  equally spaced square bars, 10 mm high and 10 mm wide, along the whole length. By
  default they are ``wall`` boundaries (finite slabs) turning with the shell by the same
  ``dpm.Rotation``; ``--lifters mesh`` replaces the shell and lifters by one triangle
  mesh of the same profile (extruded along the axis, end discs fanned from the axis).
- Charge: 3 mm glass beads (fig. 5.24) filling J = 35 % of the mill volume at a bed
  solids fraction of 0.6 (283,000 beads for the whole mill; the thesis ran 253,125 and
  303,156).
- Contacts: Hertz-Mindlin (Tsuji damping) with rolling resistance. Glass: density 2500,
  shear modulus 26 GPa, Poisson 0.23 (so E = 2 (1 + nu) G = 64 GPa); glass-glass e = 0.66,
  mu = 0.154; glass-wall e = 0.55, mu = 0.32 (fig. 5.24). Rolling friction is not given
  in the thesis: mu_r = 0.01 (constant torque) is assumed.
  **Stiffness reduced**: E = 64 GPa needs dt ~ 5e-7 s (the thesis ran 1e-6 s). Here the
  glass Young's modulus is divided by 1e4 (6.4 MPa; contact time at 1 m/s 0.35 ms instead
  of 9 us, largest overlap at 1 m/s ~4 % of the diameter) and dt = 2.5e-5 s. The wall's
  thesis modulus (shear 0.31 GPa, nu = 0.42: E = 0.88 GPa, 73 times softer than glass)
  divided by the same factor would be a rubber; the wall gets the reduced glass modulus
  with its own Poisson ratio 0.42.

Outputs per speed (``--output DIR``): ``ball_mill_<pct>.h5`` + ``.xdmf``; in the
directory ``ball_mill.json`` (all figures) and ``ball_mill.png`` (solids fraction and
velocity maps at the middle speed, toe and shoulder angles and power against speed).

- solids fraction and velocity in the transverse x-z plane: ``dpm.analysis.voxel_fields``
  on cells of 4 bead radii (the thesis' coarsest grid is 64 x 64 over 384 mm, 6 mm cells),
  averaged over the frames of the last part of the run and over the mill length;
- toe and shoulder: angles of the ends of the arc of the shell along which the charge
  lies, measured from the horizontal on the rising side (+x) in the sense of rotation
  (Morrell 1996's convention: shoulder ~ 30-60 deg, toe ~ 200-240 deg). The arc is where
  the time-averaged solids fraction in the ring just inside the lifter tips (radii
  R - H - 4 r to R - H) is at least half the bulk solids fraction; shoulder: its end on
  the rising side, toe: its end on the descending side;
- power: the drive power sum over the shell and all lifters of ``bd.power()``, sampled
  every 2 ms, and from the boundaries' ``work``; checked against the torque the charge's
  weight exerts about the axis (M g x_cm, the torque-arm model).

Modes (timed on a 2-core machine shared with other work, one thread, warm compile
cache; a cold cache adds ~110 s of compilation per scene kind):

    python examples/ball_mill.py              # default: periodic slice, 3 speeds, 26 min
    python examples/ball_mill.py --quick      # CI: thin slice, one speed, 17 s
    python examples/ball_mill.py --full-charge-steps 200   # whole mill: 800 + 200 steps, 70 s
    python examples/ball_mill.py --full-charge-revolutions 1 --threads 2  # ~1 h on 2 cores
    python examples/ball_mill.py --full-charge-revolutions 1 --full-charge-resume  # go on

The default is **not** the whole 270 mm mill: a slice of the mill 7.5 mm (2.5 bead
diameters) long with periodic ends along the axis (``sim.set_periodic``), 7,700 beads,
2 revolutions per speed after a 0.2 s ramp (steady state after the first; the averages
over the last 0.8 revolution, frames every 20 ms); the thesis ran 3 revolutions before
logging. ``--quick`` is the same 7.5 mm slice at 70 % critical with the mill filled to
J = 9 % instead of 35 % (2,000 beads) for 0.5 s (0.3 s after the ramp: a transient).
``--full-charge-steps N`` builds the whole mill with its end plates and the full charge
(283,000 beads on a lattice in the lower part, unsettled) and times N steps; it reports
particle-steps per second beside the thesis' GPU figure (13.8 s per 1000 steps at
253,125 beads = 1.83e7 particle-steps/s, fig. 6.16).

Measured (default run, slice 7.5 mm, J = 35 %; angles in 5 deg sectors; power of the
slice scaled to the 270 mm mill, end plates left out):

    speed   toe   shoulder   (Morrell 1996)   power    torque arm   solids in the bulk
    60 %   215     25         225 / 36        21.3 W    21.2 W       0.61
    70 %   220     30         225 / 47        26.0 W    26.0 W       0.60
    80 %   220     35         224 / 58        30.7 W    30.4 W       0.60

The thesis gives no toe/shoulder angles or power for this mill; it reports a bulk
solidicity of 0.5-0.6 and beads at the shell moving at the shell speed (0.73 m/s at
60 %); here the bed between the lifters (rho ~ 141 mm) moves at 0.68 m/s = omega rho at
60 %. Steady state: the drive's work rate equals the dissipation rate within 0.5 % and
the weight's torque arm within 1 %.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import dpm

D_MILL = 0.30
R_MILL = 0.5 * D_MILL
L_MILL = 0.27
R_BEAD = 1.5e-3
N_LIFTERS = 12
LIFTER_H = 0.010
LIFTER_W = 0.010
FILL = 0.35                   # J: bed volume / mill volume
BED_SOLIDS = 0.6              # solids fraction of the bed at rest
E_GLASS = 2 * (1 + 0.23) * 26e9   # thesis fig. 5.24: shear modulus 26 GPa, nu = 0.23
E_SCALE = 1e-4                # stiffness reduction (see the module docstring)
DT = 2.5e-5
G = 9.81
N_CRITICAL = 42.3 / math.sqrt(D_MILL)   # rpm
SPEEDS = (0.6, 0.7, 0.8)
# the direction of rotation: about -y, so that the bottom moves towards +x
AXIS = (0.0, -1.0, 0.0)
THESIS_PARTICLE_STEPS = 253125 * 1000 / 13.795   # fig. 6.16: 1.83e7 particle-steps/s


def rpm_of(fraction: float) -> float:
    return fraction * N_CRITICAL


def lifter_angles() -> np.ndarray:
    """Angular positions [rad] of the lifters at t = 0, from +x towards +z."""
    return 2 * math.pi * (np.arange(N_LIFTERS) + 0.5) / N_LIFTERS


def materials() -> tuple[dpm.Material, dpm.Material]:
    glass = dpm.Material("glass", density=2500.0, young=E_GLASS * E_SCALE, poisson=0.23)
    shell = dpm.Material("shell", density=950.0, young=E_GLASS * E_SCALE, poisson=0.42)
    return glass, shell


def mill_profile(arc_points: int = 8) -> np.ndarray:
    """The mill's inner outline in the x-z plane (closed polygon, anticlockwise): arcs of
    the shell between the lifters and, at each lifter, its two sides and its top."""
    half = 0.5 * LIFTER_W
    ri = R_MILL - LIFTER_H
    dphi_shell = math.asin(half / R_MILL)
    pts = []
    th = lifter_angles()
    for k, a in enumerate(th):
        b = th[(k + 1) % N_LIFTERS] + (2 * math.pi if k == N_LIFTERS - 1 else 0.0)
        e1 = np.array([math.cos(a), math.sin(a)])
        t1 = np.array([-math.sin(a), math.cos(a)])
        # lifter k: shell corner (trailing), tip corners, shell corner (leading)
        pts.append(R_MILL * math.cos(dphi_shell) * e1 - half * t1)
        pts.append(ri * e1 - half * t1)
        pts.append(ri * e1 + half * t1)
        pts.append(R_MILL * math.cos(dphi_shell) * e1 + half * t1)
        # the shell arc to the next lifter
        for phi in np.linspace(a + dphi_shell, b - dphi_shell, arc_points + 2)[1:-1]:
            pts.append(R_MILL * np.array([math.cos(phi), math.sin(phi)]))
    return np.array(pts)


def mill_mesh(y0: float, y1: float, caps: bool) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of the shell-with-lifters mesh: the profile extruded from y0
    to y1 (faces facing the axis) and, with ``caps``, the end discs fanned from the axis
    (facing into the mill). The profile is star-shaped about the axis, so the fans are
    valid triangulations."""
    p = mill_profile()
    n = len(p)
    v0 = np.column_stack([p[:, 0], np.full(n, y0), p[:, 1]])
    v1 = np.column_stack([p[:, 0], np.full(n, y1), p[:, 1]])
    verts = [v0, v1]
    faces = []
    for i in range(n):
        j = (i + 1) % n
        # (p_j - p_i) x (+y) points left of the anticlockwise profile: towards the axis
        faces.append((i, j, n + i))
        faces.append((j, n + j, n + i))
    if caps:
        verts.append(np.array([[0.0, y0, 0.0], [0.0, y1, 0.0]]))
        c0, c1 = 2 * n, 2 * n + 1
        for i in range(n):
            j = (i + 1) % n
            faces.append((c0, j, i))            # y = y0 disc, normal +y
            faces.append((c1, n + i, n + j))    # y = y1 disc, normal -y
    v = np.vstack(verts)
    f = np.array(faces, dtype=np.int64)
    return v, f


def charge_sites(y0: float, y1: float, n: int) -> np.ndarray:
    """The ``n`` lowest sites of a simple cubic lattice (spacing ~2.1 r) inside the
    mill between y0 and y1, clear of the shell and the lifters."""
    s = 2.1 * R_BEAD
    ny = max(1, int((y1 - y0) // s))
    ys = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
    xs = np.arange(-R_MILL + s / 2, R_MILL, s)
    xx, yy, zz = np.meshgrid(xs, ys, xs, indexing="ij")
    pos = np.column_stack([xx.ravel(), yy.ravel(), zz.ravel()])
    rho = np.hypot(pos[:, 0], pos[:, 2])
    keep = rho < R_MILL - 1.3 * R_BEAD
    for a in lifter_angles():
        radial = pos[:, 0] * math.cos(a) + pos[:, 2] * math.sin(a)
        tang = -pos[:, 0] * math.sin(a) + pos[:, 2] * math.cos(a)
        keep &= ~((radial > R_MILL - LIFTER_H - 1.3 * R_BEAD)
                  & (np.abs(tang) < 0.5 * LIFTER_W + 1.3 * R_BEAD))
    pos = pos[keep]
    if len(pos) < n:
        raise ValueError(f"{n} beads do not fit on the lattice ({len(pos)} sites)")
    return pos[np.argsort(pos[:, 2], kind="stable")][:n]


def bead_count(length: float, fill: float) -> int:
    free = math.pi * R_MILL**2 - N_LIFTERS * LIFTER_H * LIFTER_W
    return int(fill * free * length * BED_SOLIDS / (4 / 3 * math.pi * R_BEAD**3))


def build(fraction: float = 0.7, length: float = 0.0075, periodic: bool = True,
          fill: float = FILL, lifters: str = "bars", ramp: float = 0.2,
          dt: float = DT, seed: int = 0) -> dpm.Simulation:
    """The mill turning at ``fraction`` of critical speed. ``periodic``: a slice of
    ``length`` with periodic ends along y (no end plates; shell and lifters run past the
    periodic faces); else the mill of that length with end plates."""
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, -G))
    glass, shell = materials()
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.66, friction=0.154,
                rolling_friction=0.01)
    sim.contact(glass, shell, model="hertz_mindlin", restitution=0.55, friction=0.32,
                rolling_friction=0.01)
    motion = dpm.Rotation(axis=AXIS, rpm=rpm_of(fraction), center=(0.0, 0.0, 0.0),
                          ramp=ramp)
    margin = 4 * R_BEAD if periodic else 0.0
    y0, y1 = -margin, length + margin
    sim.mill_boundaries = []
    if lifters == "mesh":
        v, f = mill_mesh(y0, y1, caps=not periodic)
        sim.mill_boundaries.append(sim.add_boundary(
            "mesh", material=shell, vertices=v, faces=f, motion=motion,
            side="both" if periodic else "inside"))
    elif lifters == "bars":
        sim.mill_boundaries.append(sim.add_boundary(
            "tube", material=shell, start=(0.0, y0, 0.0), axis=(0.0, 1.0, 0.0),
            length=y1 - y0, radius=R_MILL, caps="none" if periodic else "both",
            motion=motion))
        for a in lifter_angles():
            e_r = np.array([math.cos(a), 0.0, math.sin(a)])
            e_t = np.array([-math.sin(a), 0.0, math.cos(a)])
            # the bar reaches 1 mm into the shell, so that no gap is left at its foot
            sim.mill_boundaries.append(sim.add_boundary(
                "wall", material=shell, center=(R_MILL - 0.5 * LIFTER_H + 0.5e-3) * e_r
                + np.array([0.0, 0.5 * (y0 + y1), 0.0]),
                normal=e_t, u=e_r, half_extents=(0.5 * LIFTER_H + 0.5e-3, 0.5 * (y1 - y0)),
                thickness=LIFTER_W, motion=motion))
    else:
        raise ValueError(f"lifters={lifters!r}; allowed: bars, mesh")
    if periodic:
        sim.set_periodic("y", 0.0, length)
    gap = 0.0 if periodic else 1.3 * R_BEAD
    pos = charge_sites(gap, length - gap, bead_count(length, fill))
    rng = np.random.default_rng(seed)
    sim.add_particles("sphere", material=glass, radius=R_BEAD, positions=pos,
                      velocities=rng.normal(0.0, 0.01, pos.shape))
    sim.omega = 2 * math.pi * rpm_of(fraction) / 60.0
    sim.slice_length = length
    return sim


def drive(sim: dpm.Simulation) -> tuple[float, float, float]:
    """(power [W], torque about the axis in the sense of rotation [N m], work [J]) of the
    shell and all lifters together."""
    ax = np.asarray(AXIS)
    power = sum(b.power() for b in sim.mill_boundaries)
    torque = sum(float(b.torque @ ax) for b in sim.mill_boundaries)
    work = sum(b.work for b in sim.mill_boundaries)
    return power, torque, work


def toe_shoulder(field, bulk: float | None = None) -> dict:
    """Toe and shoulder angles [deg] from the time-averaged solids fraction (see the
    module docstring): the ring R - H - 4 r < rho < R - H in 5 deg sectors."""
    xc, _, zc = field.centres
    phi = field.phi.mean(axis=1)
    X, Z = np.meshgrid(xc, zc, indexing="ij")
    rho = np.hypot(X, Z)
    th = np.degrees(np.arctan2(Z, X)) % 360.0
    inner = R_MILL - LIFTER_H
    if bulk is None:
        bulk = float(np.percentile(phi[rho < inner - 4 * R_BEAD], 95))
    ring = (rho > inner - 4 * R_BEAD) & (rho < inner)
    edges = np.arange(0.0, 361.0, 5.0)
    prof = np.array([phi[ring & (th >= a) & (th < b)].mean() if np.any(
        ring & (th >= a) & (th < b)) else 0.0 for a, b in zip(edges[:-1], edges[1:],
                                                               strict=True)])
    full = prof >= 0.5 * bulk
    centres = 0.5 * (edges[:-1] + edges[1:])
    # the arc in contact contains the fullest sector of the lower half; walk from it
    # both ways
    lower = (centres > 180.0) & (centres < 360.0)
    k0 = int(np.flatnonzero(lower)[np.argmax(prof[lower])])
    if not full[k0]:
        return {"toe": float("nan"), "shoulder": float("nan"), "bulk_phi": bulk,
                "ring_profile": prof.tolist()}
    n = len(full)
    k = k0
    while full[(k + 1) % n] and (k + 1 - k0) < n:
        k += 1
    shoulder = (edges[(k % n) + 1]) % 360.0      # the far edge of the last full sector
    k = k0
    while full[(k - 1) % n] and (k0 - k + 1) < n:
        k -= 1
    toe = edges[k % n]
    return {"toe": float(toe), "shoulder": float(shoulder), "bulk_phi": bulk,
            "ring_profile": prof.tolist()}


def run_speed(fraction: float, out: Path, length: float, fill: float, revolutions: float,
              average: float, lifters: str, frame_every: float = 0.01,
              sample: int = 80) -> dict:
    """Run one speed; return its figures and the averaged field."""
    from dpm import analysis as an

    sim = build(fraction, length=length, fill=fill, lifters=lifters)
    n = len(sim.bodies)
    mass = float(sim.bodies.mass.sum())
    t_rev = 2 * math.pi / sim.omega
    until = 0.2 + revolutions * t_rev        # ramp + revolutions
    t_avg = until - average * t_rev
    path = out / f"ball_mill_{round(fraction * 100)}.h5"
    sim.output(str(path), every=frame_every, overwrite=True)
    dpm.notice(f"{fraction:.0%} critical ({rpm_of(fraction):.1f} rpm): {n} beads, slice "
               f"{length * 1e3:.1f} mm, dt = {sim.dt:g} s, {until:.2f} s to run "
               f"({revolutions:g} rev), averages from {t_avg:.2f} s", flush=True)
    rec = {k: [] for k in ("t", "power", "torque", "work", "xcm", "zcm", "Ly", "dissipated",
                           "kinetic", "overlap")}
    w0 = time.perf_counter()
    steps0 = sim.step_count
    ax = np.asarray(AXIS)
    while sim.time < until - 1e-12:
        sim.run(steps=min(sample, max(1, round((until - sim.time) / sim.dt))),
                progress=False)
        p, tq, w = drive(sim)
        x = sim.bodies.position
        bal = sim.energy.balance(sim)
        rec["t"].append(sim.time)
        rec["power"].append(p)
        rec["torque"].append(tq)
        rec["work"].append(w)
        rec["xcm"].append(float(x[:, 0].mean()))
        rec["zcm"].append(float(x[:, 2].mean()))
        rec["Ly"].append(float(sim.angular_momentum() @ ax))
        rec["dissipated"].append(bal["dissipated"])
        rec["kinetic"].append(bal["kinetic"])
        rec["overlap"].append(float(sim.backend.max_overlap()[0]))
    wall = time.perf_counter() - w0
    psteps = n * (sim.step_count - steps0) / wall
    sim.close()
    r = {k: np.asarray(v) for k, v in rec.items()}
    win = r["t"] >= t_avg
    tw = r["t"][win]
    span = tw[-1] - tw[0]
    work_rate = (r["work"][win][-1] - r["work"][win][0]) / span
    diss_rate = (r["dissipated"][win][-1] - r["dissipated"][win][0]) / span
    # the charge's angular momentum balance about the axis (sense of rotation): drive
    # torque on the charge - M g x_cm (weight) = dL/dt; the drive torque on the charge is
    # minus the torque on the boundaries
    dLdt = (r["Ly"][win][-1] - r["Ly"][win][0]) / span
    torque_drive = -float(np.mean(r["torque"][win]))
    torque_weight = mass * G * float(np.mean(r["xcm"][win]))
    run = dpm.load(str(path))
    frames = [k for k, t in enumerate(run.times) if t >= t_avg - 1e-9]
    lo = (-R_MILL, -R_BEAD, -R_MILL)
    hi = (R_MILL, length + R_BEAD, R_MILL)
    cell = 4 * R_BEAD
    field = an.voxel_fields(run, cell=(cell, hi[1] - lo[1], cell), lower=lo, upper=hi,
                            frames=frames, per_radius=2)
    # the grid reaches r past the periodic faces (it holds whole spheres); phi per
    # length of the slice
    field.phi *= (hi[1] - lo[1]) / length
    cv = np.prod([e[1] - e[0] for e in field.edges])
    bead_volume_in_map = float(field.phi.sum() * cv * length / (hi[1] - lo[1]))
    angles = toe_shoulder(field)
    speed = field.slice("speed", axis="y")[0]
    res = {
        "fraction_of_critical": fraction, "rpm": rpm_of(fraction), "omega": sim.omega,
        "beads": n, "slice_length": length, "fill": fill, "lifters": lifters,
        "simulated": float(sim.time), "averaged_from": t_avg, "frames_averaged": len(frames),
        "wall_s": wall, "particle_steps_per_s": psteps,
        "power_mean_W": float(np.mean(r["power"][win])),
        "power_from_work_W": float(work_rate),
        "dissipation_rate_W": float(diss_rate),
        "power_per_metre_W_per_m": float(np.mean(r["power"][win])) / length,
        "power_full_mill_W": float(np.mean(r["power"][win])) / length * L_MILL,
        "torque_drive_Nm": torque_drive, "torque_weight_Nm": torque_weight,
        "dL_dt_Nm": dLdt,
        "power_torque_arm_W": torque_weight * sim.omega,
        "xcm_m": float(np.mean(r["xcm"][win])), "zcm_m": float(np.mean(r["zcm"][win])),
        "toe_deg": angles["toe"], "shoulder_deg": angles["shoulder"],
        "bulk_phi": angles["bulk_phi"],
        "max_overlap_of_radius": float(np.max(r["overlap"])),
        "bead_volume_in_map": bead_volume_in_map,
        "bead_volume": n * 4 / 3 * math.pi * R_BEAD**3,
        "shell_speed": sim.omega * R_MILL,
        "max_map_speed": float(np.nanmax(speed)),
        "h5": path.name, "xdmf": path.with_suffix(".xdmf").name,
    }
    dpm.notice(f"  {wall:.0f} s wall ({psteps:.3g} particle-steps/s); power "
               f"{res['power_mean_W']:.3f} W (work rate {work_rate:.3f} W, torque arm "
               f"{res['power_torque_arm_W']:.3f} W) "
               f"for the slice; toe {angles['toe']:.0f} deg, shoulder {angles['shoulder']:.0f} "
               f"deg", flush=True)
    return {"result": res, "field": field, "series": r}


def picture(results: list[dict], path: Path, show: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 2, figsize=(10, 8.4))
    f = results[show]["field"]
    res = results[show]["result"]
    phi, ext = f.slice("phi", axis="y")
    ext = [1e3 * e for e in ext]
    im = axs[0, 0].imshow(phi.T, origin="lower", extent=ext, cmap="viridis", vmin=0,
                          vmax=0.7)
    fig.colorbar(im, ax=axs[0, 0], label="solids fraction")
    axs[0, 0].set_title(f"time-averaged solids fraction, {res['fraction_of_critical']:.0%}"
                        " critical")
    vx, _ = f.slice("vx", axis="y")
    vz, _ = f.slice("vz", axis="y")
    sp = np.hypot(vx, vz)
    xc, _, zc = f.centres
    im = axs[0, 1].imshow(sp.T, origin="lower", extent=ext, cmap="magma", vmin=0)
    fig.colorbar(im, ax=axs[0, 1], label="speed in the x-z plane [m/s]")
    step = 2
    X, Z = np.meshgrid(1e3 * xc, 1e3 * zc, indexing="ij")
    ok = np.isfinite(vx) & (phi > 0.05)
    sl = (slice(None, None, step), slice(None, None, step))
    axs[0, 1].quiver(X[sl][ok[sl]], Z[sl][ok[sl]], vx[sl][ok[sl]], vz[sl][ok[sl]],
                     color="c", scale=12, width=0.003)
    axs[0, 1].set_title("time-averaged velocity")
    th = np.linspace(0, 2 * np.pi, 200)
    for ax in axs[0]:
        ax.plot(1e3 * R_MILL * np.cos(th), 1e3 * R_MILL * np.sin(th), "w-", lw=0.8)
        for name, c in (("toe_deg", "r"), ("shoulder_deg", "orange")):
            a = math.radians(res[name])
            if math.isfinite(a):
                ax.plot([0, 1e3 * R_MILL * math.cos(a)], [0, 1e3 * R_MILL * math.sin(a)],
                        "--", color=c, lw=1.2, label=name.split("_")[0])
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("z [mm]")
        ax.set_aspect("equal")
    axs[0, 0].legend(loc="upper left", fontsize=8, framealpha=0.6)
    pct = [100 * r["result"]["fraction_of_critical"] for r in results]
    toe = [r["result"]["toe_deg"] for r in results]
    sh = [r["result"]["shoulder_deg"] for r in results]
    axs[1, 0].plot(pct, toe, "o-", color="r", label="toe (this run)")
    axs[1, 0].plot(pct, sh, "s-", color="orange", label="shoulder (this run)")
    mt = [morrell_angles(p / 100, results[0]["result"]["fill"]) for p in pct]
    axs[1, 0].plot(pct, [m[0] for m in mt], "r:+", label="toe, Morrell 1996")
    axs[1, 0].plot(pct, [m[1] for m in mt], ":+", color="orange",
                   label="shoulder, Morrell 1996")
    axs[1, 0].set_xlabel("speed [% of critical]")
    axs[1, 0].set_ylabel("angle from the rising horizontal [deg]")
    axs[1, 0].set_title("toe and shoulder of the charge")
    axs[1, 0].legend(fontsize=8)
    p = [r["result"]["power_per_metre_W_per_m"] for r in results]
    pa = [r["result"]["power_torque_arm_W"] / r["result"]["slice_length"] for r in results]
    axs[1, 1].plot(pct, p, "o-", label="drive power (shell + lifters)")
    axs[1, 1].plot(pct, pa, "x--", label="torque arm M g x_cm omega")
    axs[1, 1].set_xlabel("speed [% of critical]")
    axs[1, 1].set_ylabel("power per metre of mill [W/m]")
    axs[1, 1].set_title(f"power draw (x {L_MILL} m for the pilot mill)")
    axs[1, 1].legend(fontsize=8)
    fig.suptitle(f"300 mm ball mill, {N_LIFTERS} lifters, 3 mm glass beads, J = "
                 f"{results[0]['result']['fill']:.0%}, periodic slice "
                 f"{1e3 * results[0]['result']['slice_length']:.1f} mm")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def morrell_angles(phi: float, fill: float) -> tuple[float, float]:
    """Toe and shoulder [deg, from the rising horizontal in the sense of rotation] of
    Morrell's empirical charge-shape model (Morrell, S. 1996, "Power draw of wet tumbling
    mills and its relationship to charge dynamics", Trans. IMM C 105, 43-62):
    theta_T = 2.5307 (1.2796 - J)(1 - exp(-19.42 (phi_c - phi))) + pi/2,
    theta_S = pi/2 - (theta_T - pi/2)((0.3386 + 0.1041 phi) + (1.54 - 2.5673 phi) J),
    phi_c = max(phi, 0.35 (3.364 - J)). A correlation for industrial mills, for scale
    only."""
    pc = max(phi, 0.35 * (3.364 - fill))
    tt = 2.5307 * (1.2796 - fill) * (1 - math.exp(-19.42 * (pc - phi))) + math.pi / 2
    ts = math.pi / 2 - (tt - math.pi / 2) * ((0.3386 + 0.1041 * phi)
                                            + (1.54 - 2.5673 * phi) * fill)
    return math.degrees(tt), math.degrees(ts)


def full_charge(steps: int, out: Path, settle: int = 800) -> dict:
    """Build the whole mill with the full charge, let it fall into contact for ``settle``
    steps (20 ms by default: the lattice's 0.1 r gaps close from the bottom up), then time
    ``steps`` steps (:func:`full_charge_revolutions` runs whole revolutions)."""
    t0 = time.perf_counter()
    sim = build(0.7, length=L_MILL, periodic=False, ramp=0.0)
    n = len(sim.bodies)
    t_build = time.perf_counter() - t0
    dpm.notice(f"full charge: {n} beads in the whole {L_MILL * 1e3:.0f} mm mill (built in "
               f"{t_build:.1f} s); {settle} steps to fall into contact, then {steps} timed "
               f"steps at dt = {sim.dt:g} s", flush=True)
    t0 = time.perf_counter()
    sim.run(steps=1, progress=False)         # prepare + (cached) compile + neighbour lists
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    if settle > 1:
        sim.run(steps=settle - 1, progress=False)
    t_settle = time.perf_counter() - t0
    contacts = sim.contact_count()
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    ps = n * steps / wall
    res = {"beads": n, "steps": steps, "settle_steps": settle, "wall_s": wall,
           "first_step_s": t_first, "settle_s": t_settle, "build_s": t_build,
           "contacts_per_bead": contacts / n,
           "particle_steps_per_s": ps, "s_per_1000_steps": 1000 * wall / steps,
           "settle_particle_steps_per_s": n * max(settle - 1, 0) / max(t_settle, 1e-9),
           "thesis_particle_steps_per_s": THESIS_PARTICLE_STEPS,
           "thesis_s_per_1000_steps": 13.795, "ratio_to_thesis": ps / THESIS_PARTICLE_STEPS,
           "simulated_s": (settle + steps) * sim.dt,
           "revolution_steps_70pct": 60 / rpm_of(0.7) / sim.dt,
           "note": f"{steps} steps of a charge {settle} steps after release from a "
                   "lattice, not a revolution"}
    sim.close()
    dpm.notice(f"  {contacts / n:.2f} contacts per bead; {wall:.1f} s for {steps} steps: "
               f"{ps:.3g} particle-steps/s, {res['s_per_1000_steps']:.0f} s per 1000 steps "
               f"(thesis GPU: 13.8 s, {THESIS_PARTICLE_STEPS:.3g}); one revolution at 70 % = "
               f"{res['revolution_steps_70pct']:.0f} steps")
    if dpm.is_root():  # (rank 0 writes: every rank holds the result)
        (out / "ball_mill_full_charge.json").write_text(json.dumps(res, indent=1))
    return res


def full_charge_revolutions(revolutions: float, out: Path, settle: int,
                            threads: int | None = None, resume: bool = False) -> dict:
    """The whole mill (full charge, end plates) for ``revolutions`` revolutions at 70 %
    critical after ``settle`` steps: cost per step along the run, drive power and torque,
    and the weight's torque arm M g x_cm omega (the steady-state check of the slice).

    A checkpoint (``ball_mill_full_charge.ckpt.h5``, with the figures up to it in
    ``.ckpt.json``) is written every 20 samples; ``resume`` goes on from it (a run of
    ~1.5 h on one core may be done in pieces), the samples and wall time adding up."""
    ckpt = out / "ball_mill_full_charge.ckpt.h5"
    js = out / "ball_mill_full_charge.json"
    t0 = time.perf_counter()
    if resume and ckpt.exists() and ckpt.with_suffix(".json").exists():
        sim = dpm.restart(ckpt)
        res = json.loads(ckpt.with_suffix(".json").read_text())
        dpm.notice(f"resumed at step {res['steps_done']}", flush=True)
    else:
        sim = build(0.7, length=L_MILL, periodic=False, ramp=0.0)
        res = None
    if threads:
        sim.threads = threads
    n = len(sim.bodies)
    mass = float(sim.bodies.mass.sum())
    total = int(round(revolutions * 60 / rpm_of(0.7) / sim.dt))
    sample = int(round(0.01 / sim.dt))
    if res is not None:
        res["steps"], res["revolutions"] = total, revolutions
        return _full_charge_loop(sim, res, out, ckpt, js, total, sample, mass)
    res = {"beads": n, "revolutions": revolutions, "settle_steps": settle,
           "threads": int(threads or 1),
           "steps": total, "dt_s": sim.dt, "build_s": time.perf_counter() - t0,
           "thesis_particle_steps_per_s": THESIS_PARTICLE_STEPS,
           "samples": {k: [] for k in ("t", "steps_done", "wall_s", "particle_steps_per_s",
                                       "contacts_per_bead", "power_W", "torque_Nm",
                                       "torque_arm_W", "work_J")}}
    dpm.notice(f"full charge: {n} beads, {settle} settling steps then {revolutions} "
               f"revolution(s) = {total} steps at 70 % critical", flush=True)
    t0 = time.perf_counter()
    sim.run(steps=settle, progress=False)
    res["settle_s"] = time.perf_counter() - t0
    res["run_wall_s"] = 0.0
    res["steps_done"] = 0
    return _full_charge_loop(sim, res, out, ckpt, js, total, sample, mass)


def _full_charge_loop(sim, res, out, ckpt, js, total, sample, mass) -> dict:
    n = len(sim.bodies)
    run_wall = res["run_wall_s"]
    done = res["steps_done"]
    smp = res["samples"]
    while done < total:
        k = min(sample, total - done)
        t1 = time.perf_counter()
        sim.run(steps=k, progress=False)
        dt_wall = time.perf_counter() - t1
        run_wall += dt_wall
        done += k
        p, tq, w = drive(sim)
        xcm = float(sim.bodies.mass @ sim.bodies.position[:, 0]) / mass
        for key, v in (("t", sim.time), ("steps_done", done), ("wall_s", run_wall),
                       ("particle_steps_per_s", n * k / dt_wall),
                       ("contacts_per_bead", sim.contact_count() / n), ("power_W", p),
                       ("torque_Nm", tq), ("torque_arm_W", mass * G * xcm * sim.omega),
                       ("work_J", w)):
            smp[key].append(float(v))
        res["particle_steps_per_s"] = n * done / run_wall
        res["s_per_1000_steps"] = 1000 * run_wall / done
        res["ratio_to_thesis"] = res["particle_steps_per_s"] / THESIS_PARTICLE_STEPS
        res["steps_done"] = done
        res["run_wall_s"] = run_wall
        half = slice(len(smp["t"]) // 2, None)  # the second half of the run
        res["power_second_half_W"] = float(np.mean(smp["power_W"][half]))
        res["torque_arm_second_half_W"] = float(np.mean(smp["torque_arm_W"][half]))
        if len(smp["t"]) % 20 == 0 or done >= total:
            sim.checkpoint(ckpt)  # (with the figures up to it, which a resume takes)
            if dpm.is_root():
                ckpt.with_suffix(".json").write_text(json.dumps(res))
        if dpm.is_root():  # (rank 0 writes: every rank holds the result)
            js.write_text(json.dumps(res, indent=1))
        dpm.notice(f"  t = {sim.time:.3f} s, {done}/{total} steps, {run_wall:.0f} s, "
                   f"{res['particle_steps_per_s']:.3g} p-s/s, power {p:.1f} W", flush=True)
    sim.close()
    if dpm.is_root():
        full_charge_picture(res, out / "ball_mill_full_charge.png")
    return res


def full_charge_picture(res: dict, path: Path) -> None:
    """Cost (particle-steps/s, contacts per bead) and drive power along the full-charge
    run, from its JSON (``res``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = res["samples"]
    t = np.asarray(s["t"])
    fig, axs = plt.subplots(1, 2, figsize=(11, 3.8))
    axs[0].plot(t, np.asarray(s["particle_steps_per_s"]) / 1e6,
                label=f"dpm, {res.get('threads', 1)} thread(s)")
    axs[0].axhline(res["thesis_particle_steps_per_s"] / 1e6, color="k", ls="--",
                   label="thesis GPU (GTX 560 Ti)")
    axs[0].set_xlabel("simulated time [s]")
    axs[0].set_ylabel("million particle-steps per second")
    ax2 = axs[0].twinx()
    ax2.plot(t, s["contacts_per_bead"], color="tab:orange", label="contacts per bead")
    ax2.set_ylabel("contacts per bead", color="tab:orange")
    axs[0].legend(loc="lower right", bbox_to_anchor=(1.0, 0.15), fontsize=8)
    axs[0].set_title(f"{res['beads']:,} beads: {res['particle_steps_per_s']:.3g} "
                     f"particle-steps/s over {res['steps_done']:,} steps", fontsize=9)
    axs[1].plot(t, s["power_W"], label="drive power (shell + lifters + end plates)")
    axs[1].plot(t, s["torque_arm_W"], "--", label="torque arm M g x_cm omega")
    axs[1].set_xlabel("simulated time [s]")
    axs[1].set_ylabel("power [W]")
    turns = res["revolutions"] * res["steps_done"] / res["steps"]
    axs[1].set_title(f"{turns:.2g} revolution(s) at 70 % critical; second half: "
                     f"{res['power_second_half_W']:.1f} W drive, "
                     f"{res['torque_arm_second_half_W']:.1f} W torque arm", fontsize=8)
    axs[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help="CI: thin slice at J = 9 %%, 70 %% critical, 0.5 s")
    p.add_argument("--output", default=".", help="directory for the outputs")
    p.add_argument("--lifters", choices=("bars", "mesh"), default="bars",
                   help="lifters as wall slabs (default) or shell + lifters as one mesh")
    p.add_argument("--speeds", type=float, nargs="+", default=None,
                   help="fractions of critical speed (default 0.6 0.7 0.8)")
    p.add_argument("--revolutions", type=float, default=2.0,
                   help="revolutions per speed after the 0.2 s ramp (default mode)")
    p.add_argument("--full-charge-steps", type=int, default=0, metavar="N",
                   help="build the whole mill with the full charge and time N steps")
    p.add_argument("--full-charge-settle", type=int, default=800, metavar="S",
                   help="steps before the timed ones (the lattice falls into contact)")
    p.add_argument("--full-charge-revolutions", type=float, default=0.0, metavar="R",
                   help="whole mill: run R revolutions at 70 %% (sampled every 10 ms)")
    p.add_argument("--full-charge-resume", action="store_true",
                   help="go on from the full-charge run's checkpoint in --output")
    p.add_argument("--threads", type=int, default=None, help="threads of the full charge")
    args = p.parse_args(argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    if args.full_charge_steps or args.full_charge_revolutions:
        if args.full_charge_revolutions:
            return {"full_charge": full_charge_revolutions(
                args.full_charge_revolutions, out, args.full_charge_settle, args.threads,
                args.full_charge_resume)}
        return {"full_charge": full_charge(args.full_charge_steps, out,
                                           args.full_charge_settle)}
    if args.quick:
        speeds = args.speeds or [0.7]
        # 0.5 s: the 0.2 s ramp and 0.3 s at speed; averages over the last quarter turn
        kw = dict(length=0.0075, fill=0.09, revolutions=0.3 * rpm_of(speeds[0]) / 60,
                  average=0.25)
    else:
        speeds = args.speeds or list(SPEEDS)
        kw = dict(length=0.0075, fill=FILL, revolutions=args.revolutions, average=0.8,
                  frame_every=0.02)
    t0 = time.perf_counter()
    results = [run_speed(s, out, lifters=args.lifters, **kw) for s in speeds]
    wall = time.perf_counter() - t0
    summary = {
        "scene": "300 mm x 270 mm pilot ball mill with lifters (Hromnik 2013)",
        "mode": "quick" if args.quick else "default",
        "lifters": {"kind": args.lifters, "count": N_LIFTERS, "height_m": LIFTER_H,
                    "width_m": LIFTER_W},
        "bead_radius_m": R_BEAD, "young_glass_Pa": E_GLASS * E_SCALE,
        "young_thesis_Pa": E_GLASS, "young_scale": E_SCALE, "dt_s": DT,
        "critical_rpm": N_CRITICAL, "wall_s": wall,
        "morrell_1996": {f"{s:.2f}": dict(zip(("toe_deg", "shoulder_deg"),
                                              morrell_angles(s, kw["fill"]), strict=True))
                         for s in speeds},
        "speeds": [r["result"] for r in results],
    }
    if dpm.is_root():  # (rank 0 writes: every rank holds the result)
        (out / "ball_mill.json").write_text(json.dumps(summary, indent=1))
        picture(results, out / "ball_mill.png", show=len(results) // 2)
    dpm.notice(f"{len(speeds)} speed(s) in {wall:.0f} s; {out / 'ball_mill.json'}, "
               f"{out / 'ball_mill.png'}")
    summary["_results"] = results
    return summary


if __name__ == "__main__":
    main()
