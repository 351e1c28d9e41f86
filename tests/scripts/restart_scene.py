"""A scene with everything a checkpoint must carry, run in a process of its own by
tests/io/test_checkpoint.py: clustered bodies (cylinders) in a box, spheres and cylinders fed
by an inlet (a size range, random orientations), an outlet in a floor corner, a rotating
triangle-mesh paddle, the Gear integrator, output frames and periodic checkpoints, bodies
renumbered in cell order.

    python restart_scene.py DIR full STEPS           one uninterrupted run
    python restart_scene.py DIR start STEPS          run with checkpoints every CK steps
    python restart_scene.py DIR resume STEPS         dpm.restart the newest, run to STEPS
    python restart_scene.py DIR half STEPS           run STEPS/2, checkpoint, exit
    python restart_scene.py DIR rest STEPS           restart that one, run the other half

Each run ends by writing DIR/<mode>.npz with the whole state (every array, by row).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

import dpm
from dpm.backends import CpuBackend

CK = 150  # steps between checkpoints (start/resume)
FRAME = 100  # steps between output frames


def scene(out: Path | None) -> dpm.Simulation:
    # (renumbered in cell order every 2 rebuilds, decided every 1,000 steps: a restart
    # must renumber at the same steps as the uninterrupted run)
    sim = dpm.Simulation(dt=2e-5, gravity=(0, 0, -9.81), integrator="gear4", dt_check="warn",
                         device=CpuBackend(sort_every=2))
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.5, friction=0.3,
                rolling_friction=0.05)
    sim.add_boundary("box", material=steel, lower=(0, 0, 0), upper=(0.016, 0.016, 0.04),
                     open=("+z",))
    paddle = trimesh.creation.box(extents=(0.010, 0.002, 0.004))
    paddle.apply_translation((0.008, 0.008, 0.007))
    sim.add_boundary("mesh", material=steel, vertices=paddle.vertices, faces=paddle.faces,
                     motion=dpm.Rotation(axis=(0, 0, 1), center=(0.008, 0.008, 0.0), rpm=60,
                                         ramp=0.01))
    xyz = dpm.lattice((0.001, 0.001, 0.011), (0.015, 0.015, 0.02), spacing=3.4e-3,
                      jitter=4e-5)
    sim.add_particles("cylinder", material=glass, r=1e-3, l=2e-3, positions=xyz)
    sim.add_inlet(dpm.BoxRegion((0.002, 0.002, 0.026), (0.014, 0.014, 0.036)), glass,
                  rate=4000, seed=7, every=1e-3,
                  shapes=[{"shape": "sphere", "fraction": 2, "radius": (0.8e-3, 1.1e-3)},
                          {"shape": "cylinder", "fraction": 1, "r": 0.8e-3, "l": 1.6e-3}])
    # (in the fall path of the inlet: it removes from the first milliseconds on)
    sim.add_outlet(dpm.BoxRegion((0.002, 0.002, 0.021), (0.010, 0.010, 0.025)), every=5e-4)
    if out is not None:
        sim.output(out, every_steps=FRAME, overwrite=True)
    return sim


def save(sim: dpm.Simulation, path: Path) -> None:
    b, c, wc = sim.bodies, sim.contacts, sim.wall_contacts
    np.savez(path, id=b.id, position=b.position, velocity=b.velocity,
             orientation=b.orientation, angular_velocity=b.angular_velocity, force=b.force,
             torque=b.torque, aux=sim.backend.aux, c_start=c.start,
             c_key=c.key[:c.count], c_hist=c.history[:c.count], w_start=wc.start,
             w_key=wc.key[:wc.count], w_hist=wc.history[:wc.count],
             frame=sim.walls.frame, load=sim.walls.load[:, :6],
             removed=sim.outlets[0].records["id"], inserted=sim.inlets[0].inserted,
             step=sim.step_count, time=sim.time,
             torque_paddle=sim.boundaries[1].torque, work=sim.boundaries[1].work)


def main() -> None:
    d, mode, steps = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
    ck = d / "run.ckpt.h5"
    if mode == "full":
        sim = scene(d / "full.h5")
        sim.run(steps=steps, progress=False)
    elif mode == "start":
        sim = scene(d / "run.h5")
        sim.checkpoint_every(ck, every_steps=CK, keep=2)
        sim.run(steps=1, progress=False)  # (compiled and stepping: a run split anywhere
        print("running", flush=True)      # gives the same bits)
        sim.run(steps=steps - 1, progress=False)
    elif mode == "resume":
        sim = dpm.restart(ck)
        if sim.step_count < steps:
            sim.run(steps=1, progress=False)
        print("running", flush=True)
        sim.run(steps=steps - sim.step_count, progress=False)
    elif mode == "half":
        sim = scene(d / "half.h5")
        sim.run(steps=steps // 2, progress=False)
        sim.checkpoint(d / "half.ckpt.h5")
        return
    elif mode == "rest":
        sim = dpm.restart(d / "half.ckpt.h5")
        sim.run(steps=steps - sim.step_count, progress=False)
    else:
        raise SystemExit(f"unknown mode {mode!r}")
    sim.close()
    save(sim, d / f"{mode}.npz")


if __name__ == "__main__":
    main()
