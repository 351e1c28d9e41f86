"""Test-suite defaults: every scene runs on its own step module (the universal one only
where a test asks for it, tests/kernels/test_universal_step.py), and no run starts a
background compile.

The tests are in folders by kind (kernels, objects, physics, io, plugins, parallel, gpu,
examples); the helpers they share stay here, in tests/ (``backend_contract.py``,
``mpi_scenes.py``, ``small_scene.py``, ``scripts/``, ``data/``), and this directory is put
on ``sys.path`` once so that ``import backend_contract`` and ``import mpi_scenes`` work from
any folder."""

import os
import sys
from pathlib import Path

os.environ.setdefault("DPM_KERNELS", "scene")
os.environ.setdefault("DPM_BACKGROUND_COMPILE", "0")

TESTS = str(Path(__file__).resolve().parent)
if TESTS not in sys.path:
    sys.path.insert(0, TESTS)


import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _keep_the_registry():
    """Each test ends with the plugin registry it began with: a test that reloads it (a
    fake plugin distribution) must not drop what test modules registered at import
    (``dpm.register`` at module level) for the tests after it in the same process."""
    from dpm import plugins

    before = plugins._REGISTRY
    yield
    plugins._REGISTRY = before
