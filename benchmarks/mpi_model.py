"""A model of one rank's step time, calibrated on ``results/mpi_scaling.json``, that
predicts the parallel efficiency of dpm's MPI backend at 64-1024 ranks for 1e7-1e9
particles, and says which term breaks it down.

Per step, on each of P ranks holding n = N / P particles (box_settle-like packing):

    compute  = c * n * (1 + g)             c: one rank's cost per particle-step
                                           g = k_g n^(-1/3): ghosts per owned particle
                                           (contacts with ghosts are computed on both
                                           ranks: Newton's third law is not used across
                                           ranks)
    halo     = o + m * alpha + B / beta    o: per-step software cost (pack, unpack,
                                           message calls), m messages of B bytes in all
                                           (13 floats per ghost), alpha latency, beta
                                           bandwidth of the interconnect
    reduce   = alpha_r * log2(P)           the per-step vote (posted with the halo,
                                           counted whole as if not overlapped)
    migrate  = mu * n / r                  mu: cost per particle of a rebuild's
                                           migration, r: steps between rebuilds
    gather   = sigma * N / s               sigma: cost per particle of a whole-state
                                           gather (with the scatters), s: steps between
                                           gathers. A kernel call ends without one: the
                                           host is gathered where the run loop needs it
                                           (``MpiBackend.sync_host``): at output frames,
                                           flow events, hooks and a run's end, so s is
                                           the steps between frames (``--frame-every``)

    efficiency = c N / (P * step)

c, o, mu, sigma and r are the measured 2-rank figures of this machine; g's constant is
the measured slab ghost layer turned into a cube's six faces; alpha, beta are those of a
typical InfiniBand cluster (2 us, 10 GB/s) and alpha_r = 2 us. Writes
``results/mpi_model[_quick].json``.

    python benchmarks/mpi_model.py [--quick] [--scaling results/mpi_scaling.json]
                                   [--frame-every 1000]

Calibrations on runs written before calls ended without a gather (no ``gathers`` in the
JSON's rank rows) count one gather per call, as those runs did.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import harness

from dpm.kernels.halo import HALO_WIDTH as FLOATS_PER_GHOST

HERE = Path(__file__).resolve().parent
ALPHA, BETA, ALPHA_R = 2e-6, 10e9, 2e-6
NEIGHBOURS_3D = 14  # a rank of a recursive bisection in 3D talks to ~14 others


def calibrate(scaling: dict) -> dict:
    row = max(scaling["strong"], key=lambda r: r["particles"])
    one = row["dpm_1"]
    two = row["dpm_2_ranks"]
    ranks = two["ranks"]
    n = row["particles"] / 2
    steps = two["timed_steps"]
    c = 1.0 / one["particle_steps_per_s"]
    fast = min(ranks, key=lambda r: r["halo_s"])
    g_slab = sum(r["ghosts"] for r in ranks) / sum(r["owned"] for r in ranks)
    # a slab's one ghost face holds n^(2/3) * w particles: w in particle spacings
    w = g_slab * n ** (1 / 3)
    rebuilds = max(r["rebuilds"] for r in ranks)
    # (whole-state gathers in the timed run: one per call before calls ended without one)
    gathers = max(r.get("gathers", r["calls"]) for r in ranks)
    return {
        "particles_calibrated_on": row["particles"], "c_s": c,
        "overhead_per_step_s": fast["halo_s"] / steps,
        "ghost_layer_spacings": w, "k_g_3d": 6 * w,
        "migrate_per_particle_s": sum(r["migrate_s"] for r in ranks) / len(ranks)
        / max(rebuilds, 1) / n,
        "steps_per_rebuild": steps / max(rebuilds, 1),
        "gather_per_particle_s": sum(r["gather_s"] + r["scatter_s"] for r in ranks)
        / len(ranks) / max(gathers, 1) / row["particles"],
        "gathers_calibrated_on": gathers,
    }


def step_time(cal: dict, N: float, P: int, frame_every: float) -> dict:
    """One rank's step time and the efficiency, a whole-state gather every
    ``frame_every`` steps (an output frame; ``inf``: none but a run's end, not counted)."""
    n = N / P
    g = cal["k_g_3d"] * n ** (-1 / 3)
    compute = cal["c_s"] * n * (1 + g)
    halo = (cal["overhead_per_step_s"] + NEIGHBOURS_3D * ALPHA
            + 2 * g * n * FLOATS_PER_GHOST * 8 / BETA)
    reduce = ALPHA_R * math.log2(P)
    migrate = cal["migrate_per_particle_s"] * n / cal["steps_per_rebuild"]
    base = compute + halo + reduce + migrate
    gather = cal["gather_per_particle_s"] * N / frame_every
    total = base + gather
    parts = {"compute": compute, "halo": halo, "reduce": reduce, "migrate": migrate,
             "gather": gather}
    return {"ranks": P, "particles": N, "per_rank": n, "ghost_fraction": g,
            "step_s": total, "efficiency": cal["c_s"] * N / (P * total),
            "largest_loss": max((k for k in parts if k != "compute"), key=parts.get),
            "memory_per_rank_GB": N * 600 / 1e9, **{f"{k}_s": v for k, v in parts.items()}}


def main() -> None:
    ap = harness.parser(__doc__, "calibrate on mpi_scaling_quick.json when there is one "
                                 "(this run's --results, then benchmarks/results); write "
                                 "mpi_model_quick.json")
    ap.add_argument("--scaling", default=None, help="(results/mpi_scaling.json)")
    ap.add_argument("--frame-every", type=float, default=1000.0,
                    help="steps between output frames (each gathers the whole state)")
    ap.add_argument("--out", default=None, help="(results/mpi_model[_quick].json)")
    a = ap.parse_args()
    if a.scaling is None:  # this run's results first (--results), then the shipped ones
        names = ["mpi_scaling_quick.json"] * a.quick + ["mpi_scaling.json"]
        found = [d / n for n in names for d in (harness.RESULTS, harness.SHIPPED)
                 if (d / n).exists()]
        if not found:
            path = harness.write("mpi_model", {"calibration": None, "prediction": None,
                                               "why": "no mpi_scaling JSON to calibrate on "
                                               "(run benchmarks/mpi_scaling.py)"}, a.quick)
            print(f"no mpi_scaling JSON: wrote {path} without a model")
            return
        a.scaling = str(found[0])
    cal = calibrate(json.loads(Path(a.scaling).read_text()))
    grid = [(N, P) for N in (1e6, 1e7, 1e8, 1e9) for P in (2, 64, 256, 1024)]
    rows = [step_time(cal, N, P, a.frame_every) for N, P in grid]
    # the same with no frame during the run (one gather at its end, not counted): what
    # a distributed host state (each rank keeping only its own rows, output written
    # collectively) would give with frames too
    no_frames = [dict(step_time(cal, N, P, math.inf), note="no frames")
                 for N, P in grid]
    out = {"scaling": a.scaling, "frame_every_steps": a.frame_every, "calibration": cal,
           "assumed": {"alpha_s": ALPHA, "beta_B_per_s": BETA,
                       "allreduce_alpha_s": ALPHA_R, "neighbours": NEIGHBOURS_3D},
           "prediction": rows, "prediction_no_frames": no_frames}
    if a.out:
        Path(a.out).write_text(json.dumps(out | {"run": harness.machine()}, indent=1))
    else:
        harness.write("mpi_model", out, a.quick)
    print(json.dumps(cal, indent=1))
    print(f"{'N':>8} {'P':>5} {'n/rank':>9} {'ghosts':>7} {'eff':>6} {'loss':>8} "
          f"{'GB/rank':>8}   (no frames: eff, loss)")
    for r, d in zip(rows, no_frames, strict=True):
        print(f"{r['particles']:8.0e} {r['ranks']:5d} {r['per_rank']:9.3g} "
              f"{r['ghost_fraction']:7.2f} {r['efficiency']:6.2f} {r['largest_loss']:>8} "
              f"{r['memory_per_rank_GB']:8.2f}   {d['efficiency']:.2f} {d['largest_loss']}")


if __name__ == "__main__":
    main()
