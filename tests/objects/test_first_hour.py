"""A new user's first hour (#56): slips that run but mislead are warned about before the
first step, and the small things a first session meets read right.

Plausibility warnings (dpm.plausibility, issued by the scene check before step 1, once
per scene): a Young's modulus typed in GPa, a mesh in mm read as m (or scaled twice), a
tube turned about an axis off its own, particles larger than their box or tube. None of
them fires on the repository's examples (each example's scene is built here, not run).

Small breaks: plain numbers in error messages (not ``np.float64(0.1)``), ``dpm analyse
--picture frame=99`` on a shorter run (a ParameterError naming the frame count, not an
IndexError), ``dpm analyse --thermo | head`` (quiet, no BrokenPipeError), ``--flow z=``'s
default normal (the help's ``normal=0,0,-1``), readable reprs of boundaries, materials
and motions, and ``py.typed`` in the package.

No test here compiles or runs a step: the scene check is called directly, or the scene
lacks a contact law so that ``sim.run`` stops in the check.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import textwrap
import tomllib
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import dpm
from dpm import plausibility, scene_check
from dpm.errors import ParameterError, SceneError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def scene(young: float = 5e6, wall_young: float = 2e8) -> tuple[dpm.Simulation, dpm.Material,
                                                                dpm.Material]:
    """A scene with contact laws between glass and glass, and glass and steel."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0.0, 0.0, -9.81))
    glass = dpm.Material("glass", density=2500.0, young=young, poisson=0.3)
    steel = dpm.Material("steel", density=7800.0, young=wall_young, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return sim, glass, steel


def checked(sim: dpm.Simulation) -> list[str]:
    """The warnings the scene check issues now."""
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        scene_check.validate_scene(sim)
    return [str(w.message) for w in got if issubclass(w.category, UserWarning)]


def quiet(sim: dpm.Simulation) -> None:
    """The scene check passes without any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene_check.validate_scene(sim)


def drum(motion: dpm.Motion | None, radius: float = 0.05, bead: float = 2e-3, **tube):
    sim, glass, steel = scene()
    kw = {"start": (0.0, 0.0, 0.0), "axis": (0.0, 1.0, 0.0), "length": 0.04,
          "radius": radius, **tube}
    sim.add_boundary("tube", material=steel, motion=motion, **kw)
    sim.add_particles("sphere", material=glass, radius=bead, positions=[(0.0, 0.02, 0.0)])
    return sim


# ------------------------------------------------------------------ 1a Young's modulus
def test_young_in_gpa_is_named_with_the_fix():
    sim, glass, steel = scene(young=70)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("plane", material=steel)
    text = " ".join(checked(sim))
    assert "Material('glass'): young=70 Pa" in text, text
    assert "did you mean 70e9 (GPa)?" in text and "young=70e9 for 70 GPa" in text
    assert "rubber" in text and "4e11 Pa" in text  # the range of real materials
    assert "steel" not in text
    # above 1200 (no solid is stiffer than 1200 GPa) the number was MPa
    sim, glass, steel = scene(young=5000)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    assert any("did you mean 5000e6 (MPa)?" in w for w in checked(sim))


def test_young_of_a_boundary_material_and_the_softened_examples():
    sim, glass, steel = scene(wall_young=200)  # steel's 200 GPa typed as 200
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("plane", material=steel)
    assert any("young=200 Pa" in w and "200e9" in w for w in checked(sim))
    # examples/grate.py's softened wood (5e4 Pa, its source's Table 4.2) is meant
    sim, glass, steel = scene(young=5e4)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("plane", material=steel)
    quiet(sim)


def test_young_of_a_material_no_body_or_boundary_uses_is_not_checked():
    """dpm.impact.measure.bind gives laws to bodiless materials of young=1: never met."""
    sim, glass, steel = scene()
    ghost = dpm.Material("_bind", density=1.0, young=1.0, poisson=0.0)
    sim.contact(ghost, ghost, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("plane", material=steel)
    quiet(sim)


# ------------------------------------------------------------------ 1b mesh scale
def square(size: float) -> dict:
    v = np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], float) * size / 2
    return {"vertices": v, "faces": [(0, 1, 2), (0, 2, 3)], "side": "both"}


def test_mesh_in_mm_read_as_m():
    sim, glass, steel = scene()
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("mesh", material=steel, **square(300.0))  # a 0.3 m floor in mm
    text = " ".join(checked(sim))
    assert "boundary 0 (mesh): the mesh is 300 m across (scale=1)" in text, text
    assert "7.5e+04 times the largest particle's diameter (4 mm" in text
    assert "scale=0.001" in text


def test_mesh_file_scaled_twice(tmp_path):
    import trimesh

    stl = tmp_path / "floor.stl"
    trimesh.Trimesh(**{k: v for k, v in square(0.3).items() if k != "side"}).export(stl)
    sim, glass, steel = scene()
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
    sim.add_boundary("mesh", material=steel, file=stl, scale=1e-3, side="both")
    text = " ".join(checked(sim))
    assert f"boundary 0 (mesh, file={str(stl)!r}): the mesh is 300 um across (scale=" \
           "0.001), 1/13.3 of the largest particle's diameter (4 mm)" in text, text
    assert "scale=1 if the mesh is in m already" in text


def test_mesh_near_the_thresholds_is_quiet():
    """The examples' and tests' meshes are 2 to 120 particle diameters across; the
    warnings start at 1e4 and 1/10."""
    for size in (4e-3 * 0.11, 4e-3 * 9000):
        sim, glass, steel = scene()
        sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.01)])
        sim.add_boundary("mesh", material=steel, **square(size))
        quiet(sim)


# ------------------------------------------------------------------ 1c orbiting drum
def test_drum_turned_about_a_centre_off_its_axis_orbits():
    sim = drum(dpm.Rotation(axis=(0, 1, 0), rpm=30, center=(0.1, 0.0, 0.0)))
    text = " ".join(checked(sim))
    assert "boundary 0 (tube): its Rotation turns it about an axis (0, 1, 0) through " \
           "(0.1, 0, 0), which passes 100 mm from the tube's own axis" in text, text
    assert "orbits" in text and "center=(0, 0, 0) (on the tube's axis)" in text


def test_skew_axis_orbits_too():
    sim = drum(dpm.Rotation(axis=(0, 0, 1), rpm=30, center=(0.2, 0.02, 0.0)))
    text = " ".join(checked(sim))
    assert "passes 200 mm from the tube's own axis" in text, text
    assert "center=(0, 0, 0) (the tube's start) and axis=(0, 1, 0)" in text


@pytest.mark.parametrize("motion", [
    dpm.Rotation(axis=(0, 1, 0), rpm=30),                            # about its axis
    dpm.Rotation(axis=(0, -1, 0), omega=2.0, center=(0, 0.5, 0)),    # another point on it
    dpm.Rotation(axis=(0, 1, 0), rpm=30, center=(0.0004, 0, 0)),     # within 1 % of r
    dpm.Rotation(axis=(0, 0, 1), rpm=30, center=(0, 0.02, 0)),       # end over end
    dpm.Tumbling(rpm=50, alpha=0.02, beta=0.02, u=0.05),              # gyrating: meant
])
def test_drums_that_turn_in_place_are_quiet(motion):
    quiet(drum(motion))


# ------------------------------------------------------------------ 1d too large to fit
def test_particle_larger_than_its_tube_and_box():
    sim, glass, steel = scene()
    sim.add_boundary("tube", material=steel, start=(0, 0, 0), axis=(0, 1, 0), length=0.1,
                     radius=0.05)
    sim.add_boundary("box", material=steel, lower=(-1, -0.5, -1), upper=(1, 0.5, 1))
    sim.add_particles("sphere", material=glass, radius=2.0, positions=[(0, 0.05, 0)])  # mm
    got = checked(sim)
    text = " ".join(got)
    assert "1 particle(s) lie in boundary 0 (tube) but are larger than it: diameter up " \
           "to 4 m (id(s) 0) against its inner diameter of 100 mm" in text, text
    assert "boundary 1 (box) but are larger than it" in text and "its y side of 1 m" in text
    assert "radius=2e-3" in text


def test_inlet_bringing_spheres_larger_than_the_tube():
    sim, glass, steel = scene()
    sim.add_boundary("tube", material=steel, start=(0, 0, 0), axis=(0, 0, 1), length=1.0,
                     radius=0.05)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.5)])
    sim.add_inlet(dpm.BoxRegion((-0.1, -0.1, 0.2), (0.1, 0.1, 0.8)), glass, rate=10.0,
                  radius=(0.02, 0.06))
    text = " ".join(checked(sim))
    assert "inlet 0 brings spheres up to 120 mm across into boundary 0 (tube), against " \
           "its inner diameter of 100 mm" in text, text


def test_squeezed_within_the_overlap_tolerance_is_meant():
    """tests/physics/test_physics_foundation.py squeezes a sphere between two walls by
    0.002 of its radius each: within overlap_tolerance, so no warning; a sphere that just
    fits, a cone's narrow end and an open box side are no containers either."""
    r = 1e-3
    sim, glass, steel = scene()
    sim.add_boundary("box", material=steel, lower=(0, -1, -1), upper=(2 * r - 0.004 * r, 1, 1))
    sim.add_particles("sphere", material=glass, radius=r, positions=[(r - 0.002 * r, 0, 0)])
    quiet(sim)
    sim, glass, steel = scene()
    sim.add_boundary("tube", material=steel, start=(0, 0, 0), axis=(0, 0, 1), length=0.1,
                     radius_start=0.001, radius_end=0.05)  # a hopper: beads above its outlet
    sim.add_boundary("box", material=steel, lower=(-0.1, -0.1, 0), upper=(0.1, 0.1, 0.003),
                     open=("+z",))
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=[(0, 0, 0.09)])
    quiet(sim)


# ------------------------------------------------------------------ once, before step 1
def test_warned_once_per_scene_at_the_callers_line():
    """Through sim.run: the scene lacks a contact law, so the check refuses it after
    warning (no step runs); the second run warns no more, a new scene warns again."""
    def build():
        sim = dpm.Simulation(dt=1e-5)
        glass = dpm.Material("glass", density=2500.0, young=70, poisson=0.3)
        sim.add_particles("sphere", material=glass, radius=2e-3,
                          positions=[(0, 0, 0), (0.01, 0, 0)])
        return sim

    sim = build()
    with pytest.warns(UserWarning, match="did you mean 70e9") as got:
        with pytest.raises(SceneError, match="no contact law"):
            sim.run(steps=1, progress=False)
    assert [w.filename for w in got if "70e9" in str(w.message)] == [__file__]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SceneError):
            sim.run(steps=1, progress=False)
    with pytest.warns(UserWarning, match="did you mean 70e9"):
        with pytest.raises(SceneError):
            build().run(steps=1, progress=False)


# ------------------------------------------------------------------ the examples
def _example(name: str):
    spec = importlib.util.spec_from_file_location(f"first_hour_{name}", EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # (dataclasses look their module up)
    spec.loader.exec_module(mod)
    return mod


def _example_scenes(tmp_path):
    mill = _example("ball_mill")
    yield "ball_mill bars", mill.build()
    yield "ball_mill mesh", mill.build(lifters="mesh")
    yield "ball_mill closed", mill.build(periodic=False, length=mill.L_MILL)
    box = _example("box_settle")
    csv = tmp_path / "box.csv"
    pos = dpm.lattice((1e-3, 1e-3, 1e-3), (6e-3, 6e-3, 6e-3), 2.1e-3)
    rows = np.hstack([pos, np.zeros_like(pos), np.full((len(pos), 1), 1e-3)])
    np.savetxt(csv, rows, delimiter=",", header="x,y,z,vx,vy,vz,r box=0.0063,0.0063,0.0147",
               comments="")
    yield "box_settle", box.build(csv)
    drop = _example("drop_test")
    yield "drop_test", drop.build()[0]
    grate = _example("grate")
    for g in grate.GRATES:
        for material in grate.MATERIALS:
            yield f"grate {g} {material}", grate.build(grate.Case(grate=g, material=material))[0]
    yield "grate periodic", grate.build(grate.Case(periodic=True, width=3.0))[0]
    hopper = _example("hopper_discharge")
    for label, sim in (("silo", hopper.silo(0.02)), ("cone mesh", hopper.conical(True)),
                       ("cone tube", hopper.conical(False)), ("wedge", hopper.wedge()),
                       ("steel", hopper.steel_hopper())):
        yield f"hopper {label}", sim[0] if isinstance(sim, tuple) else sim
    kiln = _example("rotary_kiln")
    for fr in (0.01, 3.0):
        yield f"rotary_kiln {fr}", kiln.build(fr, 0.04, 4 * 2 * kiln.R_BEAD)
    yield "rotating_drum", _example("rotating_drum").build()
    tsm = _example("screening_machine")
    yield "screening_machine", tsm.Machine(tsm.Case()).sim
    yield "tumbling_screen", _example("tumbling_screen").build()
    from dpm.io.scene import load_scene

    for toml in sorted(EXAMPLES.glob("*.toml")):
        yield toml.name, load_scene(toml, output=False)[0]


def test_no_warning_fires_on_the_examples(tmp_path):
    seen = 0
    for label, sim in _example_scenes(tmp_path):
        assert plausibility.plausibility_problems(sim) == [], label
        seen += 1
    assert seen >= 23  # (every example file, the .toml scenes included)


# ------------------------------------------------------------------ 2a plain numbers
def test_numbers_in_messages_are_plain():
    sim, glass, steel = scene()
    with pytest.raises(ParameterError) as err:
        sim.add_boundary("box", material=steel, lower=np.array([0.0, 0.0, 0.2]),
                         upper=np.array([0.1, 0.1, 0.1]))
    msg = str(err.value)
    assert "upper=(0.1, 0.1, 0.1) must exceed lower=(0.0, 0.0, 0.2)" in msg, msg
    for make in (lambda: sim.add_boundary("plane", material=steel, normal=np.zeros(3)),
                 lambda: dpm.Rotation(axis=np.zeros(3), rpm=1),
                 lambda: dpm.Material("g", density=2500, yung=np.float64(5e6)),
                 lambda: sim.add_boundary("box", material=steel, lower=[np.float64(0), 0, "0"],
                                          upper=(1, 1, 1)),
                 lambda: sim.add_boundary("wall", material=steel,
                                          half_extents=np.array([0.1, -0.1]))):
        with pytest.raises(ParameterError) as err:
            make()
        msg = str(err.value)
        assert "np.float64" not in msg and "array(" not in msg, msg
    from dpm.parameters import shown

    assert shown((np.float64(0.1), np.int64(2), np.float32(0.1))) == "(0.1, 2, 0.1)"
    assert shown(np.arange(20.0)).endswith("... (20 items))")


# ------------------------------------------------------------------ 2b-2d dpm analyse
class _Rows(SimpleNamespace):
    def __len__(self):
        return len(self.radius)


def _fake_sim(k: int, t: float) -> SimpleNamespace:
    n = 8
    x = np.column_stack([np.arange(n) * 2e-3, np.zeros(n), np.full(n, 0.01 - 2e-3 * k)])
    bodies = _Rows(id=np.arange(n), position=x, velocity=np.tile([0.0, 0.0, -1.0], (n, 1)),
                   orientation=np.tile([1.0, 0, 0, 0], (n, 1)),
                   angular_velocity=np.zeros((n, 3)), radius=np.full(n, 1e-3),
                   mass=np.full(n, 1e-5), material=np.zeros(n, "i4"))
    return SimpleNamespace(dt=1e-5, gravity=(0.0, 0.0, -9.81),
                           integrator=SimpleNamespace(name="velocity_verlet"),
                           materials=[SimpleNamespace(name="glass")],
                           boundaries=[SimpleNamespace(name="box", force=np.zeros(3),
                                                       torque=np.zeros(3))],
                           bodies=bodies, elements=[], plan=None, step_count=k * 100,
                           time=t)


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A run of 4 frames (8 bodies falling through z = 0.005) and 3000 thermo rows."""
    from dpm.io.hdf5 import Writer

    path = tmp_path_factory.mktemp("first_hour") / "run.h5"
    w = Writer(path, _fake_sim(0, 0.0))
    for k in range(4):
        w.write(_fake_sim(k, k * 1e-3))
    for j in range(3000):
        w.write_thermo({"time": j * 1e-6, "step": j, "kinetic_energy": 1e-6 * j})
    w.close()
    return path


def test_picture_of_a_frame_the_run_lacks(run_file, tmp_path, capsys):
    from dpm import analysis as an
    from dpm.cli import main

    run = dpm.load(run_file, repair_xdmf=False)
    with pytest.raises(ParameterError, match=r"frame=99: .* has 4 frame\(s\); allowed: 0 "
                       r"\.\. 3, or -1 \.\. -4"):
        an.as_frame(run, 99)
    with pytest.raises(ParameterError, match="has 4 frame"):
        an.kinetic_energy_series(run, frames=[0, 4])
    assert main(["analyse", str(run_file), "--coordination", "frame=-5"]) == 2
    assert "frame=-5" in capsys.readouterr().err
    pytest.importorskip("matplotlib")
    assert main(["analyse", str(run_file), "--picture", "frame=99",
                 f"out={tmp_path / 'p.png'}"]) == 2
    err = capsys.readouterr().err
    assert "ParameterError: frame=99" in err and "has 4 frame(s)" in err, err


def test_thermo_into_a_closed_pipe_ends_quietly(run_file):
    code = textwrap.dedent(f"""
        import sys
        from dpm.cli import main
        sys.exit(main(["analyse", {str(run_file)!r}, "--thermo"]))
    """)
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    first = p.stdout.readline()  # (| head -1)
    p.stdout.close()
    err = p.stderr.read().decode()
    status = p.wait(timeout=120)
    assert first.strip(), "no table header"
    assert err == "", err
    assert status == 141


def test_flow_default_normal_is_the_helps(run_file, capsys):
    """`--flow z=0.005` measures along (0, 0, -1) (the help: z=0.0 [normal=0,0,-1]): the
    falling bodies count positive."""
    from dpm.cli import main

    assert main(["analyse", str(run_file), "--flow", "z=0.005"]) == 0
    out = capsys.readouterr().out
    assert "along normal (0, 0, -1) [kg/s]" in out, out
    rates = [float(line.split()[1]) for line in out.splitlines()[2:]]
    assert sum(rates) > 0 and min(rates) >= 0
    assert main(["analyse", str(run_file), "--flow", "x=0.005"]) == 0
    assert "along normal (1, 0, 0)" in capsys.readouterr().out


# ------------------------------------------------------------------ 2e reprs
def test_reprs_name_the_declared_parameters():
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    assert repr(glass) == "Material('glass', density=2500, young=5000000, poisson=0.45)"
    assert repr(dpm.Material("sand", density=2650.0)) == "Material('sand', density=2650)"
    rot = dpm.Rotation(axis=(0, 1, 0), rpm=30)
    assert repr(rot) == "Rotation(axis=(0, 1, 0), rpm=30)"
    assert repr(rot.then(dpm.Oscillation(amplitude=(0, 0, 1e-3), frequency=50))) == (
        "Compose(Rotation(axis=(0, 1, 0), rpm=30), "
        "Oscillation(amplitude=(0, 0, 0.001), frequency=50))")
    sim = dpm.Simulation(dt=1e-5)
    tube = sim.add_boundary("tube", material=glass, radius=0.05, length=1.0, motion=rot)
    assert repr(tube) == ("Tube(material='glass', length=1, radius=0.05, "
                          "motion=Rotation(axis=(0, 1, 0), rpm=30))")
    box = sim.add_boundary("box", material=glass, lower=(0, 0, 0),
                           upper=np.array([0.1, 0.1, 0.2]), open=("+z",))
    assert repr(box) == ("Box(material='glass', lower=(0, 0, 0), upper=(0.1, 0.1, 0.2), "
                         "open=('+z',))")
    mesh = sim.add_boundary("mesh", material=glass, **square(1.0))
    assert repr(mesh) == ("Mesh(material='glass', vertices=<array of shape (4, 3)>, "
                          "faces=<array of shape (2, 3)>, side='both')")


# ------------------------------------------------------------------ 2f py.typed
def test_package_is_typed():
    from importlib.resources import files

    assert files("dpm").joinpath("py.typed").is_file()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "py.typed" in data["tool"]["setuptools"]["package-data"]["dpm"]
