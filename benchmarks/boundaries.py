"""Cost of element-boundary contacts: per kind, and for meshes against the triangle count.

1. Per kind: the contact geometry of one element-primitive check (``closest_any`` of
   :mod:`dpm.kernels.boundary_geometry`, the function every candidate entry costs in the
   contact pass and the search) timed directly in a numba loop over 1e6 random sphere
   centres near a primitive of each kind. The step itself compiles a ``closest`` of the
   scene's kinds only, which dispatches the same inlined functions.
2. Meshes: flat floors of 2 to ~2e5 triangles (cells of 4 mm split in two, the floor grows
   with the count) under up to 2000 spheres (r = 2 mm) resting on it (no gravity, touching);
   and a second series, the same 2000 spheres on one 210 mm floor meshed by 200 to ~2e5
   triangles (cells of 21 to 0.66 mm: a part's mesh resolution at a fixed scene), timed on
   one thread and on two.
   We time (a) the candidate search (counting pass of the grid search) per sphere and (b) the
   step (contact pass with the mesh edge rules, no rebuild) per sphere. With triangles of
   bounded size the grid makes both independent of the triangle count; the table also
   reports the preparation (packing the triangles, feature flags, grid) per triangle.

3. Peer: the same mesh scene in LIGGGHTS (when ``liggghts`` is on PATH), in the same run:
   the floor written as an ASCII STL with the same triangles (``fix mesh/surface`` +
   ``fix wall/gran ... mesh``), the same spheres, Hertz-Mindlin with the same material
   constants, dt, Verlet skin (0.4 mm) and number of steps, one core
   (benchmarks/scenes/mesh_floor). Its step
   time per sphere is the "Loop time" of the timed ``run`` (best of three) and the ratio
   dpm / LIGGGHTS is reported per triangle count (for the fixed floor also dpm's two
   threads over LIGGGHTS' one core).

Run: ``python benchmarks/boundaries.py`` (writes benchmarks/results/boundaries.json and
.png; ``--quick`` uses fewer sizes, ``--no-liggghts`` skips the peer).
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import harness
import numba
import numpy as np

import dpm
from dpm.kernels.boundary_geometry import AXI, PLANE, SIEVE, SLAB, TORUS, TRIANGLE, closest_any

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

SCENE = Path(__file__).parent / "scenes" / "mesh_floor"
R = 2e-3
#: the Verlet skin of both codes (``neighbor 0.0004 bin`` in mesh_floor.liggghts; dpm's
#: default, 0.2 d = 0.8 mm here, would list about twice the triangles per sphere)
SKIN = 4e-4
FAR = 10.0
#: side of the floor of the fixed-floor series: 2,000 spheres on a lattice of 45 x 45 at
#: 2.2 r (198 mm) and their radius inside it
FIXED_FLOOR = 0.21


@numba.njit(cache=False)
def _loop(kind, par, pts, r):
    acc = 0.0
    for i in range(pts.shape[0]):
        acc += closest_any(kind, par, pts[i, 0], pts[i, 1], pts[i, 2], r)[0]
    return acc


def per_kind(n: int = 1_000_000, repeats: int = 5) -> dict:
    rng = np.random.default_rng(0)
    par = {k: np.zeros(20) for k in (PLANE, SLAB, AXI, TORUS, TRIANGLE, SIEVE)}
    par[PLANE][3:6] = (0, 0, 1)
    par[SLAB][3:12] = (1, 0, 0, 0, 1, 0, 0.01, 0.01, 0.001)
    par[AXI][3:11] = (0, 0, 1, 0.01, 0.0, 0.01, 0.05, 0.0)
    par[TORUS][3:13] = (0, 0, 1, 1, 0, 0, 0.05, 0.01, 1.5, 0.0)
    par[TRIANGLE][0:13] = (-0.01, -0.01, 0, 0.01, -0.01, 0, 0, 0.01, 0, 0, 0, 0, 1)
    par[SIEVE][3:17] = (1, 0, 0, 0, 1, 0, 0.03, 0.03, 0.0, 4e-3, 6e-3, 0, 2, 0.6)
    names = {PLANE: "plane", SLAB: "wall (slab)", AXI: "tube (axi)", TORUS: "bend (torus)",
             TRIANGLE: "mesh triangle", SIEVE: "sieve (clearance)"}
    pts = rng.uniform(-0.02, 0.02, (n, 3))
    pts[:, 2] *= 0.2
    out = {}
    for k, p in par.items():
        _loop(k, p, pts[:10], R)
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            _loop(k, p, pts, R)
            best = min(best, time.perf_counter() - t0)
        out[names[k]] = best / n * 1e9
    return out


def grid_floor(m: int, cell: float = 4e-3) -> tuple[np.ndarray, np.ndarray]:
    """Flat floor of m x m cells (2 m^2 triangles) centred on the origin."""
    xs = (np.arange(m + 1) - 0.5 * m) * cell
    xx, yy = np.meshgrid(xs, xs, indexing="ij")
    verts = np.c_[xx.ravel(), yy.ravel(), np.zeros(xx.size)]
    i, j = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
    a = (i * (m + 1) + j).ravel()
    b, c, d = a + (m + 1), a + (m + 2), a + 1
    faces = np.concatenate([np.c_[a, b, c], np.c_[a, c, d]])
    return verts, faces


def sentinels(sim, w):
    """Far-away boundaries of every kind: the scene compiles the same step module as
    tests/physics/test_boundaries.py (one compile for both)."""
    sim.add_boundary("plane", material=w, point=(0, 0, -FAR), normal=(0, 0, 1))
    sim.add_boundary("wall", material=w, center=(FAR, 0, 0), half_extents=(0.01, 0.01))
    sim.add_boundary("tube", material=w, start=(FAR, FAR, 0), axis=(0, 0, 1), length=0.01,
                     radius=0.01)
    sim.add_boundary("bend", material=w, center=(-FAR, 0, 0), bend_radius=0.05,
                     pipe_radius=0.01, angle=1.0)
    sim.add_boundary("mesh", material=w, vertices=[(0, FAR, 0), (0.01, FAR, 0),
                                                   (0, FAR + 0.01, 0)], faces=[(0, 1, 2)])
    sim.add_boundary("sieve", material=w, center=(0, -FAR, 0), half_extents=(0.01, 0.01),
                     hole=2e-3, bar=1e-3, clearance_model="fixed")


def write_stl(path: Path, verts: np.ndarray, faces: np.ndarray) -> None:
    """ASCII STL of the triangles (normals from the vertex order)."""
    t = verts[faces]
    nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    rows = np.concatenate([nrm[:, None, :], t], axis=1).reshape(-1, 12)
    facet = (" facet normal %.9g %.9g %.9g\n  outer loop\n" + "   vertex %.9g %.9g %.9g\n" * 3
             + "  endloop\n endfacet\n")
    with open(path, "w") as f:
        f.write("solid floor\n")
        f.write("".join(facet % tuple(r) for r in rows))
        f.write("endsolid floor\n")


def run_liggghts(verts, faces, pos, steps: int, repeats: int = 3) -> dict | None:
    """The dpm mesh scene in LIGGGHTS (1 core): best "Loop time" of ``repeats`` runs of
    ``steps`` steps after 5 warm-up steps, as us per step and sphere."""
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    lo, hi = verts.min(0), verts.max(0)
    pad = 2 * R
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        write_stl(d / "floor.stl", verts, faces)
        with open(d / "mesh_floor.data", "w") as f:
            f.write(f"mesh floor\n\n{len(pos)} atoms\n2 atom types\n\n"
                    f"{lo[0] - pad} {hi[0] + pad} xlo xhi\n{lo[1] - pad} {hi[1] + pad} ylo yhi\n"
                    f"{-pad} {3 * pad} zlo zhi\n\nAtoms\n\n")
            f.write("".join(f"{i} 1 {2 * R} 2500.0 {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n"
                            for i, p in enumerate(pos, 1)))
        shutil.copy(SCENE / "mesh_floor.liggghts", d)
        cmd = [exe, "-in", "mesh_floor.liggghts", "-echo", "none", "-log", "log.txt",
               "-var", "STEPS", str(steps), "-var", "REPEATS", str(repeats)]
        t0 = time.perf_counter()
        subprocess.run(cmd, cwd=tmp, check=True, capture_output=True, text=True,
                       env={**os.environ, "OMP_NUM_THREADS": "1"})
        whole = time.perf_counter() - t0
        log = (d / "log.txt").read_text()
    loops = [float(t) for t, n in re.findall(
        r"Loop time of ([0-9.eE+-]+) on 1 procs for (\d+) steps", log) if int(n) == steps]
    builds = [int(b) for b in re.findall(r"Neighbor list builds = (\d+)", log)]
    return {"loop_s": min(loops), "whole_run_s": whole, "neighbor_builds": sum(builds),
            "step_us_per_sphere": min(loops) / steps / len(pos) * 1e6}


def best_steps(sim, nsteps: int) -> float:
    """Best wall time of three runs of ``nsteps`` steps with no list rebuild (after five
    untimed steps)."""
    sim.run(steps=5, progress=False)
    best = math.inf
    for _ in range(3):
        r0 = sim.rebuild_count
        t1 = time.perf_counter()
        sim.run(steps=nsteps, progress=False)
        el = time.perf_counter() - t1
        if sim.rebuild_count == r0:
            best = min(best, el)
    return best


def mesh_scaling(sizes, n_spheres: int = 2000, steps: int = 1000, sphere_steps: float = 1e6,
                 liggghts: bool = False, side: float | None = None,
                 two_threads: bool = False) -> list[dict]:
    """Rows of the floor of m x m cells for m in ``sizes``: cells of 4 mm (the floor
    grows with m and holds up to ``n_spheres``), or, with ``side``, a floor of that side
    whatever m (the same spheres on a coarser or finer mesh of the same floor).
    ``two_threads``: time the steps on two threads too (the LIGGGHTS peer stays on one
    core: the ratio is dpm's two threads against its one core)."""
    rows = []
    for m in sizes:
        cell = 4e-3 if side is None else side / m
        verts, faces = grid_floor(m, cell)
        a = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
        w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
        # (sphere_orientation=False: single spheres' quaternions not integrated, as the
        # peer's nve/sphere; positions, velocities and spins are the same bit for bit)
        sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, 0), dt_check="off", threads=1,
                             skin=SKIN, sphere_orientation=False)
        sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=0.5)
        sim.contact(a, w, model="hertz_mindlin", restitution=0.3, friction=0.5)
        t0 = time.perf_counter()
        sim.add_boundary("mesh", material=w, vertices=verts, faces=faces)
        sentinels(sim, w)
        half = 0.5 * m * cell
        rng = np.random.default_rng(1)
        # spheres on a jittered lattice (spacing 2.2 r) over the middle of the floor
        k = max(1, min(int(math.ceil(math.sqrt(n_spheres))), int(2 * half / (2.2 * R))))
        g = (np.arange(k) - 0.5 * (k - 1)) * 2.2 * R
        xy = np.array([(x, y) for x in g for y in g])[:n_spheres]
        xy = xy + rng.uniform(-0.02 * R, 0.02 * R, xy.shape)
        pos = np.c_[xy, np.full(len(xy), R * 0.9999)]
        sim.add_particles("sphere", material=a, radius=R, positions=pos)
        sim.run(steps=0, progress=False)
        prep = time.perf_counter() - t0
        # (a) search: the counting pass of the candidate search (grid for the floor, plain
        # loop for the sentinels) of every sphere, repeated for >= 0.05 s
        e, wt = sim.elements, sim.walls
        counts = np.zeros(len(pos), np.int64)
        args = (e.position, e.radius, sim.skin, wt.frame, wt.kind, wt.par, wt.grid_int,
                wt.grid_flt, wt.cell_start, wt.cell_items, wt.prim_cells, counts,
                sim.wall_contacts.start, sim.wall_contacts.start[1:], sim.wall_contacts.key,
                False, np.arange(len(e.radius)))
        sim.backend.module.boundary_search_pass(*args)
        reps = max(1, int(20000 / len(pos)))
        best = math.inf
        for _ in range(5):
            t1 = time.perf_counter()
            for _ in range(reps):
                sim.backend.module.boundary_search_pass(*args)
            best = min(best, (time.perf_counter() - t1) / reps)
        rebuild = best / len(pos)
        # (b) steps without rebuild (the spheres barely move); at least 1e6 sphere-steps
        # per timing (few spheres: many steps), so that each lasts ~0.2 s or more
        nsteps = int(min(100000, max(steps, sphere_steps / len(pos))))
        best = best_steps(sim, nsteps)
        entries = int(sim.wall_contacts.count)
        rows.append(dict(triangles=len(faces), spheres=len(pos), cell_m=cell,
                         floor_m=m * cell, prepare_s=prep,
                         rebuild_us_per_sphere=rebuild * 1e6,
                         step_us_per_sphere=best / nsteps / len(pos) * 1e6, steps=nsteps,
                         candidates_per_sphere=entries / len(pos)))
        if two_threads:
            # the same steps on two threads (sim.threads: the parallel form of the step
            # module; the same bits), best of three again
            sim.threads = 2
            best2 = best_steps(sim, nsteps)
            rows[-1].update(step_us_per_sphere_2_threads=best2 / nsteps / len(pos) * 1e6,
                            two_thread_gain=best / best2)
        if liggghts:
            lg = run_liggghts(verts, faces, pos, nsteps)
            if lg:
                rows[-1].update(liggghts_step_us_per_sphere=lg["step_us_per_sphere"],
                                liggghts_whole_run_s=lg["whole_run_s"],
                                liggghts_neighbor_builds=lg["neighbor_builds"],
                                ratio_dpm_over_liggghts=rows[-1]["step_us_per_sphere"]
                                / lg["step_us_per_sphere"])
                if two_threads:  # (time ratio, as the one above)
                    rows[-1]["ratio_dpm_2_threads_over_liggghts"] = (
                        rows[-1]["step_us_per_sphere_2_threads"] / lg["step_us_per_sphere"])
        print(rows[-1], flush=True)
    return rows


def plot(res: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    names = list(res["per_kind_ns"])
    ax1.barh(names, [res["per_kind_ns"][n] for n in names], color="tab:blue")
    ax1.set_xlabel("ns per element-primitive check (closest_any, 1 thread)")
    ax1.set_title("contact geometry per boundary kind")
    rows = res["mesh"]
    tri = [r["triangles"] for r in rows]
    ax2.loglog(tri, [r["rebuild_us_per_sphere"] for r in rows], "o-",
               label="candidate search per sphere")
    ax2.loglog(tri, [r["step_us_per_sphere"] for r in rows], "s-",
               label="step per sphere (contact pass, no rebuild)")
    lg = [r for r in rows if "liggghts_step_us_per_sphere" in r]
    if lg:
        lt = [r["triangles"] for r in lg]
        ax2.loglog(lt, [r["liggghts_step_us_per_sphere"] for r in lg], "D-", color="tab:gray",
                   label="LIGGGHTS step per sphere (same scene, 1 core)")
        for r in lg:
            ax2.annotate(f"{r['ratio_dpm_over_liggghts']:.2f}x",
                         (r["triangles"], r["liggghts_step_us_per_sphere"]),
                         textcoords="offset points", xytext=(0, -12), ha="center", fontsize=7,
                         color="tab:gray")
    ax2.loglog(tri, [r["prepare_s"] / r["triangles"] * 1e6 for r in rows], "^--",
               label="prepare per triangle (once)")
    fixed = res.get("mesh_fixed_floor") or []
    if fixed:
        ft = [r["triangles"] for r in fixed]
        ax2.loglog(ft, [r["step_us_per_sphere"] for r in fixed], "s-", color="tab:red",
                   label=f"step per sphere, {fixed[0]['spheres']} spheres on one "
                         f"{fixed[0]['floor_m'] * 1e3:.0f} mm floor")
        flg = [r for r in fixed if "liggghts_step_us_per_sphere" in r]
        if flg:
            ax2.loglog([r["triangles"] for r in flg],
                       [r["liggghts_step_us_per_sphere"] for r in flg], "D--",
                       color="tab:pink", label="LIGGGHTS, the same floor")
            for r in flg:
                ax2.annotate(f"{r['ratio_dpm_over_liggghts']:.2f}x",
                             (r["triangles"], r["step_us_per_sphere"]),
                             textcoords="offset points", xytext=(0, 6), ha="center",
                             fontsize=7, color="tab:red")
    t = np.array(tri, float)
    base = rows[0]["rebuild_us_per_sphere"]
    ax2.loglog(t, base * (1 + np.log(t / t[0])), ":", color="gray",
               label="1 + log(n / 2): log growth, for scale")
    ax2.set_xlabel("triangles in the floor mesh")
    ax2.set_ylabel("time [us]")
    title = "flat floor mesh, up to 2000 spheres resting (r = 2 mm, cells 4 mm)"
    if lg:
        title += "\nlabels: dpm / LIGGGHTS step time per sphere"
    ax2.set_title(title, fontsize=10)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = harness.parser(__doc__, "fewer sizes")
    ap.add_argument("--no-liggghts", action="store_true", help="skip the LIGGGHTS peer")
    ap.add_argument("--plot-only", action="store_true", help="redraw the PNG from the JSON")
    args = ap.parse_args()
    if args.plot_only:
        name = "boundaries_quick" if args.quick else "boundaries"
        path = harness.RESULTS / f"{name}.json"
        harness.png(plot, json.loads(path.read_text()), path=path.with_suffix(".png"))
        return
    numba.set_num_threads(1)  # the search kernels are parallel loops; time one thread
    sizes = [1, 3, 10, 32, 100, 316] if not args.quick else [1, 10, 100]
    res = {"per_kind_ns": per_kind()}
    print(res["per_kind_ns"], flush=True)
    mesh_scaling([1], n_spheres=1, steps=5, sphere_steps=0)  # compile / load the step module first
    res["mesh"] = mesh_scaling(sizes, liggghts=not args.no_liggghts)
    # the same 2,000 spheres on one floor (a little wider than the lattice they rest on)
    # meshed by 200 to ~2e5 triangles: a CAD part's mesh resolution at a fixed scene
    # (two threads here only: the growing floor holds 1 to 841 spheres below 20,000
    # triangles, too few bodies for a second thread to pay in any code)
    res["mesh_fixed_floor"] = mesh_scaling([10, 32, 100, 316] if not args.quick else [10],
                                           liggghts=not args.no_liggghts, side=FIXED_FLOOR,
                                           two_threads=True)
    res["peer"] = harness.peer(args.no_liggghts)
    res["liggghts"] = (None if args.no_liggghts or shutil.which("liggghts") is None else
                       subprocess.run(["liggghts", "-h"], capture_output=True, text=True)
                       .stdout.split("\n\n")[0].strip()[:120])
    path = harness.write("boundaries", res, args.quick)
    harness.png(plot, res, path=path.with_suffix(".png"))
    print("wrote", path)


if __name__ == "__main__":
    main()
