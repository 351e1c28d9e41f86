"""The CUDA backend (``device="cuda"``) on numba's CUDA simulator, against the CPU path.

CI has no GPU: every kernel of :mod:`dpm.kernels.cuda_step` runs here on the simulator
(``NUMBA_ENABLE_CUDASIM=1``, which numba reads at import: each case runs in a subprocess,
this file's ``__main__``). The simulator runs the kernels as Python threads and the
``@njit`` functions they call (the scene's contact laws, geometry, integrator parts) as
compiled CPU code, so a run must give the CPU's two-pass step bit for bit: the tests hold
it to 1e-12 of the field's largest magnitude (the backend contract's float64 bound) and
report whether the bits agree.

The scenes reuse the step modules the backend contract compiles (the same laws and
boundary kinds), so a warm cache pays no extra compile.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

#: tests/, where the shared helper backend_contract.py is (for the subprocess's imports)
TESTS = Path(__file__).resolve().parents[1]
TOL = 1e-12
#: steps of the small scene
STEPS = 24


def _run_case(case: str, timeout: float = 900.0, sim: bool = True) -> dict:
    env = dict(os.environ)
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    if sim:
        env["NUMBA_ENABLE_CUDASIM"] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), case],
                         capture_output=True, text=True, timeout=timeout, env=env,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    line = [s for s in out.stdout.splitlines() if s.startswith("RESULT ")][-1]
    return json.loads(line[len("RESULT "):])


# ---------------------------------------------------------------------- the cases
def _state(sim) -> dict[str, np.ndarray]:
    b = sim.bodies
    o = np.argsort(b.id, kind="stable")
    return {"id": b.id[o], "position": b.position[o], "velocity": b.velocity[o],
            "angular_velocity": b.angular_velocity[o], "orientation": b.orientation[o],
            "force": b.force[o], "torque": b.torque[o],
            "load": np.array([[*bd.force, *bd.torque] for bd in sim.boundaries])}


def _compare(a: dict, b: dict) -> dict:
    """Per field: max |a - b| / max |a| and whether the bits agree."""
    out = {}
    for f in a:
        if f == "id":
            out["same_ids"] = bool(np.array_equal(a[f], b[f]))
            continue
        scale = max(float(np.abs(a[f]).max(initial=0.0)), 1e-300)
        if a[f].shape != b[f].shape:
            out[f] = [math.inf, False]
            continue
        out[f] = [float(np.abs(a[f] - b[f]).max(initial=0.0)) / scale,
                  bool(np.array_equal(a[f], b[f]))]
    return out


def _pipes_small(backend):
    """clusters_pipes' boundaries and laws (its step module) with five bodies: two balls
    on the turning drum's wall, two balls and a cube rolling in the pipe towards the
    joint. A small skin makes the lists rebuild every few steps."""
    import backend_contract as bc

    import dpm

    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -bc.G), device=backend)
    glass, steel = bc._materials()
    bc._laws(sim, glass, steel, 1.0, rolling=False)
    _, rp = bc.drum_and_pipe(sim, steel)
    rb = 1.5e-3
    z = -rp + rb - 5e-6  # (resting on the pipe's wall)
    v = np.tile([1.5, 0.0, 0.0], (2, 1))
    sim.add_particles("sphere", material=glass,
                      positions=[[0.0593, 0, z], [0.0560, 0, z]], velocities=v,
                      angular_velocities=np.cross([0, 0, 1], v) / rb, radius=rb)
    sim.add_particles("sphere", material=glass,
                      positions=[[0.0, 0.0, -0.01361], [0.00282, 0.0, -0.01325]],
                      velocities=[[0.3, 0, -0.05], [-0.3, 0, -0.6]], radius=1.4e-3)
    sim.add_particles("cube", material=glass, positions=[[0.045, 0, -rp + 1.6e-3]],
                      velocities=[[1.0, 0.0, 0.0]], angular_velocities=[[0.0, 30.0, 0.0]],
                      orientations=[[0.96, 0.1, 0.2, 0.15]], a=2e-3)
    sim.skin = 2e-5
    return sim


def case_pipes() -> dict:
    """CPU two-pass and CUDA (simulator) runs of :func:`_pipes_small`."""
    import time

    from dpm.backends.cpu import CpuBackend

    res = {}
    states = []
    for backend in (CpuBackend(threads=1, force_pass="two_pass"), "cuda"):
        sim = _pipes_small(backend)
        t0 = time.perf_counter()
        sim.run(steps=STEPS, progress=False)
        res[f"seconds_{sim.backend.name}"] = time.perf_counter() - t0
        res[f"rebuilds_{sim.backend.name}"] = sim.rebuild_count
        res[f"contacts_{sim.backend.name}"] = sim.backend.contact_count()
        states.append(_state(sim))
    res["compare"] = _compare(*states)
    res["implicit"] = implicit_refused()
    return res


def case_contract(name: str, steps: int) -> dict:
    """The first ``steps`` steps of a backend contract scene on the CPU (two-pass) and the
    CUDA backend (simulator)."""
    import time

    import backend_contract as bc

    from dpm.backends.cpu import CpuBackend

    res = {}
    states = []
    for backend in (CpuBackend(threads=1, force_pass="two_pass"), "cuda"):
        sim, _ = bc.SCENES[name]({"device": backend})
        t0 = time.perf_counter()
        for _ in range(2):
            sim.run(steps=steps // 2, progress=False)
        res[f"seconds_{sim.backend.name}"] = time.perf_counter() - t0
        res[f"rebuilds_{sim.backend.name}"] = sim.rebuild_count
        res[f"bodies_{sim.backend.name}"] = len(sim.bodies)
        states.append(_state(sim))
    res["compare"] = _compare(*states)
    return res


def implicit_refused() -> str:
    """The error of an implicit integrator on the CUDA backend (raised at the first run,
    before anything is compiled)."""
    import dpm
    from dpm.errors import ParameterError

    sim = dpm.Simulation(dt=1e-5, integrator="backward_euler", device="cuda")
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=glass, positions=[[0, 0, 2e-3]], radius=1e-3)
    try:
        sim.run(steps=1, progress=False)
    except ParameterError as exc:
        return str(exc)
    return "ran"


def case_ptx() -> dict:
    """Every kernel of the small scene compiled to PTX for sm_90 (no GPU: NVVM only)."""
    try:
        from numba.cuda.cudadrv.nvvm import NVVM

        NVVM()
    except Exception as exc:  # noqa: BLE001 (no NVVM library: nothing to compile with)
        return {"skip": f"no NVVM ({type(exc).__name__}: {' '.join(str(exc).split())[:200]})"}
    from dpm.backends.cpu import CpuBackend
    from dpm.backends.cuda import CudaBackend

    sim = _pipes_small(CpuBackend(threads=1))
    sim.run(steps=1, progress=False)
    return {"sizes": CudaBackend.compile_check(sim, (9, 0))}


def case_restart() -> dict:
    """8 + 8 steps on the CUDA backend, and the same from a checkpoint written after 8."""
    import tempfile

    import dpm

    a = _pipes_small("cuda")
    a.run(steps=8, progress=False)
    with tempfile.TemporaryDirectory() as d:
        path = a.checkpoint(Path(d) / "c.h5")
        a.run(steps=8, progress=False)
        b = dpm.restart(path)
        b.run(steps=8, progress=False)
        b.close()
    a.close()
    return {"backend": type(b.backend).__name__, "compare": _compare(_state(a), _state(b))}


def case_overflow() -> dict:
    """The small scene with the device lists cut to their entries at each upload, so that
    a rebuild that finds more entries fills them: the device grows them and finishes the
    step (``finish_step``), as the CPU does."""
    from dpm.backends.cpu import CpuBackend
    from dpm.backends.cuda import CudaBackend

    upload = CudaBackend._upload

    def tight(self) -> None:
        upload(self)
        dev = self._dev
        for pre, fields in (("nl_", ("key", "hist", "active", "force", "t_pair")),
                            ("wl_", ("key", "hist", "active", "force", "tag"))):
            count = int(dev[pre + "start"].copy_to_host()[-1])
            for f in fields:
                dev[pre + f] = dev[pre + f][:count]
        self._scratch_lists(dev, dev["nl_key"].shape[0], dev["wl_key"].shape[0],
                            len(self.sim.elements))

    CudaBackend._upload = tight
    states, grown = [], {}
    for backend in (CpuBackend(threads=1, force_pass="two_pass"), "cuda"):
        sim = _pipes_small(backend)
        sim.run(steps=STEPS, progress=False)
        states.append(_state(sim))
        grown = getattr(sim.backend, "_grown", grown)
    return {"grown": grown, "compare": _compare(*states)}


def case_no_device() -> dict:
    """``Simulation(device="cuda")`` without the simulator: on a machine without a GPU,
    a clear error; ``import dpm`` alone never imports numba.cuda."""
    import dpm

    out = {"imported_numba_cuda": "numba.cuda" in sys.modules}
    try:
        dpm.Simulation(dt=1e-5, device="cuda")
        out["error"] = None
    except dpm.errors.ParameterError as exc:
        out["error"] = str(exc)
    return out


# ---------------------------------------------------------------------- the tests
def _check(res: dict) -> None:
    cmp = res["compare"]
    assert cmp.pop("same_ids")
    bad = {f: v for f, v in cmp.items() if not v[0] <= TOL}
    assert not bad, f"CUDA (simulator) vs CPU beyond {TOL:g}: {bad}"


def test_small_scene_matches_cpu():
    """Spheres and a clustered cube in a turning drum and a pipe joined to a bend (moving
    boundary, tube, bend, caps, joint; rebuilds every few steps): the CUDA backend on the
    simulator gives the CPU path's state and loads within 1e-12 (bit for bit here)."""
    res = _run_case("pipes")
    print(json.dumps(res))
    assert res["rebuilds_cuda"] == res["rebuilds_cpu"] >= 3
    assert res["contacts_cuda"] == res["contacts_cpu"] > 0
    assert "implicit backward_euler integrator is not supported on the GPU" in res["implicit"]
    _check(res)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spheres_walls", "flow_periodic"])
def test_contract_scene_start_matches_cpu(name):
    """The first 30 steps of the backend contract's sphere scenes (box, slab, mesh
    pyramid, sieve, rolling resistance; periodic faces with an inlet and an outlet whose
    first events fall inside the run) on the simulator, within 1e-12 of the CPU path.
    The whole contract (300-400 steps) takes ~10-20 min per scene on the simulator:
    ``NUMBA_ENABLE_CUDASIM=1 python tests/backend_contract.py --backend
    '{"device": "cuda"}'``."""
    res = _run_case(f"contract:{name}:30", timeout=1800)
    print(json.dumps(res))
    assert res["bodies_cuda"] == res["bodies_cpu"]
    _check(res)


@pytest.mark.slow
def test_kernels_compile_for_sm90():
    """numba-cuda compiles every kernel, with the scene's laws, geometry and integrator
    called from it, for a real GPU (PTX for compute capability 9.0; needs NVVM, from
    ``numba-cuda[cu12]``, not a GPU)."""
    res = _run_case("ptx", sim=False)
    if "skip" in res:
        pytest.skip(res["skip"])
    from dpm.kernels import cuda_step

    assert set(res["sizes"]) == set(cuda_step.KERNELS)
    assert all(v > 1000 for v in res["sizes"].values())


@pytest.mark.slow
def test_checkpoint_restart_continues_bit_for_bit():
    """A checkpoint of a CUDA run (the host state is whole between calls) restarts on the
    CUDA backend and continues with the bits of the uninterrupted run."""
    res = _run_case("restart")
    assert res["backend"] == "CudaBackend"
    cmp = res["compare"]
    assert cmp.pop("same_ids")
    assert all(bits for _, bits in cmp.values()), cmp


@pytest.mark.slow
def test_full_device_lists_grow_and_the_step_is_finished():
    res = _run_case("overflow")
    assert set(res["grown"]) == {"nl_", "wl_"}, res["grown"]
    _check(res)


def test_no_device_is_a_clear_error():
    res = _run_case("no_device", sim=False)
    assert not res["imported_numba_cuda"]
    if res["error"] is None:
        pytest.skip("this machine has a usable GPU")
    assert "no usable NVIDIA GPU" in res["error"]
    assert "pip install 'dpm-granular[cuda]'" in res["error"]
    assert "NUMBA_ENABLE_CUDASIM=1" in res["error"]


if __name__ == "__main__":
    case = sys.argv[1]
    if case == "pipes":
        result = case_pipes()
    elif case == "overflow":
        result = case_overflow()
    elif case == "restart":
        result = case_restart()
    elif case == "ptx":
        result = case_ptx()
    elif case.startswith("contract:"):
        _, scene, n = case.split(":")
        result = case_contract(scene, int(n))
    else:
        result = case_no_device()
    print("RESULT " + json.dumps(result))
