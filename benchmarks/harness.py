"""The benchmarks' shared harness (in the manner of hoomd-benchmarks).

Every benchmark in this folder answers one question, takes ``--quick`` (a short run of the
same measurement, minutes rather than an hour) and writes ``results/NAME.json`` (or
``NAME_quick.json``; a PNG beside it where the benchmark draws one). What they share:

- :func:`parser`: an argument parser with ``--quick`` and ``--results DIR`` (where this
  run's files go, default ``benchmarks/results``: a run elsewhere leaves the shipped
  results alone; every file a benchmark writes goes under :data:`RESULTS`, read at call
  time as ``harness.RESULTS``);
- :func:`repeat`: warm-up calls, then repeats; median, min and max;
- :func:`ratio`: a figure against the peer's (LIGGGHTS) measured in the same run;
  :func:`peer`: what the JSON says of that peer (run, skipped, or missing: then dpm's
  figures only, never a failed run);
- :func:`machine`: the facts a figure depends on besides dpm's code;
- :func:`write`: the JSON, with those facts under ``"run"``; :func:`png`: the plot, when
  matplotlib is installed (``pip install -e '.[bench]'``);
- :func:`example`: a scene of ``examples/`` loaded by path (no ``sys.path`` edits).

Run a benchmark from the repository root: ``python benchmarks/NAME.py [--quick]``; the
folder of the script is then on ``sys.path`` and ``import harness`` finds this file.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SHIPPED = HERE / "results"
#: where this run writes (``--results DIR``; the shipped ``benchmarks/results`` by default)
RESULTS = SHIPPED
SCENES = HERE / "scenes"
EXAMPLES = ROOT / "examples"


class _Results(argparse.Action):
    """``--results DIR``: :data:`RESULTS` becomes ``DIR`` for the rest of the run."""

    def __call__(self, parser, namespace, values, option_string=None):
        global RESULTS
        RESULTS = Path(values).resolve()
        setattr(namespace, self.dest, RESULTS)


def parser(doc: str | None, quick_help: str = "a short run of the same measurement"
           ) -> argparse.ArgumentParser:
    """An argument parser described by the first line of ``doc``, with ``--quick`` and
    ``--results DIR`` (sets :data:`RESULTS`, where :func:`write` and :func:`png` put files;
    back to ``benchmarks/results`` with each new parser)."""
    global RESULTS
    RESULTS = SHIPPED
    p = argparse.ArgumentParser(description=(doc or "").strip().split("\n")[0])
    p.add_argument("--quick", action="store_true", help=quick_help)
    p.add_argument("--results", action=_Results, default=SHIPPED, metavar="DIR",
                   help="write this run's JSON and PNG files to DIR (default "
                   "benchmarks/results)")
    return p


def stem(name: str, quick: bool = False, tag: str | None = None) -> str:
    """The file name (without suffix) of a benchmark's results: ``tag`` if given, else
    ``name`` or ``name_quick``."""
    return tag or (f"{name}_quick" if quick else name)


def repeat(fn: Callable[[], object], repeats: int = 3, warmup: int = 1) -> dict:
    """Seconds per call of ``fn`` after ``warmup`` untimed calls: every repeat, and their
    median, min and max."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return {"times_s": times, "median_s": statistics.median(times), "min_s": min(times),
            "max_s": max(times), "repeats": repeats, "warmup": warmup}


def ratio(ours: float | None, peer: float | None) -> float | None:
    """``ours / peer`` of two rates measured in the same run (above 1: dpm faster when both
    are particle-steps per second); None when either is missing or the peer's is 0."""
    if ours is None or not peer:
        return None
    return ours / peer


def liggghts() -> str | None:
    """The LIGGGHTS executable on PATH (``apt-get install -y liggghts``), or None."""
    return shutil.which("liggghts")


def peer(skipped: bool = False) -> str:
    """What a JSON says of its LIGGGHTS peer (key ``"peer"``): run in the same run,
    skipped (``--no-liggghts``), or missing (no ``liggghts`` on PATH: dpm's figures only)."""
    if skipped:
        return "skipped (--no-liggghts): dpm's figures only, no ratios"
    exe = liggghts()
    if exe is None:
        return ("missing: no liggghts on PATH (apt-get install -y liggghts): dpm's figures "
                "only, no ratios")
    return f"LIGGGHTS ({exe}), one core, in the same run"


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def machine() -> dict:
    """What a figure depends on besides dpm's code: processor, cores, load, the versions
    of Python, numpy, numba and llvmlite, dpm's version and commit, and the date (UTC)."""
    facts: dict = {"cpu": _cpu_model(), "machine": platform.machine(),
                   "cpu_count": os.cpu_count(), "python": platform.python_version(),
                   "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
                   "commit": _commit(), "liggghts": liggghts()}
    if hasattr(os, "getloadavg"):
        facts["load_average"] = os.getloadavg()
    for mod in ("numpy", "numba", "llvmlite", "dpm"):
        try:
            facts[mod] = __import__(mod).__version__
        except Exception:  # noqa: BLE001  (a fact missing, not a failed benchmark)
            facts[mod] = None
    try:
        import numba

        facts["numba_threads"] = numba.config.NUMBA_NUM_THREADS
    except ImportError:
        pass
    return facts


def write(name: str, result, quick: bool = False, tag: str | None = None,
          **dumps) -> Path:
    """Write ``result`` to ``RESULTS/<stem>.json`` (:func:`stem`); a dict gains the key
    ``"run"`` (:func:`machine`, ``quick``, the command line), a list is written as
    ``{"rows": result, "run": ...}``. Returns the path."""
    run = machine() | {"quick": quick, "argv": sys.argv[1:]}
    if isinstance(result, dict):
        result = {**result, "run": run}
    else:
        result = {"rows": result, "run": run}
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{stem(name, quick, tag)}.json"
    dumps.setdefault("indent", 1)
    path.write_text(json.dumps(result, **dumps) + "\n")
    return path


def png(draw: Callable[..., object], *args, path: Path | str) -> Path | None:
    """``draw(*args, path)`` with matplotlib's Agg backend; None (and a note) when
    matplotlib is not installed. A relative ``path`` is taken under :data:`RESULTS`."""
    path = RESULTS / path
    try:
        import matplotlib
    except ImportError:
        print(f"matplotlib not installed: {Path(path).name} not drawn "
              "(pip install -e '.[bench]')", file=sys.stderr)
        return None
    matplotlib.use("Agg")
    path.parent.mkdir(parents=True, exist_ok=True)
    draw(*args, path)
    return Path(path)


_EXAMPLES: dict = {}


def example(name: str):
    """The module ``examples/<name>.py``, loaded by path once (as ``<name>_example``: some
    benchmarks have the same name as the example they time)."""
    if name not in _EXAMPLES:
        spec = importlib.util.spec_from_file_location(f"{name}_example",
                                                      EXAMPLES / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod  # (dataclasses and pickling look the module up)
        spec.loader.exec_module(mod)
        _EXAMPLES[name] = mod
    return _EXAMPLES[name]
