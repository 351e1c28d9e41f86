"""Command line: ``dpm run``, ``dpm sweep``, ``dpm plugins``, ``dpm xdmf``, ``dpm analyse``,
``dpm shapes``, ``dpm validate``, ``dpm new-plugin``, ``dpm compile``, ``dpm clear-cache``,
``dpm advise``."""

from __future__ import annotations

import argparse
import inspect
import sys
import time
from pathlib import Path

from .errors import DpmError, ParameterError


def say(text: str) -> None:
    """Print (on rank 0 only under MPI: every rank runs the same command)."""
    from .parallel import notice

    notice(text)


def _cmd_run(args: argparse.Namespace) -> int:
    if args.reference is not None:
        from .scene_reference import text

        sys.stdout.write(text(args.reference or None))
        return 0
    if args.scene is None:
        raise DpmError("dpm run: give a scene file (dpm run scene.toml), or --reference "
                       "[TABLE] for its tables and keys")
    from .io.scene import load_scene

    sets = args.set or ()
    if args.restart is not None:
        # the scene as the file describes it: the checkpoint must be of it, and the run
        # settings it changes (dt, max_overlap, output interval, ...) take effect
        scene, run_kw = load_scene(args.scene, output=True, create_output=False, sets=sets)
        from .checkpoint import apply_scene_settings, restart

        sim = restart(args.restart, scene=scene)
        changed = apply_scene_settings(sim, scene, args.scene)
        changed += _scene_checkpoints(sim, scene, args.scene)
        say(f"restarted from step {sim.step_count} (t = {sim.time:.6g} s)")
        for line in changed:
            say(f"  {line}")
    else:
        try:
            sim, run_kw = load_scene(args.scene, overwrite=True if args.overwrite else None,
                                     sets=sets)
        except ParameterError as exc:
            if "already exists and is kept" not in str(exc):
                raise
            raise ParameterError(f"{exc} (on the command line: dpm run --overwrite)") from None
    if args.steps is not None:
        run_kw = {"steps": args.steps}
    elif args.until is not None:
        run_kw = {"until": args.until}
    if not run_kw:
        raise DpmError(f"{args.scene}: no [run] table and no --steps/--until given")
    if args.restart is not None and "steps" in run_kw:  # steps count from the start
        run_kw = {"steps": max(0, int(run_kw["steps"]) - sim.step_count)}
    ck = _checkpoints(sim)  # the scene file's [checkpoint] (or the checkpoint's own)
    if args.checkpoint_every is not None or (args.checkpoint is not None and ck is not None):
        # the command line wins over [checkpoint]: its interval, its path
        base = args.checkpoint or (str(ck.base) if ck is not None else
                                   str(Path(args.scene).with_suffix(".ckpt.h5").name))
        every, every_steps = ((args.checkpoint_every, None) if args.checkpoint_every is not None
                              else (ck.every, ck.every_steps))
        sim.checkpoint_every(base, every=every, every_steps=every_steps,
                             keep=ck.keep if ck is not None else 2)
    t0 = time.perf_counter()
    try:
        sim.run(**run_kw, progress=None if not args.no_progress else False)
    finally:
        sim.close()
    wall = time.perf_counter() - t0
    n = len(sim.bodies)
    say(f"{sim.step_count} steps, t = {sim.time:.6g} s, {n} particles, {wall:.1f} s wall "
        f"({n * sim.step_count / max(wall, 1e-9):.3g} particle-steps/s incl. compile)")
    w = sim.last_output
    if w is not None:
        say(f"output: {w.path} ({w.frames} frames) + {w.path.with_suffix('.xdmf').name}")
    return 0


def _checkpoints(sim: object) -> object | None:
    """The periodic-checkpoint schedule of ``sim`` (None: none)."""
    return getattr(getattr(sim, "operations", None), "checkpoints", None)


def _scene_checkpoints(sim: object, scene: object, source: str) -> list[str]:
    """After a restart: the scene file's [checkpoint] interval takes effect where it
    differs from the restored run's (whose base name, perhaps moved beside a copied
    checkpoint, is kept); a line for the change."""
    theirs, mine = _checkpoints(scene), _checkpoints(sim)
    if theirs is None:
        return []
    want = (theirs.every, theirs.every_steps, theirs.keep)
    if mine is not None and (mine.every, mine.every_steps, mine.keep) == want:
        return []
    base = mine.base if mine is not None else theirs.base
    sim.checkpoint_every(base, every=theirs.every, every_steps=theirs.every_steps,
                         keep=theirs.keep)
    every = (f"every {theirs.every:g} s" if theirs.every is not None
             else f"every {theirs.every_steps} steps")
    return [f"checkpoints: {every}, the last {theirs.keep} kept, to {base} (from {source})"]


# ---- dpm sweep -------------------------------------------------------------------------

#: the end quantities of a sweep's table: (column, key of a run's result, format)
SWEEP_COLUMNS = (("steps", "steps", "d"), ("t [s]", "time", ".4g"), ("wall [s]", "wall", ".1f"),
                 ("particles", "particles", "d"), ("KE [J]", "kinetic_energy", ".4g"),
                 ("mean z [m]", "mean_z", ".4g"))


def _sweep_run(scene: str, sets: list[str], run_kw: dict) -> dict:
    """One run of a sweep (in a worker process): the scene with the edits ``sets``, run
    for ``run_kw`` (empty: its [run]); its end quantities, or its error."""
    import math

    t0 = time.perf_counter()
    try:
        from .io.scene import load_scene

        sim, own = load_scene(scene, sets=sets)
        run_kw = run_kw or own
        if not run_kw:
            raise DpmError(f"{scene}: no [run] table and no --steps/--until given")
        try:
            sim.run(**run_kw, progress=False)
        finally:
            sim.close()
        z = sim.bodies.position[:, 2]
        return {"steps": sim.step_count, "time": sim.time, "wall": time.perf_counter() - t0,
                "particles": len(sim.bodies), "kinetic_energy": sim.kinetic_energy(),
                "mean_z": float(z.mean()) if len(z) else math.nan,
                "output": "" if sim.last_output is None else str(sim.last_output.path),
                "error": ""}
    except Exception as exc:  # one run's failure is its row of the table, not the sweep's
        return {"wall": time.perf_counter() - t0, "error": f"{type(exc).__name__}: {exc}"}


def _label(words: list[tuple[str, str]]) -> str:
    """``friction=0.3-dt=1e-05``: a run's values as a file name's part."""
    import re

    return "-".join(f"{k}={re.sub(r'[^A-Za-z0-9.+_-]+', '_', v).strip('_')}"
                    for k, v in words) or "run"


def _cmd_sweep(args: argparse.Namespace) -> int:
    import csv
    import itertools
    import json
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from .scene_file import parse_path, read_scene, split_values

    if args.jobs < 1:
        raise ParameterError(f"dpm sweep: --jobs {args.jobs}; allowed: an integer >= 1")
    axes: list[tuple[str, list[str]]] = []
    for text in args.set:
        if "=" not in text:
            raise ParameterError(f"dpm sweep: --set {text!r}: write PATH=V1,V2,... "
                                 "(contacts[0].friction=0.2,0.3)")
        path, values = (x.strip() for x in text.split("=", 1))
        try:
            parse_path(path)
        except ParameterError as exc:
            raise ParameterError(f"dpm sweep: --set {text}: {exc}") from None
        axes.append((path, split_values(values)))
    swept = [(p, v) for p, v in axes if len(v) > 1]
    lasts = [p.rsplit(".", 1)[-1] for p, _ in swept]
    short = {p: (last if lasts.count(last) == 1 else p)
             for (p, _), last in zip(swept, lasts, strict=True)}
    combos = list(itertools.product(*[[(p, v) for v in values] for p, values in axes]))
    scene = Path(args.scene)
    # every combination checked before any run: a bad path or value is refused now
    docs = [read_scene(scene, [f"{p}={v}" for p, v in c]) for c in combos]
    stem = Path(docs[0].get("output", {}).get("path", scene.name)).stem
    out = Path(args.out)
    runs, labels, existing = [], set(), []
    for k, (combo, doc) in enumerate(zip(combos, docs, strict=True)):
        label = _label([(short[p], v) for p, v in combo if p in short])
        if label in labels:
            label = f"{label}-{k}"
        labels.add(label)
        sets = [f"{p}={v}" for p, v in combo]
        target = None
        if "output" in doc:
            target = out / f"{stem}-{label}.h5"
            sets += [f"output.path={json.dumps(str(target))}",
                     f"output.overwrite={'true' if args.overwrite else 'false'}"]
            if target.exists() and not args.overwrite:
                existing.append(str(target))
        if "checkpoint" in doc:
            sets.append(f"checkpoint.path={json.dumps(str(out / f'{stem}-{label}.ckpt.h5'))}")
        runs.append((combo, sets, target))
    if existing:
        raise ParameterError(f"dpm sweep: {len(existing)} output file(s) already exist and "
                             f"are kept: {', '.join(existing)} (dpm sweep --overwrite "
                             "replaces them)")
    out.mkdir(parents=True, exist_ok=True)
    run_kw = ({"steps": args.steps} if args.steps is not None
              else {"until": args.until} if args.until is not None else {})
    results: list[dict] = [{}] * len(runs)
    say(f"{len(runs)} run(s) of {scene} on {min(args.jobs, len(runs))} process(es)")
    t0 = time.perf_counter()
    spawn = multiprocessing.get_context("spawn")  # (fresh workers: no forked threads)
    with ProcessPoolExecutor(max_workers=min(args.jobs, len(runs)), mp_context=spawn) as pool:
        todo = {pool.submit(_sweep_run, str(scene), sets, run_kw): k
                for k, (_, sets, _) in enumerate(runs)}
        for done, fut in enumerate(as_completed(todo), 1):
            k = todo[fut]
            results[k] = fut.result()
            what = results[k]["error"] or f"{results[k]['wall']:.1f} s"
            print(f"[{done}/{len(runs)}] {', '.join(f'{p}={v}' for p, v in runs[k][0])}: "
                  f"{what}", file=sys.stderr, flush=True)
    head = [p for p, _ in axes] + [c for c, _, _ in SWEEP_COLUMNS] + ["output"]
    table = []
    for (combo, _, _), r in zip(runs, results, strict=True):
        row = [v for _, v in combo]
        for _, key, f in SWEEP_COLUMNS:
            row.append(format(r[key], f) if key in r else "-")
        row.append(r.get("output") or ("error: " + r["error"] if r["error"] else "-"))
        table.append(row)
    w = [max(len(str(x)) for x in col) for col in zip(head, *table, strict=True)]
    for row in [head, *table]:
        say("  ".join(f"{str(x):<{w[i]}}" for i, x in enumerate(row[:-1])) + "  " + row[-1])
    failed = sum(bool(r["error"]) for r in results)
    say(f"{len(runs)} run(s) in {time.perf_counter() - t0:.1f} s"
        + (f"; {failed} failed" if failed else ""))
    if args.csv:
        with open(args.csv, "w", newline="", encoding="utf-8") as f:
            csv.writer(f).writerows([head, *table])
    return 1 if failed else 0


def summary_of(obj: object) -> str:
    """The first sentence of ``obj``'s docstring as plain text: reST roles and literals
    unwrapped (``:class:`~a.b.C``` -> C, ````x```` -> x), lines joined, never cut."""
    import re

    doc = inspect.getdoc(obj) or ""
    para = " ".join(doc.split("\n\n")[0].split())
    para = re.sub(r":[a-z]+:`~?([^`<]*?)(?:\s*<[^>]*>)?`",
                  lambda m: m.group(1).rsplit(".", 1)[-1]
                  if m.group(0).count("~") else m.group(1), para)
    para = re.sub(r"``([^`]*)``", r"\1", para)
    para = re.sub(r"(?<![\w*])\*([^*]+)\*(?![\w*])", r"\1", para)
    # a sentence ends at a full stop before a capital or the end ("eq. 2.53" goes on)
    m = re.search(r"(?<!\be\.g)(?<!\bi\.e)\.(?=\s+[A-Z]|$)", para)
    return para[:m.start() + 1] if m else para


def _cmd_plugins(args: argparse.Namespace) -> int:
    from .plugins import KINDS, registry

    reg = registry()
    rows = []
    for kind in KINDS:
        for name in reg.names(kind):
            e = reg.entries[kind][name]
            rows.append((kind, name, e.source, e.version or "-",
                         f"{e.cls.__module__}.{e.cls.__qualname__}", summary_of(e.cls)))
    cols = ["kind", "name", "source", "version"] + (["class"] if args.verbose else [])
    w = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(cols)]
    print("  ".join(f"{c:<{w[i]}}" for i, c in enumerate(cols)) + "  summary")
    for r in rows:
        print("  ".join(f"{r[i]:<{w[i]}}" for i in range(len(cols))) + "  " + r[5])
    for (kind, name), entries in sorted(reg.conflicts.items()):
        print(f"CONFLICT {kind} {name!r}: registered by "
              + " and by ".join(e.source for e in entries))
    for source in reg.blocked:
        print(f"BLOCKED plugin {source} (DPM_BLOCK_PLUGINS)")
    for source, why in reg.broken:
        print(f"BROKEN plugin {source}: {why}")
    return 0


def _cmd_xdmf(args: argparse.Namespace) -> int:
    from .io.xdmf import write_xdmf

    print(write_xdmf(args.run))
    return 0


def _cmd_analyse(args: argparse.Namespace) -> int:
    from .analysis.cli import analyse

    return analyse(args)


def _cmd_shapes(args: argparse.Namespace) -> int:
    from .shapes.metrics import report_table

    res = None if args.resolutions is None else [float(x) for x in args.resolutions.split(",")]
    print(report_table(args.shapes, res, samples=args.samples))
    return 0


def _cmd_clear_cache(args: argparse.Namespace) -> int:
    from .plan import clear_cache

    removed = clear_cache()
    print(f"removed {len(removed)} cached kernel file(s)")
    return 0


def _cmd_compile(args: argparse.Namespace) -> int:
    from .warm import compile_builtins

    t0 = time.perf_counter()
    print("compiling the universal step kernels (every built-in contact law and boundary "
          "kind), one module per integrator:", flush=True)
    done = compile_builtins(args.integrator, jobs=args.jobs,
                            say=lambda text: print(text, flush=True))
    print(f"{len(done)} module(s) in {time.perf_counter() - t0:.1f} s; new scenes of built-in "
          "parts now start without compiling")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from . import validation

    rows = validation.run(cases=args.case, quick=args.quick, models=args.model,
                          progress=lambda text: print(text, file=sys.stderr, flush=True))
    print(validation.table(rows))
    if args.markdown:
        Path(args.markdown).write_text(validation.table(rows, markdown=True) + "\n")
    if args.json:
        Path(args.json).write_text(validation.to_json(rows) + "\n")
    failed = len(validation.unexpected(rows))
    known = sum(not r.passed for r in rows) - failed
    print(f"{sum(r.passed for r in rows)} of {len(rows)} rows within tolerance"
          + (f"; {known} known failure(s), explained in docs/validation.md" if known else "")
          + (f"; {failed} FAILED" if failed else ""))
    return 1 if failed else 0


def _cmd_new_plugin(args: argparse.Namespace) -> int:
    from .scaffold import new_plugin

    root = new_plugin(args.name, args.dir)
    print(f"created {root}: python -m pytest {root} runs its tests; pip install -e {root} "
          "makes dpm find it (dpm plugins)")
    return 0


def _cmd_advise(args: argparse.Namespace) -> int:
    import json

    from .advice import advise
    from .io.scene import load_scene

    sim, run_kw = load_scene(args.scene, output=False)
    run_time = args.run_time
    if run_time is None and run_kw:
        run_time = (float(run_kw["until"]) if "until" in run_kw
                    else float(run_kw.get("steps", 0)) * sim.dt or None)
    advice = advise(sim, tolerance=args.tolerance, quantity=args.quantity, verify=args.verify,
                    run_time=run_time, window=None if args.window is None else
                    tuple(args.window), impact_speed=args.impact_speed,
                    integrators=args.integrator, models=args.model,
                    max_rayleigh=args.max_rayleigh,
                    pilot=lambda: load_scene(args.scene, output=False)[0])
    print(advice)
    if args.json:
        Path(args.json).write_text(json.dumps(advice.as_dict(), indent=1, default=str) + "\n")
    return 0


_RUN_EPILOG = """\
The tables of a scene file (dpm run --reference TABLE prints one's keys, with units,
defaults and ranges; docs/scene-files.md has them all):
{tables}

A number goes in the key's unit; a string is a quantity converted to it: "2 mm",
"30 deg", "5e6 Pa", "sin(30 deg)", "2 mm / 2" (dpm run --reference units). A
value of another dimension is refused by name.

examples:
  dpm run examples/box_settle.toml --steps 2000
  dpm run scene.toml --set contacts[0].friction=0.3 --set simulation.dt=1e-5
  dpm run --reference boundaries.tube
  dpm sweep scene.toml --set contacts[0].friction=0.2,0.3,0.4 --jobs 2
"""


class _RunHelp(argparse.RawDescriptionHelpFormatter):
    """``dpm run --help``: the tables of a scene file listed in the epilog (made only
    when the help is shown)."""

    def add_text(self, text: str | None) -> None:
        if text and "{tables}" in text:
            from .scene_reference import index

            text = text.replace("{tables}", index())
        super().add_text(text)


def main(argv: list[str] | None = None) -> int:
    from .plugins import version

    p = argparse.ArgumentParser(prog="dpm", description="Discrete Particle Method (DEM)")
    p.add_argument("--version", action="version", version=f"dpm {version()}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a TOML scene file", formatter_class=_RunHelp,
                       description="Build the scene a TOML file describes and run it "
                       "(every table and key:\ndocs/scene-files.md, or --reference).",
                       epilog=_RUN_EPILOG)
    r.add_argument("scene", nargs="?", help="the scene file")
    r.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                   help="change a value of the file before it is checked and built "
                   "(repeatable): contacts[0].friction=0.3, simulation.dt=1e-5, "
                   "'particles[0].radius=2 mm'; VALUE is a TOML value or else text")
    r.add_argument("--reference", nargs="?", const="", default=None, metavar="TABLE",
                   help="print the tables and keys of a scene file (with units, defaults "
                   "and ranges) and exit; TABLE: one of them (boundaries, "
                   "boundaries.box, units)")
    g = r.add_mutually_exclusive_group()
    g.add_argument("--steps", type=int, help="override the scene's [run]")
    g.add_argument("--until", type=float, help="override the scene's [run] (seconds)")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--overwrite", action="store_true",
                   help="replace an existing output file (it is kept otherwise)")
    r.add_argument("--restart", metavar="CHECKPOINT", default=None,
                   help="go on from a checkpoint of this scene (a file, or the base name of "
                   "numbered ones: the newest). A checkpoint is plain data: loading it "
                   "runs no code from the file. The run's output file "
                   "is continued only from a checkpoint where its run wrote it; a copy "
                   "restarted elsewhere leaves the original's files alone and writes no "
                   "output)")
    r.add_argument("--checkpoint-every", type=float, default=None, metavar="SECONDS",
                   help="write checkpoints every SECONDS of simulated time (wins over the "
                   "file's [checkpoint])")
    r.add_argument("--checkpoint", default=None, metavar="PATH",
                   help="base name of the checkpoints (default: [checkpoint] path, else "
                   "SCENE.ckpt.h5)")
    r.set_defaults(func=_cmd_run)
    sw = sub.add_parser("sweep", help="run a scene file for every combination of values "
                        "(--set PATH=V1,V2,...) on a pool of processes; print a table of "
                        "the results", description="Run a TOML scene file once for every "
                        "combination of the values of its --set options (their product), "
                        "each run in a worker process with its own output file "
                        "(OUT/SCENE-KEY=VALUE.h5); print the values with each run's steps, "
                        "simulated and wall time, particles, kinetic energy and mean "
                        "height. Exit status 1 if a run failed (its row says why).")
    sw.add_argument("scene", help="the scene file")
    sw.add_argument("--set", action="append", default=[], required=True,
                    metavar="PATH=V1[,V2...]", help="the values of a key (repeatable; "
                    "commas inside brackets or quotes do not split): "
                    "contacts[0].friction=0.2,0.3,0.4")
    sw.add_argument("--jobs", type=int, default=1, help="runs at once, each in its own "
                    "process (default 1)")
    gs = sw.add_mutually_exclusive_group()
    gs.add_argument("--steps", type=int, help="override the scene's [run]")
    gs.add_argument("--until", type=float, help="override the scene's [run] (seconds)")
    sw.add_argument("--out", default=".", metavar="DIR", help="folder of the runs' output "
                    "files (default: here)")
    sw.add_argument("--overwrite", action="store_true", help="replace existing output files")
    sw.add_argument("--csv", default=None, metavar="FILE", help="also write the table as CSV")
    sw.set_defaults(func=_cmd_sweep)
    pl = sub.add_parser("plugins", help="list every registered shape, boundary, impact model, "
                        "integrator, backend, motion, region and rolling model")
    pl.add_argument("-v", "--verbose", action="store_true", help="with each one's class")
    pl.set_defaults(func=_cmd_plugins)
    x = sub.add_parser("xdmf", help="(re)write the XDMF sidecar of an HDF5 run")
    x.add_argument("run")
    x.set_defaults(func=_cmd_xdmf)
    a = sub.add_parser("analyse", help="print residence times, flow rates, energies, the "
                       "thermo log, mixing, coordination, drum surface of an HDF5 run; draw "
                       "a frame", description="Options take KEY=VALUE words; see "
                       "docs/analysis.md. With no option: a summary.")
    a.add_argument("run")
    a.add_argument("--residence", nargs="*", metavar="KEY=VALUE",
                   help="residence time distribution (outlet=K, mass=1, bins=N)")
    a.add_argument("--flow", nargs="+", metavar="KEY=VALUE",
                   help="mass flow rate through a plane (z=0.0 [normal=0,0,-1; default: along "
                   "gravity] [bin=S]) or "
                   "out of the outlets (outlet[=K] bin=S)")
    a.add_argument("--energy", action="store_true", help="kinetic energy of every frame")
    a.add_argument("--thermo", action="store_true", help="the /thermo table")
    a.add_argument("--lacey", nargs="+", metavar="KEY=VALUE",
                   help="Lacey mixing index against time: cell=S and material=K or "
                   "below=ID (species A: ids < ID) [min=N]")
    a.add_argument("--coordination", nargs="*", metavar="KEY=VALUE",
                   help="coordination number distribution (frame=K, tol=X)")
    a.add_argument("--drum", nargs="+", metavar="KEY=VALUE",
                   help="drum free surface and angle of repose: radius=R axis=0,1,0 "
                   "[point=0,0,0] [frame=K] [method=highest|fraction]")
    a.add_argument("--picture", nargs="*", metavar="KEY=VALUE",
                   help="draw a frame: frame=-1 color=speed view=xz|3d out=frame.png")
    a.set_defaults(func=_cmd_analyse)
    s = sub.add_parser("shapes", help="sphere count, volume and surface error of shapes at "
                       "several resolutions")
    s.add_argument("shapes", nargs="+", help="registered name (cylinder, 'block:a=4e-3,b=2e-3'),"
                   " library name (rock) or mesh file (grain.stl:scale=1e-3)")
    s.add_argument("--resolutions", default=None, help="comma-separated, e.g. 0.1,0.3,0.6")
    s.add_argument("--samples", type=int, default=4000, help="surface samples per shape")
    s.set_defaults(func=_cmd_shapes)
    sub.add_parser("clear-cache", help="delete compiled kernels and generated step modules"
                   ).set_defaults(func=_cmd_clear_cache)
    c = sub.add_parser("compile", help="compile the universal step kernels ahead (every "
                       "built-in law and boundary kind; once per install): new scenes then "
                       "start in seconds")
    c.add_argument("--integrator", action="append", default=None, metavar="NAME",
                   help="only this integrator (repeatable; default: every built-in one)")
    c.add_argument("--jobs", type=int, default=1, help="modules compiled at once, each in "
                   "its own process (default 1)")
    c.set_defaults(func=_cmd_compile)
    v = sub.add_parser("validate", help="run the validation cases (Chung & Ooi 2011 impact "
                       "benchmarks and analytic cases) and print the table; exit status 1 "
                       "if a row is outside its tolerance (docs/validation.md)")
    v.add_argument("--quick", action="store_true", help="fewer impacts, coarser steps")
    v.add_argument("--model", action="append", default=None, metavar="NAME",
                   help="only this impact model (repeatable)")
    v.add_argument("--case", action="append", default=None, metavar="NAME",
                   help="only this case: co1 ... co8, sandwich, rolling_stop, flip, "
                   "jkr_pull_off, jkr_sticking (repeatable)")
    v.add_argument("--markdown", default=None, metavar="FILE", help="also write the table "
                   "as Markdown")
    v.add_argument("--json", default=None, metavar="FILE", help="also write the rows as JSON")
    v.set_defaults(func=_cmd_validate)
    n = sub.add_parser("new-plugin", help="create a plugin package NAME (pyproject with the "
                       "entry point, an impact model and a shape, tests with dpm.testing)")
    n.add_argument("name", metavar="NAME", help="distribution name, e.g. dpm-pebbles")
    n.add_argument("--dir", default=".", help="where to create NAME/ (default: here)")
    n.set_defaults(func=_cmd_new_plugin)
    ad = sub.add_parser("advise", help="the cheapest impact model, integrator, time step, "
                        "skin, shape resolution and number of replicas (runs with perturbed "
                        "starts, averaged) that meet a tolerance on a quantity, with the "
                        "predicted error and cost (docs/advise.md)")
    ad.add_argument("scene", help="a TOML scene file")
    ad.add_argument("--tolerance", type=float, default=0.01,
                    help="relative error of the quantity allowed (default 0.01: 1 %%)")
    ad.add_argument("--quantity", default="settled_height",
                    help="settled_height, angle_of_repose or discharge_rate")
    ad.add_argument("--verify", action="store_true", help="also run the scene at the chosen "
                    "step and at half of it (Richardson estimate of the error)")
    ad.add_argument("--run-time", type=float, default=None, metavar="SECONDS",
                    help="simulated time of the run (default: the scene's [run])")
    ad.add_argument("--window", type=float, nargs=2, default=None, metavar=("START", "END"),
                    help="the quantity's averaging window [s]")
    ad.add_argument("--impact-speed", type=float, default=None, metavar="M_S",
                    help="the speed contacts are resolved at (default: the time-step check's)")
    ad.add_argument("--integrator", action="append", default=None, metavar="NAME",
                    help="only this integrator (repeatable)")
    ad.add_argument("--model", action="append", default=None, metavar="NAME",
                    help="only this impact model ('as set': the scene's own; repeatable)")
    ad.add_argument("--max-rayleigh", type=float, default=0.3,
                    help="largest step as a fraction of the Rayleigh step (default 0.3)")
    ad.add_argument("--json", default=None, metavar="FILE", help="also write the advice "
                    "as JSON")
    ad.set_defaults(func=_cmd_advise)
    args = p.parse_args(argv)
    try:
        return args.func(args)
    except DpmError as exc:
        print(f"dpm: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
