"""Clustered bodies settling in a box: dpm against LIGGGHTS' ``fix multisphere``, one run.

N four-sphere clusters (default 2,000; ``--quick`` 300, from one LIGGGHTS seed, a
settled window of 5,000 steps and 1,000-step turns of the thread counts): four
equal spheres (r = 1 mm) at the corners of a regular tetrahedron 0.866 mm from its centre
(overlapping: edge 1.414 mm), 2500 kg/m3, Hertz-Mindlin (E = 5 MPa, nu = 0.45, e = 0.3,
mu = 0.5, as box_settle), dt = 1e-5 s, fall from rest under gravity into a square box of
planar walls open at the top. dpm: ``dpm.shapes.Multisphere(centres=, radii=)``; LIGGGHTS 3.8:
``particletemplate/multisphere`` + ``particledistribution/discrete`` + ``fix insert/pack``
(``insert_every once``, random orientation, overlap check) + ``fix multisphere``.

The same start: LIGGGHTS 3.8 places multisphere bodies only through its insertion fixes
(no ``read_data`` or ``create_atoms`` route for them), at seed-dependent positions. So
each LIGGGHTS run (three insertion seeds) dumps its spheres after its first step (the
insertion step), and dpm starts from each dump (body centre = mean of its four spheres,
orientation = the rotation of the template onto them, fitted to ~1e-12 m; velocities of
the dump; state at t = dt): three same-start pairs, and LIGGGHTS' seed-to-seed scatter
(the same count in the same region) to judge them by. The runs go in turn (LIGGGHTS seed
k, then dpm from its start) so that a change of load falls on both codes. Without
LIGGGHTS dpm starts once from its own lattice placement.

Compared: mean z of the body centres against time (LIGGGHTS' thermo ``reduce ave z`` of
the spheres: the same, four equal spheres per body with the centre at their mean), the
settled height and packing fraction (solid fraction of the union of spheres by Monte
Carlo in a slab inside the bed, the same slab for every run), speed as body-steps per
second in two phases (the fall and settling; then a window of 10,000 steps in the
settled bed, timed apart), dpm on 1 thread from every start and on 2 threads from the
first (``DPM_THREADS`` in subprocesses and ``sim.threads`` set: a scene under
``dpm.simulation.SMALL_SCENE`` (4,000) elements runs one thread otherwise; each after a
warm-up run in the same process that compiles or loads the cache), LIGGGHTS on one core;
then, in the 2-thread process after its window, one and two threads in turn on the same
settled bed (3 x 2,000 steps each; the ratio of the medians: the thread gain free of the
differences between two processes' beds, their rebuilds and a load change between them);
peak resident memory (ru_maxrss, os.wait4) of each process, per body. The machine may be
shared while this runs (stated in the JSON).

    python benchmarks/clusters_settle.py [--quick | --bodies N] [--no-liggghts]

Writes benchmarks/results/clusters_settle[_quick | _N].json and .png.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness
import numpy as np
from shared_scenes import LIGGGHTS_BOX_MATERIALS, LIGGGHTS_HEADER

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent

DT = 1e-5
R, A = 1e-3, 0.5e-3  # sphere radius, template corner coordinate (centre distance A sqrt 3)
TEMPLATE = A * np.array([[1, 1, 1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1]], float)
DENSITY, YOUNG, POISSON, RESTITUTION, FRICTION = 2500.0, 5e6, 0.45, 0.3, 0.5
SKIN = 4e-4
R_BOUND = A * np.sqrt(3) + R
#: thermo / sampling interval [steps], steps of the settled window timed apart
EVERY, WINDOW = 1000, 10000
#: the settled bed after the window, one and two threads in turn in the 2-thread process
AB_STEPS, AB_REPEATS = 2000, 3
#: --quick: the settled window and the steps of each thread count in turn
QUICK_WINDOW, QUICK_AB_STEPS = 5000, 1000
SEEDS = (32452843, 86028121, 15485867)
#: volume fraction of the bounding spheres in the insertion region (what insert/pack reaches)
INSERT_FRACTION = 0.4


def geometry(n: int, side: float, window: int = WINDOW, ab_steps: int = AB_STEPS) -> dict:
    """Box side, insertion region and step counts for n bodies on a side x side floor."""
    m = R_BOUND + 2e-4
    height = n * 4 / 3 * np.pi * (R_BOUND + 2e-4) ** 3 / INSERT_FRACTION / (side - 2 * m) ** 2
    region = (m, side - m, m, side - m, m, m + height)
    fall = np.sqrt(2 * region[5] / 9.81)
    settle = int(round((fall + 0.1) / DT / EVERY)) * EVERY
    return {"side": side, "top": region[5] + 3 * R_BOUND, "region": region,
            "settle_steps": settle, "window_steps": window, "ab_steps": ab_steps}


#: the header and box lines shared with meshgran.py (shared_scenes), on this scene's box
LIGGGHTS_IN = LIGGGHTS_HEADER + LIGGGHTS_BOX_MATERIALS.format(
    region="0 {side} 0 {side} 0 {top}") + """\
pair_style gran model hertz tangential history
pair_coeff * *
timestep {dt}
fix xw1 all wall/gran model hertz tangential history primitive type 1 xplane 0.0
fix xw2 all wall/gran model hertz tangential history primitive type 1 xplane {side}
fix yw1 all wall/gran model hertz tangential history primitive type 1 yplane 0.0
fix yw2 all wall/gran model hertz tangential history primitive type 1 yplane {side}
fix zw1 all wall/gran model hertz tangential history primitive type 1 zplane 0.0
fix grav all gravity 9.81 vector 0.0 0.0 -1.0
fix pts1 all particletemplate/multisphere 15485863 atom_type 1 density constant {density} &
    nspheres 4 ntry 1000000 spheres {spheres} type 1
fix pdd1 all particledistribution/discrete 49979687 1 pts1 1.0
region ins block {r0} {r1} {r2} {r3} {r4} {r5} units box
fix ins all insert/pack seed {seed} distributiontemplate pdd1 maxattempt 1000 &
    insert_every once overlapcheck yes orientation random all_in yes vel constant 0 0 0 &
    particles_in_region {n} region ins ntry_mc 10000
fix ms all multisphere
compute zc all reduce ave z
thermo_style custom step atoms ke c_zc
thermo {every}
thermo_modify lost ignore norm no
dump d0 all custom 1 start.dump id x y z vx vy vz
dump_modify d0 format "%d %.12g %.12g %.12g %.12g %.12g %.12g"
run 1
undump d0
run {settle}
run {window}
write_dump all custom end.dump id x y z
"""


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


def _dump(path: Path) -> np.ndarray:
    """Rows of the last snapshot of a LIGGGHTS custom dump, sorted by atom id."""
    lines = path.read_text().splitlines()
    start = max(i for i, ln in enumerate(lines) if ln.startswith("ITEM: ATOMS")) + 1
    d = np.array([[float(x) for x in ln.split()] for ln in lines[start:] if ln.strip()])
    return d[np.argsort(d[:, 0])]


def run_liggghts(n: int, geo: dict, seed: int, keep: Path | None) -> dict | None:
    exe = harness.liggghts()
    if exe is None:
        return None
    reg = geo["region"]
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        (t / "in.clusters").write_text(LIGGGHTS_IN.format(
            side=geo["side"], top=geo["top"], skin=SKIN, young=YOUNG, poisson=POISSON,
            restitution=RESTITUTION, friction=FRICTION, dt=DT, density=DENSITY,
            spheres=" ".join(f"{x:.6g} {y:.6g} {z:.6g} {R:.6g}" for x, y, z in TEMPLATE),
            r0=reg[0], r1=reg[1], r2=reg[2], r3=reg[3], r4=reg[4], r5=reg[5], seed=seed,
            n=n, every=EVERY, settle=geo["settle_steps"] - 1, window=geo["window_steps"]))
        out, whole, rss = _wait([exe, "-in", "in.clusters", "-echo", "none", "-log", "none"],
                                tmp, {**os.environ, "OMP_NUM_THREADS": "1"})
        start, end = _dump(t / "start.dump"), _dump(t / "end.dump")
        if keep is not None:
            np.save(keep, start)
    loops = [float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", out)]
    rows = {}
    for ln in out.splitlines():
        f = ln.split()
        if len(f) == 4 and f[0].isdigit() and f[1].isdigit():
            rows[int(f[0])] = float(f[3])
    steps = sorted(s for s in rows if s % EVERY == 0 and s > 0 or s == 1)
    bodies = len(start) // 4
    settle, window = geo["settle_steps"] - 1, geo["window_steps"]
    return {"seed": seed, "bodies": bodies, "spheres": len(start),
            "step": steps, "mean_z_m": [rows[s] for s in steps],
            "final_mean_z_m": rows[max(rows)], "spheres_end": end[:, 1:4].tolist(),
            "loop_s": {"insert_step": loops[0], "settle": loops[1], "window": loops[2]},
            "body_steps_per_s": {"settle": bodies * settle / loops[1],
                                 "window": bodies * window / loops[2]},
            "whole_process_s": whole, "max_rss_kb": rss}


def start_from_dump(d: np.ndarray) -> dict:
    """Body centres, orientations (w, x, y, z) and velocities from LIGGGHTS' first dump
    (ids 4k+1..4k+4 are body k: insert/pack numbers a body's spheres in a row)."""
    x = d[:, 1:4].reshape(-1, 4, 3)
    v = d[:, 4:7].reshape(-1, 4, 3)
    c = x.mean(axis=1)
    quats = np.empty((len(x), 4))
    for k in range(len(x)):  # Kabsch: the rotation taking the template onto the spheres
        h = TEMPLATE.T @ (x[k] - c[k])
        u, _, vt = np.linalg.svd(h)
        s = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
        quats[k] = _quat(vt.T @ s @ u.T)
    err = np.abs(np.einsum("kij,lj->kli", _rot(quats), TEMPLATE) + c[:, None] - x).max()
    return {"position": c, "orientation": quats, "velocity": v.mean(axis=1),
            "fit_error_m": float(err)}


def _quat(m: np.ndarray) -> np.ndarray:
    w = np.sqrt(max(0.0, 1 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    if w > 1e-6:
        return np.array([w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                         (m[1, 0] - m[0, 1]) / (4 * w)])
    i = int(np.argmax(np.diag(m)))
    j, k = (i + 1) % 3, (i + 2) % 3
    q = np.zeros(4)
    q[1 + i] = np.sqrt(max(0.0, 1 + m[i, i] - m[j, j] - m[k, k])) / 2
    q[0] = (m[k, j] - m[j, k]) / (4 * q[1 + i])
    q[1 + j] = (m[j, i] + m[i, j]) / (4 * q[1 + i])
    q[1 + k] = (m[k, i] + m[i, k]) / (4 * q[1 + i])
    return q


def _rot(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q.T
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def own_start(n: int, geo: dict, seed: int = 1) -> dict:
    """The first n cells of a lattice of bounding-sphere cubes filling the insertion
    region, random orientations, at rest (dpm's start when LIGGGHTS is not there)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array(geo["region"][0::2]), np.array(geo["region"][1::2])
    counts = np.floor((hi - lo) / (2 * R_BOUND)).astype(int)
    ijk = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"), -1)
    cells = ijk.reshape(-1, 3)[np.lexsort(ijk.reshape(-1, 3).T)][:n]
    q = rng.normal(size=(n, 4))
    return {"position": lo + (cells + 0.5) * 2 * R_BOUND,
            "orientation": q / np.linalg.norm(q, axis=1)[:, None],
            "velocity": np.zeros((n, 3)), "fit_error_m": 0.0}


def scene(start: dict, geo: dict):
    import dpm

    sim = dpm.Simulation(dt=DT, gravity=(0.0, 0.0, -9.81), skin=SKIN)
    m = dpm.Material("grains", density=DENSITY, young=YOUNG, poisson=POISSON)
    sim.contact(m, m, model="hertz_mindlin", restitution=RESTITUTION, friction=FRICTION)
    sim.add_boundary("box", material=m, lower=(0.0, 0.0, 0.0),
                     upper=(geo["side"], geo["side"], geo["top"]), open=("+z",))
    shape = dpm.shapes.Multisphere(centres=TEMPLATE, radii=[R] * 4)
    sim.add_particles(shape, m, positions=start["position"], velocities=start["velocity"],
                      orientations=start["orientation"])
    return sim


def worker(start_file: str, geo_json: str, out_file: str) -> None:
    """One dpm run (threads from DPM_THREADS): mean height every EVERY steps, the fall and
    settling timed, then the settled window timed apart."""
    geo = json.loads(geo_json)
    z = np.load(start_file)
    start = {k: z[k] for k in ("position", "orientation", "velocity")}
    threads = int(os.environ.get("DPM_THREADS", "1"))
    t0 = time.perf_counter()
    warm = scene(start, geo)
    warm.threads = threads
    warm.run(steps=2, progress=False)  # compile (or load from the cache)
    first = time.perf_counter() - t0
    sim = scene(start, geo)
    sim.threads = threads  # (given: a scene under SMALL_SCENE elements runs 1 otherwise)
    n = len(sim.bodies)
    steps, heights = [1], [float(sim.bodies.position[:, 2].mean())]
    settle = geo["settle_steps"] - 1
    loop = 0.0
    done = 0
    while done < settle:
        k = min(EVERY - (done + 1) % EVERY, settle - done) or EVERY
        c0 = time.perf_counter()
        sim.run(steps=k, progress=False)
        loop += time.perf_counter() - c0
        done += k
        steps.append(done + 1)
        heights.append(float(sim.bodies.position[:, 2].mean()))
    r0 = sim.rebuild_count
    c0 = time.perf_counter()
    sim.run(steps=geo["window_steps"], progress=False)
    window = time.perf_counter() - c0
    window_rebuilds = sim.rebuild_count - r0
    steps.append(done + 1 + geo["window_steps"])
    heights.append(float(sim.bodies.position[:, 2].mean()))
    ab = None
    if threads > 1:
        # one and two threads in turn on the same settled bed in this process (after the
        # window): the thread gain free of the differences between two processes' beds
        # and of a load change between them
        ab_steps = geo.get("ab_steps", AB_STEPS)
        ab = {"steps_each": ab_steps, "us_per_step": {"1": [], str(threads): []},
              "rebuilds": {"1": [], str(threads): []}}
        for _ in range(AB_REPEATS):
            for th in (1, threads):
                sim.threads = th
                r0 = sim.rebuild_count
                c0 = time.perf_counter()
                sim.run(steps=ab_steps, progress=False)
                ab["us_per_step"][str(th)].append((time.perf_counter() - c0) / ab_steps * 1e6)
                ab["rebuilds"][str(th)].append(sim.rebuild_count - r0)
        ab["ratio_of_medians"] = (float(np.median(ab["us_per_step"]["1"]))
                                  / float(np.median(ab["us_per_step"][str(threads)])))
    Path(out_file).write_text(json.dumps({
        "bodies": n, "spheres": len(sim.elements), "threads": threads,
        "step": steps, "mean_z_m": heights, "final_mean_z_m": heights[-1],
        "spheres_end": sim.elements.position.tolist(),
        "loop_s": {"settle": loop, "window": window},
        "body_steps_per_s": {"settle": n * settle / loop,
                             "window": n * geo["window_steps"] / window},
        "time_to_first_steps_s": first, "neighbour_rebuilds": sim.rebuild_count,
        "window_rebuilds": window_rebuilds, "threads_in_turn": ab}))


def run_dpm(start_file: Path, geo: dict, threads: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "dpm.json"
        _, whole, rss = _wait([sys.executable, __file__, "--worker", str(start_file),
                               json.dumps(geo), str(out)], None,
                              {**os.environ, "DPM_THREADS": str(threads),
                               "DPM_BACKGROUND_COMPILE": "0"})
        d = json.loads(out.read_text())
    d.update(whole_process_s=whole, max_rss_kb=rss)
    return d


def packing(spheres: np.ndarray, lo, hi, samples: int = 400_000) -> float:
    """Solid fraction of the union of the spheres (radius R) in the box lo-hi (Monte Carlo,
    the same points for every run)."""
    from scipy.spatial import cKDTree

    p = np.asarray(lo) + np.random.default_rng(7).random((samples, 3)) * (
        np.asarray(hi) - np.asarray(lo))
    dist, _ = cKDTree(spheres).query(p)
    return float(np.mean(dist < R))


def plot(result: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    curves = [(r, f"LIGGGHTS seed {r['seed']}", f"C{k}", "-", 1.0)
              for k, r in enumerate(result["liggghts"] or [])]
    curves += [(d, f"dpm 1 thread, start {k}", f"C{k}", "--", 1.8)
               for k, d in enumerate(result["dpm"])]
    if result.get("dpm_2_threads"):
        curves.append((result["dpm_2_threads"], "dpm 2 threads, start 0", "k", ":", 1.8))
    t_settle = result["geometry"]["settle_steps"] * DT
    for a in ax[:2]:
        for d, lab, col, ls, lw in curves:
            t = np.array(d["step"]) * DT
            z = np.array(d["mean_z_m"]) * 1e3
            keep = t >= (0.0 if a is ax[0] else 0.6 * t_settle)
            a.plot(t[keep], z[keep], color=col, ls=ls, lw=lw, label=lab)
        a.axvline(t_settle, color="0.7", lw=0.8)
        a.set_xlabel("time [s] (grey line: start of the timed settled window)")
        a.set_ylabel("mean z of body centres [mm]")
    ax[0].legend(fontsize=7)
    ax[1].set_title("settled (zoom)", fontsize=9)
    names, vals = [], []
    for key, lab in (("dpm_over_liggghts", "dpm/LGT"),
                     ("dpm_2_threads_over_liggghts", "dpm 2t/LGT"),
                     ("dpm_2_threads_over_1_thread", "dpm 2t/1t")):
        for phase in ("settle", "window"):
            v = (result["speed_ratios"][key] or {}).get(phase)
            if v:
                names.append(f"{lab}\n{'falling' if phase == 'settle' else 'settled'}")
                vals.append(v)
    turn = result["speed_ratios"].get("dpm_2_threads_over_1_thread_in_turn")
    if turn:
        names.append("dpm 2t/1t\nsettled,\nin turn")
        vals.append(turn)
    bars = ax[2].bar(range(len(vals)), vals, color=(["C0", "C1"] * 4)[:len(vals)])
    ax[2].set_xticks(range(len(vals)), names, fontsize=7)
    ax[2].bar_label(bars, labels=[f"{v:.2f}" for v in vals])
    ax[2].axhline(1.0, color="0.5", lw=0.8)
    ax[2].set_ylabel("speed ratio (body-steps/s; LGT = LIGGGHTS 1 core)")
    n = result["bodies"]
    fig.suptitle(f"{n} four-sphere clusters settling: dpm vs LIGGGHTS 3.8 fix multisphere "
                 "(shared 2-core machine)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main(argv: list[str] | None = None) -> dict:
    p = harness.parser(__doc__, "300 clusters, one LIGGGHTS seed (one same-start pair)")
    p.add_argument("--bodies", type=int, default=None)
    p.add_argument("--no-liggghts", action="store_true")
    p.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.worker:
        worker(*a.worker)
        return {}
    n = a.bodies or (300 if a.quick else 2000)
    seeds = SEEDS[:1] if a.quick else SEEDS
    geo = geometry(n, side=0.02 if n <= 500 else 0.035,
                   **({"window": QUICK_WINDOW, "ab_steps": QUICK_AB_STEPS} if a.quick else {}))
    runs, dpm_runs, d2 = [], [], None
    with tempfile.TemporaryDirectory() as tmp:
        # in turn (LIGGGHTS seed k, then dpm from its start), so that a change of load on
        # a shared machine falls on both codes alike
        for k, seed in enumerate((None,) if a.no_liggghts else seeds):
            r = None if seed is None else run_liggghts(n, geo, seed,
                                                       Path(tmp) / f"start_{seed}.npy")
            if r is not None:
                runs.append(r)
                origin = f"LIGGGHTS seed {seed} after its first step (insert/pack)"
                start = start_from_dump(np.load(Path(tmp) / f"start_{seed}.npy"))
                print(f"LIGGGHTS seed {seed}: {r['bodies']} bodies, mean z "
                      f"{r['final_mean_z_m'] * 1e3:.3f} mm, {r['body_steps_per_s']}",
                      flush=True)
            elif k == 0:
                origin, start = "dpm's own lattice placement", own_start(n, geo)
            else:
                break
            start_file = Path(tmp) / f"start_{k}.npz"
            np.savez(start_file, **{x: start[x] for x in ("position", "orientation",
                                                          "velocity")})
            for threads in (1, 2) if k == 0 and (os.cpu_count() or 1) >= 2 else (1,):
                d = run_dpm(start_file, geo, threads)
                d.update(start=origin, start_fit_error_m=start["fit_error_m"])
                print(f"dpm {threads} thread(s), start {k}: mean z "
                      f"{d['final_mean_z_m'] * 1e3:.3f} mm, {d['body_steps_per_s']}",
                      flush=True)
                if threads == 2:
                    d2 = d
                else:
                    dpm_runs.append(d)
    d1 = dpm_runs[0]
    # packing: a slab inside the bed (two bounding radii from the side walls, four above
    # the floor, to four below twice the lowest mean height), the same for every run
    all_runs = [*dpm_runs, *([d2] if d2 else []), *runs]
    h = min(x["final_mean_z_m"] for x in all_runs)
    lo = (2 * R_BOUND, 2 * R_BOUND, 4 * R_BOUND)
    hi = (geo["side"] - 2 * R_BOUND, geo["side"] - 2 * R_BOUND, 2 * h - 4 * R_BOUND)
    for x in all_runs:
        x["packing_fraction"] = packing(np.array(x.pop("spheres_end")), lo, hi)

    def mean_rate(rs):
        return {"body_steps_per_s": {ph: float(np.mean([r["body_steps_per_s"][ph]
                                                        for r in rs]))
                                     for ph in ("settle", "window")}} if rs else None

    def ratio(u, v):
        return {ph: u["body_steps_per_s"][ph] / v["body_steps_per_s"][ph]
                for ph in ("settle", "window")} if u and v else None

    lg, dm = mean_rate(runs), mean_rate(dpm_runs)
    speed = {"dpm_over_liggghts": ratio(dm, lg), "dpm_2_threads_over_liggghts": ratio(d2, lg),
             "dpm_2_threads_over_1_thread": ratio(d2, d1),
             "dpm_2_threads_over_1_thread_in_turn": (d2.get("threads_in_turn") or {}).get(
                 "ratio_of_medians") if d2 else None,
             "note": "dpm 1 thread and LIGGGHTS: means over the runs (one per start)"}
    physics = None
    if runs:
        def band(key):
            lv = np.array([r[key] for r in runs])
            dv = np.array([d[key] for d in dpm_runs])
            return {"liggghts": lv.tolist(), "dpm_same_starts": dv.tolist(),
                    "liggghts_mean": float(lv.mean()), "dpm_mean": float(dv.mean()),
                    "dpm_mean_rel_diff": float(dv.mean() / lv.mean() - 1),
                    "per_start_rel_diff": (dv / lv - 1).tolist(),
                    "liggghts_seed_scatter_rel": float(np.ptp(lv) / lv.mean()),
                    "liggghts_seed_std_rel": float(lv.std(ddof=1) / lv.mean())
                    if len(lv) > 1 else None,
                    "dpm_start_scatter_rel": float(np.ptp(dv) / dv.mean())}
        physics = {"settled_mean_z_m": band("final_mean_z_m"),
                   "packing_fraction": band("packing_fraction"),
                   "packing_slab_m": [list(lo), list(hi)]}
    mem = {"dpm_1_thread_kb_per_body": d1["max_rss_kb"] / n,
           "dpm_2_threads_kb_per_body": d2["max_rss_kb"] / n if d2 else None}
    if runs:
        mem["liggghts_kb_per_body"] = runs[0]["max_rss_kb"] / n
    result = {"scene": "four-sphere clusters settling in a box", "bodies": n, "quick": a.quick,
              "dt": DT, "template": {"centres_m": TEMPLATE.tolist(), "radius_m": R},
              "material": {"density": DENSITY, "young": YOUNG, "poisson": POISSON,
                           "restitution": RESTITUTION, "friction": FRICTION},
              "geometry": geo, "seeds": list(seeds) if runs else None,
              "timing_note": "2-core machine (load average in run.load_average); dpm "
                             "threads given (DPM_THREADS in subprocesses, sim.threads set) after a "
                             "warm-up that compiles; LIGGGHTS one core; ru_maxrss includes "
                             "each process's base (Python + numba for dpm)",
              "physics": physics, "speed_ratios": speed, "memory": mem,
              "peer": harness.peer(a.no_liggghts), "dpm": dpm_runs, "dpm_2_threads": d2,
              "liggghts": runs or None}
    path = harness.write("clusters_settle", result, a.quick,
                         tag=f"clusters_settle_{n}" if a.bodies else None)
    harness.png(plot, result, path=path.with_suffix(".png"))
    print(json.dumps({"physics": physics, "speed_ratios": speed, "memory": mem}, indent=1))
    return result


if __name__ == "__main__":
    main()
