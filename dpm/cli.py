"""Command line: ``dpm run``, ``dpm plugins``, ``dpm xdmf``, ``dpm analyse``, ``dpm shapes``,
``dpm validate``, ``dpm new-plugin``, ``dpm compile``, ``dpm clear-cache``, ``dpm advise``."""

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
    from .io.scene import load_scene

    if args.restart is not None:
        # the scene as the file describes it: the checkpoint must be of it, and the run
        # settings it changes (dt, max_overlap, output interval, ...) take effect
        scene, run_kw = load_scene(args.scene, output=True, create_output=False)
        from .checkpoint import apply_scene_settings, restart

        sim = restart(args.restart, scene=scene)
        changed = apply_scene_settings(sim, scene, args.scene)
        say(f"restarted from step {sim.step_count} (t = {sim.time:.6g} s)")
        for line in changed:
            say(f"  {line}")
    else:
        try:
            sim, run_kw = load_scene(args.scene, overwrite=True if args.overwrite else None)
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
    if args.checkpoint_every is not None:
        base = args.checkpoint or str(Path(args.scene).with_suffix(".ckpt.h5").name)
        sim.checkpoint_every(base, every=args.checkpoint_every)
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


def main(argv: list[str] | None = None) -> int:
    from .plugins import version

    p = argparse.ArgumentParser(prog="dpm", description="Discrete Particle Method (DEM)")
    p.add_argument("--version", action="version", version=f"dpm {version()}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a TOML scene file")
    r.add_argument("scene")
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
                   help="write checkpoints every SECONDS of simulated time")
    r.add_argument("--checkpoint", default=None, metavar="PATH",
                   help="base name of the checkpoints (default: SCENE.ckpt.h5)")
    r.set_defaults(func=_cmd_run)
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
                   help="mass flow rate through a plane (z=0.0 [normal=0,0,-1] [bin=S]) or "
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
