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
    gather   = sigma * N / s               sigma: cost per particle of the whole-state
                                           gather and scatter at a call's ends, s: steps
                                           per call (a call lasts 50 times its gather,
                                           at least 1 s and at most 30 s:
                                           ``MpiBackend.call_aim``)

    efficiency = c N / (P * step)

c, o, mu, sigma and r are the measured 2-rank figures of this machine; g's constant is
the measured slab ghost layer turned into a cube's six faces; alpha, beta are those of a
typical InfiniBand cluster (2 us, 10 GB/s) and alpha_r = 2 us. Writes
``results/mpi_model.json``.

    python benchmarks/mpi_model.py [--scaling results/mpi_scaling.json]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from dpm.kernels.halo import HALO_WIDTH as FLOATS_PER_GHOST
from dpm.parallel.backend import MpiBackend

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
    calls = max(r["calls"] for r in ranks)
    return {
        "particles_calibrated_on": row["particles"], "c_s": c,
        "overhead_per_step_s": fast["halo_s"] / steps,
        "ghost_layer_spacings": w, "k_g_3d": 6 * w,
        "migrate_per_particle_s": sum(r["migrate_s"] for r in ranks) / len(ranks)
        / max(rebuilds, 1) / n,
        "steps_per_rebuild": steps / max(rebuilds, 1),
        "gather_per_particle_s": sum(r["gather_s"] + r["scatter_s"] for r in ranks)
        / len(ranks) / max(calls, 1) / row["particles"],
        "call_aim_s": MpiBackend.CALL_AIM, "gather_share": MpiBackend.GATHER_SHARE,
        "call_aim_max_s": MpiBackend.CALL_AIM_MAX,
    }


def step_time(cal: dict, N: float, P: int) -> dict:
    n = N / P
    g = cal["k_g_3d"] * n ** (-1 / 3)
    compute = cal["c_s"] * n * (1 + g)
    halo = (cal["overhead_per_step_s"] + NEIGHBOURS_3D * ALPHA
            + 2 * g * n * FLOATS_PER_GHOST * 8 / BETA)
    reduce = ALPHA_R * math.log2(P)
    migrate = cal["migrate_per_particle_s"] * n / cal["steps_per_rebuild"]
    base = compute + halo + reduce + migrate
    gather_call = cal["gather_per_particle_s"] * N
    call_s = min(max(cal.get("call_aim_s", 1.0), cal.get("gather_share", 0.0) * gather_call),
                 cal.get("call_aim_max_s", 1.0))
    steps_per_call = max(1.0, call_s / base)
    gather = gather_call / steps_per_call
    total = base + gather
    parts = {"compute": compute, "halo": halo, "reduce": reduce, "migrate": migrate,
             "gather": gather}
    return {"ranks": P, "particles": N, "per_rank": n, "ghost_fraction": g,
            "step_s": total, "efficiency": cal["c_s"] * N / (P * total),
            "largest_loss": max((k for k in parts if k != "compute"), key=parts.get),
            "memory_per_rank_GB": N * 600 / 1e9, **{f"{k}_s": v for k, v in parts.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scaling", default=str(HERE / "results" / "mpi_scaling.json"))
    a = ap.parse_args()
    cal = calibrate(json.loads(Path(a.scaling).read_text()))
    rows = [step_time(cal, N, P) for N in (1e6, 1e7, 1e8, 1e9) for P in (2, 64, 256, 1024)]
    # the same without the whole-state gather (each rank keeping only its own rows)
    distributed = [dict(step_time({**cal, "gather_per_particle_s": 0.0}, N, P),
                        note="host state distributed") for N in (1e7, 1e8, 1e9)
                   for P in (64, 256, 1024)]
    out = {"calibration": cal, "assumed": {"alpha_s": ALPHA, "beta_B_per_s": BETA,
                                          "allreduce_alpha_s": ALPHA_R,
                                          "neighbours": NEIGHBOURS_3D},
           "prediction": rows, "prediction_distributed_host_state": distributed}
    (HERE / "results" / "mpi_model.json").write_text(json.dumps(out, indent=1))
    print(json.dumps(cal, indent=1))
    print(f"{'N':>8} {'P':>5} {'n/rank':>9} {'ghosts':>7} {'eff':>6} {'loss':>8} "
          f"{'GB/rank':>8}   (distributed host state: eff)")
    dist = {(r["particles"], r["ranks"]): r for r in distributed}
    for r in rows:
        d = dist.get((r["particles"], r["ranks"]))
        print(f"{r['particles']:8.0e} {r['ranks']:5d} {r['per_rank']:9.3g} "
              f"{r['ghost_fraction']:7.2f} {r['efficiency']:6.2f} {r['largest_loss']:>8} "
              f"{r['memory_per_rank_GB']:8.2f}   "
              f"{'' if d is None else format(d['efficiency'], '.2f')}")


if __name__ == "__main__":
    main()
