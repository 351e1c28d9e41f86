"""LIGGGHTS' "meshGran" tutorial ported to dpm, both codes on the same scene in one run.

The tutorial (LIGGGHTS-PUBLIC ``examples/LIGGGHTS/Tutorials_public/meshGran``): a CAD
wall read from STL, 5 mm spheres (2500 kg/m3) streamed at 1000/s through a square
insertion face (``insert/stream``, ``vel constant 0 0 -1``, ``extrude_length 0.02``:
a batch every 0.02 s), Hooke with history (E = 5 MPa, nu = 0.45, e = 0.7, mu = 0.05,
``characteristicVelocity 2``), dt = 5e-5 s, insertion for 0.5 s then run to 2.5 s. Its
STL is not shipped here: this script writes its own with trimesh from simple geometry, in
the tutorial's spirit (an inclined chute with side walls below the face, a container
below the chute's end), and gives the same STL files to both codes. LIGGGHTS reads the
insertion face as ``fix mesh/surface``; dpm as ``dpm.MeshFace`` of the same file.

Mapping (docs/from-liggghts.md): ``gran/hooke/history`` with ``characteristicVelocity V``
is dpm's ``maw_linear_spring, impact_velocity=V`` with ``tangential_stiffness_ratio=1``
(LIGGGHTS' k_t = k_n). dpm cuts the normal force off at zero and solves the damping for
the set restitution with the cut-off; LIGGGHTS (``limitForce off``) does not (item 1 of
the defaults that differ): a small difference in the bounce off the chute.

Compared: bodies inserted and bodies in the container against time; LIGGGHTS is run
twice with different insertion seeds (its run-to-run spread), dpm once; speed is
particle-steps per second over each code's whole loop on one core (dpm: after a warm-up
run that compiles, so compile time is reported apart), and dpm's on two threads
(``sim.threads = 2``: the same counts bit for bit) against LIGGGHTS' one core. The machine
may be shared while this runs: the timings are noisy (stated in the JSON); the physics is
what must agree.

    python benchmarks/meshgran.py [--quick] [--no-liggghts]

Writes benchmarks/results/meshgran[_quick].json and .png.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent

DT = 5e-5
RADIUS, DENSITY = 0.005, 2500.0
YOUNG, POISSON, RESTITUTION, FRICTION, CHAR_VEL = 5e6, 0.45, 0.7, 0.05, 2.0
RATE, SPEED, EXTRUDE = 1000.0, 1.0, 0.02
#: insertion face (a square at z = 0) and the container (an open-top box)
FACE = (-0.02, 0.02, -0.02, 0.02, 0.0)
CONTAINER = (0.15, 0.45, -0.1, 0.1, -0.6, -0.3)
#: count interval [s] (thermo)
EVERY = 0.02

#: the input after shared_scenes' header and box lines (:func:`liggghts_input`)
LIGGGHTS_REST = """\
fix m5 all property/global characteristicVelocity scalar {char_vel}
pair_style gran model hooke tangential history
pair_coeff * *
timestep {dt}
fix 1 all nve/sphere
fix 2 all gravity 9.81 vector 0.0 0.0 -1.0
fix cad all mesh/surface file walls.stl type 1
fix granwalls all wall/gran model hooke tangential history mesh n_meshes 1 meshes cad
fix inface all mesh/surface file face.stl type 1
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant {density} &
    radius constant {radius}
fix pdd1 all particledistribution/discrete 49979687 1 pts1 1.0
group nve_group region reg
fix ins nve_group insert/stream seed {seed} distributiontemplate pdd1 maxattempt 100 &
    nparticles {n_total} particlerate {rate} overlapcheck yes all_in no &
    vel constant 0. 0. -{speed} insertion_face inface extrude_length {extrude}
region cont block {cx0} {cx1} {cy0} {cy1} {cz0} {cz1} units box
variable ncont equal count(all,cont)
thermo_style custom step atoms v_ncont
thermo {thermo}
thermo_modify lost ignore norm no
run {insert_steps}
unfix ins
run {rest_steps}
"""


def geometry(folder: Path) -> tuple[Path, Path]:
    """Write walls.stl (chute, its side walls and back wall, the container) and face.stl
    (the insertion square) with trimesh; return their paths."""
    import trimesh

    def quad(a, b, c, d):
        return trimesh.Trimesh(vertices=[a, b, c, d], faces=[[0, 1, 2], [0, 2, 3]])

    tilt = np.radians(30.0)
    x0, x1, y = -0.05, 0.22, 0.05
    z0 = -0.05
    z1 = z0 - (x1 - x0) * np.tan(tilt)
    h = 0.06  # side-wall height above the chute
    parts = [quad((x0, -y, z0), (x1, -y, z1), (x1, y, z1), (x0, y, z0)),  # chute floor
             quad((x0, -y, z0), (x1, -y, z1), (x1, -y, z1 + h), (x0, -y, z0 + h)),
             quad((x0, y, z0), (x1, y, z1), (x1, y, z1 + h), (x0, y, z0 + h)),
             quad((x0, -y, z0), (x0, y, z0), (x0, y, z0 + h), (x0, -y, z0 + h))]
    cx0, cx1, cy0, cy1, cz0, cz1 = CONTAINER
    parts += [quad((cx0, cy0, cz0), (cx1, cy0, cz0), (cx1, cy1, cz0), (cx0, cy1, cz0)),
              quad((cx0, cy0, cz0), (cx1, cy0, cz0), (cx1, cy0, cz1), (cx0, cy0, cz1)),
              quad((cx0, cy1, cz0), (cx1, cy1, cz0), (cx1, cy1, cz1), (cx0, cy1, cz1)),
              quad((cx0, cy0, cz0), (cx0, cy1, cz0), (cx0, cy1, cz1), (cx0, cy0, cz1)),
              quad((cx1, cy0, cz0), (cx1, cy1, cz0), (cx1, cy1, cz1), (cx1, cy0, cz1))]
    walls = trimesh.util.concatenate(parts)
    fx0, fx1, fy0, fy1, fz = FACE
    face = quad((fx0, fy0, fz), (fx1, fy0, fz), (fx1, fy1, fz), (fx0, fy1, fz))
    wp, fp = folder / "walls.stl", folder / "face.stl"
    walls.export(wp, file_type="stl_ascii")  # (LIGGGHTS reads ASCII STL)
    face.export(fp, file_type="stl_ascii")
    return wp, fp


def in_container(pos: np.ndarray) -> int:
    cx0, cx1, cy0, cy1, cz0, cz1 = CONTAINER
    return int(np.sum((pos[:, 0] >= cx0) & (pos[:, 0] <= cx1) & (pos[:, 1] >= cy0)
                      & (pos[:, 1] <= cy1) & (pos[:, 2] >= cz0) & (pos[:, 2] <= cz1)))


def scene(folder: Path, t_insert: float, seed: int = 5330):
    import dpm

    walls, face = geometry(folder)
    sim = dpm.Simulation(dt=DT, gravity=(0.0, 0.0, -9.81), sphere_orientation=False)
    m = dpm.Material("beads", density=DENSITY, young=YOUNG, poisson=POISSON)
    sim.contact(m, m, model="maw_linear_spring", restitution=RESTITUTION, friction=FRICTION,
                impact_velocity=CHAR_VEL, tangential_stiffness_ratio=1.0)
    sim.add_boundary("mesh", material=m, file=str(walls))
    inlet = sim.add_inlet(dpm.MeshFace(file=str(face)), m, rate=RATE, radius=RADIUS,
                          velocity=(0.0, 0.0, -SPEED), every=EXTRUDE / SPEED, stop=t_insert,
                          seed=seed, max_attempts=100, random_orientation=False)
    return sim, inlet


def run_dpm(t_insert: float, t_end: float, threads: int = 1) -> dict:
    """dpm's run on ``threads`` threads (``sim.threads``: a run's results are the same bit
    for bit for any count, so the counts against time must match the one-thread run's)."""
    import numba

    import dpm  # noqa: F401  (first: it picks numba's OpenMP layer before any launch)

    numba.set_num_threads(threads)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        warm, _ = scene(Path(tmp), t_insert)  # compiles (or loads the cache)
        warm.threads = threads
        warm.run(steps=2, progress=False)
        first = time.perf_counter() - t0
        sim, inlet = scene(Path(tmp), t_insert)
        sim.threads = threads
        times, inserted, cont, bodies = [], [], [], []
        loop, psteps = 0.0, 0.0
        n_int = round(t_end / EVERY)
        for k in range(1, n_int + 1):
            n0, s0 = len(sim.bodies), sim.step_count
            c0 = time.perf_counter()
            sim.run(until=k * EVERY, progress=False)
            loop += time.perf_counter() - c0
            psteps += 0.5 * (n0 + len(sim.bodies)) * (sim.step_count - s0)
            times.append(sim.time)
            # (as LIGGGHTS' thermo line: before the batch inserted at this very time)
            inserted.append(inlet.inserted - int(np.sum(sim.bodies.birth == sim.time)))
            cont.append(in_container(sim.bodies.position))
            bodies.append(len(sim.bodies))
    return {"time_s": times, "inserted": inserted, "in_container": cont, "bodies": bodies,
            "escaped": int(len(getattr(sim, "escaped", {}).get("id", [])))
            if isinstance(getattr(sim, "escaped", None), dict) else None,
            "loop_s": loop, "particle_steps": psteps,
            "particle_steps_per_s": psteps / loop, "time_to_first_steps_s": first,
            "skin": sim.skin, "threads": threads}


def liggghts_input() -> str:
    """The LIGGGHTS input, a template of ``str.format`` (imported here, not at the top:
    tests/ load this file by path, without benchmarks/ on ``sys.path``)."""
    from shared_scenes import LIGGGHTS_BOX_MATERIALS, LIGGGHTS_HEADER

    box = LIGGGHTS_BOX_MATERIALS.format(region="-0.1 0.5 -0.12 0.12 -0.62 0.05")
    return LIGGGHTS_HEADER + box + LIGGGHTS_REST


def run_liggghts(t_insert: float, t_end: float, skin: float, seed: int) -> dict | None:
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    insert_steps = round(t_insert / DT)
    rest_steps = round(t_end / DT) - insert_steps
    cx0, cx1, cy0, cy1, cz0, cz1 = CONTAINER
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        geometry(t)
        (t / "in.meshgran").write_text(liggghts_input().format(
            skin=skin, young=YOUNG, poisson=POISSON, restitution=RESTITUTION,
            friction=FRICTION, char_vel=CHAR_VEL, dt=DT, density=DENSITY, radius=RADIUS,
            seed=seed, n_total=int(RATE * t_insert), rate=RATE, speed=SPEED,
            extrude=EXTRUDE, cx0=cx0, cx1=cx1, cy0=cy0, cy1=cy1, cz0=cz0, cz1=cz1,
            thermo=round(EVERY / DT), insert_steps=insert_steps, rest_steps=rest_steps))
        t0 = time.perf_counter()
        out = subprocess.run([exe, "-in", "in.meshgran", "-echo", "none", "-log", "log.txt"],
                             cwd=tmp, check=True, capture_output=True, text=True,
                             env={**os.environ, "OMP_NUM_THREADS": "1"}).stdout
        whole = time.perf_counter() - t0
    loops = [float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", out)]
    rows = {}
    for ln in out.splitlines():
        if re.match(r"\s+\d+\s+\d+\s+\d+\s*$", ln):
            s, n, c = (int(x) for x in ln.split())
            rows[s] = (n, c)
    steps = np.array(sorted(rows))
    atoms = np.array([rows[s][0] for s in steps])
    cont = np.array([rows[s][1] for s in steps])
    psteps = float(np.sum(0.5 * (atoms[1:] + atoms[:-1]) * np.diff(steps)))
    keep = steps > 0
    return {"seed": seed, "time_s": (steps[keep] * DT).tolist(),
            "inserted": atoms[keep].tolist(), "in_container": cont[keep].tolist(),
            "loop_s": sum(loops), "whole_run_s": whole, "particle_steps": psteps,
            "particle_steps_per_s": psteps / sum(loops)}


def compare(d: dict, runs: list[dict]) -> dict:
    """dpm's counts against the LIGGGHTS runs at the same times: the largest gap to the
    nearest LIGGGHTS run and the LIGGGHTS runs' own largest gap (their spread)."""
    out = {}
    for key in ("inserted", "in_container"):
        lg = [np.interp(d["time_s"], r["time_s"], r[key]) for r in runs]
        lo, hi = np.min(lg, axis=0), np.max(lg, axis=0)
        dp = np.asarray(d[key], float)
        gap = np.maximum(lo - dp, dp - hi).clip(0)
        out[key] = {"dpm_final": float(dp[-1]), "liggghts_final": [float(x[-1]) for x in lg],
                    "liggghts_spread_max": float(np.max(hi - lo)),
                    "dpm_outside_liggghts_max": float(gap.max())}
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    d = result["dpm"]
    for k, key in enumerate(("inserted", "in_container")):
        for r in result["liggghts"] or []:
            ax[k].plot(r["time_s"], r[key], color="0.5", lw=1,
                       label=f"LIGGGHTS seed {r['seed']}")
        ax[k].plot(d["time_s"], d[key], color="C0", lw=2, label="dpm")
        ax[k].set_xlabel("time [s]")
        ax[k].set_ylabel(key.replace("_", " "))
        ax[k].legend()
    ratio = result.get("speed_ratio_dpm_over_liggghts")
    fig.suptitle("meshGran port: dpm vs LIGGGHTS 3.8" + (
        f" (speed ratio dpm/LIGGGHTS {ratio:.2f}, one core, shared machine)" if ratio
        else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main(argv: list[str] | None = None) -> dict:
    import harness  # (here: tests/ load this file by path)

    p = harness.parser(__doc__, "insert 0.2 s, run to 0.8 s")
    p.add_argument("--no-liggghts", action="store_true")
    a = p.parse_args(argv)
    t_insert, t_end = (0.2, 0.8) if a.quick else (0.5, 2.5)
    d = run_dpm(t_insert, t_end)
    print(f"dpm: {d['inserted'][-1]} inserted, {d['in_container'][-1]} in the container, "
          f"{d['particle_steps_per_s']:.3g} particle-steps/s", flush=True)
    d2 = run_dpm(t_insert, t_end, threads=2)
    same = all(d2[k] == d[k] for k in ("inserted", "in_container", "bodies"))
    print(f"dpm 2 threads: {d2['particle_steps_per_s']:.3g} particle-steps/s "
          f"({d2['particle_steps_per_s'] / d['particle_steps_per_s']:.2f}x one thread; "
          f"counts {'the same' if same else 'DIFFERENT'})", flush=True)
    runs = [] if a.no_liggghts else [
        r for r in (run_liggghts(t_insert, t_end, d["skin"], s) for s in (67867967, 86028121)) if r]
    result = {"scene": "meshGran tutorial port (own STL)", "quick": a.quick, "dt": DT,
              "t_insert_s": t_insert, "t_end_s": t_end, "rate_per_s": RATE,
              "timing_note": "one core each; the machine was shared with other jobs while "
                             "this ran, so the timings are noisy; the physics is what "
                             "must agree",
              "dpm": d, "dpm_2_threads": d2, "two_thread_counts_identical": same,
              "two_thread_gain": d2["particle_steps_per_s"] / d["particle_steps_per_s"],
              "peer": harness.peer(a.no_liggghts), "liggghts": runs or None}
    if runs:
        result["physics"] = compare(d, runs)
        lg = float(np.mean([r["particle_steps_per_s"] for r in runs]))
        result["speed_ratio_dpm_over_liggghts"] = harness.ratio(d["particle_steps_per_s"], lg)
        result["speed_ratio_dpm_2_threads_over_liggghts"] = harness.ratio(
            d2["particle_steps_per_s"], lg)
        for r in runs:
            print(f"LIGGGHTS seed {r['seed']}: {r['inserted'][-1]} inserted, "
                  f"{r['in_container'][-1]} in the container, "
                  f"{r['particle_steps_per_s']:.3g} particle-steps/s")
        print(json.dumps(result["physics"], indent=1))
        print(f"speed ratio dpm / LIGGGHTS {result['speed_ratio_dpm_over_liggghts']:.2f}, "
              f"dpm 2 threads / LIGGGHTS one core "
              f"{result['speed_ratio_dpm_2_threads_over_liggghts']:.2f}")
    path = harness.write("meshgran", result, a.quick)
    harness.png(plot, result, path=path.with_suffix(".png"))
    return result


if __name__ == "__main__":
    main()
