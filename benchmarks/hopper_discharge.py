"""Silo discharge, dpm against LIGGGHTS on the same scene in the same run.

The flat-bottomed silo of examples/hopper_discharge.py (tube of radius 40 mm, orifice plate
with a round orifice of D mm, 5 mm glass beads from the same lattice, Hertz-Mindlin,
e = 0.5, mu = 0.5, E = 10 MPa, dt = 2e-5 s): the bed settles on a plug plane for T_OPEN,
the plug goes (dpm: ``sim.switch_off``; LIGGGHTS: ``unfix``), and the beads that fall
50 mm below the orifice are counted. LIGGGHTS gets the cylinder as its ``zcylinder``
primitive and the orifice floor as an STL of the same annulus (the hole a 64-gon). The
discharge rate W is the mass that left per second in the same window (0.08 s after the
opening, ``--window`` long); speed is particle-steps per second of the whole loop on one
core each (LIGGGHTS keeps the beads that fell out, dpm's outlet removes them). The box of
the LIGGGHTS run reaches 3 m down: with ``boundary f f f`` a bead that leaves the box is
lost and the count of those that fell out would miss it.

    python benchmarks/hopper_discharge.py [--quick] [--orifice 0.025] [--no-liggghts]

Writes benchmarks/results/hopper_discharge[_quick].json.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import harness
import numpy as np
from shared_scenes import LIGGGHTS_HEADER

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent
# the example's scene (loaded by path: this script has the same module name)
hd = harness.example("hopper_discharge")

RADIUS, HEIGHT = 0.04, 0.1
#: --quick: a lower bed and a shorter rate window
QUICK_HEIGHT, QUICK_WINDOW = 0.05, 0.1

LIGGGHTS_IN = LIGGGHTS_HEADER + """\
read_data silo.data
neighbor {skin} bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype 1e7 1e7
fix m2 all property/global poissonsRatio peratomtype 0.3 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.5 0.5 0.5 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5
pair_style gran model hertz tangential history
pair_coeff * *
timestep {dt}
fix cyl all wall/gran model hertz tangential history primitive type 2 zcylinder {radius} 0 0
fix floor all mesh/surface file floor.stl type 2
fix fl all wall/gran model hertz tangential history mesh n_meshes 1 meshes floor
fix plug all wall/gran model hertz tangential history primitive type 2 zplane 0.0
fix grav all gravity 9.81 vector 0.0 0.0 -1.0
fix integr all nve/sphere
region gone block -1 1 -1 1 -2 -0.05 units box
variable nout equal count(all,gone)
thermo_style custom step atoms v_nout
thermo {every}
run {open_steps}
unfix plug
run {flow_steps}
"""


def floor_stl(path: Path, hole: float, outer: float, n: int = 64) -> None:
    """ASCII STL of the annulus hole/2 .. outer in z = 0 (n sides each)."""
    ang = np.arange(n) * 2 * np.pi / n
    inner = np.c_[hole / 2 * np.cos(ang), hole / 2 * np.sin(ang), np.zeros(n)]
    out = np.c_[outer * np.cos(ang), outer * np.sin(ang), np.zeros(n)]
    lines = ["solid floor"]
    for k in range(n):
        a, b = k, (k + 1) % n
        for tri in ((inner[a], out[a], out[b]), (inner[a], out[b], inner[b])):
            lines.append("facet normal 0 0 1\nouter loop")
            lines += [f"vertex {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}" for p in tri]
            lines.append("endloop\nendfacet")
    lines.append("endsolid floor")
    path.write_text("\n".join(lines) + "\n")


def run_dpm(orifice: float, window: float, height: float = HEIGHT) -> dict:
    sim, _ = hd.silo(orifice, radius=RADIUS, height=height)
    mass = float(sim.bodies.mass.sum())
    r = hd.discharge(sim, window)
    r["bulk_density"] = hd.bulk_density(sim, mass, RADIUS, r["bed_top_m"])
    r["skin"] = sim.skin
    r["steps"] = sim.step_count
    return r


def run_liggghts(orifice: float, skin: float, window: float,
                 keep: str | None = None, height: float = HEIGHT) -> dict | None:
    exe = harness.liggghts()
    if exe is None:
        return None
    sim, _ = hd.silo(orifice, radius=RADIUS, height=height)
    pos, rad = sim.bodies.position, sim.bodies.radius
    m1 = float(sim.bodies.mass[0])
    dt = hd.DT
    every = round(2e-3 / dt)
    open_steps = round(hd.T_OPEN / dt)
    flow_steps = round((hd.T_START + window) / dt)
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        with open(t / "silo.data", "w") as f:
            f.write(f"silo\n\n{len(pos)} atoms\n2 atom types\n\n")
            f.write("-0.06 0.06 xlo xhi\n-0.06 0.06 ylo yhi\n-3 0.3 zlo zhi\n\nAtoms\n\n")
            for a, (p, r) in enumerate(zip(pos, rad, strict=True), 1):
                f.write(f"{a} 1 {2 * r:.9g} 2500 {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n")
        floor_stl(t / "floor.stl", orifice, RADIUS + 0.01)
        (t / "silo.in").write_text(LIGGGHTS_IN.format(
            skin=skin, dt=dt, radius=RADIUS, every=every, open_steps=open_steps,
            flow_steps=flow_steps))
        t0 = time.perf_counter()
        out = subprocess.run([exe, "-in", "silo.in", "-echo", "none", "-log", "log.txt"],
                             cwd=tmp, check=True, capture_output=True, text=True,
                             env={**os.environ, "OMP_NUM_THREADS": "1"}).stdout
        whole = time.perf_counter() - t0
        if keep:
            shutil.copytree(tmp, keep, dirs_exist_ok=True)
    loops = [float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", out)]
    rows = [ln.split() for ln in out.splitlines() if re.match(r"\s+\d+\s+\d+\s+\d+\s*$", ln)]
    step = np.array([int(r[0]) for r in rows])
    nout = np.array([int(r[2]) for r in rows])
    time_s = step * dt
    lo, hi = hd.T_OPEN + hd.T_START, hd.T_OPEN + hd.T_START + window
    k0, k1 = np.searchsorted(time_s, lo - 1e-12), np.searchsorted(time_s, hi - 1e-12)
    k1 = min(k1, len(time_s) - 1)
    rate = (nout[k1] - nout[k0]) * m1 / (time_s[k1] - time_s[k0])
    return {"rate_kg_s": float(rate), "bodies": int(len(pos)), "removed": int(nout[-1]),
            "loop_s": sum(loops), "whole_run_s": whole,
            "particle_steps_per_s": len(pos) * (open_steps + flow_steps) / sum(loops)}


def main(argv: list[str] | None = None) -> dict:
    p = harness.parser(__doc__, f"a bed {QUICK_HEIGHT * 1e3:.0f} mm high, a rate window of "
                                f"{QUICK_WINDOW} s")
    p.add_argument("--orifice", type=float, default=0.025)
    p.add_argument("--window", type=float, default=None, help="rate window [s] (0.5)")
    p.add_argument("--no-liggghts", action="store_true")
    a = p.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    height = QUICK_HEIGHT if a.quick else HEIGHT
    a.window = a.window or (QUICK_WINDOW if a.quick else 0.5)
    d = run_dpm(a.orifice, a.window, height)
    print(f"dpm: W = {d['rate_kg_s']:.4f} kg/s, {d['particle_steps_per_s']:.3g} "
          "particle-steps/s", flush=True)
    lg = None if a.no_liggghts else run_liggghts(a.orifice, d["skin"], a.window,
                                                 height=height)
    result = {"orifice_m": a.orifice, "silo_radius_m": RADIUS, "bed_height_m": height,
              "d": hd.D_BEAD,
              "window_s": a.window, "dpm": d, "peer": harness.peer(a.no_liggghts),
              "liggghts": lg}
    if lg:
        result["rate_ratio_dpm_over_liggghts"] = d["rate_kg_s"] / lg["rate_kg_s"]
        result["speed_ratio_dpm_over_liggghts"] = harness.ratio(d["particle_steps_per_s"],
                                                                lg["particle_steps_per_s"])
        print(f"LIGGGHTS: W = {lg['rate_kg_s']:.4f} kg/s, {lg['particle_steps_per_s']:.3g} "
              f"particle-steps/s; W ratio dpm / LIGGGHTS "
              f"{result['rate_ratio_dpm_over_liggghts']:.3f}")
    harness.write("hopper_discharge", result, a.quick)
    return result


if __name__ == "__main__":
    main()
