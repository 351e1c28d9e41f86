"""The step gives the same trajectories for any number of threads, whichever way it sums
the forces: the fused pass of sphere scenes (one chunk per thread) and the two-pass sum of
clustered bodies add every contribution in the same order."""

import numba
import numpy as np
import pytest

import dpm


def _scene(threads, clusters=False):
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -9.81), threads=threads)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5,
                rolling_friction=0.02)
    sim.contact(glass, steel, model="linear_spring_dashpot", stiffness=2e3, restitution=0.5,
                friction=0.3)
    sim.contact(steel, steel, model="hertz_mindlin", restitution=0.6, friction=0.4)
    sim.add_boundary("box", material=steel, lower=(0, 0, 0), upper=(0.012, 0.012, 0.03),
                     open="+z")
    xyz = dpm.lattice((0, 0, 0), (0.012, 0.012, 0.02), 2.1e-3, jitter=5e-5, seed=3)
    rng = np.random.default_rng(1)
    half = len(xyz) // 2
    sim.add_particles("sphere", material=glass, positions=xyz[:half],
                      radius=rng.uniform(0.8e-3, 1.0e-3, half),
                      velocities=rng.uniform(-0.1, 0.1, (half, 3)))
    if clusters:  # clusters of 11 sub-spheres: the two-pass sum
        sim.add_particles("cylinder", material=steel, positions=xyz[half:], r=0.45e-3,
                          l=0.9e-3, resolution=0.1,
                          velocities=rng.uniform(-0.1, 0.1, (len(xyz) - half, 3)))
    else:
        sim.add_particles("sphere", material=steel, positions=xyz[half:], radius=0.9e-3,
                          velocities=rng.uniform(-0.1, 0.1, (len(xyz) - half, 3)))
    return sim


def _state(sim):
    return (sim.bodies.position.copy(), sim.bodies.velocity.copy(),
            sim.bodies.angular_velocity.copy(), sim.boundaries[0].force.copy())


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
@pytest.mark.parametrize("two_pass", [False, True])
def test_one_and_two_threads_give_identical_trajectories(two_pass):
    runs = []
    for threads in (1, 2):
        sim = _scene(threads)
        sim.backend.force_pass = "two_pass" if two_pass else "auto"
        sim.run(steps=5000, progress=False)
        assert sim.backend.diag[6] > 20  # a colliding scene, not a free fall
        runs.append((sim.bodies.position.copy(), sim.bodies.velocity.copy(),
                     sim.bodies.angular_velocity.copy(), sim.boundaries[0].force.copy()))
    for a, b in zip(*runs, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(a).max())
        np.testing.assert_array_equal(a, b)  # in fact bit for bit


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_fused_pass_and_two_pass_sum_agree_bit_for_bit():
    """Sphere scenes sum forces as they are computed, in one chunk per thread; the
    two-pass sum of the same scene gives the same numbers, and so does switching between
    the two in the middle of a run (the fused pass leaves stale force rows)."""
    runs = []
    for threads, two_pass in ((1, False), (2, False), (2, True), (1, "switch")):
        sim = _scene(threads)
        if two_pass == "switch":
            for k in range(4):
                sim.backend.force_pass = "two_pass" if k % 2 == 1 else "auto"
                sim.run(steps=500, progress=False)
        else:
            sim.backend.force_pass = "two_pass" if two_pass else "auto"
            sim.run(steps=2000, progress=False)
        runs.append(_state(sim))
    for other in runs[1:]:
        for a, b in zip(runs[0], other, strict=True):
            np.testing.assert_array_equal(a, b)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_clustered_bodies_one_and_two_threads_identical():
    runs = []
    for threads in (1, 2):
        sim = _scene(threads, clusters=True)
        sim.run(steps=3000, progress=False)
        assert sim.backend.fused_chunks() == 0 and sim.backend.diag[6] > 5
        runs.append(_state(sim))
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_thread_count_follows_a_scene_an_inlet_grows(monkeypatch):
    """DPM_THREADS=2: a scene of 4 spheres runs on one thread (below the small-scene
    size), and on two once an inlet has brought 5,000 more, in the same run."""
    monkeypatch.setenv("DPM_THREADS", "2")
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, 0), dt_check="off")
    steel = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    sim.contact(steel, steel, model="hertz_mindlin", restitution=0.6, friction=0.4)
    sim.add_particles("sphere", material=steel, radius=5e-4,
                      positions=dpm.lattice((0, 0, 0), (4e-3, 4e-3, 2e-3), 2e-3))
    sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.01), (0.1, 0.1, 0.11)), steel, rate=5e6,
                  radius=5e-4, every=1e-3, start=1e-3, stop=2e-3, seed=4)
    seen = []

    class Probe:
        @dpm.hookimpl
        def dpm_after_step(self, sim):
            seen.append((len(sim.elements), numba.get_num_threads()))

    probe = Probe()
    sim._registry.manager.register(probe, name="thread-probe")
    try:
        sim.run(steps=200, progress=False)
    finally:
        sim._registry.manager.unregister(probe)
    assert seen[0] == (4, 1)
    assert seen[-1] == (5004, 2)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_a_run_on_one_thread_takes_the_one_thread_form(monkeypatch):
    """On one thread the step module's ``prange`` loops are plain loops (no parallel
    launch per loop and step); two threads take the parallel form; a backend that
    declines the one-thread form (``one_thread_ok = False``, as the CUDA backend's host
    parts) keeps the parallel form on one thread. (That both forms give the same bits is
    the one-and-two-threads tests above and in tests/kernels/test_backend_contract.py.)"""
    from pathlib import Path

    from dpm.backends.cpu import CpuBackend

    def module_of(threads):
        sim = _scene(threads)
        sim.run(steps=10, progress=False)
        return sim.backend.module

    one, two = module_of(1), module_of(2)
    assert one is not two
    assert "prange(" not in Path(one.__file__).read_text()
    assert "prange(" in Path(two.__file__).read_text()
    monkeypatch.setattr(CpuBackend, "one_thread_ok", False)
    assert module_of(1) is two


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_a_run_loads_only_the_form_of_its_own_thread_count(monkeypatch):
    """The run sets its thread count before the scene is planned and handed to the
    backend, so that a one-thread run in a process of several numba threads never loads
    (and compiles) the parallel form as well: the first run of a scene compiled both
    before, and a cold cache paid for a module it never stepped on."""
    from dpm.plan import ScenePlan

    asked = []
    module = ScenePlan.module

    def spy(self, fused, one_thread=False):
        asked.append(one_thread)
        return module(self, fused, one_thread)

    monkeypatch.setattr(ScenePlan, "module", spy)
    numba.set_num_threads(2)  # (the process's count outside the run)
    sim = _scene(1)
    sim.run(steps=5, progress=False)
    sim.run(steps=5, progress=False)
    assert asked and all(asked), asked
    assert numba.get_num_threads() == 2  # (restored after each run)
    asked.clear()
    sim = _scene(2)
    sim.run(steps=5, progress=False)
    assert asked and not any(asked), asked


def test_a_threading_layer_chosen_before_dpm_is_named(monkeypatch):
    """numba takes its threading layer at a process's first parallel launch; one made
    before ``import dpm`` (which puts OpenMP first) leaves TBB or the workqueue in place,
    and a run on several threads says so once, with what to do."""
    from dpm.backends import cpu

    monkeypatch.delenv("NUMBA_THREADING_LAYER", raising=False)
    monkeypatch.setattr(cpu, "_LAYER_WARNED", [])
    monkeypatch.setattr(numba, "threading_layer", lambda: "tbb")
    assert cpu.threading_layer_advice(1) is None  # one thread: no parallel launches
    text = cpu.threading_layer_advice(2)
    assert text is not None and "'tbb'" in text and "NUMBA_THREADING_LAYER=omp" in text
    assert cpu.threading_layer_advice(2) is None  # once per process
    monkeypatch.setattr(cpu, "_LAYER_WARNED", [])
    monkeypatch.setattr(numba, "threading_layer", lambda: "omp")
    assert cpu.threading_layer_advice(2) is None
    monkeypatch.setattr(numba, "threading_layer", lambda: "workqueue")
    monkeypatch.setenv("NUMBA_THREADING_LAYER", "workqueue")  # the user's choice
    assert cpu.threading_layer_advice(2) is None


def test_dpm_puts_openmp_first_in_a_fresh_process():
    import os
    import subprocess
    import sys

    pytest.importorskip("numba.np.ufunc.omppool", reason="no OpenMP layer on this machine")
    code = ("import dpm, numba, numpy as np\n"
            "f = numba.njit(parallel=True)(lambda a: a.sum())\n"
            "f(np.ones(10)); print(numba.threading_layer())")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_THREADING_LAYER"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True)
    assert out.stdout.split()[-1] == "omp", out


def test_renumbering_does_not_depend_on_how_a_run_is_split():
    """A scene of spheres and clustered bodies renumbered in cell order every 2 rebuilds,
    run as one run of 3,000 steps and as twelve of 250: the renumberings are decided at
    the same steps (``SORT_CHECK_STEPS``), not after whichever time-sized kernel call
    ended first, so both end bit for bit alike. (Decided after every call, as before,
    they differ in the last bits.)"""
    from dpm.backends.cpu import SORT_CHECK_STEPS

    assert SORT_CHECK_STEPS <= 1500
    whole = _scene(1, clusters=True)
    whole.backend.sort_every = 2
    whole.run(steps=3000, progress=False)
    parts = _scene(1, clusters=True)
    parts.backend.sort_every = 2
    for _ in range(12):
        parts.run(steps=250, progress=False)
    assert np.any(whole.bodies.id != np.arange(len(whole.bodies)))  # it did renumber
    np.testing.assert_array_equal(parts.bodies.id, whole.bodies.id)
    for a, b in zip(_state(whole), _state(parts), strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_scene_an_inlet_grows_past_sort_from_is_renumbered_in_the_same_run(monkeypatch):
    """The renumbering follows the scene's size as the thread count does: 4 spheres, then
    an inlet brings 5,000 falling ones (past ``SORT_FROM``) within one run, which then
    renumbers them in cell order at its next check."""
    from dpm.backends import cpu

    monkeypatch.setattr(cpu, "SORT_EVERY", 1)  # (a renumbering at the first check)
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81), dt_check="off", threads=1)
    steel = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    sim.contact(steel, steel, model="hertz_mindlin", restitution=0.6, friction=0.4)
    sim.add_particles("sphere", material=steel, radius=5e-4,
                      positions=dpm.lattice((0, 0, 0), (4e-3, 4e-3, 2e-3), 2e-3))
    sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.01), (0.1, 0.1, 0.11)), steel, rate=5e6,
                  radius=5e-4, every=1e-3, start=1e-3, stop=2e-3, seed=4,
                  velocity=(0.0, 0.0, -1.0))
    sim.run(steps=cpu.SORT_CHECK_STEPS + 10, progress=False)
    assert len(sim.elements) == 5004 >= cpu.SORT_FROM
    assert np.any(np.diff(sim.bodies.id) < 0)  # renumbered (an inlet appends in id order)


def test_threads_chunks_share_the_work_of_a_scene_without_pairs():
    """Spheres apart from each other (no listed pair) on a floor: each of two chunks takes
    half the elements (balanced by listed pairs alone, every element fell in the last
    chunk and one thread did all the work); a uniform bed is split in the middle as
    before."""
    from dpm.kernels.step import chunk_bounds

    n = 2000
    no_pairs = np.zeros(n + 1, np.int64)
    one_entry = np.arange(n + 1, dtype=np.int64)  # (a floor entry each)
    b = chunk_bounds(2, no_pairs, one_entry)
    assert b[0] == 0 and b[2] == n and b[1] == n // 2
    assert list(chunk_bounds(4, no_pairs, no_pairs)) == [0, 500, 1000, 1500, 2000]
    bed = 4 * np.arange(n + 1, dtype=np.int64)  # four pairs each
    assert chunk_bounds(2, bed, no_pairs)[1] == n // 2
    # a dense half (pairs) and a dilute half (none): the dense half's chunk is shorter
    mixed = np.concatenate([6 * np.arange(n // 2 + 1), np.full(n // 2, 6 * (n // 2))])
    split = chunk_bounds(2, mixed.astype(np.int64), no_pairs)[1]
    assert 0.5 * n // 2 < split < n // 2
