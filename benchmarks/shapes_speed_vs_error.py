"""Clustered shapes: sphere count against shape error, cost per body-step and critical dt.

For the cylinder, the torus and the tetrahedron (default parameters, see docs/shapes.md)
at several resolutions: the sphere count, the union-of-spheres volume over the ideal
volume, the surface deviation (max and RMS, both ways, in % of the equal-volume radius),
the smallest element radius and the critical time step it sets (Rayleigh step of r_min,
glass-like material: 2500 kg/m3, E = 100 MPa, nu = 0.3), and the engine's cost: wall time
per body-step for a small bed of bodies (3 x 3 x 3 lattice of randomly oriented bodies,
bounding spheres 5 % apart, random speeds of 0.05 m/s, Hertz-Mindlin, velocity Verlet,
dt = 0.2 x the critical step, one thread, best of three runs after a warm-up), and the cost
per body per simulated millisecond (cost per step / dt). If the engine refuses clusters,
that column holds the error message.

Writes benchmarks/results/shapes_speed_vs_error.json and .png (``--quick``:
shapes_speed_vs_error_quick.*) and prints the table.

    python benchmarks/shapes_speed_vs_error.py           # 6 resolutions, 300 steps
    python benchmarks/shapes_speed_vs_error.py --quick   # 3 resolutions, 100 steps
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import harness
import numpy as np

import dpm
from dpm.shapes import BUILTIN_SHAPES
from dpm.shapes.metrics import shape_report

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent
SHAPES = ("cylinder", "torus", "tetrahedron")
MATERIAL = dict(density=2500.0, young=1e8, poisson=0.3)


def _orientations(n: int, rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    return q


def engine_cost(shape, dt: float, steps: int, side: int = 3) -> dict:
    """Wall seconds per body-step for a side^3 lattice of bodies of ``shape``."""
    rng = np.random.default_rng(0)
    batch = shape.build(1, MATERIAL["density"])
    rb = float(batch.bounding_radius[0])
    g = np.arange(side) * 2.1 * rb
    xyz = np.array([[x, y, z + 1.2 * rb] for x in g for y in g for z in g])
    n = len(xyz)
    vel = rng.normal(size=(n, 3))
    vel *= 0.05 / np.linalg.norm(vel, axis=1)[:, None]
    m = dpm.Material("glass", **MATERIAL)
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, -9.81), integrator="velocity_verlet",
                         dt_check="off", threads=1)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.0)
    sim.add_boundary("plane", point=(0, 0, 0), normal=(0, 0, 1), material=m)
    sim.add_particles(shape, material=m, positions=xyz, velocities=vel,
                      orientations=_orientations(n, rng))
    sim.run(steps=20, progress=False)  # compile and build the neighbour list
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        sim.run(steps=steps, progress=False)
        best = min(best, time.perf_counter() - t0)
    return {"bodies": n, "elements": int(len(sim.elements)), "steps": steps,
            "seconds_per_body_step": best / (n * steps)}


def measure(name: str, res: float, steps: int) -> dict:
    shape = BUILTIN_SHAPES[name](resolution=res)
    rep = shape_report(shape, samples=3000, volume_samples=60000)
    mat = dpm.Material("glass", **MATERIAL)
    dt_crit = mat.rayleigh_time_step(rep["r_min"])
    row = {"shape": name, "params": shape.describe(resolution=False), "resolution": res,
           "count": rep["count"], "volume_ratio": rep["volume_ratio"],
           "volume_ratio_err": rep["volume_ratio_err"],
           "dev_max_rel": rep["dev_max"] / rep["r_eq"],
           "dev_rms_rel": rep["dev_rms"] / rep["r_eq"], "r_min": rep["r_min"],
           "r_eq": rep["r_eq"], "dt_critical": dt_crit, "generation_s": rep["seconds"]}
    try:
        cost = engine_cost(shape, 0.2 * dt_crit, steps)
        row.update(cost)
        row["seconds_per_body_simulated_ms"] = cost["seconds_per_body_step"] / (
            0.2 * dt_crit) * 1e-3
    except Exception as exc:  # the engine may refuse clusters: keep the column, say why
        row["seconds_per_body_step"] = None
        row["engine_error"] = f"{type(exc).__name__}: {exc}"
    return row


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 3, figsize=(13, 4))
    for k, name in enumerate(SHAPES):
        col = f"C{k}"
        r = [x for x in rows if x["shape"] == name]
        n = [x["count"] for x in r]
        axs[0].loglog(n, [100 * x["dev_rms_rel"] for x in r], "o-", color=col,
                      label=f"{name} RMS")
        axs[0].loglog(n, [100 * x["dev_max_rel"] for x in r], "s--", color=col, alpha=0.5,
                      label=f"{name} max")
        axs[1].semilogx(n, [100 * (1 - x["volume_ratio"]) for x in r], "o-", color=col,
                        label=name)
        cost = [x["seconds_per_body_step"] for x in r]
        if all(c is not None for c in cost):
            axs[2].loglog(n, [1e6 * c for c in cost], "o-", color=col, label=f"{name}: per step")
            axs[2].loglog(n, [1e6 * x["seconds_per_body_simulated_ms"] for x in r], "s--",
                          color=col, alpha=0.6, label=f"{name}: per simulated ms")
    axs[0].set(xlabel="spheres per body", ylabel="surface deviation [% of r_eq]",
               title="shape error")
    axs[1].set(xlabel="spheres per body", ylabel="volume missed by the union [%]",
               title="volume error")
    axs[2].set(xlabel="spheres per body", ylabel="wall time per body [us]",
               title="cost (dt = 0.2 x Rayleigh step of r_min)")
    for ax in axs:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = harness.parser(__doc__, "3 resolutions, 100 steps")
    ap.add_argument("--plot-only", action="store_true", help="redraw the PNG from the JSON")
    args = ap.parse_args()
    if args.plot_only:
        suffix = "_quick" if args.quick else ""
        path = harness.RESULTS / f"shapes_speed_vs_error{suffix}.json"
        rows = json.loads(path.read_text())["rows"]
        harness.png(plot, rows, path=path.with_suffix(".png"))
        return
    resolutions = (0.1, 0.3, 0.6) if args.quick else (0.05, 0.15, 0.3, 0.5, 0.7, 1.0)
    steps = 100 if args.quick else 300
    rows = []
    for name in SHAPES:
        for res in resolutions:
            row = measure(name, res, steps)
            rows.append(row)
            cost = row["seconds_per_body_step"]
            print(f"{name:12s} res={res:<4g} n={row['count']:5d} "
                  f"V={100 * row['volume_ratio']:5.1f}% dev_rms={100 * row['dev_rms_rel']:5.2f}% "
                  f"dev_max={100 * row['dev_max_rel']:5.1f}% r_min={row['r_min']:.3g} m "
                  f"dt_crit={row['dt_critical']:.3g} s "
                  + (f"cost={1e6 * cost:.2f} us/body-step" if cost is not None
                     else f"engine: {row['engine_error']}"), flush=True)
    out = {"material": MATERIAL, "steps": steps, "rows": rows}
    jpath = harness.write("shapes_speed_vs_error", out, args.quick)
    harness.png(plot, rows, path=jpath.with_suffix(".png"))
    print(f"wrote {jpath} and .png")


if __name__ == "__main__":
    main()
