"""LIGGGHTS' meshGran tutorial itself, dpm and LIGGGHTS: counts out of the chute, and how
far the scene's overlaps go.

The tutorial's own files (Debian's ``liggghts-doc``; GPL, read where Debian puts them): the
CAD container with an inner chute (``meshes/mesh.stl``, scale 0.001, turned -90 degrees
about x), 5 mm glass spheres streamed through ``insertion_face.stl`` at 1000/s for 0.5 s,
``hooke`` with ``characteristicVelocity 2``, dt = 5e-5 s. Measured:

1. spheres below z = -0.6 m (out of the chute) at 0.5, 1.0, 2.0 and 2.5 s: LIGGGHTS on
   the tutorial's input with that count added to its thermo output, for several insertion
   seeds, and dpm with a stream inlet (as the tutorial) and with the box inlet of issue
   #62 (x 0.205-0.255, y -0.05-0, z -0.025-0.005 m, a packet every 0.02 s);
2. the overlaps the scene reaches: dpm runs with the guard lowered (``max_overlap`` 0.3
   and 0.42 of the radius) and the step and overlap where each stops. The spring is
   sized for 2 m/s; the spheres fall up to 1.2 m (4.9 m/s) and meet rebounding ones
   head-on (dpm warns of it before the first step: dpm.impact.design_speed).

    python benchmarks/meshgran_tutorial.py [--quick] [--no-liggghts]

Writes benchmarks/results/meshgran_tutorial[_quick].json. tests/physics/
test_meshgran_tutorial.py runs :func:`scene` against the LIGGGHTS counts in the slow set.
"""

from __future__ import annotations

import re
import subprocess
import tempfile
import warnings
from pathlib import Path

import numpy as np

import dpm

TUTORIAL = Path("/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/meshGran")
MESH, FACE = TUTORIAL / "meshes" / "mesh.stl", TUTORIAL / "meshes" / "insertion_face.stl"
TIMES = (0.5, 1.0, 2.0, 2.5)
#: below this height a sphere is out of the chute [m]
Z_OUT = -0.6
LIGGGHTS_SEEDS = (32452843, 67867967, 86028121)


def scene(inlet: str, seed: int, threads: int = 1, max_overlap: float = 0.5):
    """The tutorial in dpm: ``inlet`` "stream" (the tutorial's face) or "box"."""
    sim = dpm.Simulation(dt=5e-5, gravity=(0.0, 0.0, -9.81), integrator="velocity_verlet",
                         sphere_orientation=False, threads=threads, max_overlap=max_overlap)
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="maw_linear_spring", impact_velocity=2.0,
                restitution=0.7, friction=0.05, tangential_stiffness_ratio=1.0,
                tangential_restitution=0.7)
    sim.add_boundary("mesh", material=glass, file=str(MESH), scale=0.001,
                     rotate=(1, 0, 0, -90), side="both")
    region = (dpm.MeshFace(file=str(FACE)) if inlet == "stream"
              else dpm.BoxRegion((0.205, -0.05, -0.025), (0.255, 0.0, 0.005)))
    sim.add_inlet(region, glass, rate=1000.0, radius=0.005, velocity=(0.0, 0.0, -1.0),
                  every=0.02, stop=0.5, seed=seed, max_attempts=100,
                  random_orientation=False)
    sim.add_outlet(dpm.BoxRegion((-0.01, -0.06, -1.22), (0.51, 0.01, 0.01)),
                   remove="outside")
    return sim


def run_dpm(inlet: str, seed: int, max_overlap: float = 0.5) -> dict:
    """Counts below Z_OUT at TIMES, or where the guard stopped the run."""
    sim = scene(inlet, seed, max_overlap=max_overlap)
    out: dict = {"inlet": inlet, "seed": seed, "max_overlap": max_overlap, "below": []}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the design-speed warning, every run)
        try:
            for t in TIMES:
                sim.run(until=t, progress=False)
                out["below"].append(int(np.sum(sim.bodies.position[:, 2] < Z_OUT)))
        except dpm.UnstableRunError as e:
            m = re.search(r"step (\d+) .*overlap reached ([0-9.]+)", str(e))
            out["stopped"] = {"step": int(m.group(1)), "overlap": float(m.group(2))}
    return out


def run_liggghts(seed: int) -> dict | None:
    """The tutorial's input, its insertion seed set, dumps dropped, a count below Z_OUT in
    the thermo output, run to 2.5 s."""
    import harness  # (here: tests load this file by path, without benchmarks/ on sys.path)

    exe = harness.liggghts()
    if exe is None or not MESH.exists():
        return None
    text = (TUTORIAL / "in.meshGran").read_text()
    text = re.sub(r"insert/stream seed \d+", f"insert/stream seed {seed}", text)
    text = "\n".join(line for line in text.splitlines() if not line.startswith("dump"))
    text = re.sub(r"thermo_style.*", f"region below block -0.01 0.51 -0.06 0.01 -1.22 {Z_OUT} "
                  "units box\nvariable nb equal count(all,below)\n"
                  "thermo_style custom step atoms v_nb", text)
    text = re.sub(r"run\t+40000 upto", "run 50000 upto", text)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "meshes").symlink_to(TUTORIAL / "meshes")
        (Path(tmp) / "in.tutorial").write_text(text)
        log = subprocess.run([exe, "-in", "in.tutorial", "-log", "none"], cwd=tmp,
                             capture_output=True, text=True, check=True).stdout
    rows = {int(a): int(c) for a, _, c in re.findall(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s*$", log,
                                                      re.M)}
    return {"seed": seed, "below": [rows.get(round(t / 5e-5)) for t in TIMES]}


def main() -> None:
    import harness

    ap = harness.parser(__doc__, "one seed of each (LIGGGHTS, dpm inlets, guard sweep)")
    ap.add_argument("--no-liggghts", action="store_true")
    args = ap.parse_args()
    if not MESH.exists():
        why = f"{MESH} is missing (apt-get install liggghts-doc): the tutorial's own mesh"
        if not args.quick:
            raise SystemExit(why)
        # (--quick: a JSON that says why nothing was measured, not a failed run)
        print("written", harness.write("meshgran_tutorial", {
            "times_s": list(TIMES), "z_out_m": Z_OUT, "measured": None, "why": why,
            "peer": harness.peer(args.no_liggghts), "liggghts": [], "dpm": [],
            "guard_sweep": []}, quick=True))
        return
    n = 1 if args.quick else None
    res: dict = {"times_s": list(TIMES), "z_out_m": Z_OUT,
                 "peer": harness.peer(args.no_liggghts)}
    res["liggghts"] = [] if args.no_liggghts else [
        r for r in (run_liggghts(s) for s in LIGGGHTS_SEEDS[:n]) if r is not None]
    res["dpm"] = [run_dpm(inlet, s) for inlet in ("stream", "box") for s in range(n or 6)]
    res["guard_sweep"] = [run_dpm("box", s, mo) for mo, k in ((0.3, 8), (0.42, 12))
                          for s in range(n or k)]
    for key in ("liggghts", "dpm", "guard_sweep"):
        for r in res[key]:
            print(key, {k: v for k, v in r.items() if k != "max_overlap"}
                  | ({"max_overlap": r["max_overlap"]} if key == "guard_sweep" else {}))
    print("written", harness.write("meshgran_tutorial", res, quick=args.quick))


if __name__ == "__main__":
    main()
