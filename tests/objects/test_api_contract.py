"""The public API contract of ARCHITECTURE.md: these names keep working."""

import inspect

import numpy as np

import dpm


def test_contract_names_and_signatures():
    for name in ("Simulation", "Material", "Shape", "Boundary", "ImpactModel", "Integrator",
                 "load", "ParameterError", "UnknownNameError", "SceneError",
                 "UnstableRunError", "OutputError", "restart"):
        assert hasattr(dpm, name), name
    sig = inspect.signature(dpm.Simulation)
    for p in ("dt", "gravity", "integrator"):
        assert p in sig.parameters
    sig = inspect.signature(dpm.Simulation.add_particles)
    for p in ("shape", "material", "positions", "velocities", "angular_velocities",
              "orientations"):
        assert p in sig.parameters
    assert "model" in inspect.signature(dpm.Simulation.contact).parameters
    run = inspect.signature(dpm.Simulation.run).parameters
    assert "steps" in run and "until" in run


def test_contract_example_runs():
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81), integrator="velocity_verlet")
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5,
                rolling_friction=0.0)
    sim.add_boundary("plane", point=(0, 0, 0), normal=(0, 0, 1), material=m)
    xyz = np.array([[0, 0, 1e-3], [0, 0, 3.5e-3], [3e-3, 0, 1.2e-3]])
    ids = sim.add_particles("sphere", material=m, radius=1e-3, positions=xyz,
                            velocities=np.zeros((3, 3)), angular_velocities=np.zeros((3, 3)),
                            orientations=np.tile([1.0, 0, 0, 0], (3, 1)))
    assert list(ids) == [0, 1, 2]
    sim.run(steps=100, progress=False)
    sim.run(until=0.002, progress=False)
    assert sim.step_count == 200 and abs(sim.time - 0.002) < 1e-15
    b = sim.bodies
    for name in ("position", "velocity", "angular_velocity", "force", "torque"):
        assert getattr(b, name).shape == (3, 3)
    assert b.orientation.shape == (3, 4) and b.mass.shape == (3,)


def test_engine_seam_names():
    """The backend seam and the state-order names that scripts and backends call."""
    from dpm.backends import Backend, CpuBackend, StepResult, step_by_parts  # noqa: F401

    assert "device" in inspect.signature(dpm.Simulation).parameters
    for name in ("permute", "contact_count", "material_index", "kinetic_energy"):
        assert callable(getattr(dpm.Simulation, name)), name
    for name in ("pre_force", "needs_rebuild", "rebuild", "forces", "post_force", "advance",
                 "max_speed", "max_overlap", "nan_count", "boundary_loads", "contact_count",
                 "to_host", "from_host"):
        assert callable(getattr(CpuBackend, name)), name
    sim = dpm.Simulation(dt=1e-5, device=CpuBackend(force_pass="two_pass"))
    assert isinstance(sim.backend, Backend) and sim.plan is None and sim.shape_names == []


def test_registered_names_of_this_version():
    reg = dpm.registry()
    assert {"sphere"} <= set(reg.names("shape"))
    assert {"plane", "box"} <= set(reg.names("boundary"))
    assert {"linear_spring_dashpot", "hertz_mindlin"} <= set(reg.names("impact_model"))
    assert {"symplectic_euler", "velocity_verlet"} <= set(reg.names("integrator"))
    assert {"cpu"} <= set(reg.names("backend"))


def test_kernels_layer_imports_only_numpy_numba_math():
    import pathlib
    import re

    kdir = pathlib.Path(dpm.__file__).parent / "kernels"
    for f in kdir.glob("*.py"):
        for line in f.read_text().splitlines():
            m = re.match(r"\s*(?:from|import)\s+([\w.]+)", line)
            if m:
                root = m.group(1).split(".")[0]
                assert root in ("", "numpy", "numba", "math"), (f.name, line)
    # no @njit outside the kernel layer
    for f in pathlib.Path(dpm.__file__).parent.rglob("*.py"):
        if "kernels" not in f.parts:
            decorated = re.findall(r"^\s*@(?:njit|jit)\b", f.read_text(), flags=re.M)
            assert not decorated, f


def test_notice_and_is_root_in_one_process(capsys):
    """Serial: ``dpm.notice`` is print (its arguments too) and this process is the root
    (under mpiexec: tests/parallel/test_mpi.py)."""
    assert dpm.is_root() is True
    dpm.notice("a", 1, sep="-", end="!\n")
    assert capsys.readouterr().out == "a-1!\n"
