"""Scenes, inputs and references that more than one benchmark uses (no benchmark imports
another benchmark's helpers: what two share lives here or in :mod:`harness`).

- the dilute and dense sphere lattices of ``scaling.py`` (also ``profile_step.py``,
  ``neighbour_search.py``);
- box_settle's bed after S steps of dpm, in both codes' formats (``mpi_scaling.py``,
  ``neighbour_search.py --settled``);
- the opening lines of the LIGGGHTS inputs (``hopper_discharge.py``, ``meshgran.py``,
  ``clusters_settle.py``);
- the head-on impact of ``impact_models.py`` and its analytic references (also
  ``advise_tables.py``).
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import harness
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

BOX_SETTLE = harness.SCENES / "box_settle"

# ------------------------------------------------------------ lattices (scaling.py)

D, RHO = 0.002, 2500.0
CASES = {"dilute": (0.0021, 0.05, 0.0), "dense": (0.999 * D, 0.0, -9.81)}


def scene_arrays(k: int, case: str):
    spacing, vscale, _ = CASES[case]
    rng = np.random.default_rng(7)
    i, j, m = np.meshgrid(np.arange(k), np.arange(k), np.arange(k), indexing="ij")
    pos = (np.stack([i, j, m], -1).reshape(-1, 3) + 0.5) * spacing
    if case == "dense":
        pos[:, 2] += (D / 2 - 0.5 * spacing) * 0.999
    vel = rng.uniform(-vscale, vscale, pos.shape)
    box = np.array([k * spacing, k * spacing, (k + 4) * spacing])
    return pos, vel, box


# ------------------------------------------------ a settled bed (mpi_scaling.py)


def settled_packing(lat: tuple[int, int, int], settle: int, threads: int = 2) -> Path:
    """The box_settle lattice ``lat`` after ``settle`` steps of dpm (``threads`` threads,
    one process), written once (then reused) beside the lattice's own files in gen_init.py's
    two formats: ``box_settle_NXxNYxNZ_settledS.csv`` (x,y,z,vx,vy,vz,r, the same box) and
    ``.data`` (LIGGGHTS). Positions and velocities only: both codes start from the same
    bed with no spin and no contact history (what a data file can carry)."""
    tag = f"box_settle_{lat[0]}x{lat[1]}x{lat[2]}_settled{settle}"
    csv = BOX_SETTLE / f"{tag}.csv"
    if csv.exists():
        return csv
    ex = harness.example("box_settle")
    start = ex.initial_packing(*lat)
    with open(start) as f:
        header = f.readline().strip()
    box = [float(x) for x in header.split("box=")[1].split(",")]
    sim = ex.build(start)
    sim.threads = threads
    sim.run(steps=settle, progress=False)
    b = sim.bodies
    by_id = np.argsort(b.id, kind="stable")
    pos, vel = b.position[by_id], b.velocity[by_id]
    r = sim.elements.radius[b.element_start[:-1]][by_id]
    rho = b.mass[by_id] / (4.0 / 3.0 * np.pi * r ** 3)
    n = len(pos)
    with tempfile.TemporaryDirectory(dir=BOX_SETTLE) as tmpd:  # (renamed into place, CSV last)
        data = Path(tmpd) / "x.data"
        with open(data, "w") as f:
            f.write(f"box settle {n}, settled {settle} steps\n\n{n} atoms\n1 atom types\n\n")
            f.write(f"0 {box[0]} xlo xhi\n0 {box[1]} ylo yhi\n0 {box[2]} zlo zhi\n\n")
            f.write("Atoms\n\n")
            for a in range(n):
                f.write(f"{a + 1} 1 {2 * r[a]:.17g} {rho[a]:.17g} {pos[a, 0]:.17g} "
                        f"{pos[a, 1]:.17g} {pos[a, 2]:.17g}\n")
            f.write("\nVelocities\n\n")
            for a in range(n):
                f.write(f"{a + 1} {vel[a, 0]:.17g} {vel[a, 1]:.17g} {vel[a, 2]:.17g} 0 0 0\n")
        np.savetxt(Path(tmpd) / "x.csv", np.column_stack([pos, vel, r]), delimiter=",",
                   header=header.lstrip("# "), comments="", fmt="%.17g")
        os.replace(data, csv.with_suffix(".data"))
        os.replace(Path(tmpd) / "x.csv", csv)
    return csv


# ----------------------------------------------------------------- LIGGGHTS inputs

#: the lines every LIGGGHTS input of these benchmarks starts with (granular atoms, SI
#: units, a fixed box)
LIGGGHTS_HEADER = """\
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
"""

#: after the header: the box ``region reg`` ({region}: its ``block`` bounds), the
#: neighbour list and four material properties (meshgran.py, clusters_settle.py)
LIGGGHTS_BOX_MATERIALS = """\
region reg block {region} units box
create_box 1 reg
neighbor {{skin}} bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype {{young}}
fix m2 all property/global poissonsRatio peratomtype {{poisson}}
fix m3 all property/global coefficientRestitution peratomtypepair 1 {{restitution}}
fix m4 all property/global coefficientFriction peratomtypepair 1 {{friction}}
"""

# ------------------------------------------- the head-on impact (impact_models.py)

#: the error runs bind every law in one step (compiled once); the cost runs do not
NAMES = ["linear_spring_dashpot", "maw_linear_spring", "hooke", "hertz_brilliantov",
         "hertz_mindlin", "walton_braun", "linear_cohesion"]

R, RHO, YOUNG, NU, V = 1e-3, 2500.0, 1e7, 0.3, 0.5
ESTAR = YOUNG / (2.0 * (1.0 - NU**2))
M = 4.0 / 3.0 * math.pi * R**3 * RHO
KH = 4.0 / 3.0 * ESTAR * math.sqrt(R)  # Hertz constant


def linear_cutoff(k: float, c: float) -> dict:
    """m d'' = -max(0, k d + c d'), d(0) = 0, d'(0) = V: exact (thesis eq. 2.25, true peak)."""
    b = c / (2 * M)
    w = math.sqrt(k / M - b * b)
    T = (math.pi + math.atan(c * 2 * w * M / (c * c - 2 * M * k))) / w
    tm = math.atan2(w, b) / w
    dd = V * math.exp(-b * T) * (math.cos(w * T) - b / w * math.sin(w * T))
    return {"duration": T, "max_overlap": V / w * math.exp(-b * tm) * math.sin(w * tm),
            "restitution": -dd / V}


def linear_for(k: float, e: float) -> dict:
    cc = 2 * math.sqrt(k * M)
    c = brentq(lambda c: linear_cutoff(k, c)["restitution"] - e, 1e-9 * cc, 0.999 * cc,
               xtol=1e-16 * cc) if e < 1 else 0.0
    return linear_cutoff(k, c)


def ode(force, release: bool = True) -> dict:
    """solve_ivp of m d'' = -F(d, d') until d = 0 or (release) F = 0 while separating."""
    t_s = (M * M / (KH * KH * V)) ** 0.2

    def rhs(t, y):
        return [y[1], -force(max(y[0], 0.0), y[1]) / M]

    def out(t, y):
        return y[0]

    def rel(t, y):
        return force(max(y[0], 0.0), y[1]) if (y[1] < 0 and release) else 1.0

    def peak(t, y):
        return y[1]

    out.terminal = rel.terminal = True
    out.direction = rel.direction = peak.direction = -1
    s = solve_ivp(rhs, (0, 50 * t_s), [0.0, V], method="DOP853", events=(out, rel, peak),
                  rtol=1e-11, atol=1e-16, max_step=t_s / 50)
    k = 0 if len(s.t_events[0]) else 1
    return {"duration": float(s.t_events[k][0]), "max_overlap": float(s.y_events[2][0][0]),
            "restitution": -float(s.y_events[k][0][1]) / V}


def tsuji(beta: float):
    def f(d, dd):
        sn = 2 * ESTAR * math.sqrt(R * d)
        return max(4 / 3 * ESTAR * math.sqrt(R * d) * d
                   + 2 * math.sqrt(5 / 6) * beta * math.sqrt(sn * M) * dd, 0.0)
    return f


def maw_k(v: float) -> float:
    return 16 / 15 * math.sqrt(R) * ESTAR * (15 * M * v * v / (16 * math.sqrt(R) * ESTAR)) ** 0.2
