"""A rotating drum, dpm against LIGGGHTS' ``fix move/mesh`` on the same scene in one run.

A drum of radius 20 mm (axis y, horizontal, through the origin; depth 44 mm, ``--quick``
12 mm) half filled with glass beads of r = 1 mm (2500 kg/m3, E = 5 MPa, nu = 0.3) turns at
a fixed speed from t = 0 (Froude number omega^2 R / g = 0.04: 42 rpm, the rolling regime).
Hertz-Mindlin, no rolling resistance: beads e = 0.5, mu = 0.5; beads on the steel drum
(E = 20 MPa, nu = 0.3) e = 0.5, mu = 0.8; dt = 2e-5 s, skin 0.4 mm (0.2 d, both codes).

The drum, three ways:

- LIGGGHTS 3.8: an ASCII STL (the barrel as a 96-gon of the circle's area, rings about
  1.3 x 2 mm; both end caps as Delaunay triangulations of ~2 mm), ``fix mesh/surface`` +
  ``fix wall/gran model hertz tangential history mesh`` + ``fix move/mesh ... rotate origin
  0 0 0 axis 0 1 0 period T`` (``benchmarks/scenes/drum/drum.liggghts``);
- dpm, the same STL as a ``mesh`` boundary moved by ``dpm.Rotation``;
- dpm, the analytic ``tube`` (``caps="both"``) moved by the same rotation (LIGGGHTS has
  no rotating analytic cylinder: its ``primitive`` walls do not take ``move/mesh``).

The same starts: the beads on a jittered lattice in the lower part of the drum with small
random velocities, generated here for two seeds; LIGGGHTS reads them from a data file
(``read_data``, with a Velocities section). LIGGGHTS runs from both starts (its
run-to-run spread), and so do dpm's mesh and tube. The runs go in turn (LIGGGHTS 1, dpm
mesh 1, dpm tube 1, LIGGGHTS 2, ...) so that a change of load on a shared machine falls
on both codes.

Compared, every 0.05 s from the same positions, velocities and spins (LIGGGHTS' dump,
dpm's state): the dynamic angle of repose (``dpm.analysis.drum_surface``, ``method=
"fraction"``: the bed's surface in 10 columns over the middle 70 % of the diameter, a line
fitted through them), the bed's centre of mass in the cross-section (x: horizontal,
positive on the lifted side; z: height above the axis) and the mean kinetic energy per
bead (translational and rotational). Means over the steady window are compared (the
spin-up, in which the bed settles and is lifted and the first avalanche overshoots, is
0.5 s = 0.35 revolution, 0.4 s at ``--quick``; the window 0.7 s = 0.49 revolution, 0.4 s
at ``--quick``: the bed is steady from about 0.35 s on, see the figure), dpm against the
LIGGGHTS runs' range and the window mean's own statistical error.

Speed: particle-steps per second of each phase (spin-up; steady window). dpm runs the
scene's own step module (``DPM_KERNELS=scene``), after a warm-up in a process of its own
that compiles or loads it, and in each run after a warm-up scene of 500 steps. Start 1's
window runs its 0.05 s intervals on 1 and 2 threads in turn (``sim.threads``; a run's
results are the same bit for bit for any thread count): both counts timed on the same
steps under the same load; everything else on 1 thread. LIGGGHTS on one core ("Loop
time" of each ``run``). Peak resident memory (ru_maxrss) of each process.

    python benchmarks/drum_peer.py [--quick] [--starts N] [--no-liggghts]

``--quick`` runs the 12 mm drum from start 1 only (``--starts 2``: from both, as the
reference of tests/physics/test_drum_peer.py was recorded).

Writes benchmarks/results/drum_peer[_quick].json and .png.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TEMPLATE = HERE / "scenes" / "drum" / "drum.liggghts"

R_DRUM, R_BEAD, DENSITY = 0.02, 1e-3, 2500.0
E_BEAD, NU_BEAD, E_WALL, NU_WALL = 5e6, 0.3, 2e7, 0.3
E_PP, E_PW, MU_PP, MU_PW = 0.5, 0.5, 0.5, 0.8
FROUDE = 0.04
OMEGA = math.sqrt(FROUDE * 9.81 / R_DRUM)  # [rad/s]
PERIOD = 2 * math.pi / OMEGA
DT, SKIN = 2e-5, 4e-4
#: barrel polygon sides, cap mesh spacing [m]
N_THETA, CAP_SPACING = 96, 2e-3
#: bulk solid fraction of the settled bed, filled fraction of the cross-section
PACKING, FILL = 0.6, 0.5
#: sampling interval [s]; warm-up steps of dpm (boundary moved 0.9 mm: a rebuild or more)
SAMPLE, WARMUP = 0.05, 500
STARTS = (1, 2)
SIZES = {"full": {"length": 0.044, "spin": 0.5, "window": 0.7},
         "quick": {"length": 0.012, "spin": 0.4, "window": 0.4}}
#: the surface fit (drum_surface)
SURFACE = {"bins": 10, "span": 0.7, "method": "fraction"}


def steps_of(seconds: float) -> int:
    return int(round(seconds / DT))


def config(size: str) -> dict:
    s = SIZES[size]
    sample = steps_of(SAMPLE)
    return {"size": size, "length": s["length"],
            "spin_steps": int(round(s["spin"] / SAMPLE)) * sample,
            "window_steps": int(round(s["window"] / SAMPLE)) * sample,
            "sample_steps": sample}


# ---------------------------------------------------------------- geometry and starts

def drum_triangles(length: float) -> np.ndarray:
    """Triangles (k, 3, 3) of the closed drum: the barrel (a N_THETA-gon with the circle's
    area, split into rings about as long as a side and a half) and both caps (Delaunay
    triangulations of the polygon's corners and a hexagonal grid inside)."""
    from scipy.spatial import Delaunay

    rv = R_DRUM * math.sqrt(2 * math.pi / (N_THETA * math.sin(2 * math.pi / N_THETA)))
    th = np.arange(N_THETA) * 2 * math.pi / N_THETA
    ring = np.c_[rv * np.cos(th), rv * np.sin(th)]  # (x, z)
    side = 2 * rv * math.sin(math.pi / N_THETA)
    ny = max(1, int(round(length / (1.5 * side))))
    ys = np.linspace(0.0, length, ny + 1)
    tris = []
    for a, b in zip(ys[:-1], ys[1:], strict=True):
        for k in range(N_THETA):
            p, q = ring[k], ring[(k + 1) % N_THETA]
            p0, q0, p1, q1 = ([p[0], a, p[1]], [q[0], a, q[1]], [p[0], b, p[1]],
                              [q[0], b, q[1]])
            tris += [(p0, q0, q1), (p0, q1, p1)]
    # a cap: the polygon's corners and a hexagonal grid at least half a spacing inside
    h = CAP_SPACING
    gx, gz = np.meshgrid(np.arange(-R_DRUM, R_DRUM + h, h),
                         np.arange(-R_DRUM, R_DRUM + h, h * math.sqrt(3) / 2))
    gx = gx + (np.arange(gx.shape[0])[:, None] % 2) * h / 2
    grid = np.c_[gx.ravel(), gz.ravel()]
    grid = grid[np.hypot(grid[:, 0], grid[:, 1]) < rv * math.cos(math.pi / N_THETA) - h / 2]
    pts = np.vstack([ring, grid])
    for f in Delaunay(pts).simplices:
        for y in (0.0, length):
            tris.append(tuple([pts[i][0], y, pts[i][1]] for i in f))
    tris = np.array(tris, float)
    # normals inwards, to the beads (dpm: a closed mesh with inward normals is a container)
    c = tris.mean(axis=1)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    out = c - np.array([0.0, 0.5 * length, 0.0])
    out[np.abs(c[:, 1] - 0.5 * length) < 0.5 * length - 1e-12, 1] = 0.0  # barrel: radial
    flip = np.einsum("ij,ij->i", n, out) > 0
    tris[flip] = tris[flip][:, ::-1]
    return tris


def write_stl(path: Path, tris: np.ndarray) -> None:
    """ASCII STL (LIGGGHTS reads ASCII STL)."""
    lines = ["solid drum"]
    for t in tris:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n /= np.linalg.norm(n)
        lines.append(f"facet normal {n[0]:.6g} {n[1]:.6g} {n[2]:.6g}\nouter loop")
        lines += [f"vertex {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}" for p in t]
        lines.append("endloop\nendfacet")
    lines.append("endsolid drum")
    path.write_text("\n".join(lines) + "\n")


def bead_count(length: float) -> int:
    return int(FILL * PACKING * math.pi * R_DRUM**2 * length / (4 / 3 * math.pi * R_BEAD**3))


def start(length: float, seed: int) -> dict:
    """The lowest lattice sites (spacing 2.1 r, jittered by 0.02 r) inside the drum, one
    bead each, with velocities of 0.01 m/s rms: the start of seed ``seed``."""
    rng = np.random.default_rng(seed)
    a = 2.1 * R_BEAD
    xs = np.arange(-R_DRUM + a / 2, R_DRUM, a)
    ny = int((length - 2.1 * R_BEAD) / a) + 1
    ys = 0.5 * length + (np.arange(ny) - 0.5 * (ny - 1)) * a
    g = np.stack(np.meshgrid(xs, ys, xs, indexing="ij"), -1).reshape(-1, 3)
    g = g[np.hypot(g[:, 0], g[:, 2]) < R_DRUM - 1.3 * R_BEAD]
    n = bead_count(length)
    if len(g) < n:
        raise ValueError(f"{len(g)} lattice sites for {n} beads")
    g = g[np.lexsort((g[:, 0], g[:, 1], g[:, 2]))][:n]
    pos = g + rng.uniform(-0.01, 0.01, g.shape) * R_BEAD
    vel = rng.normal(0.0, 0.01 / math.sqrt(3), g.shape)
    return {"position": pos, "velocity": vel, "seed": seed}


def write_data(path: Path, st: dict, length: float) -> None:
    """LIGGGHTS data file (atom_style granular: id type diameter density x y z) with a
    Velocities section (id vx vy vz wx wy wz)."""
    pos, vel = st["position"], st["velocity"]
    b = R_DRUM * 1.2
    rows = [f"drum start seed {st['seed']}", "", f"{len(pos)} atoms", "2 atom types", "",
            f"{-b} {b} xlo xhi", f"{-0.2 * length} {1.2 * length} ylo yhi", f"{-b} {b} zlo zhi",
            "", "Atoms", ""]
    rows += [f"{i} 1 {2 * R_BEAD:.9g} {DENSITY:.9g} {p[0]:.12g} {p[1]:.12g} {p[2]:.12g}"
             for i, p in enumerate(pos, 1)]
    rows += ["", "Velocities", ""]
    rows += [f"{i} {v[0]:.12g} {v[1]:.12g} {v[2]:.12g} 0 0 0" for i, v in enumerate(vel, 1)]
    path.write_text("\n".join(rows) + "\n")


# ---------------------------------------------------------------- the measures

def measures(pos: np.ndarray, vel: np.ndarray, spin: np.ndarray, length: float) -> dict:
    """Angle of repose [deg] (drum_surface), centre of mass [m] (x, z; x positive on the
    lifted side, -x for the rotation about +y) and mean kinetic energy per bead [J]."""
    from dpm.analysis import drum_surface

    surf = drum_surface({"position": pos, "radius": R_BEAD}, (0.0, 0.5 * length, 0.0),
                        (0.0, 1.0, 0.0), R_DRUM, **SURFACE)
    m = DENSITY * 4 / 3 * math.pi * R_BEAD**3
    inertia = 0.4 * m * R_BEAD**2
    return {"angle_deg": surf.angle, "surface_residual_m": surf.residual,
            "com_x_m": float(-pos[:, 0].mean()), "com_z_m": float(pos[:, 2].mean()),
            "ke_trans_J": float(0.5 * m * np.mean(np.sum(vel**2, axis=1))),
            "ke_rot_J": float(0.5 * inertia * np.mean(np.sum(spin**2, axis=1)))}


def series(frames: list[dict], length: float) -> dict:
    """Measures of each frame as lists, with the frames' times."""
    rows = [measures(f["position"], f["velocity"], f["spin"], length) for f in frames]
    out = {"time_s": [f["time"] for f in frames]}
    for k in rows[0]:
        out[k] = [r[k] for r in rows]
    return out


# ---------------------------------------------------------------- dpm

def scene(kind: str, st: dict, length: float, stl: Path | None = None):
    """dpm's drum: ``kind`` "mesh" (the STL file ``stl``) or "tube" (analytic)."""
    import dpm

    sim = dpm.Simulation(dt=DT, gravity=(0.0, 0.0, -9.81), skin=SKIN,
                         sphere_orientation=False)
    glass = dpm.Material("glass", density=DENSITY, young=E_BEAD, poisson=NU_BEAD)
    steel = dpm.Material("steel", density=7800.0, young=E_WALL, poisson=NU_WALL)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=E_PP, friction=MU_PP)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=E_PW, friction=MU_PW)
    turn = dpm.Rotation(axis=(0.0, 1.0, 0.0), omega=OMEGA, center=(0.0, 0.0, 0.0))
    if kind == "mesh":
        sim.drum = sim.add_boundary("mesh", material=steel, file=str(stl), side="inside",
                                    motion=turn)
    else:
        sim.drum = sim.add_boundary("tube", material=steel, start=(0.0, 0.0, 0.0),
                                    axis=(0.0, 1.0, 0.0), length=length, radius=R_DRUM,
                                    caps="both", motion=turn)
    sim.add_particles("sphere", material=glass, radius=R_BEAD, positions=st["position"],
                      velocities=st["velocity"])
    return sim


def _frame(sim) -> dict:
    b = sim.bodies
    return {"time": float(sim.time), "position": np.array(b.position),
            "velocity": np.array(b.velocity), "spin": np.array(b.angular_velocity)}


def simulate(kind: str, st: dict, cfg: dict, stl: Path, threads: tuple = (1,),
             warmup: int = WARMUP) -> dict:
    """One dpm run: a warm-up of ``warmup`` steps in a throwaway scene (it compiles or
    loads the step module, and takes the rebuild path once), then the spin-up and the
    steady window, the state sampled every sample_steps. The spin-up runs on
    ``threads[0]`` threads; the window's sample intervals take the counts of ``threads``
    in turn, each timed (a run's results are the same bit for bit for any thread count, so
    this times the thread counts on the same steps under the same load). The measures of
    every sample (:func:`series`) and particle-steps per second per phase and thread count.
    """
    t0 = time.perf_counter()
    warm = scene(kind, st, cfg["length"], stl)
    for k in sorted(set(threads)):
        warm.threads = k
        warm.run(steps=warmup, progress=False)
    first = time.perf_counter() - t0
    del warm
    sim = scene(kind, st, cfg["length"], stl)
    n = len(sim.bodies)
    frames = [_frame(sim)]
    loops = {"spin": {}, "window": {}}
    steps = {"spin": {}, "window": {}}
    for phase in ("spin", "window"):
        for k in range(cfg[f"{phase}_steps"] // cfg["sample_steps"]):
            th = threads[0] if phase == "spin" else threads[k % len(threads)]
            sim.threads = th  # (given: a scene under SMALL_SCENE elements runs 1 otherwise)
            c0 = time.perf_counter()
            sim.run(steps=cfg["sample_steps"], progress=False)
            loops[phase][th] = loops[phase].get(th, 0.0) + time.perf_counter() - c0
            steps[phase][th] = steps[phase].get(th, 0) + cfg["sample_steps"]
            frames.append(_frame(sim))
    out = series(frames, cfg["length"])
    out.update({"kind": kind, "threads": list(threads), "beads": n,
                "start_seed": st["seed"], "loop_s": loops, "steps": steps,
                "particle_steps_per_s": {ph: {th: n * steps[ph][th] / loops[ph][th]
                                              for th in loops[ph]} for ph in loops},
                "warmup_s": first, "neighbour_rebuilds": sim.rebuild_count,
                "drum_torque_y_Nm": float(sim.drum.torque[1])})
    return out


def worker(kind: str, start_file: str, cfg_json: str, threads: str, out_file: str) -> None:
    """:func:`simulate` in its own process, for its peak memory; ``threads`` "1" or
    "1,2"."""
    z = np.load(start_file)
    st = {"position": z["position"], "velocity": z["velocity"], "seed": int(z["seed"])}
    out = simulate(kind, st, json.loads(cfg_json), Path(start_file).with_name("drum.stl"),
                   tuple(int(x) for x in threads.split(",")))
    Path(out_file).write_text(json.dumps(out))


def _wait(cmd, cwd, env) -> tuple[str, float, int]:
    """Run cmd; its stdout, wall time and peak resident memory [kB] (os.wait4)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if p.returncode:
        raise RuntimeError(f"{cmd[0]} failed ({p.returncode}):\n{out[-3000:]}")
    return out, wall, usage.ru_maxrss


def run_dpm(kind: str, start_file: Path, cfg: dict, threads: tuple = (1,)) -> dict:
    out = start_file.with_name(f"dpm_{kind}.json")
    _, whole, rss = _wait([sys.executable, __file__, "--worker", kind, str(start_file),
                           json.dumps(cfg), ",".join(map(str, threads)), str(out)], None,
                          {**os.environ, "DPM_KERNELS": "scene", "DPM_BACKGROUND_COMPILE": "0"})
    d = json.loads(out.read_text())
    # (JSON keys are strings: the thread counts back to ints)
    for key in ("loop_s", "steps", "particle_steps_per_s"):
        d[key] = {ph: {int(th): v for th, v in x.items()} for ph, x in d[key].items()}
    d.update(whole_process_s=whole, max_rss_kb=rss)
    return d


# ---------------------------------------------------------------- LIGGGHTS

def read_dump(path: Path) -> list[dict]:
    """Frames of LIGGGHTS' custom dump (id x y z vx vy vz omegax omegay omegaz, sorted)."""
    frames = []
    lines = path.read_text().splitlines()
    k = 0
    while k < len(lines):
        if lines[k].startswith("ITEM: TIMESTEP"):
            step = int(lines[k + 1])
            n = int(lines[k + 3])
            start_row = k + 9  # TIMESTEP, step, NUMBER, n, BOX x3+1, ATOMS header
            d = np.array([[float(x) for x in ln.split()]
                          for ln in lines[start_row:start_row + n]])
            d = d[np.argsort(d[:, 0])]
            frames.append({"time": step * DT, "position": d[:, 1:4], "velocity": d[:, 4:7],
                           "spin": d[:, 7:10]})
            k = start_row + n
        else:
            k += 1
    return frames


def run_liggghts(start_file: Path, cfg: dict) -> dict | None:
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    z = np.load(start_file)
    st = {"position": z["position"], "velocity": z["velocity"], "seed": int(z["seed"])}
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        write_data(t / "drum.data", st, cfg["length"])
        shutil.copy(start_file.with_name("drum.stl"), t / "drum.stl")
        shutil.copy(TEMPLATE, t / "drum.liggghts")
        var = {"DT": DT, "SKIN": SKIN, "PERIOD": repr(PERIOD), "SPIN": cfg["spin_steps"],
               "WINDOW": cfg["window_steps"], "SAMPLE": cfg["sample_steps"], "EP": E_BEAD,
               "EW": E_WALL, "NUP": NU_BEAD, "NUW": NU_WALL, "EPP": E_PP, "EPW": E_PW,
               "MUPP": MU_PP, "MUPW": MU_PW}
        cmd = [exe, "-in", "drum.liggghts", "-echo", "none", "-log", "none"]
        for k, v in var.items():
            cmd += ["-var", k, str(v)]
        out, whole, rss = _wait(cmd, tmp, {**os.environ, "OMP_NUM_THREADS": "1"})
        frames = read_dump(t / "drum.dump")
    loops = [float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", out)]
    builds = [int(x) for x in re.findall(r"Neighbor list builds = (\d+)", out)]
    n = len(st["position"])
    d = series(frames, cfg["length"])
    d.update({"beads": n, "start_seed": st["seed"],
              "loop_s": {"spin": loops[0], "window": loops[1]},
              "particle_steps_per_s": {"spin": n * cfg["spin_steps"] / loops[0],
                                       "window": n * cfg["window_steps"] / loops[1]},
              "whole_process_s": whole, "max_rss_kb": rss, "neighbour_rebuilds": sum(builds),
              "warnings": sorted({ln.strip() for ln in out.splitlines()
                                  if ln.startswith("WARNING")})[:10]})
    return d


# ---------------------------------------------------------------- comparison and plot

KEYS = ("angle_deg", "com_x_m", "com_z_m", "ke_trans_J", "ke_rot_J")


def window_means(d: dict, cfg: dict) -> dict:
    """Mean and standard deviation of each measure over the samples of the steady window
    (after the spin-up)."""
    t = np.array(d["time_s"])
    sel = t > cfg["spin_steps"] * DT + 1e-9
    return {k: {"mean": float(np.mean(np.array(d[k])[sel])),
                "std": float(np.std(np.array(d[k])[sel]))} for k in KEYS}


def compare(runs: dict, cfg: dict) -> dict:
    """Each dpm variant's window means against the LIGGGHTS runs'. Two starts give a
    rough range, so the statistical error of one run's window mean is given too:
    ``window_mean_se`` = rms in-time standard deviation over all runs / sqrt(samples)
    (the samples taken as independent). ``dpm_KIND_within`` is true when the mean of dpm's
    runs is within max(LIGGGHTS' range / 2, 2 window_mean_se) of LIGGGHTS' mean."""
    lg = [window_means(r, cfg) for r in runs["liggghts"]]
    every = [window_means(r, cfg) for k in ("liggghts", "mesh", "tube") for r in runs[k]]
    n = cfg["window_steps"] // cfg["sample_steps"]
    out = {}
    for k in KEYS:
        lv = np.array([x[k]["mean"] for x in lg])
        se = float(np.sqrt(np.mean([x[k]["std"] ** 2 for x in every]) / n))
        row = {"liggghts": lv.tolist(), "liggghts_range": float(np.ptp(lv)),
               "liggghts_mean": float(lv.mean()),
               "liggghts_std_in_time": [x[k]["std"] for x in lg], "window_mean_se": se}
        for kind in ("mesh", "tube"):
            dv = np.array([window_means(d, cfg)[k]["mean"] for d in runs[kind]])
            gap = np.maximum(lv.min() - dv, dv - lv.max()).clip(0)
            diff = float(dv.mean() - lv.mean())
            row[f"dpm_{kind}"] = dv.tolist()
            row[f"dpm_{kind}_mean"] = float(dv.mean())
            row[f"dpm_{kind}_diff"] = diff
            row[f"dpm_{kind}_rel_diff"] = float(dv.mean() / lv.mean() - 1)
            row[f"dpm_{kind}_outside_liggghts_range"] = gap.tolist()
            row[f"dpm_{kind}_within"] = bool(abs(diff) <= max(np.ptp(lv) / 2, 2 * se))
        out[k] = row
    return out


def speeds(runs: dict, n: int, cfg: dict) -> dict:
    """Particle-steps per second per phase: LIGGGHTS (all its runs), dpm per drum and
    thread count (all intervals run on that count, over both starts), their ratios, and
    dpm's 2 threads against 1 on the interleaved intervals of start 1 alone."""
    def total(rs, phase, th=None):
        steps = time_ = 0.0
        for r in rs:
            if th is None:  # LIGGGHTS
                steps += n * cfg[f"{phase}_steps"]
                time_ += r["loop_s"][phase]
            elif th in r["loop_s"][phase]:
                steps += n * r["steps"][phase][th]
                time_ += r["loop_s"][phase][th]
        return steps / time_ if time_ > 0 else None

    lg = {ph: total(runs["liggghts"], ph) for ph in ("spin", "window")} \
        if runs["liggghts"] else None
    out = {"liggghts_1_core": lg,
           "note": "particle-steps/s; dpm 1 thread: the spin-up of both starts, the window "
                   "of start 2 and every other window interval of start 1; 2 threads: the "
                   "other window intervals of start 1 (same run, bit-identical results, so "
                   "the same work under the same load)"}
    for kind in ("mesh", "tube"):
        rs = runs[kind]
        d1 = {ph: total(rs, ph, 1) for ph in ("spin", "window")}
        d2 = total(rs, "window", 2)
        out[f"dpm_{kind}_1_thread"] = d1
        out[f"dpm_{kind}_2_threads_window"] = d2
        if lg:
            out[f"{kind}_1_thread_over_liggghts"] = {ph: d1[ph] / lg[ph] for ph in lg}
            out[f"{kind}_2_threads_over_liggghts_window"] = d2 / lg["window"] if d2 else None
        if d2:
            out[f"{kind}_2_over_1_threads_window_start_1"] = (
                total(rs[:1], "window", 2) / total(rs[:1], "window", 1))
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(16, 8.5))
    panels = [("angle_deg", "dynamic angle of repose [deg]", 1.0),
              ("com_x_m", "centre of mass, x (lifted side) [mm]", 1e3),
              ("com_z_m", "centre of mass, z above the axis [mm]", 1e3),
              ("ke_trans_J", "mean translational KE per bead [nJ]", 1e9),
              ("ke_rot_J", "mean rotational KE per bead [nJ]", 1e9)]
    curves = []
    for k, r in enumerate(result["runs"]["liggghts"] or []):
        curves.append((r, f"LIGGGHTS start {r['start_seed']}", "0.35", "-", 1.2, k))
    for kind, col in (("mesh", "C0"), ("tube", "C3")):
        for k, d in enumerate(result["runs"][kind]):
            curves.append((d, f"dpm {kind} start {d['start_seed']}",
                           col, "--", 1.4, k))
    t_spin = result["config"]["spin_steps"] * DT
    for a, (key, label, scale) in zip(ax.ravel()[:5], panels, strict=True):
        for d, lab, col, ls, lw, k in curves:
            a.plot(d["time_s"], np.array(d[key]) * scale, color=col, ls=ls if k == 0 else ":",
                   lw=lw, label=lab)
        a.axvline(t_spin, color="0.7", lw=0.8)
        a.set_xlabel("time [s] (grey line: start of the steady window)")
        a.set_ylabel(label)
    ax[0, 0].legend(fontsize=7)
    a = ax[1, 2]
    names, vals, cols = [], [], []
    sp = result["speed"]
    for kind, col in (("mesh", "C0"), ("tube", "C3")):
        for key, lab in ((f"{kind}_1_thread_over_liggghts", "1 thread"),
                         (f"{kind}_2_threads_over_liggghts_window", "2 threads")):
            v = sp.get(key)
            v = v.get("window") if isinstance(v, dict) else v
            if v:
                names.append(f"{kind}\n{lab}")
                vals.append(v)
                cols.append(col)
    if vals:
        bars = a.bar(range(len(vals)), vals, color=cols)
        a.set_xticks(range(len(vals)), names)
        a.bar_label(bars, labels=[f"{v:.2f}" for v in vals])
        a.axhline(1.0, color="0.5", lw=0.8)
    a.set_ylabel("dpm / LIGGGHTS 1 core, steady window\n(particle-steps/s)")
    c = result["config"]
    fig.suptitle(f"Rotating drum, {result['beads']} beads, R = {R_DRUM * 1e3:g} mm, "
                 f"depth {c['length'] * 1e3:g} mm, {60 / PERIOD:.1f} rpm (Fr {FROUDE:g}): "
                 f"dpm (STL mesh, analytic tube) vs LIGGGHTS 3.8 move/mesh; load average "
                 f"{result['load_average'][0]:.1f}-{result['load_average'][1]:.1f}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main(argv: list[str] | None = None) -> dict:
    import harness  # (here: tests/ load this file by path)

    p = harness.parser(__doc__, "12 mm deep drum, 1.2 s")
    p.add_argument("--no-liggghts", action="store_true")
    p.add_argument("--starts", type=int, default=None, choices=range(1, len(STARTS) + 1),
                   help=f"run from the first N starts (default {len(STARTS)}; --quick 1)")
    p.add_argument("--worker", nargs=5, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.worker:
        worker(*a.worker)
        return {}
    cfg = config("quick" if a.quick else "full")
    starts = STARTS[:a.starts or (1 if a.quick else len(STARTS))]
    two = (os.cpu_count() or 1) >= 2
    runs = {"liggghts": [], "mesh": [], "tube": []}
    loads = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        tris = drum_triangles(cfg["length"])
        write_stl(t / "drum.stl", tris)
        prep = {}
        for k, seed in enumerate(starts):
            st = start(cfg["length"], seed)
            sf = t / f"start_{seed}.npz"
            np.savez(sf, position=st["position"], velocity=st["velocity"], seed=seed)
            if k == 0:  # compile (or load) each step module in a process of its own first
                for kind in ("mesh", "tube"):
                    w = run_dpm(kind, sf, {**cfg, "spin_steps": 0, "window_steps": 0},
                                (1, 2) if two else (1,))
                    prep[kind] = {"whole_process_s": w["whole_process_s"],
                                  "max_rss_kb": w["max_rss_kb"]}
            # start 1: the window's intervals on 1 and 2 threads in turn; start 2: 1 thread
            threads = (1, 2) if k == 0 and two else (1,)
            r = None if a.no_liggghts else run_liggghts(sf, cfg)
            if r is not None:
                runs["liggghts"].append(r)
                print(f"LIGGGHTS start {seed}: {r['particle_steps_per_s']}", flush=True)
            for kind in ("mesh", "tube"):
                d = run_dpm(kind, sf, cfg, threads)
                runs[kind].append(d)
                print(f"dpm {kind} start {seed}, threads {threads}: "
                      f"{d['particle_steps_per_s']}", flush=True)
            loads.append(os.getloadavg()[0])
    n = runs["mesh"][0]["beads"]
    speed = speeds(runs, n, cfg)
    physics = compare(runs, cfg) if runs["liggghts"] else None
    mem = {f"dpm_{kind}_start_{d['start_seed']}_kb": d["max_rss_kb"]
           for kind in ("mesh", "tube") for d in runs[kind]}
    if runs["liggghts"]:
        mem["liggghts_kb"] = runs["liggghts"][0]["max_rss_kb"]
    result = {"scene": "rotating drum, half filled", "beads": n, "quick": a.quick,
              "config": cfg, "dt": DT, "skin": SKIN, "omega_rad_s": OMEGA, "period_s": PERIOD,
              "rpm": 60 / PERIOD, "froude": FROUDE,
              "drum": {"radius": R_DRUM, "length": cfg["length"], "n_theta": N_THETA,
                       "cap_spacing": CAP_SPACING, "stl_triangles": int(len(tris))},
              "material": {"bead": {"density": DENSITY, "young": E_BEAD, "poisson": NU_BEAD},
                           "wall": {"young": E_WALL, "poisson": NU_WALL},
                           "restitution": {"bead-bead": E_PP, "bead-wall": E_PW},
                           "friction": {"bead-bead": MU_PP, "bead-wall": MU_PW},
                           "rolling_friction": 0.0},
              "surface_fit": SURFACE, "starts": list(starts),
              "load_average": [min(loads), max(loads)],
              "timing_note": ("load_average: 1-minute figures sampled between runs (on 2 "
                              "cores, above ~1.2 another process shared the machine and the "
                              "timings are noisy; the 2-thread intervals themselves lift "
                              "it); dpm after a warm-up that compiles; LIGGGHTS one core"),
              "peer": harness.peer(a.no_liggghts),
              "physics": physics, "speed": speed, "memory_max_rss": mem,
              "dpm_compile_or_load": prep, "runs": runs}
    path = harness.write("drum_peer", result, a.quick)
    harness.png(plot, result, path=path.with_suffix(".png"))
    print(json.dumps({"physics": physics, "speed": speed, "memory": mem}, indent=1))
    return result


if __name__ == "__main__":
    main()
