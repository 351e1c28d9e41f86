"""Box settle: the reference speed scene (10,000 glass spheres settling in a box).

Spheres (d = 2 mm, rho = 2500 kg/m3, E = 5 MPa, nu = 0.45, e = 0.3, mu = 0.5, Hertz-Mindlin)
start on a jittered lattice with small random velocities and settle under gravity in a
box of planar walls open at the top; dt = 1e-5 s, 20,000 steps. The initial packing is the
CSV that benchmarks/scenes/box_settle/gen_init.py writes (the same file LIGGGHTS and Yade
read, see benchmarks/scenes/box_settle/README.md). LIGGGHTS ends at a mean height of
21.270 mm.

    python examples/box_settle.py                 # 10,000 spheres, 20,000 steps
    python examples/box_settle.py --quick         # 1,000 spheres, 5,000 steps
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import dpm

SCENE_DIR = Path(__file__).resolve().parent.parent / "benchmarks" / "scenes" / "box_settle"
LIGGGHTS_MEAN_Z = 0.021270  # m, after 20,000 steps of the 10,000-sphere scene


def initial_packing(nx: int, ny: int, nz: int, workdir: Path = SCENE_DIR) -> Path:
    """Path of box_settle_NXxNYxNZ.csv for an nx x ny x nz lattice (written by gen_init.py;
    named by the lattice: two lattices of one sphere count are different scenes)."""
    csv = workdir / f"box_settle_{nx}x{ny}x{nz}.csv"
    if not csv.exists():
        workdir.mkdir(parents=True, exist_ok=True)
        # written in a private folder and renamed into place (the CSV last): MPI ranks
        # of one run all come here at once, and none may read another's half-written file
        with tempfile.TemporaryDirectory(dir=workdir) as tmp:
            subprocess.run([sys.executable, str(SCENE_DIR / "gen_init.py"), str(nx),
                            str(ny), str(nz)], cwd=tmp, check=True, capture_output=True)
            for suffix in (".data", ".csv"):
                os.replace(Path(tmp) / (csv.stem + suffix), csv.with_suffix(suffix))
    return csv


def build(csv: Path, dt: float = 1e-5) -> dpm.Simulation:
    """The box-settle scene from its CSV (header holds the box size; x,y,z,vx,vy,vz,r)."""
    with open(csv) as f:
        box = [float(x) for x in f.readline().split("box=")[1].split(",")]
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    # the physics of the LIGGGHTS input (fix nve/sphere): no force depends on a sphere's
    # orientation, so it is not integrated
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, -9.81), integrator="velocity_verlet",
                         sphere_orientation=False)
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=glass, lower=(0.0, 0.0, 0.0), upper=box, open=("+z",))
    sim.add_particles("sphere", material=glass, radius=data[:, 6], positions=data[:, :3],
                      velocities=data[:, 3:6])
    return sim


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="1,000 spheres, 5,000 steps")
    p.add_argument("--lattice", type=int, nargs=3, default=None, metavar=("NX", "NY", "NZ"))
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--output", default="box_settle.h5", help="HDF5 output (+ .xdmf)")
    p.add_argument("--every", type=float, default=0.01, help="output interval [s]")
    a = p.parse_args(argv)
    lat = a.lattice or ((10, 10, 10) if a.quick else (20, 20, 25))
    steps = a.steps or (5000 if a.quick else 20000)
    sim = build(initial_packing(*lat))
    sim.output(a.output, every=a.every, overwrite=True)  # (the example's own file)
    t0 = time.perf_counter()
    sim.run(steps=steps)
    sim.close()
    wall = time.perf_counter() - t0
    z = float(sim.bodies.position[:, 2].mean())
    n = len(sim.bodies)
    if not dpm.is_root():  # (under mpiexec every rank holds the whole result: one reports)
        return
    print(f"{n} spheres, {steps} steps in {wall:.1f} s ({n * steps / wall:.3g} particle-steps/s"
          f" incl. compile); mean height {z * 1e3:.3f} mm")
    if n == 10000 and steps == 20000:
        print(f"LIGGGHTS: {LIGGGHTS_MEAN_Z * 1e3:.3f} mm; difference "
              f"{(z / LIGGGHTS_MEAN_Z - 1) * 100:+.3f} %")
    run = dpm.load(a.output)
    print(f"wrote {a.output}: {run.n_frames} frames, t = {run.times[0]:g} .. {run.times[-1]:g} s")


if __name__ == "__main__":
    main()
