"""Insertion as process engineers state it: a total count or mass, and size distributions
(normal, log-normal, a sieve table of mass fractions) for the radii an inlet draws.

References, each independent of the code under test:

- counts and masses: the bodies present in ``sim.bodies`` (their masses from the sphere
  builder, 4/3 pi r^3 rho) and the inlet's insertion order (``inlet.ids``);
- the normal and log-normal samples: ``scipy.stats.truncnorm`` (mean, std, median,
  fourth moment, distribution function for a Kolmogorov-Smirnov test), with bounds of 4
  standard errors (SE of a mean sigma / sqrt(n); of a standard deviation
  sqrt(mu4 - sigma^4) / (2 sigma sqrt(n)); of a median sqrt(1/4 / n) / f(median));
- the sieve table: the mass fraction per class of the inserted bodies' masses, a ratio
  estimator F = sum(m 1[class]) / sum(m) whose standard error is
  sqrt(sum(m^2 (1[class] - F)^2)) / sum(m) (delta method); the same for the mass median
  of a log-normal on a mass basis.

The scenes hold a few thousand millimetre spheres in a 1 m box without gravity (no
contacts occur); the bodies are checked right after their insertion, a few steps in.
"""

import math

import numpy as np
import pytest
from scipy import stats

import dpm
from dpm.errors import ParameterError
from dpm.io.scene import load_scene

STEEL = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
BOX = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
N = 3000
#: the statistical bound: standard errors
K = 4.0


def scene():
    sim = dpm.Simulation(dt=1e-3, gravity=(0.0, 0.0, 0.0), dt_check="off")
    sim.contact(STEEL, STEEL, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return sim


def insert(n=N, seed=1, steps=12, **kw):
    """``n`` bodies (count=n) over 10 flow events of 1 ms; the simulation and inlet."""
    sim = scene()
    inlet = sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, rate=n * 100.0, count=n, every=1e-3,
                          seed=seed, **kw)
    sim.run(steps=steps, progress=False)
    assert inlet.inserted == len(sim.bodies) == n and inlet.finished
    return sim, inlet


def in_order(sim, inlet, field):
    """``field`` of the inlet's bodies in the order it inserted them."""
    ids = np.concatenate(inlet.ids)
    order = np.argsort(sim.bodies.id)
    return getattr(sim.bodies, field)[order[np.searchsorted(sim.bodies.id[order], ids)]]


# ------------------------------------------------------------------ totals: count, mass
def test_count_is_exact_and_the_rate_sets_the_pace():
    sim = scene()
    inlet = sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, rate=500.0, count=37, radius=1e-3,
                          seed=3)
    sim.run(until=0.05, progress=False)
    assert 20 <= inlet.inserted <= 26 and not inlet.finished  # 500/s: 25 by 0.05 s
    sim.run(until=0.3, progress=False)
    assert inlet.inserted == len(sim.bodies) == 37 and inlet.finished
    assert inlet.owed(10.0) == 0.0


def test_count_with_a_mass_rate_stops_inside_an_event():
    """About 10 bodies a 1 ms event by mass; the 4th event stops at the 37th body."""
    m1 = 4 / 3 * math.pi * 1e-3**3 * STEEL.density
    sim = scene()
    inlet = sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, mass_rate=10 * m1 / 1e-3, count=37,
                          radius=(0.9e-3, 1.1e-3), seed=4)
    sim.run(steps=20, progress=False)
    assert inlet.inserted == len(sim.bodies) == 37 and inlet.finished
    assert inlet.inserted_mass == pytest.approx(float(sim.bodies.mass.sum()), rel=1e-12)


def test_count_alone_inserts_everything_at_the_first_event():
    sim = scene()
    inlet = sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, count=250, radius=(1e-3, 2e-3))
    sim.run(steps=1, progress=False)
    assert len(sim.bodies) == 250 and inlet.rate == math.inf and inlet.finished
    sim.run(steps=5, progress=False)
    assert len(sim.bodies) == 250


@pytest.mark.parametrize("how", [{"mass_rate": 0.2}, {"rate": 2e4}, {}])
def test_a_total_mass_is_reached_by_the_last_body(how):
    """Bodies until their mass reaches ``mass``: all but the last weigh less than it."""
    sim = scene()
    inlet = sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, mass=3e-3, radius=(1e-3, 2e-3),
                          seed=5, **how)
    sim.run(steps=40, progress=False)
    m = in_order(sim, inlet, "mass")
    assert inlet.finished and len(m) == inlet.inserted
    assert m[:-1].sum() < 3e-3 <= m.sum()
    assert inlet.inserted_mass == pytest.approx(m.sum(), rel=1e-12)


def test_restart_keeps_what_the_inlet_has_inserted(tmp_path):
    """Checkpointed after 30 of 60 bodies, the restarted run inserts the other 30: the
    same bodies as the run that was never stopped."""
    def build():
        sim = scene()
        sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, rate=1000.0, count=60, seed=8,
                      radius=dpm.Normal(1e-3, 1e-4, 8e-4, 1.2e-3))
        return sim

    a = build()
    a.run(until=0.03, progress=False)
    assert 25 <= a.inlets[0].inserted < 60
    path = a.checkpoint(tmp_path / "c.h5")
    a.run(until=0.1, progress=False)
    b = dpm.restart(path)
    assert b.inlets[0].count == 60 and b.inlets[0].inserted < 60
    b.run(until=0.1, progress=False)
    for sim in (a, b):
        assert sim.inlets[0].inserted == len(sim.bodies) == 60 and sim.inlets[0].finished
    np.testing.assert_array_equal(a.bodies.id, b.bodies.id)
    np.testing.assert_array_equal(a.bodies.radius, b.bodies.radius)


# ------------------------------------------------------------------ distributions
def test_normal_mean_std_and_truncation():
    mean, std, low, high = 1e-3, 2e-4, 7e-4, 1.3e-3  # +-1.5 std: a visible cut
    sim, _ = insert(radius=dpm.Normal(mean, std, low, high))
    r = sim.bodies.radius
    ref = stats.truncnorm((low - mean) / std, (high - mean) / std, loc=mean, scale=std)
    m, v, _, kurt = (float(x) for x in ref.stats(moments="mvsk"))
    s = math.sqrt(v)
    mu4 = (kurt + 3.0) * v**2
    assert r.min() > low and r.max() < high  # conditioned, not clipped: nothing at a bound
    assert abs(r.mean() - m) < K * s / math.sqrt(N)
    assert abs(r.std() - s) < K * math.sqrt(mu4 - v**2) / (2 * s * math.sqrt(N))
    assert r.std() < 0.8 * std  # the truncated std (0.74 std), not the untruncated one
    assert stats.kstest(r, ref.cdf).pvalue > 1e-4


def lognormal_reference(mu, sigma, low, high):
    return stats.truncnorm((math.log(low) - mu) / sigma, (math.log(high) - mu) / sigma,
                           loc=mu, scale=sigma)


def test_lognormal_median_and_geometric_std():
    median, gsd, low, high = 1e-3, 1.5, 3e-4, 4e-3
    sim, _ = insert(radius=dpm.LogNormal(median, gsd, low, high), seed=2)
    x = np.log(sim.bodies.radius)
    ref = lognormal_reference(math.log(median), math.log(gsd), low, high)
    _, v, _, kurt = (float(y) for y in ref.stats(moments="mvsk"))
    s = math.sqrt(v)
    med = float(ref.median())
    assert x.min() >= math.log(low) and x.max() <= math.log(high)
    se_median = math.sqrt(0.25 / N) / float(ref.pdf(med))
    assert abs(np.median(x) - med) < K * se_median
    assert abs(x.std() - s) < K * math.sqrt((kurt + 2.0) * v**2) / (2 * s * math.sqrt(N))
    # the truncation at about -3 and +3.4 sigma hardly moves them from the given values
    assert math.exp(med) == pytest.approx(median, rel=0.01)
    assert math.exp(s) == pytest.approx(gsd, rel=0.02)
    assert stats.kstest(x, ref.cdf).pvalue > 1e-4


def test_lognormal_mu_sigma_is_median_gsd():
    a = dpm.LogNormal(1e-3, 1.5, 3e-4, 4e-3)
    b = dpm.LogNormal(mu=math.log(1e-3), sigma=math.log(1.5), low=3e-4, high=4e-3)
    ra, rb = np.random.default_rng(9), np.random.default_rng(9)
    assert [a.sample(ra) for _ in range(200)] == pytest.approx(
        [b.sample(rb) for _ in range(200)], rel=1e-12)


def test_lognormal_on_a_mass_basis_has_the_mass_median():
    """basis="mass": the given median is the mass median (x50,3) of the bodies."""
    median, gsd, low, high = 1e-3, 1.4, 2e-4, 3e-3
    sim, _ = insert(radius=dpm.LogNormal(median, gsd, low, high, basis="mass"), seed=3)
    r, m = sim.bodies.radius, sim.bodies.mass
    ref = lognormal_reference(math.log(median), math.log(gsd), low, high)  # mass-weighted
    med = math.exp(float(ref.median()))
    below = (r <= med).astype(float)
    f = float((m * below).sum() / m.sum())
    se = math.sqrt(float((m**2 * (below - f) ** 2).sum())) / float(m.sum())
    assert abs(f - 0.5) < K * se
    # and not on a number basis: half the bodies by number are far below the mass median
    assert np.mean(r <= med) > 0.75
    mean_w = float((m * np.log(r)).sum() / m.sum())
    se_w = math.sqrt(float((m**2 * (np.log(r) - mean_w) ** 2).sum())) / float(m.sum())
    assert abs(mean_w - float(ref.mean())) < K * se_w


@pytest.mark.parametrize("within", ["uniform", "log"])
def test_sieve_table_mass_fractions_are_reproduced(within):
    edges = [3e-4, 5e-4, 7e-4, 1e-3, 1.4e-3]
    fractions = [0.1, 0.25, 0.4, 0.25]
    sim, inlet = insert(radius=dpm.Sieve(edges, fractions, within=within), seed=4)
    r, m = sim.bodies.radius, sim.bodies.mass
    assert r.min() >= edges[0] and r.max() <= edges[-1]
    k = np.searchsorted(edges, r, side="right") - 1
    total = float(m.sum())
    for c, w in enumerate(fractions):
        inside = (k == c).astype(float)
        f = float((m * inside).sum()) / total
        se = math.sqrt(float((m**2 * (inside - f) ** 2).sum())) / total
        assert abs(f - w) < K * se, (c, f, w, se)
        # within a class: uniform in size (mean (a + b) / 2) or in log size
        a, b = edges[c], edges[c + 1]
        x = r[k == c] if within == "uniform" else np.log(r[k == c])
        lo, hi = (a, b) if within == "uniform" else (math.log(a), math.log(b))
        assert abs(x.mean() - (lo + hi) / 2) < K * (hi - lo) / math.sqrt(12 * len(x))
    # by number the fine classes dominate: mass fractions were not used as number fractions
    assert np.mean(k == 0) > 0.2 > fractions[0] * 1.5


def test_sieve_with_an_empty_class_and_a_mesh_like_size():
    """A class of fraction 0 gets no bodies; a cube's edge scales the whole body (mass ~
    a^3), so the sieve applies to it as to a radius."""
    d = dpm.Sieve([1e-3, 2e-3, 3e-3, 4e-3], [0.0, 1.0, 0.0])
    assert (d.low, d.high) == (2e-3, 3e-3)
    rng = np.random.default_rng(0)
    v = np.array([d.sample(rng) for _ in range(500)])
    assert v.min() >= 2e-3 and v.max() <= 3e-3
    sim = scene()
    sim.add_inlet(dpm.BoxRegion(*BOX), STEEL, count=3, shape="cube",
                  a=dpm.Sieve([1e-3, 2e-3], [1.0]))
    sim.run(steps=1, progress=False)
    m = sim.bodies.mass
    assert len(m) == 3 and np.all((m > 1e-9 * STEEL.density) & (m < 8e-9 * STEEL.density))


def test_reproducible_from_the_seed():
    def run(seed):
        sim, _ = insert(n=200, seed=seed, steps=11,
                        radius=dpm.Sieve([3e-4, 6e-4, 1e-3], [0.4, 0.6]))
        return sim.bodies.radius.copy(), sim.bodies.position.copy()

    a, b, c = run(5), run(5), run(6)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


# ------------------------------------------------------------------ scene files
SCENE = """
[simulation]
dt = 1e-3
gravity = [0, 0, 0]
dt_check = "off"

[materials.steel]
density = 7800.0
young = 2e8
poisson = 0.3

[[contacts]]
materials = ["steel", "steel"]
model = "hertz_mindlin"
restitution = 0.5
friction = 0.5

[[inlets]]
material = "steel"
region = { box = { lower = [0, 0, 0], upper = [1, 1, 1] } }
rate = 20000
count = 150
seed = 7
radius = { normal = { mean = 1e-3, std = 1e-4, low = 8e-4, high = 1.2e-3 } }

[[inlets]]
material = "steel"
region = { box = { lower = [0, 0, 0], upper = [1, 1, 1] } }
mass_rate = 5.0
mass = 0.02
seed = 8

[[inlets.shapes]]
shape = "sphere"
fraction = 0.5
radius = { sieve = { edges = [5e-4, 1e-3, 2e-3], fractions = [0.3, 0.7], within = "log" } }

[[inlets.shapes]]
shape = "sphere"
fraction = 0.5
radius.lognormal = { median = 1e-3, gsd = 1.2, low = 6e-4, high = 2e-3, basis = "mass" }
"""


def test_scene_file_builds_the_same_inlets_as_python(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE)
    toml, _ = load_scene(path, output=False)
    py = scene()
    box = dpm.BoxRegion(*BOX)
    py.add_inlet(box, STEEL, rate=20000, count=150, seed=7,
                 radius=dpm.Normal(1e-3, 1e-4, 8e-4, 1.2e-3))
    py.add_inlet(box, STEEL, mass_rate=5.0, mass=0.02, seed=8, shapes=[
        {"shape": "sphere", "fraction": 0.5,
         "radius": dpm.Sieve([5e-4, 1e-3, 2e-3], [0.3, 0.7], within="log")},
        {"shape": "sphere", "fraction": 0.5,
         "radius": dpm.LogNormal(1e-3, 1.2, 6e-4, 2e-3, basis="mass")}])
    for a, b in zip(toml.inlets, py.inlets, strict=True):
        assert a.shapes == b.shapes
        assert (a.count, a.mass, a.rate, a.mass_rate, a.seed) == (
            b.count, b.mass, b.rate, b.mass_rate, b.seed)
    for sim in (toml, py):
        sim.run(steps=12, progress=False)
    assert toml.inlets[0].inserted == 150 and toml.inlets[1].finished
    np.testing.assert_array_equal(toml.bodies.radius, py.bodies.radius)
    np.testing.assert_array_equal(toml.bodies.position, py.bodies.position)


@pytest.mark.parametrize("line, match", [
    ("radius = { normal = { mean = 1e-3, sd = 1e-4, low = 8e-4, high = 1.2e-3 } }",
     r"inlets\[0\]: radius.normal: unknown key sd = 0.0001 \(did you mean std\?\).*\(line 22\)"),
    ("radius = { gauss = { mean = 1e-3 } }", r"inlets\[0\]: radius: unknown distribution gauss"),
    ("radius = { sieve = { edges = [1e-3, 2e-3] } }",
     r"inlets\[0\]: radius.sieve: fractions is required"),
    ("radius = { lognormal = { median = 1e-3, gsd = 1.2, high = 2e-3 } }",
     r"radius.lognormal: low is required"),
    ("radius = { sieve = { edges = [2e-3, 1e-3, 3e-3], fractions = [0.5, 0.5] } }",
     r"Inlet\(\): shapes\[0\] radius: dpm.Sieve\(\): edges=.* are not sorted: edge 1"),
    ("cont = 5\nradius = 1e-3", r"unknown key cont = 5 \(did you mean count\?\)"),
    ('shapes = [{ shape = "sphere", radius = { normal = { mean = 1e-3 } } }]',
     r"inlets\[0\]: shapes\[0\]: radius.normal: std is required"),
])
def test_scene_file_refuses_bad_distribution_tables_by_name(tmp_path, line, match):
    text = SCENE.split("[[inlets]]")[0] + """[[inlets]]
material = "steel"
region = { box = { lower = [0, 0, 0], upper = [1, 1, 1] } }
rate = 100
""" + line + "\n"
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=match):
        load_scene(path, output=False)


# ------------------------------------------------------------------ bad inputs, named
R = dpm.Normal(1e-3, 1e-4, 8e-4, 1.2e-3)


@pytest.mark.parametrize("make, match", [
    (lambda: dpm.Sieve([1e-3, 2e-3, 3e-3], [0.5, 0.4]), r"sum to 0.9; allowed: .* within"),
    (lambda: dpm.Sieve([1e-3, 2e-3, 3e-3], [50, 50]), r"percentages\? divide them by 100"),
    (lambda: dpm.Sieve([1e-3, 3e-3, 2e-3], [0.5, 0.5]), r"not sorted: edge 2 \(0.002\)"),
    (lambda: dpm.Sieve([1e-3, 2e-3, 3e-3], [1.1, -0.1]), r"fraction 1 is -0.1"),
    (lambda: dpm.Sieve([1e-3, 2e-3, 3e-3], [1.0]), r"3 edges bound 2 classes, but 1"),
    (lambda: dpm.Sieve([0.0, 2e-3], [1.0]), r"finite sizes > 0"),
    (lambda: dpm.Sieve([1e-3, 2e-3], [1.0], within="cubic"), r"within='cubic'"),
    (lambda: dpm.Normal(1e-3, 0.0, 8e-4, 1.2e-3), r"std=0 is outside \(0, inf\)"),
    (lambda: dpm.Normal(1e-3, 1e-4, 1.2e-3, 8e-4), r"low=0.0012 must be below high"),
    (lambda: dpm.Normal(1.0, 1e-4, 8e-4, 1.2e-3), r"hold 0 of the distribution.*units"),
    (lambda: dpm.LogNormal(1e-3, None, 5e-4, 2e-3), r"give median and gsd .* or mu and"),
    (lambda: dpm.LogNormal(1e-3, 1.2, 5e-4, 2e-3, mu=-7.0, sigma=0.2),
     r"one pair in full"),
    (lambda: dpm.LogNormal(1e-3, 0.5, 5e-4, 2e-3), r"gsd=0.5 is outside \(1, inf\)"),
    (lambda: dpm.LogNormal(1e-3, 1.2, 5e-4, 2e-3, basis="volume"), r"basis='volume'"),
    (lambda: dpm.LogNormal(1e-3, 1.2, None, 2e-3), r"low is required"),
])
def test_bad_distributions_are_named(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


@pytest.mark.parametrize("kw, match", [
    (dict(rate=100.0, count=10, mass=1.0), r"count \(bodies\) or mass \(kg\) in all, not both"),
    (dict(rate=100.0, count=50, stop=0.2),
     r"count=50 at rate=100.0/s takes 0.5 s from start=0.0 s, past stop=0.2 s .*only 20"),
    (dict(mass_rate=1.0, mass=2.0, start=1.0, stop=2.5), r"mass=2.0 at mass_rate=1.0 kg/s"),
    (dict(mass_rate=1.0, count=50, stop=2.0), r"count=50 with mass_rate=1.0: the time"),
    (dict(rate=10.0, mass=1.0, stop=2.0), r"mass=1.0 with rate=10.0: the time"),
    (dict(count=50, stop=2.0), r"count=50 without a rate .* stop=2.0 has no meaning"),
    (dict(rate=100.0, count=0), r"count=0 is outside \[1, inf\)"),
    (dict(rate=100.0, count=2.5), r"count=2.5 is not an integer"),
    (dict(rate=100.0, mass=-1.0), r"mass=-1 is outside \(0, inf\)"),
    (dict(), r"give exactly one of rate \(1/s\) or mass_rate \(kg/s\), or a total alone"),
    (dict(count=5, radius={"normal": {"mean": 1e-3, "sd": 1e-4, "low": 8e-4,
                                      "high": 1.2e-3}}),
     r"shapes\[0\] radius.normal: unknown key sd"),
    (dict(count=5, radius=dpm.Normal(1e-3, 5e-4, -1e-4, 2e-3)),
     r"radius=dpm.Normal\(.*\): sphere at the low end: radius=-0.0001"),
    (dict(count=5, shape="cylinder", l=3e-3, r=dpm.Sieve([1e-3, 2e-3], [1.0])),
     r"shapes\[0\] r=dpm.Sieve.*scales the whole body .* changes by 4 .* not 8"),
])
def test_bad_inlet_totals_and_sizes_are_named(kw, match):
    if "shape" not in kw:
        kw.setdefault("radius", R)
    with pytest.raises(ParameterError, match=match):
        scene().add_inlet(dpm.BoxRegion(*BOX), STEEL, **kw)


def test_a_total_that_fits_its_stop_is_accepted():
    inlet = scene().add_inlet(dpm.BoxRegion(*BOX), STEEL, rate=500.0, count=500, start=0.2,
                              stop=1.2, radius=R)
    assert inlet.owed(5.0) == 500.0
