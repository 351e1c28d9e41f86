"""Reordering the state in the middle of a run (``sim.permute``): every container follows,
each contact keeps its history, and the run goes on as if nothing happened.

Two things can change the last bit after a reordering, by design: the order in which a
body's contacts are summed, and, for a pair now stored the other way round, the side its
contact point and lever arms are computed from. The bit-for-bit test therefore uses a scene
where no body sums more than two forces at once (gravity and one contact: a + b == b + a
exactly in IEEE arithmetic) and a permutation that moves every interacting pair as a block
(its two bodies keep their relative order); any difference is then a bug of the
reordering (a history row left with the wrong pair, a stale reference position, the
integrator's state left behind). Pairs stored the other way round (their springs negated)
are checked exactly on the history itself, and a pile whose bodies touch several others
at once is compared with a tolerance."""

from __future__ import annotations

import numpy as np
import pytest

import dpm

R = 1e-3
GLASS = dict(density=2500, young=5e6, poisson=0.45)


def _isolated_contacts(reverse_after: int | None, steps: int = 1600,
                       model: str = "hertz_mindlin"):
    """Pairs of spheres colliding obliquely with spin in free flight (tangential and
    rolling springs; Walton-Braun adds its plastic overlap, a scalar) and spheres sliding
    on a floor (boundary history); each body touches at most one thing at a time."""
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81), threads=1)
    g = dpm.Material("glass", **GLASS)
    s = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    law = dict(restitution=0.5, friction=0.4, rolling_friction=0.05)
    if model == "walton_braun":
        law = dict(stiffness=2e3, restitution=0.5, friction=0.4, rolling_friction=0.05)
    else:
        law["rolling_model"] = "epsd"
    sim.contact(g, g, model=model, **law)
    sim.contact(g, s, model=model, **law)
    sim.add_boundary("plane", material=s, point=(0, 0, 0), normal=(0, 0, 1))
    pos, vel, spin = [], [], []
    for k in range(6):  # colliding pairs, high above the floor
        x = 10 * R * k
        pos += [(x, 0.0, 20 * R), (x + 2.05 * R, 0.4 * R, 20.3 * R)]
        vel += [(0.3, 0.0, 0.0), (-0.3, 0.02 * k, 0.0)]
        spin += [(0.0, 5.0 * k, 20.0), (3.0, 0.0, -10.0)]
    for k in range(5):  # sliding and spinning on the floor
        pos.append((10 * R * k, 30 * R, 0.999 * R))
        vel.append((0.2, 0.05 * k, 0.0))
        spin.append((0.0, 0.0, 30.0))
    sim.add_particles("sphere", material=g, radius=R, positions=pos, velocities=vel,
                      angular_velocities=spin)
    if reverse_after is None:
        sim.run(steps=steps, progress=False)
    else:
        sim.run(steps=reverse_after, progress=False)
        assert sim.contact_count() >= 6 + 5  # the pairs touch now: their springs are loaded
        # pairs (rows 2k, 2k+1) and floor spheres as blocks, in reverse block order
        blocks = [[2 * k, 2 * k + 1] for k in range(6)] + [[12 + k] for k in range(5)]
        sim.permute(np.concatenate(blocks[::-1]))
        sim.run(steps=steps - reverse_after, progress=False)
    return sim


def _by_id(sim):
    o = np.argsort(sim.bodies.id)
    b = sim.bodies
    return [a[o] for a in (b.position, b.velocity, b.angular_velocity, b.orientation,
                           b.force, b.torque)]


def test_permuting_mid_run_continues_bit_for_bit():
    ref = _isolated_contacts(None)
    got = _isolated_contacts(300)
    assert not np.array_equal(got.bodies.id, ref.bodies.id)  # rows really were reordered
    for a, b in zip(_by_id(ref), _by_id(got), strict=True):
        np.testing.assert_array_equal(a, b)
    # the floor's load sums its contacts in list order, which did change
    np.testing.assert_allclose(got.boundaries[0].force, ref.boundaries[0].force,
                               rtol=1e-12, atol=0)


def _pair_history(sim):
    """{(id a, id b) with a < b: history of a relative to b} of the touching pairs (the
    vector floats, as the laws' parts declare them, negated where b is stored first)."""
    c, ids, mat = sim.contacts, sim.bodies.id, sim.elements.material
    rows = np.repeat(np.arange(len(c.start) - 1), np.diff(c.start))
    out = {}
    for k in range(c.count):
        if c.active[k]:
            a, b = int(ids[rows[k]]), int(ids[c.key[k]])
            h = c.history[k].copy()
            if a > b:
                a, b = b, a
                flips = sim.plan.history_flips[sim.plan.pair_model[mat[rows[k]],
                                                                   mat[c.key[k]]]]
                h[flips[:len(h)]] *= -1.0
            out[(a, b)] = h
    return out


@pytest.mark.parametrize("model", ["hertz_mindlin", "walton_braun"])
def test_each_contact_keeps_its_history(model):
    sim = _isolated_contacts(None, steps=300, model=model)
    flips = sim.plan.history_flips[0]
    width = sim.contacts.history_width
    if model == "walton_braun":  # tangential spring, then delta_max and delta_0 (scalars)
        assert list(flips[:width]) == [True] * 3 + [False] * 2
    else:  # tangential spring, rolling spring
        assert list(flips[:width]) == [True] * 6
    before = _pair_history(sim)
    walls = {int(sim.bodies.id[sim.elements.owner[i]]): sim.wall_contacts.history[q].copy()
             for i in range(len(sim.elements))
             for q in range(sim.wall_contacts.start[i], sim.wall_contacts.start[i + 1])
             if sim.wall_contacts.active[q]}
    assert len(before) == 6 and (len(walls) == 5 or model == "walton_braun")  # (it bounces)
    assert all(np.any(h[:3] != 0) for h in before.values())
    if model == "walton_braun":
        assert all(h[3] > 0 for h in before.values())  # delta_max: must not be negated
    else:
        assert all(np.any(h[3:6] != 0) for h in before.values())
    order = np.random.default_rng(3).permutation(len(sim.bodies))
    sim.permute(order)
    assert _pair_history(sim).keys() == before.keys()
    for key, h in _pair_history(sim).items():
        np.testing.assert_array_equal(h, before[key])
    e, wc = sim.elements, sim.wall_contacts
    for i in range(len(e)):
        for q in range(wc.start[i], wc.start[i + 1]):
            if wc.active[q]:
                np.testing.assert_array_equal(wc.history[q], walls[int(sim.bodies.id[e.owner[i]])])


def _pile(permute_at: int | None, steps: int = 1500, device=None):
    """Spheres and clustered bodies jostling in a box: many contacts per body."""
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81), threads=1,
                         **({} if device is None else {"device": device}))
    g = dpm.Material("glass", **GLASS)
    sim.contact(g, g, model="hertz_mindlin", restitution=0.4, friction=0.5)
    sim.add_boundary("box", material=g, lower=(0, 0, 0), upper=(0.016, 0.016, 0.03),
                     open=("+z",))
    xyz = dpm.lattice((0, 0, 0), (0.016, 0.016, 0.008), spacing=2.02 * R, jitter=1e-5,
                      seed=2)
    rng = np.random.default_rng(5)
    sim.add_particles("sphere", material=g, radius=R, positions=xyz,
                      velocities=rng.uniform(-0.2, 0.2, xyz.shape))
    top = dpm.lattice((0, 0, 0.0085), (0.016, 0.016, 0.012), spacing=3.0 * R, seed=4)
    sim.add_particles("ellipsoid", material=g, a=1.3 * R, b=0.9 * R, c=0.9 * R,
                      positions=top, velocities=np.tile([0.0, 0.0, -0.5], (len(top), 1)))
    if permute_at is None:
        sim.run(steps=steps, progress=False)
    else:
        sim.run(steps=permute_at, progress=False)
        sim.permute(np.random.default_rng(7).permutation(len(sim.bodies)))
        sim.run(steps=steps - permute_at, progress=False)
    return sim


def test_permuting_a_pile_of_clusters_changes_only_rounding():
    ref = _pile(None)
    got = _pile(600)
    assert ref.contact_count() > 60  # (of 147 spheres and 25 clusters)
    for a, b in zip(_by_id(ref)[:4], _by_id(got)[:4], strict=True):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-9 * max(np.abs(a).max(), 1.0))


def test_permute_refuses_what_is_not_a_permutation():
    sim = _isolated_contacts(None, steps=1)
    n = len(sim.bodies)
    for bad in (np.zeros(n, int), np.arange(n - 1), np.arange(n) + 0.5):
        with pytest.raises(dpm.ParameterError, match="permutation"):
            sim.permute(bad)


def test_renumbering_in_cell_order_changes_only_rounding():
    """``CpuBackend(sort_every=1)``: the pile renumbered in cell order at every list
    rebuild runs as the unsorted pile, to rounding; its rows end in cell order."""
    from dpm.backends import CpuBackend

    ref = _pile(None)
    ref_rebuilds = ref.rebuild_count
    got = _pile(None, device=CpuBackend(threads=1, sort_every=1))
    assert got.rebuild_count == ref_rebuilds > 3
    assert np.any(got.bodies.id != np.arange(len(got.bodies)))  # rows did move
    for a, b in zip(_by_id(ref)[:4], _by_id(got)[:4], strict=True):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-9 * max(np.abs(a).max(), 1.0))


def test_large_scenes_are_renumbered_by_default():
    from dpm.backends import CpuBackend
    from dpm.backends.cpu import SORT_EVERY, SORT_FROM

    auto = CpuBackend()
    assert auto.sort_interval(SORT_FROM - 1) == 0
    assert auto.sort_interval(SORT_FROM) == SORT_EVERY > 0
    assert CpuBackend(sort_every=0).sort_interval(10**6) == 0
    assert CpuBackend(sort_every=3).sort_interval(10) == 3
    for bad in (-1, 2.5, True, "20"):
        with pytest.raises(dpm.ParameterError, match="sort_every"):
            CpuBackend(sort_every=bad)
