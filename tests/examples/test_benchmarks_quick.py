"""Every benchmark script of benchmarks/ in its quick mode (#54): ``python
benchmarks/NAME.py --quick --results DIR`` from the repository root exits 0 and writes at
least one JSON file, which parses, into DIR, and nothing into the shipped
benchmarks/results.

Why: the benchmarks are scripts run by hand (a few physics tests load scenes from them,
none runs them), so an API change in dpm, a missing peer (LIGGGHTS, MPI, a GPU) or a
harness change breaks them silently until someone wants a figure. Their ``--quick`` runs
are the same measurements made short (under a minute for most on a 2-core machine once
numba's cache is warm, about three for the longest: first_step's compile, the drum, the
advisor's smoke test), and a peer that is missing is said in the JSON, never a failed
run. The scripts are found by listing benchmarks/*.py less the libraries they share, so
a new benchmark is tested without being named here. The figures themselves are not
checked: speed is never asserted in a test (docs/benchmarks.md)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = ROOT / "benchmarks"
#: modules of benchmarks/ that are imported by the scripts, not run
LIBRARIES = {"harness", "shared_scenes"}
SCRIPTS = sorted(p.stem for p in BENCHMARKS.glob("*.py") if p.stem not in LIBRARIES)
#: seconds for one quick run: about a minute warm, the first run also compiles the
#: scenes' step modules (several minutes on 2 cores)
TIMEOUT = 900


def _shipped() -> dict[str, tuple[int, int]]:
    """The shipped results' files, with their sizes and modification times."""
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns)
            for p in (BENCHMARKS / "results").glob("*") if p.is_file()}


@pytest.mark.slow
def test_scripts_found():
    assert len(SCRIPTS) >= 10
    assert "box_settle" in SCRIPTS and "harness" not in SCRIPTS


@pytest.mark.slow
@pytest.mark.parametrize("name", SCRIPTS)
def test_quick_run_writes_its_json(name, tmp_path):
    out = tmp_path / "results"
    before = _shipped()
    proc = subprocess.run([sys.executable, f"benchmarks/{name}.py", "--quick", "--results",
                           str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=TIMEOUT, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    files = sorted(out.glob("*.json"))
    assert files, f"no JSON in {out}: {sorted(p.name for p in out.glob('*'))}"
    for f in files:
        doc = json.loads(f.read_text())
        assert isinstance(doc, dict) and doc, f.name
    assert _shipped() == before, "a quick run wrote into benchmarks/results"
