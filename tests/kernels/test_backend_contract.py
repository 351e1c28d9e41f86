"""The backend contract (scenes, references and tolerances in ``tests/backend_contract.py``):
every backend reproduces the stored end states within each scene's tolerance; one and two
CPU threads give the same bits; the tolerances absorb a rounding-sized perturbation and
catch a 0.01 % change of the friction.

Another backend runs the same tests with ``DPM_BACKENDS='[{"device": "cuda"}]'`` (a JSON
list of ``dpm.Simulation`` keyword dicts). Regenerate the references (only for an intended
change of the physics) with ``python tests/backend_contract.py --write``.
"""

from __future__ import annotations

import backend_contract as bc
import numba
import pytest

SCENES = list(bc.SCENES)
BACKENDS = bc.backends()
_RESULTS: dict[tuple[str, str], dict] = {}


def _skip_unavailable(backend: dict) -> None:
    threads = backend.get("threads")
    if threads is not None and threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip(f"needs {threads} threads (NUMBA_NUM_THREADS="
                    f"{numba.config.NUMBA_NUM_THREADS})")


def result(name: str, backend: dict) -> dict:
    """The end state of scene ``name`` on ``backend``, run once per session."""
    key = (name, bc.backend_id(backend))
    if key not in _RESULTS:
        _skip_unavailable(backend)
        _RESULTS[key] = bc.run(name, backend)
    return _RESULTS[key]


@pytest.fixture(params=BACKENDS, ids=bc.backend_id)
def backend(request) -> dict:
    return request.param


@pytest.mark.parametrize("name", SCENES)
def test_scene_matches_its_reference(name, backend):
    err = bc.errors(result(name, backend), bc.load_reference(name))
    print(f"[{bc.backend_id(backend)}] {name}: "
          + ", ".join(f"{f} {e:.2g}" for f, e in err.items()))
    problems = bc.violations(name, err)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", SCENES)
def test_one_and_two_threads_bit_identical(name):
    one, two = {"threads": 1}, {"threads": 2}
    ids = [bc.backend_id(b) for b in BACKENDS]
    if bc.backend_id(one) not in ids or bc.backend_id(two) not in ids:
        pytest.skip("the CPU thread backends are not among the selected backends")
    a, b = result(name, one), result(name, two)
    for f in ("id", *bc.STATE_FIELDS, *bc.LOAD_FIELDS):
        assert (a[f] == b[f]).all(), f"{name}: {f} differs between one and two threads"


def test_periodic_results_do_not_depend_on_where_a_run_is_split_into_calls():
    """The periodic wrap happens inside the step, every step (it used to happen between
    kernel calls, whose lengths follow the wall time: the same one-thread scene run in
    calls of 400, 1 or 7 steps ended 1.8e-13 m/s apart)."""
    ends = []
    for calls in (1, 7, 400):
        sim, steps = bc.SCENES["flow_periodic"](bc.REFERENCE_BACKEND)
        done = 0
        while done < steps:
            n = min(steps // calls if calls < steps else 1, steps - done)
            sim.run(steps=n, progress=False)
            done += n
        o = sim.bodies.id.argsort()
        ends.append([getattr(sim.bodies, f)[o] for f in bc.STATE_FIELDS])
    assert ends[0][0].shape[0] > 50
    for other in ends[1:]:
        for a, b in zip(ends[0], other, strict=True):
            assert (a == b).all()


@pytest.mark.parametrize("name", SCENES)
def test_tolerance_absorbs_a_rounding_sized_perturbation(name):
    """Every initial coordinate moved by up to 1e-15 m (~600 ulp) stays within the
    tolerance with a margin of 10 (measured: ~500-5000)."""
    err = bc.errors(bc.run(name, bc.REFERENCE_BACKEND, jitter=1e-15),
                    bc.load_reference(name))
    tol = bc.TOLERANCE[name]
    assert max(err[f] for f in bc.STATE_FIELDS) < 0.1 * tol["state"], err
    assert max(err[f] for f in bc.LOAD_FIELDS) < 0.1 * tol["load"], err


@pytest.mark.parametrize("name", SCENES)
def test_tolerance_catches_a_small_change_of_the_friction(name):
    """Friction coefficients 0.01 % larger (a stand-in for a real bug) fail the scene by
    at least 10x its tolerance (measured: 100-10000x)."""
    err = bc.errors(bc.run(name, bc.REFERENCE_BACKEND, friction_scale=1.0001),
                    bc.load_reference(name))
    tol = bc.TOLERANCE[name]
    assert max(err[f] for f in bc.STATE_FIELDS) > 10 * tol["state"], err
    assert max(err[f] for f in bc.LOAD_FIELDS) > 10 * tol["load"], err
