"""Every peer scene of dpm against LIGGGHTS in one go: one table and one plot of the speed
ratios (dpm / LIGGGHTS, > 1: dpm faster) and of the physics agreement.

Runs, one after the other on this machine (so the ratios share its load), each scene's own
benchmark script, which runs dpm and LIGGGHTS side by side and writes its JSON:

=================  =============================  ==========================================
scene              script                         physics compared
=================  =============================  ==========================================
box_settle         benchmarks/box_settle.py       mean settled height (1e4 and 1e3 spheres)
clusters           benchmarks/clusters_settle.py  settled height, packing (fix multisphere)
meshGran (STL)     benchmarks/meshgran.py         inserted and contained counts
rotating drum      benchmarks/drum_peer.py        dynamic angle of repose (move/mesh)
mesh floors        benchmarks/boundaries.py       (speed only: 2 to 2e5 triangles)
=================  =============================  ==========================================

then reads the JSONs and writes ``benchmarks/results/peers.json`` (``peers_quick.json``)
and ``peers.png``. ``--quick`` passes ``--quick`` to each script and runs only the scenes
of ``QUICK_SCENES`` (the others' quick runs take minutes each; ``--only`` picks any);
``--collect`` only reads the JSONs already there (no runs); ``--only NAME`` runs a subset
(repeatable).

    python benchmarks/peers.py [--quick] [--collect] [--only box_settle ...]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent

#: name -> (script, JSON stem[, the script's arguments])
SCENES = {
    "box_settle": ("box_settle.py", "box_settle"),
    "box_settle_1e3": ("box_settle.py", "box_settle_1e3",
                       ["--lattice", "10", "10", "10", "--steps", "20000", "--tag",
                        "box_settle_1e3"]),
    "clusters": ("clusters_settle.py", "clusters_settle"),
    "meshgran": ("meshgran.py", "meshgran"),
    "drum": ("drum_peer.py", "drum_peer"),
    "mesh_floors": ("boundaries.py", "boundaries"),
}
#: --quick without --only: the scenes whose quick runs take well under a minute (every
#: script also runs its own --quick in tests/examples/test_benchmarks_quick.py)
QUICK_SCENES = ("box_settle", "mesh_floors")


def _json(stem: str, quick: bool) -> dict | None:
    """A scene's results (the quick file if asked and present, else the full one)."""
    for name in ((f"{stem}_quick", stem) if quick else (stem,)):
        path = harness.RESULTS / f"{name}.json"
        if path.exists():
            return json.loads(path.read_text()) | {"_file": path.name}
    return None


def _find(d, *keys, default=None):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return default
        d = d[k]
    return d


def summarise(name: str, d: dict) -> list[dict]:
    """Rows (scene, variant, speed ratio one core, two threads, physics) of one JSON."""
    rows: list[dict] = []
    src = d.get("_file", "")
    if name in ("box_settle", "box_settle_1e3"):
        dz = d.get("mean_z_rel_diff")  # (None without the peer)
        rows.append({"scene": "box_settle", "variant": "x".join(map(str, d.get("lattice", []))),
                     "ratio_1": d.get("ratio"), "ratio_2": d.get("ratio_2_threads"),
                     "physics": f"mean height {100 * dz:+.2f} %" if dz is not None
                     else f"peer {d.get('peer', 'missing')}", "file": src})
    elif name == "clusters":
        sr = d.get("speed_ratios", {})
        phys = _find(d, "physics") or {}
        text = ", ".join(f"{k} {v:+.2f} %" if isinstance(v, float) else f"{k} {v}"
                         for k, v in phys.items() if "diff" in k or "rel" in k) or "see JSON"
        rows.append({"scene": "clusters", "variant": f"{d.get('bodies')} bodies, settled",
                     "ratio_1": _find(sr, "dpm_over_liggghts", "settle"),
                     "ratio_2": _find(sr, "dpm_2_threads_over_liggghts", "settle"),
                     "physics": text, "file": src})
    elif name == "meshgran":
        rows.append({"scene": "meshGran (STL + stream)", "variant": "whole loop",
                     "ratio_1": d.get("speed_ratio_dpm_over_liggghts"),
                     "ratio_2": d.get("speed_ratio_dpm_2_threads_over_liggghts"),
                     "physics": json.dumps(d.get("physics", {}))[:80], "file": src})
    elif name == "drum":
        sr = d.get("speed") or d.get("speed_ratios", {})  # (drum_peer.py writes "speed")
        phys = json.dumps(d.get("physics", {}))[:80]
        for variant in ("mesh", "tube"):
            rows.append({"scene": "rotating drum", "variant": f"{variant} (steady window)",
                         "ratio_1": _find(sr, f"{variant}_1_thread_over_liggghts", "window"),
                         "ratio_2": _find(sr, f"{variant}_2_threads_over_liggghts_window"),
                         "physics": phys, "file": src})
    elif name == "mesh_floors":
        for m in d.get("mesh", []):
            r = m.get("ratio_dpm_over_liggghts")  # (time ratio: invert to speed)
            rows.append({"scene": "mesh floor", "variant": f"{m['triangles']} triangles",
                         "ratio_1": (1.0 / r) if r else None, "ratio_2": None,
                         "physics": "(speed only)", "file": src})
        # the same 2,000 spheres on one floor meshed ever finer (timed on two threads too)
        for m in d.get("mesh_fixed_floor") or []:
            r = m.get("ratio_dpm_over_liggghts")
            r2 = m.get("ratio_dpm_2_threads_over_liggghts")
            rows.append({"scene": "mesh floor, 2,000 spheres",
                         "variant": f"{m['triangles']} triangles",
                         "ratio_1": (1.0 / r) if r else None,
                         "ratio_2": (1.0 / r2) if r2 else None,
                         "physics": "(speed only)", "file": src})
    return rows


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['scene']}\n{r['variant']}" for r in rows]
    one = [r["ratio_1"] or 0.0 for r in rows]
    two = [r["ratio_2"] or 0.0 for r in rows]
    fig, ax = plt.subplots(figsize=(max(8, 0.8 * len(rows)), 4.5))
    x = range(len(rows))
    ax.bar([i - 0.2 for i in x], one, 0.4, label="dpm 1 thread / LIGGGHTS 1 core")
    ax.bar([i + 0.2 for i in x], two, 0.4, label="dpm 2 threads / LIGGGHTS 1 core")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhline(1.8, color="grey", ls="--", lw=0.8, label="2-thread goal 1.8")
    ax.set_xticks(list(x), labels, fontsize=7, rotation=30, ha="right")
    ax.set_ylabel("speed ratio (> 1: dpm faster)")
    ax.set_title("dpm against LIGGGHTS, each scene run side by side")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "each scene script's --quick, box_settle and the mesh "
                        "floors only unless --only")
    ap.add_argument("--collect", action="store_true", help="only read the JSONs there")
    ap.add_argument("--only", action="append", choices=list(SCENES), default=None)
    args = ap.parse_args(argv)
    names = args.only or list(QUICK_SCENES if args.quick and not args.collect else SCENES)
    walls = {}
    if not args.collect:
        for name in names:
            script = HERE / SCENES[name][0]
            if not script.exists():
                print(f"{name}: {script.name} missing, skipped", file=sys.stderr)
                continue
            extra = list(SCENES[name][2]) if len(SCENES[name]) > 2 else []
            if args.quick and extra:
                continue  # (a size of its own: no quick form)
            cmd = [sys.executable, str(script), "--results", str(harness.RESULTS)] + (
                ["--quick"] if args.quick else extra)
            print(f"== {name}: {' '.join(cmd[1:])}", flush=True)
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True)
            walls[name] = time.perf_counter() - t0
    rows = []
    for name in names:
        d = _json(SCENES[name][1], args.quick)
        if d is None:
            print(f"{name}: no results", file=sys.stderr)
            continue
        rows += summarise(name, d)
    for r in rows:  # (a script whose JSON names a figure otherwise: no bar, not a crash)
        for k in ("ratio_1", "ratio_2"):
            if not isinstance(r[k], int | float):
                r[k] = None
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    out = {"quick": args.quick, "collected_only": args.collect, "load_average_at_end": load,
           "peer": None if args.collect else harness.peer(),
           "script_wall_s": walls, "rows": rows}
    path = harness.write("peers", out, args.quick)
    if rows:
        harness.png(plot, rows, path=path.with_suffix(".png"))
    for r in rows:
        r1 = f"{r['ratio_1']:.2f}" if r["ratio_1"] else "-"
        r2 = f"{r['ratio_2']:.2f}" if r["ratio_2"] else "-"
        print(f"{r['scene']:<26} {r['variant']:<22} 1 thread {r1:>6}  2 threads {r2:>6}  "
              f"{r['physics']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
