"""Scenes run on several MPI ranks and on one process, for ``tests/parallel/test_mpi.py``.

    mpiexec -n 2 python tests/mpi_scenes.py SCENE OUT.npz [--checkpoint STEP PATH]
    python tests/mpi_scenes.py SCENE OUT.npz --device cpu
    mpiexec -n 3 python tests/mpi_scenes.py SCENE OUT.npz --restart PATH

Rank 0 writes the end state by body id (position, velocity, angular velocity,
orientation), the boundary loads, the outlet and escape records and, per call, each
rank's owned bodies, step time, halo time, and the re-cuts, kernel calls, rebuilds
without a migration, whole-state gathers and bodies that changed rank so far. Every
scene but ``sticky`` (JKR) uses Hertz-Mindlin and velocity Verlet (the step modules the
rest of the suite compiles).

Scenes:

- ``settle``: 400 spheres falling into a box with a tilted wall (the cut found by the
  bisection; bodies cross the cut as they fall and settle).
- ``corner``: a cube cluster resting across the corner where the sub-domains meet
  (fixed boxes: x = 0 on 2 ranks, x = 0 and y = 0 on 3 and 4), pressed by spheres.
- ``slide``: a spinning sphere sliding obliquely on the floor across x = 0, and two
  spheres in a sliding contact crossing x = 0 together (history of a boundary contact
  and of a pair carried by migration).
- ``flow``: periodic along x (the cut axis), an inlet, an outlet: count balance.
- ``gather``: spheres pulled into one corner of a box by a slanted gravity: the cut
  follows them.
- ``sticky``: JKR contacts kept beyond touching across x = 0 (the ghost layer's reach).
- ``crash``: two spheres meeting head-on across x = 0 too fast for the overlap limit,
  beside spheres resting on the floor: the run stops on every rank at the serial step
  with the serial diagnosis (the driver records the step and the message).
- ``rod``: a 12 mm rod (a cylinder cluster) whose centre lies just right of x = 0, and a
  sphere flying into its tip 5.5 mm left of x = 0 (the ghost layer must count the rod's
  length: the sphere is far from the rod's rank's box).
- ``escape``: a sphere thrown across x = 0 and out of the scene's box beside spheres
  resting on a floor: the escape guard removes it on every rank.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

import dpm
from dpm.parallel import launched_ranks

G = 9.81
#: the integrator of every scene but ``sticky`` (``--integrator``; the test sets it for
#: its one-process reference too)
OPTIONS = {"integrator": "velocity_verlet"}


def _materials():
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    return glass, steel


def _sim(device, dt=1e-5, gravity=(0.0, 0.0, -G)) -> tuple[dpm.Simulation, object, object]:
    sim = dpm.Simulation(dt=dt, gravity=gravity, device=device,
                         integrator=OPTIONS["integrator"])
    glass, steel = _materials()
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.4, friction=0.4)
    return sim, glass, steel


def fixed_boxes(ranks: int) -> np.ndarray:
    """Sub-domains meeting at the origin: x = 0 (2 ranks), then y = 0 (3, 4 ranks)."""
    inf = np.inf
    if ranks == 2:
        return np.array([[[-inf, -inf, -inf], [0, inf, inf]],
                         [[0, -inf, -inf], [inf, inf, inf]]])
    if ranks == 3:
        return np.array([[[-inf, -inf, -inf], [0, inf, inf]],
                         [[0, -inf, -inf], [inf, 0, inf]],
                         [[0, 0, -inf], [inf, inf, inf]]])
    if ranks == 4:
        return np.array([[[-inf, -inf, -inf], [0, 0, inf]],
                         [[-inf, 0, -inf], [0, inf, inf]],
                         [[0, -inf, -inf], [inf, 0, inf]],
                         [[0, 0, -inf], [inf, inf, inf]]])
    raise SystemExit(f"fixed boxes for 2-4 ranks, not {ranks}")


def device(kind: str | None, fixed: bool, **kw):
    """"cpu", the MPI backend (fixed boxes where the scene says), or None: the default
    for where the script runs."""
    if kind in ("cpu", None):
        return kind
    from dpm.parallel.backend import MpiBackend

    n = launched_ranks()
    return MpiBackend(boxes=fixed_boxes(n) if fixed and n > 1 else None, **kw)


def settle(kind: str):
    sim, glass, steel = _sim(device(kind, False))
    sim.add_boundary("box", material=steel, lower=(0, 0, 0), upper=(0.03, 0.02, 0.04))
    sim.add_boundary("wall", material=steel, center=(0.008, 0.01, 0.012),
                     normal=(0.24, 0.0, 0.97), u=(0.97, 0.0, -0.24),
                     half_extents=(0.006, 0.008), thickness=1e-3)
    rng = np.random.default_rng(1)
    xyz = dpm.lattice((0.001, 0.001, 0.004), (0.029, 0.019, 0.03), 2.3e-3, jitter=5e-5,
                      seed=2)
    n = np.array([0.24, 0.0, 0.97]) / np.hypot(0.24, 0.97)
    clear = np.abs((xyz - [0.008, 0.01, 0.012]) @ n) > 2.2e-3  # (not inside the wall)
    xyz = xyz[clear | (xyz[:, 0] > 0.0155)][:400]
    sim.add_particles("sphere", material=glass, positions=xyz,
                      velocities=rng.uniform(-0.3, 0.3, xyz.shape),
                      angular_velocities=rng.uniform(-50, 50, xyz.shape),
                      radius=rng.uniform(0.85e-3, 1e-3, len(xyz)))
    return sim, 800


def corner(kind: str):
    sim, glass, steel = _sim(device(kind, True))
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    # the cube (edge 4 mm, centre near the corner) just above the floor
    sim.add_particles("cube", material=glass, positions=[[1e-4, -2e-4, 2.1e-3]],
                      angular_velocities=[[3.0, -2.0, 5.0]], a=2e-3)
    rng = np.random.default_rng(3)
    # spheres above and beside it, falling on it from every quadrant
    xy = np.array([[x, y] for x in (-3e-3, -1e-3, 1e-3, 3e-3) for y in (-3e-3, -1e-3, 1e-3,
                                                                       3e-3)])
    top = np.c_[xy, np.full(len(xy), 5.2e-3)]
    ring = np.array([[4.5e-3 * np.cos(a), 4.5e-3 * np.sin(a), 1.0e-3]
                     for a in np.linspace(0, 2 * np.pi, 8, endpoint=False)])
    pos = np.r_[top, ring]
    sim.add_particles("sphere", material=glass, positions=pos, radius=0.95e-3,
                      velocities=rng.uniform(-0.05, 0.05, pos.shape)
                      + np.r_[np.tile([0, 0, -0.3], (len(top), 1)),
                              -0.2 * ring / np.linalg.norm(ring, axis=1)[:, None]])
    return sim, 1200


def slide(kind: str):
    sim, glass, steel = _sim(device(kind, True))
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    r = 1e-3
    # a sphere sliding and spinning across x = 0 at 30 degrees to the face
    v = 0.4 * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6), 0.0])
    sim.add_particles("sphere", material=glass, positions=[[-2.5e-3, -5e-3, r - 1e-6]],
                      velocities=[v], angular_velocities=[[40.0, -90.0, 25.0]], radius=r)
    # two spheres pressed together (gravity + approach), sliding against each other
    # while they cross x = 0
    sim.add_particles("sphere", material=glass,
                      positions=[[-2.0e-3, 6e-3, r - 1e-6], [-2.0e-3 + 1e-3, 6e-3 + 1.7263e-3,
                                                              r - 1e-6]],
                      velocities=[[0.3, 0.05, 0.0], [0.36, -0.08, 0.0]],
                      angular_velocities=[[0.0, 0.0, 80.0], [0.0, 0.0, -60.0]], radius=r)
    return sim, 1500


def flow(kind: str):
    sim, glass, steel = _sim(device(kind, False))
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    sim.set_periodic("x", 0.0, 0.03)
    rng = np.random.default_rng(8)
    xyz = dpm.lattice((0, 0, 0), (0.03, 0.012, 0.0066), 2.2e-3, jitter=5e-5, seed=9)
    v = rng.uniform(-0.3, 0.3, xyz.shape)
    v[:, 0] += 0.8  # a drift across the periodic faces
    sim.add_particles("sphere", material=glass, positions=xyz, velocities=v,
                      radius=rng.uniform(0.85e-3, 1e-3, len(xyz)))
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 1, 0))
    sim.add_boundary("plane", material=steel, point=(0, 0.012, 0), normal=(0, -1, 0))
    sim.add_inlet(dpm.BoxRegion((0, 0, 0.009), (0.03, 0.012, 0.016)), glass, rate=12000.0,
                  radius=(0.8e-3, 1.1e-3), velocity=(0.3, 0.1, -0.8), every=2.5e-4,
                  stop=3e-3, seed=10)
    sim.add_outlet(dpm.BoxRegion((0.0, -1.0, -1.0), (0.008, 1.0, 0.0012)), every=2.5e-4)
    return sim, 600


def gather(kind: str, rebalance: float = 1.1):
    g = 9.81 * np.array([-1.0, -1.0, -0.3])
    sim = dpm.Simulation(dt=1e-5, gravity=tuple(g), device=device(kind, False,
                                                                     rebalance=rebalance)
                         if kind != "cpu" else "cpu", integrator=OPTIONS["integrator"])
    glass, steel = _materials()
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.3)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.3, friction=0.3)
    sim.add_boundary("box", material=steel, lower=(0, 0, 0), upper=(0.04, 0.04, 0.02))
    xyz = dpm.lattice((0.001, 0.001, 0.001), (0.039, 0.039, 0.008), 2.4e-3, jitter=5e-5,
                      seed=4)
    sim.add_particles("sphere", material=glass, positions=xyz, radius=1e-3)
    return sim, 8000


def sticky(kind: str):
    """JKR pairs across x = 0 with a skin far thinner than the neck: a light sphere
    bouncing on a heavy one at the face, attached beyond touching (only the ghost layer's
    extra reach shows the pair to the heavy sphere's rank), and a pair that parts."""
    sim = dpm.Simulation(dt=1e-7, gravity=(0.0, 0.0, 0.0), device=device(kind, True),
                         dt_check="off")
    putty = dpm.Material("putty", density=2500.0, young=1e7, poisson=0.3)
    heavy = dpm.Material("heavy", density=250000.0, young=1e7, poisson=0.3)
    for a, b in ((putty, putty), (putty, heavy), (heavy, heavy)):
        sim.contact(a, b, model="jkr", restitution=0.9, friction=0.5, work_of_adhesion=0.1)
    sim.skin = 1e-7
    r = 1e-3
    # the heavy sphere's centre 0.2 um right of the face, the light one touching it from
    # the left and leaving at 0.9 of the sticking speed (6.1 mm/s for this pair)
    sim.add_particles("sphere", material=heavy, radius=r, positions=[[2e-7, 0.0, 0.0]])
    sim.add_particles("sphere", material=putty, radius=r,
                      positions=[[2e-7 - 2 * r + 5e-8, 0.0, 0.0]],
                      velocities=[[-0.9 * 6.1e-3, 0.0, 0.0]])
    # a pair across the face parting at twice the sticking speed, obliquely
    sim.add_particles("sphere", material=putty, radius=r,
                      positions=[[-r + 3e-8, 5e-3, 0.0], [r - 3e-8, 5e-3, 0.0]],
                      velocities=[[-0.009, 0.002, 0.0], [0.009, -0.002, 0.0]])
    return sim, 3000


def crash(kind: str):
    """Spheres resting on a floor on both sides of x = 0, and two meeting head-on across
    it at 1.5 m/s each: their overlap passes ``max_overlap`` (3 % of the radius) after
    some 150 steps, on both ranks at once (the pair's elements are owned one a side)."""
    sim, glass, steel = _sim(device(kind, True))
    sim.max_overlap = 0.03
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    r = 1e-3
    rest = [[x, y, r - 1e-6] for x in (-6e-3, -3e-3, 3e-3, 6e-3) for y in (-4e-3, 4e-3)]
    sim.add_particles("sphere", material=glass, positions=rest, radius=r)
    sim.add_particles("sphere", material=glass, radius=r,
                      positions=[[-r - 2e-3, 0.0, 5e-3], [r + 2e-3, 0.0, 5e-3]],
                      velocities=[[1.5, 0.0, 0.0], [-1.5, 0.0, 0.0]])
    return sim, 1000


def escape(kind: str):
    """Spheres resting on a floor on both sides of x = 0, and one thrown across x = 0 at
    4 m/s that leaves the scene's box (the escape guard's) after some 750 steps: removed
    and recorded in ``sim.escaped`` on every rank, found on the ranks' state between
    calls (the host is gathered only then)."""
    sim, glass, steel = _sim(device(kind, True))
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    r = 1e-3
    # (not symmetric about the origin: the floor's torque about it is not zero, and
    # its comparison not one of round-off against zero)
    rest = [[x, y, r - 1e-6] for x in (-6e-3, -3e-3, 2e-3, 7e-3) for y in (-4e-3, 5e-3)]
    sim.add_particles("sphere", material=glass, positions=rest, radius=r)
    sim.add_particles("sphere", material=glass, radius=r, positions=[[-3e-3, 0.0, 5e-3]],
                      velocities=[[4.0, 0.0, 0.0]])
    # (5,000 steps: a call is at most 4x the one before, so in one run of these steps
    # the call in which it leaves ends before the run's end, however calls are sized)
    return sim, 5000


def rod(kind: str):
    """A rod (a cylinder cluster 12 mm long along x) whose centre lies just right of
    x = 0, its tip 5.5 mm left of it, and a sphere flying along x into that tip from
    the left: the rank that owns the rod holds the sphere as a ghost only if the ghost
    layer counts the rod's length as well as the sphere's size."""
    sim, glass, steel = _sim(device(kind, True), gravity=(0.0, 0.0, 0.0))
    sim.add_particles("cylinder", material=glass, positions=[[5e-4, 0.0, 0.0]], r=1e-3,
                      l=12e-3)
    sim.add_particles("sphere", material=glass, radius=1e-3,
                      positions=[[-12e-3, 2e-4, 1e-4]], velocities=[[1.0, 0.0, 0.0]])
    return sim, 1200


#: the silo's gate opens at this step (0.15 s: the bed has settled)
SILO_OPEN = 15000


def silo(kind: str):
    """A flat-bottomed silo (20 x 12 mm, a 7 mm slot along y in the middle of its floor,
    closed by a gate): 400 spheres settle for 0.15 s, then the gate is switched off and an
    outlet below the floor removes the spheres that fall through, for 0.25 s more. The
    bisection cuts along x, through the slot. A long run: its trajectories differ from one
    process's by more than round-off at the end (the flow amplifies the ranks' other
    summation order), so the test compares its statistics: the settled height and the
    discharge times."""
    sim, glass, steel = _sim(device(kind, False))
    for point, normal in (((0, 0, 0), (1, 0, 0)), ((0.02, 0, 0), (-1, 0, 0)),
                          ((0, 0, 0), (0, 1, 0)), ((0, 0.012, 0), (0, -1, 0))):
        sim.add_boundary("plane", material=steel, point=point, normal=normal)
    for x0, x1 in ((0.0, 0.0065), (0.0135, 0.02)):  # the floor either side of the slot
        sim.add_boundary("wall", material=steel, center=(0.5 * (x0 + x1), 0.006, 0.0),
                         normal=(0, 0, 1), u=(1, 0, 0), half_extents=(0.5 * (x1 - x0), 0.006))
    gate = sim.add_boundary("wall", material=steel, center=(0.01, 0.006, 0.0),
                            normal=(0, 0, 1), u=(1, 0, 0), half_extents=(0.004, 0.006))
    sim.switch_off(gate, at=SILO_OPEN * sim.dt)
    rng = np.random.default_rng(11)
    xyz = dpm.lattice((0.0012, 0.0012, 0.0012), (0.0188, 0.0108, 0.04), 2.3e-3, jitter=5e-5,
                      seed=12)[:400]
    sim.add_particles("sphere", material=glass, positions=xyz,
                      velocities=rng.uniform(-0.2, 0.2, xyz.shape),
                      radius=rng.uniform(0.85e-3, 1e-3, len(xyz)))
    sim.add_outlet(dpm.BoxRegion((-1.0, -1.0, -1.0), (1.0, 1.0, -0.004)), every=2e-4)
    return sim, 40000


SCENES = {"settle": settle, "corner": corner, "slide": slide, "flow": flow,
          "gather": gather, "sticky": sticky, "crash": crash, "escape": escape, "rod": rod,
          "silo": silo}


def tilt_gravity(sim: dpm.Simulation) -> None:
    """Gravity tilted 30 degrees about y, and every body's spin reversed (between runs)."""
    sim.gravity = (G * 0.5, 0.0, -G * np.sqrt(0.75))
    sim.bodies.angular_velocity[:] *= -1.0


def reductions(sim: dpm.Simulation) -> dict[str, np.ndarray]:
    """What the run loop asks between calls (energies, the fastest body, the guards'
    hits), answered from the host and, the host marked stale (right after a run's
    gather the ranks' owned rows are the host's rows), from the ranks' rows."""
    from dpm.guards import energies

    be, b = sim.backend, sim.bodies
    k = int(np.argmax(b.position[:, 0]))  # (a box that leaves out the body furthest in x)
    lo, hi = b.position.min(axis=0) - 1.0, b.position.max(axis=0) + 1.0
    cut = np.array([lo, [b.position[k, 0] - 1e-9, hi[1], hi[2]]])
    out = {"host_energies": np.array(energies(b, sim.gravity)),
           "host_fastest": np.array(be.max_speed())}
    be._stale = True
    out["ranks_energies"] = np.array(be.energies(sim.gravity))
    out["ranks_fastest"] = np.array(be.max_speed())
    out["ranks_hits"] = np.array([be.guard_hits(True, np.array([lo, hi])),
                                  be.guard_hits(False, cut), be.guard_hits(False, None)])
    be._stale = False
    return out


def state(sim: dpm.Simulation) -> dict[str, np.ndarray]:
    b = sim.bodies
    o = np.argsort(b.id, kind="stable")
    out = {"id": b.id[o], "position": b.position[o], "velocity": b.velocity[o],
           "angular_velocity": b.angular_velocity[o], "orientation": b.orientation[o],
           "boundary_force": np.array([bd.force for bd in sim.boundaries]),
           "boundary_torque": np.array([bd.torque for bd in sim.boundaries]),
           "boundary_work": np.array([bd.work for bd in sim.boundaries]),
           "time": np.array(sim.time), "steps": np.array(sim.step_count)}
    removed = [o.records for o in sim.outlets] if sim.outlets else []
    out["removed_ids"] = (np.sort(np.concatenate([r["id"] for r in removed]))
                          if removed else np.zeros(0, np.int64))
    out["removed_time"] = (np.sort(np.concatenate([r["time"] for r in removed]))
                           if removed else np.zeros(0))
    rec = sim.escaped.records
    out["escaped_ids"] = np.sort(np.asarray(rec["id"], np.int64))
    out["escaped_time"] = np.asarray(rec["time"], float).max(initial=-1.0)
    return out


class HookProbe:
    """Run-time hooks that record what they were given (``--probe-hooks``)."""

    def __init__(self) -> None:
        self.ranks_given: set[int] = set()
        self.after = 0
        self.before = 0
        self.threads: set[int] = set()

    @dpm.hookimpl
    def dpm_after_step(self, sim, rank):
        self.ranks_given.add(int(rank))
        self.after += 1
        self.threads.add(numba.get_num_threads())

    @dpm.hookimpl
    def dpm_before_step(self, sim):  # (a hook that asks for no rank is still called)
        self.before += 1

    def summary(self, sim: dpm.Simulation) -> list[int]:
        """[rank given (-1: several), this process's rank, sim.rank, after calls, before
        calls, fewest and most threads]"""
        given = self.ranks_given.pop() if len(self.ranks_given) == 1 else -1
        return [given, dpm.parallel.rank(), sim.rank, self.after, self.before,
                min(self.threads, default=0), max(self.threads, default=0)]


def gather_rows(row: list) -> list[list]:
    """Every rank's ``row``, in rank order (on one process: one row)."""
    if launched_ranks() > 1:
        from mpi4py import MPI

        return MPI.COMM_WORLD.allgather(row)
    return [row]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", choices=list(SCENES))
    ap.add_argument("out")
    ap.add_argument("--device", default="mpi", choices=("mpi", "cpu"))
    ap.add_argument("--checkpoint", nargs=2, metavar=("STEP", "PATH"), default=None)
    ap.add_argument("--restart", metavar="PATH", default=None)
    ap.add_argument("--rebalance", type=float, default=1.1)
    ap.add_argument("--output", default=None, help="also write the run to this HDF5 file")
    ap.add_argument("--calls", type=int, default=8, help="run the steps in this many calls")
    ap.add_argument("--chunk", type=int, default=None, help="steps of each call instead")
    ap.add_argument("--call-aim", type=float, default=None,
                    help="seconds of work the MPI backend aims a kernel call at (a large "
                    "value: every sim.run one call)")
    ap.add_argument("--tilt-gravity", action="store_true",
                    help="tilt gravity half-way (a script changing the scene between runs)")
    ap.add_argument("--ghost-margin", type=float, default=None,
                    help="the MPI backend's ghost_margin [m] (default: the skin)")
    ap.add_argument("--integrator", default="velocity_verlet",
                    help="the integrator of the scene (not sticky's)")
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of each rank's step kernels (NUMBA_NUM_THREADS at least)")
    ap.add_argument("--probe-hooks", action="store_true",
                    help="record, on every rank, the rank each dpm_after_step hook was "
                    "given, the calls of it and of dpm_before_step (which asks no rank), "
                    "and the threads the steps ran on")
    ap.add_argument("--python-loop", action="store_true",
                    help="step between list rebuilds from Python (two compiled calls per "
                    "step, messages by mpi4py), as on an MPI whose handles are not "
                    "pointers: this process's MPI is reported unfit for compiled calls")
    ap.add_argument("--reductions", action="store_true",
                    help="at the end, the between-calls reductions of the ranks' rows "
                    "against the gathered host's")
    args = ap.parse_args(argv)
    OPTIONS["integrator"] = args.integrator
    if args.python_loop:
        from dpm.parallel import native

        native.handles = lambda comm: (None, "the test driver's --python-loop")
    if args.restart:
        sim = dpm.restart(args.restart)
        steps = int(SCENES[args.scene](args.device)[1]) - sim.step_count \
            if args.scene != "gather" else 8000 - sim.step_count
    else:
        if args.scene == "gather" and args.device == "mpi":
            sim, steps = gather("mpi", args.rebalance)
        else:
            sim, steps = SCENES[args.scene](args.device)
        if args.output:
            sim.output(args.output, every_steps=max(1, steps // 4), overwrite=True)
    if args.ghost_margin is not None and args.device == "mpi":
        sim.backend.ghost_margin = args.ghost_margin
    if args.threads is not None:
        sim.threads = args.threads
    probe = HookProbe() if args.probe_hooks else None
    if probe:
        sim._registry.manager.register(probe, name="rank-probe")
    if args.call_aim is not None:
        sim.backend.CALL_AIM = sim.backend.CALL_AIM_MAX = args.call_aim
    per_call = []
    heights = []  # (the bodies' mean height after each call)
    stopped = (-1, "")
    done = 0
    chunk = args.chunk or max(1, steps // args.calls)
    t0 = time.perf_counter()
    while done < steps:
        k = min(chunk, steps - done)
        if args.checkpoint and done < int(args.checkpoint[0]) <= done + k:
            k = int(args.checkpoint[0]) - done
        if args.tilt_gravity and done >= steps // 2 and sim.gravity[0] == 0.0:
            tilt_gravity(sim)
        try:
            sim.run(steps=k, progress=False)
        except dpm.UnstableRunError as exc:  # (the crash scene: recorded, not raised)
            stopped = (sim.step_count, str(exc))
            break
        done += k
        heights.append(float(sim.bodies.position[:, 2].mean()) if len(sim.bodies) else 0.0)
        if args.checkpoint and sim.step_count == int(args.checkpoint[0]):
            sim.checkpoint(args.checkpoint[1])
        t = getattr(sim.backend, "timing", {}) or {}
        tot = getattr(sim.backend, "totals", {}) or {}  # (summed over the calls so far)
        if launched_ranks() > 1:
            from mpi4py import MPI

            rows = MPI.COMM_WORLD.allgather([t.get("owned", len(sim.bodies)),
                                             t.get("steps_s", 0.0), t.get("halo_s", 0.0),
                                             tot.get("recuts", 0), tot.get("calls", 0),
                                             tot.get("migrations_skipped", 0),
                                             tot.get("gathers", 0),
                                             tot.get("migrants", 0),
                                             tot.get("migrate_s", 0.0),
                                             tot.get("relist_s", 0.0)])
            per_call.append(rows)
    wall = time.perf_counter() - t0
    res = state(sim)
    if args.reductions:
        res.update(reductions(sim))
    if probe:
        res["hooks"] = np.array(gather_rows(probe.summary(sim)))
    res["mean_z"] = np.array(heights)
    res["per_call"] = np.array(per_call) if per_call else np.zeros((0, 1, 10))
    res["wall_s"] = np.array(wall)
    res["loop_used"] = np.array(getattr(sim.backend, "loop_used", ""))
    res["stopped_at"], res["stopped_why"] = np.array(stopped[0]), np.array(stopped[1])
    sim.close()
    if dpm.parallel.rank() == 0:
        np.savez(args.out, **res)
        print(f"{args.scene}: {len(res['id'])} bodies, {sim.step_count} steps, "
              f"{wall:.1f} s on {launched_ranks()} rank(s)")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    sys.exit(main())
