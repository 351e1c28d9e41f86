"""``dpm new-plugin NAME``: the scaffold passes its own tests at once; bad NAMEs and
existing directories are refused before anything is written.

The scaffold's tests run in a fresh process from its directory (its ``tests/conftest.py``
registers the plugin module, as the entry point would once installed). The fast test
runs the tests that need no simulation (registration, dpm.testing's shape contract and
the law-level check of the impact model, a closed-form volume); the slow one runs them
all, including the two-sphere runs of the impact model contract (a step module compiled
for the new law: 1-3 minutes cold).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from dpm.errors import ParameterError
from dpm.scaffold import FILES, TEMPLATES, new_plugin

NAME = "dpm-scaffold-check"


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "dpm.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120)


def run_tests(root: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           "-p", "no:xdist", *args], capture_output=True, text=True,
                          cwd=root, env=env, timeout=900)


def test_templates_ship_with_the_package():
    for template, _ in FILES:
        assert (TEMPLATES / template).is_file(), template


def test_scaffold_passes_its_own_tests(tmp_path):
    r = cli("new-plugin", NAME, "--dir", str(tmp_path), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    root = tmp_path / NAME
    assert str(root) in r.stdout
    files = sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())
    assert files == sorted(rel.replace("PKG", "dpm_scaffold_check") for _, rel in FILES)
    text = (root / "pyproject.toml").read_text()
    assert 'name = "dpm-scaffold-check"' in text
    assert 'scaffold_check = "dpm_scaffold_check.plugin"' in text
    out = run_tests(root, "-k", "not engine")
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert "8 passed" in out.stdout, out.stdout[-2000:]


@pytest.mark.slow
def test_scaffold_passes_all_its_tests_with_engine_runs(tmp_path):
    root = new_plugin("dpm-scaffold-engine", tmp_path)
    out = run_tests(root)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert "10 passed" in out.stdout, out.stdout[-2000:]


@pytest.mark.parametrize("name", ["Bad Name", "1plugin", "dpm", "a--b", "plugin-", "numpy",
                                  "class", "dpm-class", "dpm_pl\u00fcgin", ""])
def test_invalid_name_refused(tmp_path, name):
    with pytest.raises(ParameterError, match="NAME=.* is not allowed"):
        new_plugin(name, tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_existing_directory_refused_nothing_overwritten(tmp_path):
    root = tmp_path / NAME
    root.mkdir()
    (root / "pyproject.toml").write_text("mine")
    with pytest.raises(ParameterError, match="exists already; nothing was written"):
        new_plugin(NAME, tmp_path)
    assert [p.name for p in root.iterdir()] == ["pyproject.toml"]
    assert (root / "pyproject.toml").read_text() == "mine"
    r = cli("new-plugin", NAME, "--dir", str(tmp_path), cwd=tmp_path)
    assert r.returncode == 2 and "exists already" in r.stderr
    (tmp_path / "file").write_text("x")
    with pytest.raises(ParameterError, match="not a directory"):
        new_plugin(NAME, tmp_path / "file")
