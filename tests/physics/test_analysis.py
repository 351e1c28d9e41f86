"""dpm.analysis on constructed data with known answers (no simulation), and one tiny run
for the parts that work on a live Simulation (Thermo, energy balance, overlaps)."""

from types import SimpleNamespace

import h5py
import numpy as np
import pytest

import dpm
from dpm import analysis as an
from dpm.errors import DpmError, ParameterError
from dpm.io.hdf5 import THERMO_COLUMNS, Writer

R = 1e-3


def _lattice(n, spacing=2 * R, offset=0.5):
    g = (np.arange(n) + offset) * spacing
    return np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)


def _frame(x, r=R, v=(0.0, 0.0, 0.0), t=0.0, ids=None, mass=1e-5, material=None):
    n = len(x)
    return {"id": np.arange(n) if ids is None else np.asarray(ids),
            "position": np.asarray(x, float), "velocity": np.tile(np.asarray(v, float), (n, 1)),
            "orientation": np.tile([1.0, 0, 0, 0], (n, 1)),
            "angular_velocity": np.zeros((n, 3)), "radius": np.full(n, r),
            "mass": np.full(n, mass),
            "material": np.zeros(n, "i4") if material is None else np.asarray(material),
            "time": t, "step": int(round(t * 1e5))}


# ---------------------------------------------------------------- residence times
def test_plug_flow_gives_a_step_F():
    rec = {"residence_time": np.full(50, 2.0), "mass": np.linspace(1, 2, 50),
           "time": np.linspace(2, 3, 50), "outlet": np.zeros(50, "i4")}
    for weighted in (False, True):
        rt = an.residence_times(rec, mass_weighted=weighted)
        assert rt.mean == pytest.approx(2.0) and rt.variance == pytest.approx(0.0, abs=1e-24)
        assert np.array_equal(rt.F([0.0, 1.999, 2.0, 5.0]), [0, 0, 1, 1])
    edges, e = rt.E(bins=4, range=(1.0, 3.0))
    assert np.sum(e * np.diff(edges)) == pytest.approx(1.0)


def test_exponential_rtd_mean_and_variance():
    rng = np.random.default_rng(1)
    tau, n = 0.5, 20000
    t = rng.exponential(tau, n)
    rec = {"residence_time": np.concatenate([t, [99.0]]),
           "mass": np.concatenate([np.full(n, 1e-3), [1.0]]),
           "time": np.zeros(n + 1),
           "outlet": np.concatenate([np.zeros(n, "i4"), [-1]])}  # -1: escape guard, left out
    rt = an.residence_times(rec)
    assert len(rt) == n
    assert rt.mean == pytest.approx(tau, abs=4 * tau / np.sqrt(n))
    assert rt.variance == pytest.approx(tau**2, abs=4 * tau**2 * np.sqrt(8 / n))
    assert an.residence_times(rec, mass_weighted=True).mean == pytest.approx(rt.mean)
    # F(tau) = 1 - 1/e for an exponential (well-mixed vessel, Danckwerts 1953)
    assert float(rt.F(tau)) == pytest.approx(1 - np.exp(-1), abs=0.02)
    assert an.residence_times(rec, outlet=-1).mean == pytest.approx(99.0)


# ---------------------------------------------------------------- flow rates
def test_outlet_flow_rate_of_known_records():
    t = (np.arange(1000) + 0.5) * 1e-3  # a body of 10 g every ms: 10 kg/s
    rec = {"time": t, "mass": np.full(1000, 0.01), "residence_time": t,
           "outlet": np.zeros(1000, "i4")}
    s = an.outlet_flow_rate(rec, bin_width=0.1, start=0.0, stop=1.0)
    assert len(s) == 10 and s.unit == "kg/s"
    assert np.allclose(s.value, 10.0)
    assert np.allclose(s.time, np.arange(10) * 0.1 + 0.05)
    last = an.outlet_flow_rate(dict(rec, time=rec["time"] + 5e-4), bin_width=0.1)
    assert len(last) == 11 and last.value[-1] == pytest.approx(0.1)  # 1 body in the 11th
    # Beverloo 1961: W = C rho_b sqrt(g) (D - k d)^2.5; D = 0.05 m, d = 2 mm, rho_b = 1500
    w = an.beverloo(1500.0, 0.05, 2e-3)
    assert w == pytest.approx(0.58 * 1500 * np.sqrt(9.81) * 0.047**2.5)
    assert an.beverloo(1500.0, 2e-3, 2e-3) == 0.0


def test_fit_beverloo_recovers_c_and_k():
    """Rates made by the correlation with C = 0.6, k = 1.7 give them back; a 1 % scatter
    moves them a little; rates that fall with D are refused."""
    D = np.array([0.02, 0.025, 0.03, 0.04])
    W = [an.beverloo(1500.0, x, 4e-3, C=0.6, k=1.7) for x in D]
    C, k = an.fit_beverloo(D, W, 4e-3, 1500.0)
    assert C == pytest.approx(0.6, rel=1e-10) and k == pytest.approx(1.7, rel=1e-10)
    noisy = np.array(W) * (1 + 0.01 * np.array([1, -1, 1, -1]))
    C2, k2 = an.fit_beverloo(D, noisy, 4e-3, 1500.0)
    assert abs(C2 - 0.6) < 0.03 and abs(k2 - 1.7) < 0.2
    with pytest.raises(ParameterError, match="do not grow"):
        an.fit_beverloo(D, W[::-1], 4e-3, 1500.0)
    with pytest.raises(ParameterError, match="at least two"):
        an.fit_beverloo([0.02], [0.1], 4e-3, 1500.0)


def test_plane_flow_rate_of_a_falling_column():
    d, v, m = 1e-3, 0.5, 2e-3  # spacing, speed down, mass: rate m v / d = 1 kg/s
    z0 = 0.25 * d + np.arange(200) * d
    frames = []
    rng = np.random.default_rng(0)
    for k in range(101):  # 0.1 s, a frame per ms: each body moves d/2 per frame
        t = k * 1e-3
        order = rng.permutation(200)  # rows in any order: matched by id
        x = np.zeros((200, 3))
        x[:, 2] = z0 - v * t
        f = _frame(x[order], v=(0, 0, -v), t=t, ids=order, mass=m)
        frames.append(f)
    down = an.plane_flow_rate(frames, point=(0, 0, 0), normal=(0, 0, -1), bin_width=0.01)
    assert len(down) == 10 and np.allclose(down.value, 1.0)
    up = an.plane_flow_rate(frames, point=(0, 0, 0), normal=(0, 0, 1))
    assert len(up) == 100 and up.value.sum() * 1e-3 == pytest.approx(-0.1)


# ---------------------------------------------------------------- fields
def test_voxel_fields_of_a_simple_cubic_lattice():
    x = _lattice(8)  # touching spheres, spacing 2R, from 0 to 16R
    f = _frame(x, v=(0.1, 0.0, -0.2))
    for cell in (R, 2 * R, 4 * R):
        fld = an.voxel_fields(f, cell, (0, 0, 0), (16 * R,) * 3)
        assert np.allclose(fld.phi, np.pi / 6, rtol=1e-9), cell
        assert np.allclose(fld.velocity, (0.1, 0.0, -0.2))
    # cells spanning whole lattice periods get exactly pi/6 wherever they start
    fld = an.voxel_fields(f, 2 * R, (0.3 * R,) * 3, (14.3 * R,) * 3)
    assert np.allclose(fld.phi[1:-1, 1:-1, 1:-1], np.pi / 6, rtol=1e-9)
    # whole spheres to their centre's cell: right for big cells, 0 or 8 pi/6 for R cells
    big = an.voxel_fields(f, 4 * R, (0, 0, 0), (16 * R,) * 3, method="centre")
    assert np.allclose(big.phi, np.pi / 6)
    small = an.voxel_fields(f, R, (0, 0, 0), (16 * R,) * 3, method="centre")
    assert set(np.unique(np.round(small.phi / (np.pi / 6), 9))) == {0.0, 8.0}
    # two frames average; the density is mass / volume
    two = an.voxel_fields([f, f], 4 * R, (0, 0, 0), (16 * R,) * 3)
    assert two.frames == 2 and np.allclose(two.density, 1e-5 / (2 * R) ** 3)
    sl, ext = two.slice("phi", axis="y", at=5 * R)
    assert sl.shape == (4, 4) and ext == pytest.approx((0, 16 * R, 0, 16 * R))
    assert np.allclose(two.slice("vz", axis="x")[0], -0.2)


def test_coarse_grained_fields_of_a_lattice():
    x = _lattice(14)  # 28 R wide: centre cells are more than 3 w from the edges
    f = _frame(x, v=(0.3, -0.1, 0.0))
    fld = an.coarse_grain(f, 1.5 * R, 2 * R, (10 * R,) * 3, (18 * R,) * 3)
    assert fld.phi.shape == (4, 4, 4)
    assert np.allclose(fld.phi, np.pi / 6, rtol=0.02)
    assert np.allclose(fld.velocity, (0.3, -0.1, 0.0))
    assert np.allclose(fld.density / fld.phi, 1e-5 / (4 / 3 * np.pi * R**3))  # m / V
    sl, _ = fld.slice("speed", axis="z")
    assert np.allclose(sl, np.hypot(0.3, 0.1))


# ---------------------------------------------------------------- drum
def _drum_bed(angle_deg, n=20000, seed=2, axis="y"):
    """Random points filling a drum cross-section (radius 0.1, axis through the origin)
    below a plane through the axis rising at angle_deg."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-0.1, 0.1, (4 * n, 2))
    keep = (np.hypot(p[:, 0], p[:, 1]) < 0.098) & (p[:, 1] < np.tan(np.radians(angle_deg))
                                                      * p[:, 0])
    p = p[keep][:n]
    along = rng.uniform(0, 0.05, len(p))
    if axis == "y":  # h = up x axis = z x y = -x: the surface rises towards -x
        x = np.stack([-p[:, 0], along, p[:, 1]], axis=1)
    else:  # axis x: h = z x x = y
        x = np.stack([along, p[:, 0], p[:, 1]], axis=1)
    return _frame(x, r=1e-3)


@pytest.mark.parametrize("method", ["highest", "fraction"])
def test_drum_angle_of_repose(method):
    for angle, axis in ((30.0, "y"), (-35.0, "x")):
        f = _drum_bed(angle, axis=axis)
        ax = (0, 1, 0) if axis == "y" else (1, 0, 0)
        s = an.drum_surface(f, (0, 0, 0), ax, 0.1, method=method)
        assert s.angle == pytest.approx(angle, abs=1.0), (method, axis, s)
        assert an.angle_of_repose(f, (0, 0, 0), ax, 0.1, method=method) == \
            pytest.approx(abs(angle), abs=1.0)
    with pytest.raises(ParameterError, match="parallel to gravity"):
        an.drum_surface(f, (0, 0, 0), (0, 0, 1), 0.1)


# ---------------------------------------------------------------- mixing
def test_lacey_segregated_and_random():
    x = _lattice(20)  # 8000 bodies, 40 R wide
    ids = np.arange(len(x))
    seg = _frame(x)
    left = ids[x[:, 0] < 20 * R]
    r0 = an.lacey(seg, set(left.tolist()), cell=10 * R, lower=(0, 0, 0), upper=(40 * R,) * 3)
    assert r0["p"] == pytest.approx(0.5) and r0["M"] == pytest.approx(0.0, abs=1e-12)
    rng = np.random.default_rng(3)
    mixed = rng.random(len(x)) < 0.5  # boolean array indexed by id
    r1 = an.lacey(seg, mixed, cell=10 * R, lower=(0, 0, 0), upper=(40 * R,) * 3)
    assert r1["M"] == pytest.approx(1.0, abs=0.15) and r1["cells"] == 64
    # a predicate on ids, the mass-weighted variant, min_count and the time series
    r2 = an.lacey(seg, lambda i: x[i, 0] < 20 * R, cell=10 * R, lower=(0, 0, 0),
                  upper=(40 * R,) * 3, by="mass")
    assert r2["M"] == pytest.approx(0.0, abs=0.05)
    assert an.lacey(seg, mixed, cell=8 * R, min_count=10**6)["cells"] == 0
    s = an.lacey_index([dict(seg, time=0.0), dict(seg, time=1.0)], mixed, cell=8 * R)
    assert np.allclose(s.time, [0, 1]) and np.allclose(s.value, s.value[0])


# ---------------------------------------------------------------- contacts, energy
def test_coordination_of_a_simple_cubic_lattice():
    x = _lattice(6)
    z = an.coordination_numbers(_frame(x))
    interior = np.all((x > 2 * R) & (x < 10 * R), axis=1)
    assert np.all(z[interior] == 6)
    corners = np.sum(np.isclose(x, R) | np.isclose(x, 11 * R), axis=1) == 3
    assert np.all(z[corners] == 3)
    d = an.coordination_distribution(_frame(x))
    assert d["fraction"].sum() == pytest.approx(1.0)
    assert d["mean"] == pytest.approx(2 * 3 * 6 * 6 * 5 / 216)  # 2 x pairs / N
    # spheres 1 % apart touch only with tol > 1 %
    assert an.coordination_numbers(_frame(x * 1.01)).sum() == 0
    assert an.coordination_numbers(_frame(x * 1.01), tol=0.02).sum() == z.sum()


def test_kinetic_energy_of_a_frame():
    f = _frame(np.zeros((1, 3)), r=0.5, v=(3.0, 0, 0), mass=2.0)
    f["angular_velocity"] = np.array([[0.0, 0.0, 4.0]])
    f["orientation"] = np.array([[np.cos(0.3), 0.0, np.sin(0.3), 0.0]])  # a sphere: no matter
    k = an.kinetic_energy(f)  # 1/2 2 3^2 = 9 J; I = 2/5 2 0.25 = 0.2, 1/2 0.2 16 = 1.6 J
    assert k["translational"] == pytest.approx(9.0) and k["rotational"] == pytest.approx(1.6)
    assert k["total"] == pytest.approx(10.6)
    s = an.kinetic_energy_series([dict(f, time=0.0), dict(f, time=0.5)])
    assert s.value.shape == (2, 3) and np.allclose(s.value[:, 2], 10.6)


def test_force_distribution_normalised_by_the_mean():
    b = SimpleNamespace(force=np.array([[1.0, 0, 0], [0, 2.0, 0], [0, 0, -3.0]]),
                        mass=np.ones(3))
    d = an.force_distribution(b, bins=3)
    assert float(d["mean"]) == pytest.approx(2.0)
    assert np.allclose(d["values"], [0.5, 1.0, 1.5])
    assert np.sum(d["density"] * np.diff(d["edges"])) == pytest.approx(1.0)


# ---------------------------------------------------------------- the /thermo table
class _Rows(SimpleNamespace):
    def __len__(self):
        return len(self.radius)


def _fake_sim(k, t):
    """What Writer reads from a Simulation, for 'frame k' at time t."""
    f = _frame(_lattice(2), v=(0, 0, -1.0 - k), t=t)
    bodies = _Rows(**{key: f[key] for key in ("id", "position", "velocity", "orientation",
                                              "angular_velocity", "radius", "mass",
                                              "material")})
    return SimpleNamespace(dt=1e-5, gravity=(0.0, 0.0, -9.81),
                           integrator=SimpleNamespace(name="velocity_verlet"),
                           materials=[SimpleNamespace(name="glass")],
                           boundaries=[SimpleNamespace(name="box", force=np.zeros(3),
                                                       torque=np.zeros(3))],
                           bodies=bodies, elements=[], plan=None, step_count=k * 100,
                           time=t)


def _thermo_file(path, frames=4, removed=True):
    w = Writer(path, _fake_sim(0, 0.0))
    for k in range(frames):
        t = k * 1e-3
        w.write(_fake_sim(k, t))
        w.write_thermo({"time": t, "step": k * 100, "kinetic_energy": 0.5 * k})
        w.write_thermo({"time": t + 5e-4, "step": k * 100 + 50})  # between frames
    if removed:
        w.write_removed({"id": np.arange(3), "time": np.array([1e-3, 2e-3, 3e-3]),
                         "mass": np.full(3, 1e-5), "residence_time": np.array([1e-3] * 3),
                         "position": np.zeros((3, 3)), "velocity": np.zeros((3, 3))}, 0)
    return w


def test_thermo_table_written_read_and_cut_back(tmp_path):
    path = tmp_path / "run.h5"
    w = _thermo_file(path)
    with pytest.raises(ParameterError, match="unknown column"):
        w.write_thermo({"temperature": 1.0})
    w.close()
    run = dpm.load(path, repair_xdmf=False)
    assert set(run.thermo) == set(THERMO_COLUMNS) and len(run.thermo["time"]) == 8
    assert np.allclose(run.thermo["kinetic_energy"][::2], [0, 0.5, 1.0, 1.5])
    assert np.isnan(run.thermo["contacts"]).all()  # columns a row lacks are NaN
    assert "KE[J]" in an.format_table(run.thermo).splitlines()[0]
    # resume at frame 2 (last kept frame t = 1 ms): rows up to that time stay
    w = Writer.resume(path, _fake_sim(2, 2e-3), 2, 0)
    assert w.thermo_rows == 3
    w.write_thermo({"time": 2e-3, "step": 200})
    w.close()
    assert np.allclose(dpm.load(path, repair_xdmf=False).thermo["time"], [0, 5e-4, 1e-3, 2e-3])
    # a file of an older dpm, without /thermo: empty on reading, created on resume
    with h5py.File(path, "r+") as f:
        del f["thermo"]
    assert dpm.load(path, repair_xdmf=False).thermo == {}
    Writer.resume(path, _fake_sim(1, 1e-3), 1, 0).close()
    assert len(dpm.load(path, repair_xdmf=False).thermo["time"]) == 0


# ---------------------------------------------------------------- picture and CLI
def test_picture_and_cli(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = tmp_path / "run.h5"
    _thermo_file(path).close()
    run = dpm.load(path, repair_xdmf=False)
    for view, color in (("xz", "speed"), ("3d", "z"), ("xy", "material")):
        out = tmp_path / f"{view}.png"
        fig = an.picture(run, frame=-1, color=color, view=view, path=out)
        assert out.stat().st_size > 1000
        import matplotlib.pyplot as plt

        plt.close(fig)
    with pytest.raises(ParameterError, match="color"):
        an.picture(run, color="temperature", path=None)
    from dpm.cli import main

    pic = tmp_path / "cli.png"
    assert main(["analyse", str(path), "--residence", "--flow", "z=0.001", "--energy",
                 "--thermo", "--coordination", "--lacey", "cell=0.004", "below=4",
                 "--flow", "outlet", "bin=0.001", "--picture", f"out={pic}"]) == 0
    text = capsys.readouterr().out
    assert "residence times: 3 bodies: mean 0.001 s" in text
    assert "mass flow rate out of the outlets" in text and "KE[J]" in text
    assert "coordination number: mean 3" in text and pic.exists()
    assert main(["analyse", str(path)]) == 0
    assert "4 frame(s)" in capsys.readouterr().out


def test_picture_without_matplotlib(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(DpmError, match="pip install"):
        an.picture(_frame(_lattice(2)), path=None)


# ---------------------------------------------------------------- a live Simulation
def test_live_simulation_thermo_and_energy(tmp_path):
    """48 spheres in a box (the kernels of tests/io/test_io.py): Thermo at output frames and
    driven in pieces, its rows in /thermo, the energy book, overlaps and forces."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02), open="+z")
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.007), 2.2e-3, jitter=5e-5)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=xyz,
                      velocities=np.full((len(xyz), 3), 0.01))
    out = tmp_path / "live.h5"
    sim.output(str(out), every_steps=100)
    with an.Thermo(sim) as th:
        sim.run(steps=300, progress=False)
    assert [r["step"] for r in th.rows] == [0, 100, 200, 300]
    assert all(r["particles"] == len(xyz) for r in th.rows)
    assert th.rows[-1]["kinetic_energy"] == pytest.approx(sim.kinetic_energy())
    piece = an.Thermo(sim, every=1e-3, live=True)
    piece.run(until=sim.time + 2e-3)
    assert len(piece) == 3 and piece.rows[-1]["time"] == pytest.approx(sim.time)
    sim.run(steps=100, progress=False)  # th is closed: no more rows
    assert len(th) == 4
    bal = an.energy_balance(sim)
    assert bal["dissipated"] == pytest.approx(sim.energy.balance(sim)["dissipated"])
    assert len(bal["boundary_work"]) == 1
    assert an.kinetic_energy(sim)["total"] == pytest.approx(sim.kinetic_energy())
    ov = an.overlap_distribution(sim)
    assert np.all(ov["values"] > 0) and len(ov["values"]) <= sim.contact_count()
    fd = an.force_distribution(sim)
    assert np.mean(fd["values"]) == pytest.approx(1.0)
    sim.close()
    run = dpm.load(out)
    # th's rows at the frames of steps 0-300, then piece's at 300 (its start), 400, 500
    assert np.array_equal(run.thermo["step"], [0, 100, 200, 300, 300, 400, 500])
    assert np.allclose(run.thermo["kinetic_energy"][:4], [r["kinetic_energy"] for r in th.rows])
    assert "contacts" in str(th).splitlines()[0] and len(str(th).splitlines()) == 5
