"""Rotating drum: glass beads in a capped tube turning about its horizontal axis.

A drum of 100 mm diameter and 24 mm depth (a ``tube`` with both ``caps``, moved by
``dpm.Rotation``) holds about 40 % by volume of 4 mm glass beads (Hertz-Mindlin, e = 0.5,
mu = 0.4, rolling friction 0.02) and turns at 20 rpm, reached over 0.2 s. The bed is lifted
by wall friction into the rolling regime; the script reports the drive torque and power
from the boundary's recorded load and the dynamic angle of repose of the bed surface.

    python examples/rotating_drum.py            # 2 s of drum rotation
    python examples/rotating_drum.py --quick    # 0.4 s
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import dpm

R_DRUM = 0.05
DEPTH = 0.024
R_BEAD = 2e-3
RPM = 20.0


def build(fill: float = 0.4, dt: float = 1.5e-5) -> dpm.Simulation:
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, -9.81))
    glass = dpm.Material("glass", density=2500.0, young=5e7, poisson=0.3)
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.4,
                rolling_friction=0.02)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.5, friction=0.6,
                rolling_friction=0.02)
    sim.drum = sim.add_boundary(
        "tube", material=steel, start=(0.0, 0.0, 0.0), axis=(0.0, 1.0, 0.0), length=DEPTH,
        radius=R_DRUM, caps="both",
        motion=dpm.Rotation(axis=(0.0, 1.0, 0.0), rpm=RPM, center=(0.0, 0.0, 0.0), ramp=0.2))
    # beads on a lattice inside the drum, up to the fill fraction of its cross-section
    pos = dpm.lattice((-R_DRUM, R_BEAD * 1.05, -R_DRUM), (R_DRUM, DEPTH - R_BEAD * 1.05, R_DRUM),
                      2.1 * R_BEAD)
    rho = np.hypot(pos[:, 0], pos[:, 2])
    pos = pos[rho < R_DRUM - 1.2 * R_BEAD]
    n = int(fill * (math.pi * R_DRUM**2 * DEPTH) * 0.6 / (4 / 3 * math.pi * R_BEAD**3))
    pos = pos[np.argsort(pos[:, 2])][:n]  # the lowest lattice sites: a bed at rest
    rng = np.random.default_rng(0)
    sim.add_particles("sphere", material=glass, radius=R_BEAD, positions=pos,
                      velocities=rng.normal(0.0, 0.01, pos.shape))
    return sim


def repose_angle(pos: np.ndarray) -> float:
    """Angle [deg] of the free surface: a line fitted to the topmost bead of each of the
    central vertical slices of the bed (x within the middle 60 % of the drum)."""
    x, z = pos[:, 0], pos[:, 2]
    edges = np.linspace(-0.6 * R_DRUM, 0.6 * R_DRUM, 13)
    xs, zs = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (x >= a) & (x < b)
        if np.any(sel):
            xs.append(0.5 * (a + b))
            zs.append(z[sel].max())
    slope = np.polyfit(xs, zs, 1)[0]
    return math.degrees(math.atan(abs(slope)))


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="0.4 s instead of 2 s")
    p.add_argument("--output", default="rotating_drum.h5", help="HDF5 output (+ .xdmf)")
    args = p.parse_args(argv)
    until = 0.4 if args.quick else 2.0
    sim = build()
    sim.output(args.output, every=0.02, overwrite=True)  # (the example's own file)
    dpm.notice(f"{len(sim.bodies)} beads in a {2 * R_DRUM * 1e3:.0f} mm drum at {RPM:g} rpm; "
               f"dt = {sim.dt:g} s")
    t0 = time.perf_counter()
    torques, powers = [], []
    while sim.time < until - 1e-12:
        sim.run(until=min(until, sim.time + 0.05))
        torques.append(float(sim.drum.torque[1]))
        powers.append(sim.drum.power())
    wall = time.perf_counter() - t0
    sim.close()
    half = len(torques) // 2
    dpm.notice(f"simulated {sim.time:.2f} s in {wall:.1f} s "
               f"({len(sim.bodies) * sim.step_count / wall:.3g} particle-steps/s)")
    dpm.notice(f"drive torque about the axis (second half): {np.mean(torques[half:]):+.4f} N m; "
               f"power drawn {np.mean(powers[half:]):.4f} W")
    dpm.notice(f"dynamic angle of repose: {repose_angle(sim.bodies.position):.1f} deg")
    dpm.notice(f"output: {args.output} (open {args.output[:-3]}.xdmf in ParaView)")


if __name__ == "__main__":
    main()
