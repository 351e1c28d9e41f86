"""Where the meshGran port's step time goes, on one thread and on two (dpm alone).

benchmarks/meshgran.py times the whole run of LIGGGHTS' meshGran tutorial port (500
spheres streamed onto an STL chute into a container) against LIGGGHTS. This script stops
the same scene at a few moments (while streaming, while the heap slides into the
container, settled), and from each:

* runs blocks of steps on 1 and 2 threads in turn (``sim.threads``: the same bits for any
  count) and reports the median microseconds per step, the two-thread gain and the list
  rebuilds per 1,000 steps;
* times the parts of a step on one thread: the integrator's pre-force part, the fused
  force pass (on 1 and on 2 threads), and one list rebuild split into the pair list and
  the boundary list; and one boundary search pass on the scene's table against the same
  boundaries with a search grid forced on.

    python benchmarks/meshgran_steps.py [--blocks 4]

Writes benchmarks/results/meshgran_steps.json.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: (time [s] at which the scene is looked at, steps per timed block)
MOMENTS = ((0.45, 400), (1.0, 1000), (2.0, 2000))


def best_us(fn, args: tuple, reps: int) -> float:
    """Best of five means of ``reps`` calls ``fn(*args)``, microseconds per call (after one
    call); each includes numba's unpacking of the arguments, a few microseconds that the
    compiled step loop does not pay."""
    fn(*args)
    best = float("inf")
    for _ in range(5):
        t = time.perf_counter()
        for _ in range(reps):
            fn(*args)
        best = min(best, (time.perf_counter() - t) / reps * 1e6)
    return best


def search_with_and_without_grid(sim, m, skin: float, ghost: int) -> dict:
    """One boundary search pass on the scene's own table and on the same boundaries with a
    search grid forced on (``dpm.state.GRID_FROM`` = 0), three times in turn: the mesh has
    18 triangles, under the size from which dpm grids a boundary."""
    import numpy as np

    import dpm.state

    e, own = sim.backend.records()[2], sim.walls
    keep = dpm.state.GRID_FROM
    dpm.state.GRID_FROM = 0
    try:
        gridded = dpm.state.BoundaryTable(sim.boundaries, lambda mat: sim._material_index(mat, ""),
                                          float(e.radius.max()) + skin)
    finally:
        dpm.state.GRID_FROM = keep
    gridded.frame[:] = own.frame
    times: dict[str, list[float]] = {"plain_loop": [], "grid": []}
    entries = {}
    for _ in range(3):
        for name, t in (("plain_loop", own), ("grid", gridded)):
            counts = np.zeros(len(e.radius), np.int64)
            starts = np.zeros(len(e.radius) + 1, np.int64)
            args = (e.pos, e.radius, skin, t.frame, t.kind, t.par, t.grid_int, t.grid_flt,
                    t.cell_start, t.cell_items, t.prim_cells, counts, starts, starts[1:],
                    starts[:0], False, np.arange(ghost))
            times[name].append(best_us(m.boundary_search_pass, args, 200))
            entries[name] = int(counts.sum())
    assert entries["plain_loop"] == entries["grid"], entries
    return {"boundary_search_own_grid_on": bool(own.grid_int[:, 0].any()),
            "boundary_search_plain_loop_us": min(times["plain_loop"]),
            "boundary_search_grid_us": min(times["grid"])}


def parts(sim, numba) -> dict:
    """The step's parts timed on the scene's current state (each call changes it little:
    a step's worth of motion at most)."""
    be = sim.backend
    out = {}
    for th in (1, 2):
        sim.threads = th
        sim.run(steps=2, progress=False)  # (the thread count's form of the step module)
        numba.set_num_threads(th)
        m = be.module
        ctl, bodies, elems, pairs, walls, bnd = be.records()
        if th == 1:
            skin = ctl.skin + ctl.reach
            ghost = bodies.estart[ctl.n_owned]
            out["pre_force_us"] = best_us(m.pre_force, (0.0, ctl, bodies, elems), 300)
            out["rebuild_us"] = best_us(
                m.rebuild, (ctl, bodies, elems, pairs, walls, bnd, be.diag), 50)
            out["pair_list_us"] = best_us(m.build_neighbour_list, (
                elems.pos, elems.radius, elems.owner, skin, pairs.start, pairs.key,
                pairs.hist, pairs.active, pairs.t_start, pairs.t_pair, ctl.period, ghost), 50)
            out["boundary_list_us"] = best_us(m.build_boundary_list, (
                elems.pos, elems.radius, skin, bnd.frame, bnd.kind, bnd.par, bnd.grid_int,
                bnd.grid_flt, bnd.cell_start, bnd.cell_items, bnd.prim_cells, walls.start,
                walls.key, walls.hist, walls.active, ghost), 50)
            out.update(search_with_and_without_grid(sim, m, skin, ghost))
        if m.FUSED:
            out[f"force_pass_{th}_threads_us"] = best_us(
                m.fused_pass, (0.0, False, ctl, bodies, elems, pairs, walls, bnd), 300)
    out.update(listed_pairs=int(sim.contacts.count),
               boundary_entries=int(sim.wall_contacts.count))
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blocks", type=int, default=4,
                    help="timed blocks per thread count at each moment (default 4)")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    import meshgran as mg
    import numba

    import dpm  # noqa: F401  (first: it picks numba's OpenMP layer before any launch)

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        sim, _ = mg.scene(Path(tmp), 0.5)
        for t_at, block in MOMENTS:
            sim.threads = 2
            sim.run(until=t_at, progress=False)
            us: dict[int, list[float]] = {1: [], 2: []}
            rebuilds = {1: 0, 2: 0}
            for k in range(2 * a.blocks):
                th = 1 + k % 2
                sim.threads = th
                r0 = sim.rebuild_count
                t0 = time.perf_counter()
                sim.run(steps=block, progress=False)
                us[th].append((time.perf_counter() - t0) / block * 1e6)
                rebuilds[th] += sim.rebuild_count - r0
            row = {"from_time_s": t_at, "bodies": len(sim.bodies), "block_steps": block,
                   "us_per_step": {th: statistics.median(v) for th, v in us.items()},
                   "blocks_us": us,
                   "rebuilds_per_1000_steps": 1000.0 * sum(rebuilds.values())
                   / (2 * a.blocks * block)}
            row["two_thread_gain"] = row["us_per_step"][1] / row["us_per_step"][2]
            row["parts"] = parts(sim, numba)
            rows.append(row)
            p = row["parts"]
            print(f"from t = {t_at} s, {row['bodies']} bodies: {row['us_per_step'][1]:.0f} us "
                  f"per step on 1 thread, {row['us_per_step'][2]:.0f} on 2 "
                  f"(gain {row['two_thread_gain']:.2f}), "
                  f"{row['rebuilds_per_1000_steps']:.0f} rebuilds per 1,000 steps; "
                  f"one rebuild {p['rebuild_us']:.0f} us (pairs {p['pair_list_us']:.0f}, "
                  f"boundary {p['boundary_list_us']:.0f}), pre-force {p['pre_force_us']:.0f}"
                  + (f", force pass {p['force_pass_1_threads_us']:.0f} / "
                     f"{p['force_pass_2_threads_us']:.0f} us on 1 / 2 threads"
                     if "force_pass_1_threads_us" in p else "")
                  + f"; boundary search {p['boundary_search_plain_loop_us']:.0f} us plain loop, "
                  f"{p['boundary_search_grid_us']:.0f} with a grid", flush=True)
    result = {"scene": "meshGran port (benchmarks/meshgran.py), dpm alone",
              "blocks": a.blocks, "moments": rows}
    out = HERE / "results" / "meshgran_steps.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
    print("wrote", out)
    return result


if __name__ == "__main__":
    main()
