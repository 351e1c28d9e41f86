"""Backend contract: small fixed scenes whose end state every backend must reproduce.

The scenes are built only through the public API (``dpm.Simulation``, ``sim.contact``,
``sim.add_boundary``, ``sim.add_particles``, ``sim.set_periodic``, ``sim.add_inlet``,
``sim.add_outlet``), run for a few hundred steps, and their end state (per body, by id:
position, velocity, angular velocity, orientation; per boundary: force and torque; the
particle count and ids) is compared with a reference stored in
``tests/data/backend_contract/<scene>.npz``. The tests are in
``tests/kernels/test_backend_contract.py``.

Scenes (grouped so that the suite compiles three step modules: one contact law,
Hertz-Mindlin, and one integrator, velocity Verlet, everywhere):

- ``spheres_walls``: single spheres (the fused force pass) in a closed box (planes) with a
  tilted finite wall (slab), a meshed pyramid on the floor (triangles: faces, edges,
  vertex) and a sieve screen of the radius clearance model; rolling resistance on.
- ``clusters_pipes``: clustered bodies (ellipsoids, cubes) and spheres (the two-pass
  sum) in a capped drum (a tube turning at 10 rad/s), and balls and a cube rolling along a
  straight tube across its joint into a 90 degree bend.
- ``flow_periodic``: spheres on a floor plane, periodic along x and y, an inlet
  (``dpm.BoxRegion``) dropping spheres from above and an outlet removing those that
  reach a strip of the floor.

Backends
--------
A backend is the dict of keyword arguments that selects it in ``dpm.Simulation(...)``.
Today: ``BACKENDS = [{"threads": 1}, {"threads": 2}]`` (``threads=2`` is honoured even for
these small scenes, which otherwise run on one thread). A new backend joins by

1. accepting its keyword in ``dpm.Simulation`` (e.g. ``device="mpi"`` or
   ``device="cuda"``) and
2. either being appended to ``BACKENDS`` below, or being named at run time without editing
   this file: ``DPM_BACKENDS='[{"device": "cuda"}]' python -m pytest
   tests/kernels/test_backend_contract.py`` (a JSON list of keyword dicts; it replaces the list),
   or ``python tests/backend_contract.py --backend '{"device": "cuda"}'`` (prints each
   scene's error against the reference and its tolerance).

The backend must then reproduce the stored references within the tolerances below. Under
MPI, run the same command under ``mpirun``; the backend is expected to gather the state on
every rank (or on rank 0) before ``sim.bodies`` and ``boundary.force`` are read.

References
----------
Written from the code of the commit named in each file's ``meta`` by::

    python tests/backend_contract.py --write

(one thread; it first checks that two threads agree within the tolerance, and warns
unless they give the same bits). Rewrite them only when
a change of the physics is intended, and say so in the commit.

Tolerances
----------
Each field is compared as max |a - b| / scale: positions, velocities and angular
velocities with the field's largest magnitude in the reference as scale, orientations
with 1 (quaternions, sign-aligned: q and -q are the same rotation), and the force and
torque of each boundary, recorded at ``SAMPLES`` evenly spaced times of the run, with
that boundary's largest component (at least 1e-3 of the largest of all boundaries, so
that an unloaded boundary is not held to zero). The state must also
have the same ids, hence the same count.

Bit-for-bit equality cannot be the contract across machines: another CPU or compiler may
contract a * b + c into one fused multiply-add, libm's pow, sqrt-free atan2, sin and cos
may differ in the last bit, scipy's root finder gives the collision constants (Tsuji
beta) to ~1e-12, and an MPI or GPU backend adds the contact forces in another order. Each
such difference is a rounding-sized kick (~1e-16 relative) that every collision
amplifies, and dense granular matter is chaotic. The runs are therefore short (300-400
steps, a few contact times) and the tolerances are set from a measurement of that
amplification: ``python tests/backend_contract.py --sensitivity`` perturbs every initial
coordinate by up to 1e-17 m and 1e-15 m (~6 and ~600 ulp of a coordinate of 1 cm), changes
the friction by 0.01 % and 1 % and the time step by 0.001 % and 0.1 % (stand-ins for real
bugs), and prints the normalised errors. The response is linear (1e-17 m -> ~1e-12,
1e-15 m -> ~1e-10 at worst): the runs are short enough not to be chaotic at this level. A
machine that rounds differently kicks every step by about an ulp; summed over 400 steps
that is of the order of the single 600-ulp kick. ``TOLERANCE`` is ~500-5000x above that
and 100-10000x below a 0.01 % friction change (numbers in ``SENSITIVITY_NOTES``);
``tests/kernels/test_backend_contract.py`` checks both sides on every run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

import dpm

DATA = Path(__file__).parent / "data" / "backend_contract"

#: the backends, as keyword arguments of dpm.Simulation (see the module docstring)
BACKENDS: list[dict] = [{"threads": 1}, {"threads": 2}]
#: the backend whose results are stored as references
REFERENCE_BACKEND = {"threads": 1}

G = 9.81


def backends() -> list[dict]:
    """``BACKENDS``, or the JSON list in ``$DPM_BACKENDS``."""
    env = os.environ.get("DPM_BACKENDS")
    if env:
        value = json.loads(env)
        return [value] if isinstance(value, dict) else list(value)
    return list(BACKENDS)


def backend_id(backend: dict) -> str:
    return ",".join(f"{k}={v}" for k, v in sorted(backend.items())) or "default"


def _materials():
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    return glass, steel


def _laws(sim, glass, steel, friction_scale: float, rolling: bool) -> None:
    extra = {"rolling_friction": 0.02} if rolling else {}
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5,
                friction=0.5 * friction_scale, **extra)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.4,
                friction=0.4 * friction_scale, **extra)


def _jittered(xyz: np.ndarray, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """Initial positions, each coordinate moved by up to ``jitter`` [m] (0: unchanged)."""
    if jitter == 0.0:
        return xyz
    return xyz + rng.uniform(-jitter, jitter, xyz.shape)


# ------------------------------------------------------------------------------ scenes
def spheres_walls(backend: dict, jitter: float = 0.0, friction_scale: float = 1.0,
                  dt_scale: float = 1.0) -> tuple[dpm.Simulation, int]:
    """Spheres in a closed box with a tilted wall, a meshed pyramid and a sieve screen."""
    perturb = np.random.default_rng(99)
    sim = dpm.Simulation(dt=1e-5 * dt_scale, gravity=(0, 0, -G), **backend)
    glass, steel = _materials()
    _laws(sim, glass, steel, friction_scale, rolling=True)
    sim.add_boundary("box", material=steel, lower=(0, 0, 0), upper=(0.03, 0.02, 0.03))
    # a wall (slab) tilted by 14 degrees about y over the left half
    n = np.array([0.25, 0.0, 1.0]) / math.hypot(0.25, 1.0)
    u = np.array([1.0, 0.0, -0.25]) / math.hypot(0.25, 1.0)
    c = np.array([0.007, 0.01, 0.011])
    sim.add_boundary("wall", material=steel, center=tuple(c), normal=tuple(n), u=tuple(u),
                     half_extents=(0.005, 0.008), thickness=1e-3)
    # a square pyramid (closed: four sides and a base of two triangles) on the right
    verts = np.array([[0.016, 0.004, 0.0005], [0.028, 0.004, 0.0005],
                      [0.028, 0.016, 0.0005], [0.016, 0.016, 0.0005], [0.022, 0.01, 0.006]])
    faces = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1], [0, 3, 2]])
    sim.add_boundary("mesh", material=steel, vertices=verts, faces=faces)
    sim.add_boundary("sieve", material=steel, center=(0.015, 0.01, 0.02), normal=(0, 0, 1),
                     u=(1, 0, 0), half_extents=(0.0125, 0.0085), thickness=1e-3, hole=4e-3,
                     bar=2e-3, clearance_model="radius", zeta=0.5)
    rng = np.random.default_rng(1)
    # a cloud on the floor, under the wall
    floor = dpm.lattice((0, 0, 0), (0.012, 0.02, 0.0045), 2.2e-3, jitter=5e-5, seed=2)
    # spheres over the pyramid, the lowest 0.3 mm above its apex
    pyr = dpm.lattice((0.0165, 0.0045, 0.0068), (0.0275, 0.0155, 0.0112), 2.2e-3,
                      jitter=5e-5, seed=3)
    pyr[:, 2] -= 0.0008
    # a row on the wall, 0.2 mm above its face, and a layer above the sieve
    s = np.linspace(-0.004, 0.004, 4)
    t = np.linspace(-0.006, 0.006, 4)
    ss, tt = np.meshgrid(s, t, indexing="ij")
    wall = (c + ss.reshape(-1, 1) * u + tt.reshape(-1, 1) * np.cross(n, u)
            + (0.5e-3 + 1e-3 + 0.2e-3) * n)
    sieve = dpm.lattice((0.0025, 0.0015, 0.0207), (0.0275, 0.0185, 0.0229), 2.2e-3,
                        jitter=5e-5, seed=4)
    groups = [(floor, 1e-3, (0.0, 0.0, 0.0)), (pyr, 0.9e-3, (0.0, 0.0, -0.4)),
              (wall, 1e-3, -0.3 * n), (sieve, 0.8e-3, (0.0, 0.0, -0.5))]
    for xyz, r, v0 in groups:
        v = np.asarray(v0) + rng.uniform(-0.15, 0.15, xyz.shape)
        w = rng.uniform(-50.0, 50.0, xyz.shape)
        radius = rng.uniform(0.85 * r, r, len(xyz))
        sim.add_particles("sphere", material=glass, positions=_jittered(xyz, jitter, perturb),
                          velocities=v, angular_velocities=w, radius=radius)
    return sim, 400


def drum_and_pipe(sim: dpm.Simulation, steel: dpm.Material) -> tuple[float, float]:
    """The boundaries of ``clusters_pipes``: a capped drum (radius 15 mm, 20 mm long about
    the y axis) turning at 10 rad/s, and a straight pipe (radius 4 mm) closed at its start,
    joined at x = 0.06 to a quarter bend. Returns the drum's and the pipe's radius."""
    r_drum, half = 0.015, 0.01
    sim.add_boundary("tube", material=steel, start=(0, -half, 0), axis=(0, 1, 0),
                     length=2 * half, radius=r_drum, caps="both",
                     motion=dpm.Rotation(axis=(0, 1, 0), omega=10.0))
    rp = 4e-3
    sim.add_boundary("tube", material=steel, start=(0.03, 0, 0), axis=(1, 0, 0), length=0.03,
                     radius=rp, caps="start")
    sim.add_boundary("bend", material=steel, center=(0.06, 0.02, 0), axis=(0, 0, 1),
                     start_direction=(0, -1, 0), bend_radius=0.02, pipe_radius=rp,
                     angle=math.pi / 2)
    return r_drum, rp


def clusters_pipes(backend: dict, jitter: float = 0.0, friction_scale: float = 1.0,
                   dt_scale: float = 1.0) -> tuple[dpm.Simulation, int]:
    """Ellipsoids, cubes and spheres in a turning drum; balls and a cube rolling from a
    tube across its joint into a bend."""
    perturb = np.random.default_rng(98)
    sim = dpm.Simulation(dt=5e-6 * dt_scale, gravity=(0, 0, -G), **backend)
    glass, steel = _materials()
    _laws(sim, glass, steel, friction_scale, rolling=False)
    r_drum, rp = drum_and_pipe(sim, steel)
    rng = np.random.default_rng(5)
    # two rows of bodies along the drum's bottom (bounding radii 2 mm), moving outwards
    rows = [(r_drum - 2.1e-3, np.radians([-50, -25, 0, 25, 50])),
            (r_drum - 6.3e-3, np.radians([-45, -15, 15, 45]))]
    xyz = np.array([(rho * math.sin(th), y, -rho * math.cos(th)) for rho, ths in rows
                    for th in ths for y in (-0.006, 0.0, 0.006)])
    radial = xyz * np.array([1.0, 0.0, 1.0]) / np.hypot(xyz[:, 0], xyz[:, 2])[:, None]
    vel = 0.3 * radial + rng.uniform(-0.1, 0.1, xyz.shape)
    kinds = [("ellipsoid", {"a": 2e-3, "b": 1e-3}), ("cube", {"a": 2e-3}),
             ("sphere", {"radius": 1.2e-3})]
    for k, (shape, params) in enumerate(kinds):
        sel = slice(k, None, 3)
        q = rng.normal(size=(len(xyz[sel]), 4))
        sim.add_particles(shape, material=glass, positions=_jittered(xyz[sel], jitter, perturb),
                          velocities=vel[sel],
                          angular_velocities=rng.uniform(-20, 20, xyz[sel].shape),
                          orientations=q, **params)
    # in the pipe: balls resting on its bottom, rolling towards the joint at 1.5 m/s
    rb = 1.5e-3
    z = -rp + rb + 2e-6
    balls = np.array([[0.0585, 0, z], [0.0550, 0, z], [0.0515, 0, z]])
    v = np.tile([1.5, 0.0, 0.0], (3, 1))
    sim.add_particles("sphere", material=glass, positions=_jittered(balls, jitter, perturb),
                      velocities=v, angular_velocities=np.cross([0, 0, 1], v) / rb, radius=rb)
    sim.add_particles("cube", material=glass,
                      positions=_jittered(np.array([[0.045, 0, -rp + 1.6e-3]]), jitter, perturb),
                      velocities=[[1.0, 0.0, 0.0]], angular_velocities=[[0.0, 30.0, 0.0]],
                      orientations=[[0.96, 0.1, 0.2, 0.15]], a=2e-3)
    return sim, 600


def flow_periodic(backend: dict, jitter: float = 0.0, friction_scale: float = 1.0,
                  dt_scale: float = 1.0) -> tuple[dpm.Simulation, int]:
    """Spheres on a floor, periodic in x and y, fed by an inlet and drained by an outlet."""
    perturb = np.random.default_rng(97)
    sim = dpm.Simulation(dt=1e-5 * dt_scale, gravity=(0, 0, -G), **backend)
    glass, steel = _materials()
    _laws(sim, glass, steel, friction_scale, rolling=False)
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    sim.set_periodic("x", 0.0, 0.02)
    sim.set_periodic("y", 0.0, 0.02)
    rng = np.random.default_rng(8)
    xyz = dpm.lattice((0, 0, 0), (0.02, 0.02, 0.0066), 2.2e-3, jitter=5e-5, seed=9)
    v = rng.uniform(-0.3, 0.3, xyz.shape)
    v[:, 0] += 0.5  # a drift across the periodic faces
    sim.add_particles("sphere", material=glass, positions=_jittered(xyz, jitter, perturb),
                      velocities=v, radius=rng.uniform(0.85e-3, 1e-3, len(xyz)))
    sim.add_inlet(dpm.BoxRegion((0, 0, 0.009), (0.02, 0.02, 0.016)), glass, rate=12000.0,
                  radius=(0.8e-3, 1.1e-3), velocity=(0.3, 0.1, -0.8), every=2.5e-4, stop=3e-3,
                  seed=10)
    sim.add_outlet(dpm.BoxRegion((0.0, -1.0, -1.0), (0.006, 1.0, 0.0012)), every=2.5e-4)
    return sim, 400


#: name -> builder(backend, jitter=0, friction_scale=1, dt_scale=1) -> (sim, steps)
SCENES: dict[str, Callable[..., tuple[dpm.Simulation, int]]] = {
    "spheres_walls": spheres_walls,
    "clusters_pipes": clusters_pipes,
    "flow_periodic": flow_periodic,
}

#: allowed normalised error per scene, for "state" (position, velocity, angular velocity,
#: orientation) and "load" (boundary force and torque): about 500-5000x the error that a
#: 1e-15 m perturbation of the initial positions leaves after the run (the rounding
#: stand-in, see SENSITIVITY_NOTES), rounded up to a power of ten, and 100-10000x below
#: what a 0.01 % change of the friction gives. The loads of clusters_pipes (balls rolling
#: in a pipe, cubes on a drum wall: few contacts carry the whole load, F ~ d^(3/2), so a
#: relative position error e becomes ~1.5 e d_scale / overlap) are 100x more sensitive
#: than its state; its state is 100x less sensitive than the sphere scenes' (their
#: spheres spin freely at up to 500 rad/s, and the angular velocity carries the largest
#: normalised error).
TOLERANCE: dict[str, dict[str, float]] = {
    "spheres_walls": {"state": 1e-7, "load": 1e-7},
    "clusters_pipes": {"state": 1e-8, "load": 1e-7},
    "flow_periodic": {"state": 1e-7, "load": 1e-7},
}

#: boundary loads are recorded at this many evenly spaced times of each run
SAMPLES = 8
STATE_FIELDS = ("position", "velocity", "angular_velocity", "orientation")
LOAD_FIELDS = ("boundary_force", "boundary_torque")


def run(name: str, backend: dict, **variant) -> dict[str, np.ndarray]:
    """Build scene ``name`` for ``backend``, run it, return its end state by body id."""
    sim, steps = SCENES[name](backend, **variant)
    force, torque = [], []
    for _ in range(SAMPLES):  # the boundary loads at SAMPLES times
        sim.run(steps=steps // SAMPLES, progress=False)
        force.append([bd.force for bd in sim.boundaries])
        torque.append([bd.torque for bd in sim.boundaries])
    b = sim.bodies
    order = np.argsort(b.id, kind="stable")
    out = {"id": b.id[order].copy(), "count": np.array(len(b))}
    for f in STATE_FIELDS:
        out[f] = getattr(b, f)[order].copy()
    out["boundary_force"] = np.array(force).reshape(SAMPLES, -1, 3)
    out["boundary_torque"] = np.array(torque).reshape(SAMPLES, -1, 3)
    out["time"] = np.array(sim.time)
    out["pair_params"] = np.asarray(sim.plan.pair_params).copy()  # diagnosis only
    sim.close()
    return out


def errors(result: dict, reference: dict) -> dict[str, float]:
    """Normalised error of each field of ``result`` against ``reference`` (see the module
    docstring); inf where the ids differ."""
    if not np.array_equal(result["id"], reference["id"]):
        return {f: math.inf for f in (*STATE_FIELDS, *LOAD_FIELDS, "id")}
    err = {"id": 0.0}
    for f in STATE_FIELDS:
        a, b = result[f], reference[f]
        if f == "orientation":
            sign = np.where(np.einsum("ij,ij->i", a, b) < 0.0, -1.0, 1.0)
            a = a * sign[:, None]
            scale = 1.0
        else:
            scale = max(float(np.abs(b).max(initial=0.0)), 1e-300)
        err[f] = float(np.abs(a - b).max(initial=0.0)) / scale
    for f in LOAD_FIELDS:  # (samples, boundaries, 3): each boundary with its own scale
        a, b = result[f], reference[f]
        floor = 1e-3 * float(np.abs(b).max(initial=0.0)) or 1e-300
        scale = np.maximum(np.abs(b).max(axis=(0, 2)), floor)
        err[f] = float((np.abs(a - b).max(axis=(0, 2)) / scale).max(initial=0.0))
    return err


def violations(name: str, err: dict[str, float]) -> list[str]:
    """Fields whose error exceeds the scene's tolerance, as messages."""
    tol = TOLERANCE[name]
    out = []
    for f, e in err.items():
        allowed = tol["load"] if f in LOAD_FIELDS else 0.0 if f == "id" else tol["state"]
        if not e <= allowed:
            out.append(f"{name}: {f} differs by {e:.3g} (normalised; allowed {allowed:.1g})")
    return out


def reference_path(name: str) -> Path:
    return DATA / f"{name}.npz"


def load_reference(name: str) -> dict[str, np.ndarray]:
    with np.load(reference_path(name), allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _commit() -> str:
    try:
        here = Path(__file__).parent
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True,
                             text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "../dpm"], cwd=here,
                               capture_output=True, text=True, check=True).stdout.strip()
        return rev + (" (dpm/ modified)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def write_references(names: list[str]) -> None:
    import numba
    import scipy

    DATA.mkdir(parents=True, exist_ok=True)
    for name in names:
        ref = run(name, REFERENCE_BACKEND)
        two = run(name, {"threads": 2})
        differ = [f for f in (*STATE_FIELDS, *LOAD_FIELDS, "id")
                  if not np.array_equal(ref[f], two[f])]
        if violations(name, errors(two, ref)):
            raise SystemExit(f"{name}: one and two threads differ beyond the tolerance in "
                             f"{', '.join(differ)}; not written")
        if differ:  # (see NOT_BIT_IDENTICAL in test_backend_contract.py)
            print(f"{name}: warning: one and two threads differ by rounding in "
                  f"{', '.join(differ)}")
        meta = {"command": "python tests/backend_contract.py --write", "commit": _commit(),
                "backend": REFERENCE_BACKEND, "numpy": np.__version__,
                "numba": numba.__version__, "scipy": scipy.__version__,
                "python": platform.python_version(), "machine": platform.machine(),
                "processor": platform.processor()}
        np.savez_compressed(reference_path(name), meta=np.array(json.dumps(meta)), **ref)
        print(f"{name}: {int(ref['count'])} bodies, t = {float(ref['time']):.4g} s -> "
              f"{reference_path(name)}")


#: what ``--sensitivity`` printed when the tolerances were set (x86_64, numba 0.68.1,
#: numpy 2): the largest normalised error of the "state" and the "load" fields per variant
#: (a 0.001 % change of dt moves flow_periodic's inlet and outlet events: other ids)
SENSITIVITY_NOTES: dict[str, dict[str, tuple[float, float]]] = {
    "spheres_walls": {"positions +-1e-17 m": (1.5e-12, 3.3e-13),
                      "positions +-1e-15 m": (1.4e-10, 2.8e-11),
                      "friction +0.01 %": (1.2e-4, 3.0e-5), "friction +1 %": (1.2e-2, 3.0e-3),
                      "dt +0.001 %": (6.7e-4, 4.8e-4), "dt +0.1 %": (1.4e-2, 4.5e-2)},
    "clusters_pipes": {"positions +-1e-17 m": (2.2e-14, 2.5e-12),
                       "positions +-1e-15 m": (2.1e-12, 2.5e-10),
                       "friction +0.01 %": (1.3e-5, 1.3e-4), "friction +1 %": (3.3e-3, 0.14),
                       "dt +0.001 %": (3.2e-5, 7.4e-4), "dt +0.1 %": (2.8e-3, 0.15)},
    "flow_periodic": {"positions +-1e-17 m": (1.1e-12, 3.0e-13),
                      "positions +-1e-15 m": (2.1e-10, 3.6e-11),
                      "friction +0.01 %": (1.2e-3, 1.3e-4), "friction +1 %": (2.3e-2, 1.1e-2),
                      "dt +0.001 %": (math.inf, math.inf), "dt +0.1 %": (1.4e-2, 0.11)},
}

VARIANTS = {"positions +-1e-17 m": {"jitter": 1e-17},
            "positions +-1e-15 m": {"jitter": 1e-15},
            "friction +0.01 %": {"friction_scale": 1.0001},
            "friction +1 %": {"friction_scale": 1.01},
            "dt +0.001 %": {"dt_scale": 1.00001},
            "dt +0.1 %": {"dt_scale": 1.001}}


def sensitivity(names: list[str]) -> dict[str, dict[str, tuple[float, float]]]:
    """Normalised errors (state, load) of the perturbed runs against the reference."""
    table = {}
    for name in names:
        ref = load_reference(name) if reference_path(name).exists() else run(
            name, REFERENCE_BACKEND)
        table[name] = {}
        for label, variant in VARIANTS.items():
            err = errors(run(name, REFERENCE_BACKEND, **variant), ref)
            st = max(err[f] for f in STATE_FIELDS)
            ld = max(err[f] for f in LOAD_FIELDS)
            table[name][label] = (st, ld)
            tol = TOLERANCE[name]
            print(f"{name:15s} {label:32s} state {st:9.3g} (tol {tol['state']:.0e})  "
                  f"load {ld:9.3g} (tol {tol['load']:.0e})")
    return table


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="write the reference files")
    ap.add_argument("--sensitivity", action="store_true",
                    help="print the errors of perturbed runs (how the tolerances were set)")
    ap.add_argument("--backend", action="append", type=json.loads, default=None,
                    help="a backend as JSON keyword arguments, e.g. '{\"threads\": 2}'")
    ap.add_argument("scenes", nargs="*", default=list(SCENES))
    args = ap.parse_args(argv)
    if args.write:
        write_references(args.scenes)
        return 0
    if args.sensitivity:
        sensitivity(args.scenes)
        return 0
    bad = 0
    for backend in args.backend or backends():
        for name in args.scenes:
            err = errors(run(name, backend), load_reference(name))
            msgs = violations(name, err)
            bad += len(msgs)
            worst = ", ".join(f"{f} {e:.2g}" for f, e in err.items() if f != "id")
            print(f"[{backend_id(backend)}] {name}: {'FAIL' if msgs else 'ok'} ({worst})")
            for m in msgs:
                print("   ", m)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
