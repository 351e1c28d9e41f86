"""Hopper discharge: silos and hoppers emptying through an orifice, against Beverloo.

Four scenes, each settled on a plug that is switched off at ``T_OPEN`` (LIGGGHTS' ``unfix``
of a plug wall: the bed keeps its contact history when the orifice opens):

1. Flat-bottomed silo (a ``tube`` of radius 40 mm over an ``orifice_plate``), 5 mm glass
   beads, orifice diameters D = 20-35 mm: the steady discharge rate W against D, fitted to
   Beverloo's W = C rho_b sqrt(g) (D - k d)^(5/2) (``dpm.analysis.fit_beverloo``;
   Beverloo, Leniger & van de Velde 1961: C 0.55-0.65, k 1.2-3), rho_b the settled bed's
   bulk density.
2. Conical hopper (half angle 30 degrees, outlet D = 25 mm): the cone as the analytic
   ``tube`` frustum and as a triangle mesh of the same cone; the two rates agree within the
   run-to-run scatter when the mesh is fine.
3. Wedge hopper: two inclined ``wall`` plates leaving a slot, planes at the ends.
4. Flat hopper of 2,000 polydisperse steel spheres (d 8-12 mm, Samiei 2012 sec. 3.4's
   hopper test scale): the mass-weighted mean residence time after opening, from the
   outlet's removal records (``dpm.analysis.residence_times``).

The discharge rate is the removed mass per time while the bed is deeper than a few
orifice diameters (a window of ``WINDOW`` s after a start-up transient), from the outlet
records. Soft beads (E = 10 MPa) keep dt at 2e-5 s; Beverloo's law does not depend on the
stiffness while overlaps stay small (< 1 % here).

    python examples/hopper_discharge.py            # all four scenes (~8 min, one core)
    python examples/hopper_discharge.py --quick    # one small silo (CI)

Writes hopper_discharge.json, hopper_discharge.png and the HDF5 + XDMF of the silo with the
median orifice (``--output DIR``).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import dpm
from dpm import analysis as an

G = 9.81
D_BEAD = 5e-3
T_OPEN = 0.25      # settle on the plug, then open [s]
T_START = 0.08     # start-up transient after opening, left out of the rate [s]
WINDOW = 0.25      # rate window [s]
DT = 2e-5


def materials(sim: dpm.Simulation, steel_beads: bool = False):
    glass = dpm.Material("glass", density=2500.0, young=1e7, poisson=0.3)
    steel = dpm.Material("steel", density=7800.0, young=1e7, poisson=0.3)
    bead = steel if steel_beads else glass
    wall = dpm.Material("wall", density=7800.0, young=1e7, poisson=0.3)
    sim.contact(bead, bead, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(bead, wall, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return bead, wall


def lattice_in_cylinder(radius: float, z0: float, height: float, d: float,
                        seed: int = 1) -> np.ndarray:
    """Centres of a loose cubic lattice (spacing 1.05 d) inside a cylinder about z."""
    pts = dpm.lattice((-radius, -radius, z0), (radius, radius, z0 + height), spacing=1.05 * d,
                      jitter=0.02 * d, seed=seed)
    rho = np.hypot(pts[:, 0], pts[:, 1])
    return pts[rho < radius - 0.6 * d]


def add_outlet(sim: dpm.Simulation, below: float) -> dpm.Outlet:
    """Remove what falls ``below`` m under the orifice (records: time, mass, residence)."""
    return sim.add_outlet(dpm.BoxRegion((-1, -1, -2), (1, 1, -below)), every=2e-3)


def silo(orifice: float, radius: float = 0.04, height: float = 0.1, d: float = D_BEAD,
         output: str | None = None) -> tuple[dpm.Simulation, dict]:
    """The flat-bottomed silo with a round orifice of diameter ``orifice`` and its plug."""
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G))
    bead, wall = materials(sim)
    sim.add_boundary("tube", material=wall, start=(0, 0, 0), axis=(0, 0, 1), length=0.3,
                     radius=radius)
    sim.add_boundary("orifice_plate", material=wall, center=(0, 0, 0), hole=orifice,
                     radius=radius + 0.01)
    plug = sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=bead, radius=d / 2,
                      positions=lattice_in_cylinder(radius, 0.0, height, d))
    sim.switch_off(plug, at=T_OPEN)
    add_outlet(sim, 0.05)
    if output:
        sim.output(output, every=0.02, overwrite=True)
    return sim, {"orifice": orifice, "radius": radius, "d": d}


def conical(mesh: bool, orifice: float = 0.025, half_angle: float = 30.0, d: float = D_BEAD,
            top_radius: float = 0.045, height: float = 0.09) -> dpm.Simulation:
    """Conical hopper: a frustum from the outlet (radius D/2 at z = 0) widening at
    ``half_angle`` to ``top_radius``, a cylinder above; analytic or meshed (64 sides)."""
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G))
    bead, wall = materials(sim)
    r0 = orifice / 2
    cone_h = (top_radius - r0) / math.tan(math.radians(half_angle))
    if mesh:
        v, f = frustum_mesh(r0, top_radius, cone_h, 64)
        sim.add_boundary("mesh", material=wall, vertices=v, faces=f)
    else:
        sim.add_boundary("tube", material=wall, start=(0, 0, 0), axis=(0, 0, 1),
                         length=cone_h, radius_start=r0, radius_end=top_radius)
    sim.add_boundary("tube", material=wall, start=(0, 0, cone_h), axis=(0, 0, 1),
                     length=0.2, radius=top_radius)
    plug = sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    # fill the cylinder and the cone: lattice points inside the hopper's outline
    pts = lattice_in_cylinder(top_radius, 0.0, cone_h + height, d)
    rho = np.hypot(pts[:, 0], pts[:, 1])
    inside = rho < r0 + pts[:, 2] * math.tan(math.radians(half_angle)) - 0.7 * d
    sim.add_particles("sphere", material=bead, radius=d / 2, positions=pts[inside])
    sim.switch_off(plug, at=T_OPEN)
    add_outlet(sim, 0.05)
    return sim


def frustum_mesh(r0: float, r1: float, h: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of a frustum wall from radius r0 at z = 0 to r1 at z = h, n sides (the
    vertices on the analytic surface)."""
    ang = np.arange(n) * 2 * np.pi / n
    lo = np.c_[r0 * np.cos(ang), r0 * np.sin(ang), np.zeros(n)]
    hi = np.c_[r1 * np.cos(ang), r1 * np.sin(ang), np.full(n, h)]
    faces = []
    for k in range(n):
        a, b = k, (k + 1) % n
        faces += [(a, b, n + b), (a, n + b, n + a)]
    return np.vstack([lo, hi]), np.asarray(faces)


def wedge(slot: float = 0.02, depth: float = 0.06, half_angle: float = 30.0,
          d: float = D_BEAD, top: float = 0.1) -> dpm.Simulation:
    """Wedge hopper: two plates inclined at ``half_angle`` from the vertical leaving a slot
    of width ``slot`` at z = 0, over ``depth`` along y; planes close the ends."""
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G))
    bead, wall = materials(sim)
    t = math.radians(half_angle)
    length = top / math.cos(t)
    for s in (-1, 1):
        # plate from (s slot/2, 0) up and out to (s (slot/2 + top tan t), top)
        cx = s * (slot / 2 + 0.5 * top * math.tan(t))
        normal = (-s * math.cos(t), 0.0, math.sin(t))
        sim.add_boundary("wall", material=wall, center=(cx, 0, top / 2), normal=normal,
                         u=(0, 1, 0), half_extents=(depth / 2 + 0.01, length / 2))
    sim.add_boundary("plane", material=wall, point=(0, -depth / 2, 0), normal=(0, 1, 0))
    sim.add_boundary("plane", material=wall, point=(0, depth / 2, 0), normal=(0, -1, 0))
    plug = sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    w = slot / 2 + top * math.tan(t)
    pts = dpm.lattice((-w, -depth / 2, 0), (w, depth / 2, 0.9 * top), spacing=1.05 * d,
                      jitter=0.02 * d, seed=2)
    inside = np.abs(pts[:, 0]) < slot / 2 + pts[:, 2] * math.tan(t) - 0.7 * d
    sim.add_particles("sphere", material=bead, radius=d / 2, positions=pts[inside])
    sim.switch_off(plug, at=T_OPEN)
    add_outlet(sim, 0.05)
    return sim


def steel_hopper(n_target: int = 2000, seed: int = 3) -> dpm.Simulation:
    """Flat hopper (silo radius 0.12 m, orifice 60 mm) of ~2,000 steel spheres with
    diameters uniform in 8-12 mm."""
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G))
    bead, wall = materials(sim, steel_beads=True)
    radius = 0.12
    sim.add_boundary("tube", material=wall, start=(0, 0, 0), axis=(0, 0, 1), length=0.6,
                     radius=radius)
    sim.add_boundary("orifice_plate", material=wall, center=(0, 0, 0), hole=0.06,
                     radius=radius + 0.02)
    plug = sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    pts = lattice_in_cylinder(radius, 0.0, 0.5, 12.6e-3, seed=seed)[:n_target]
    rng = np.random.default_rng(seed)
    sim.add_particles("sphere", material=bead, radius=rng.uniform(4e-3, 6e-3, len(pts)),
                      positions=pts)
    sim.switch_off(plug, at=T_OPEN)
    add_outlet(sim, 0.05)
    return sim


def discharge(sim: dpm.Simulation, window: float = WINDOW) -> dict:
    """Run to T_OPEN + T_START + ``window``; the rate from the outlet records in the
    window, the bed's top at the opening and what it cost."""
    until = T_OPEN + T_START + window
    sim.run(steps=1, progress=False)  # compile (or load) the kernels; the clock starts after
    t0 = time.perf_counter()
    sim.run(until=T_OPEN, progress=False)
    b = sim.bodies
    top = np.percentile(b.position[:, 2] + b.radius, 95)
    sim.run(until=until, progress=False)
    wall = time.perf_counter() - t0
    rec = sim.outlets[0].records
    t = rec["time"]
    sel = (t > T_OPEN + T_START) & (t <= until)
    rate = float(rec["mass"][sel].sum() / window)
    return {"rate_kg_s": rate, "bed_top_m": float(top), "bodies": int(len(b) + len(t)),
            "removed": int(len(t)), "wall_s": wall,
            "particle_steps_per_s": (len(b) + len(t)) * (sim.step_count - 1) / wall}


def bulk_density(sim: dpm.Simulation, mass: float, radius: float, top: float) -> float:
    return mass / (math.pi * radius**2 * top)


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one small silo (CI)")
    p.add_argument("--output", default=".", help="directory for the files (default .)")
    a = p.parse_args(argv)
    out = Path(a.output)
    out.mkdir(parents=True, exist_ok=True)
    result: dict = {"quick": a.quick, "d": D_BEAD, "t_open": T_OPEN, "window": WINDOW}
    orifices = [0.025] if a.quick else [0.02, 0.025, 0.03, 0.035]
    radius, height = (0.025, 0.05) if a.quick else (0.04, 0.1)
    window = 0.1 if a.quick else WINDOW
    rows = []
    for k, D in enumerate(orifices):
        h5 = str(out / "hopper_discharge.h5") if k == len(orifices) // 2 else None
        sim, info = silo(D, radius=radius, height=height, output=h5)
        mass = float(sim.bodies.mass.sum())
        r = discharge(sim, window)
        rho_b = bulk_density(sim, mass, radius, r["bed_top_m"])
        r.update(orifice_m=D, bulk_density=rho_b,
                 beverloo_kg_s=an.beverloo(rho_b, D, D_BEAD, C=0.58, k=1.5))
        rows.append(r)
        dpm.notice(f"silo D = {D * 1e3:.0f} mm: W = {r['rate_kg_s']:.4f} kg/s (Beverloo C 0.58, "
                   f"k 1.5: {r['beverloo_kg_s']:.4f}), rho_b = {rho_b:.0f} kg/m3, "
                   f"{r['bodies']} beads, {r['wall_s']:.0f} s", flush=True)
    result["silo"] = rows
    if len(rows) >= 2:
        rho_b = float(np.mean([r["bulk_density"] for r in rows]))
        C, k = an.fit_beverloo([r["orifice_m"] for r in rows], [r["rate_kg_s"] for r in rows],
                               D_BEAD, rho_b)
        result["beverloo_fit"] = {"C": C, "k": k, "bulk_density": rho_b}
        dpm.notice(f"Beverloo fit: C = {C:.3f} (usual 0.55-0.65), k = {k:.2f} (usual 1.2-3)")
    if not a.quick:
        for name, build in (("cone_analytic", lambda: conical(False)),
                            ("cone_mesh", lambda: conical(True)), ("wedge", wedge)):
            r = discharge(build())
            result[name] = r
            dpm.notice(f"{name}: W = {r['rate_kg_s']:.4f} kg/s, {r['bodies']} beads, "
                       f"{r['wall_s']:.0f} s", flush=True)
        sim = steel_hopper()
        r = discharge(sim, 0.5)
        while len(sim.bodies) and sim.time < T_OPEN + 10.0:  # until nothing more leaves
            n = len(sim.bodies)
            sim.run(until=sim.time + 0.5, progress=False)
            if len(sim.bodies) == n:
                break
        rt = an.residence_times(sim.outlets[0].records, mass_weighted=True)
        r["mean_residence_after_opening_s"] = float(rt.mean - T_OPEN)
        r["removed"] = int(len(sim.outlets[0].records["time"]))
        r["left_in_hopper"] = int(len(sim.bodies))
        # (a flat bottom keeps a dead zone at the wall: it never empties completely)
        r["last_out_after_s"] = float(sim.outlets[0].records["time"].max() - T_OPEN)
        result["steel_hopper"] = r
        dpm.notice(f"steel hopper: {r['removed']} of {r['bodies']} out, the last "
                   f"{r['last_out_after_s']:.2f} s after the opening; mass-weighted mean residence "
                   "after opening "
                   f"{r['mean_residence_after_opening_s']:.3f} s")
    if dpm.is_root():  # (rank 0 writes: every rank holds the result)
        (out / "hopper_discharge.json").write_text(json.dumps(result, indent=1))
        picture(result, out / "hopper_discharge.png")
    return result


def picture(result: dict, path: Path) -> None:
    """Left: the flat silo's rate against the orifice with Beverloo's curve and the fit.
    Right: the rates of the other hoppers beside the flat silo's at the same outlet."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = result["silo"]
    D = np.array([r["orifice_m"] for r in rows])
    W = np.array([r["rate_kg_s"] for r in rows])
    others = [(n, result[n]["rate_kg_s"]) for n in ("cone_analytic", "cone_mesh", "wedge")
              if n in result]
    fig, axes = plt.subplots(1, 2 if others else 1, figsize=(10 if others else 6, 4.2),
                             squeeze=False)
    ax = axes[0, 0]
    ax.plot(D * 1e3, W, "o", label="dpm, flat silo (40 mm radius)")
    dd = np.linspace(max(1.6 * D_BEAD, D.min() * 0.8), D.max() * 1.1, 100)
    rho_b = float(np.mean([r["bulk_density"] for r in rows]))
    ax.plot(dd * 1e3, [an.beverloo(rho_b, x, D_BEAD, C=0.58, k=1.5) for x in dd], "k--",
            label="Beverloo C = 0.58, k = 1.5")
    fit = result.get("beverloo_fit")
    if fit:
        ax.plot(dd * 1e3, [an.beverloo(rho_b, x, D_BEAD, C=fit["C"], k=fit["k"]) for x in dd],
                "C0-", label=f"fit: C = {fit['C']:.2f}, k = {fit['k']:.2f}")
    ax.set_xlabel("orifice diameter D [mm]")
    ax.set_ylabel("discharge rate W [kg/s]")
    ax.set_title(f"flat-bottomed silo, {D_BEAD * 1e3:.0f} mm glass beads, "
                 f"rho_b = {rho_b:.0f} kg/m3", fontsize=10)
    ax.legend(fontsize=8)
    if others:
        ax = axes[0, 1]
        flat = [r["rate_kg_s"] for r in rows if abs(r["orifice_m"] - 0.025) < 1e-9]
        names = (["flat silo\nD 25 mm"] if flat else []) + [
            {"cone_analytic": "cone 30 deg\nanalytic, D 25", "cone_mesh":
             "cone 30 deg\nmesh, D 25", "wedge": "wedge 30 deg\nslot 20 x 60"}[n]
            for n, _ in others]
        vals = flat + [v for _, v in others]
        bars = ax.bar(names, vals, color=["C0"] * len(flat) + ["C1", "C2", "C3"][:len(others)])
        ax.bar_label(bars, labels=[f"{v:.3f}" for v in vals], fontsize=8)
        ax.set_ylabel("discharge rate W [kg/s]")
        ax.set_title("hopper shapes (outlet at z = 0)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    main()
