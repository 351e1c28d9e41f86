"""Whole-scene checks before the first step: every problem in one error.

What can meet is resolved here, once: the materials of the particles and of everything an
inlet will bring, the shapes inlets draw (names and parameters), the material pairs that
need a contact law (particle-particle only where two bodies of those materials can exist,
particle-boundary for every boundary), particles outside boundaries, NaN in the state,
initial overlaps and the periodic box. What runs but is most likely a slip (a modulus in
GPa, a mesh in mm, a drum turning about a centre off its axis, particles larger than their
container) is warned about here too, once per scene (:mod:`dpm.plausibility`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import DpmError, SceneError


def few(ids: np.ndarray, k: int = 5) -> str:
    s = ", ".join(str(int(i)) for i in ids[:k])
    return s + (f", ... ({len(ids)} in all)" if len(ids) > k else "")


def material_counts(sim: Any) -> dict[int, float]:
    """Bodies per material index that the scene can hold: those present, and (as many
    as it likes: inf) those an inlet brings."""
    counts: dict[int, float] = {}
    for m, n in zip(*np.unique(sim.bodies.material, return_counts=True), strict=True):
        counts[int(m)] = float(n)
    for inlet in sim.inlets:
        counts[sim._material_index(inlet.material, "")] = float("inf")
    return counts


def pairs_that_can_meet(sim: Any) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """(particle pairs (a <= b), (particle material, boundary index)) that can touch: a
    material with itself only where two bodies of it can exist; no more than can occur,
    so one free body needs no law with itself."""
    counts = material_counts(sim)
    mats = sorted(counts)
    particle = [(a, b) for i, a in enumerate(mats) for b in mats[i:]
                if a != b or counts[a] >= 2]
    wall = [(a, k) for a in mats for k in range(len(sim.boundaries))]
    return particle, wall


#: points of an inlet's region tried against the boundaries
REGION_SAMPLES = 2000


def inlet_problems(sim: Any) -> list[str]:
    """Inlets that cannot place a single particle: their shapes are resolved (names,
    parameters, ranges) when the inlet is made (:class:`dpm.flow.Inlet`); here each
    region is sampled (fixed seed) with the inlet's smallest bounding radius and refused
    when it has no volume, cannot hold that ball, or no sample point lies inside every
    boundary (``bd.outside``, as for the particles)."""
    problems = []
    rng = np.random.default_rng(12345)
    for n, inlet in enumerate(sim.inlets):
        region = inlet.region
        try:
            r = inlet.smallest_radius()
        except DpmError as exc:
            problems.append(f"inlet {n}: {exc}")
            continue
        try:
            volume = float(region.volume)
        except NotImplementedError:
            volume = None
        if volume is not None and not volume > 0:
            problems.append(f"inlet {n}: its region {region!r} has no volume")
            continue
        if not region.holds(r):
            problems.append(f"inlet {n}: its region {region!r} is too small for the smallest "
                            f"particle it inserts (bounding radius {r:g} m)")
            continue
        if not sim.boundaries:
            continue
        pts = np.asarray(region.sample(rng, REGION_SAMPLES, r), float)
        radii = np.full(len(pts), r)
        ok = np.ones(len(pts), bool)
        for bd in sim.boundaries:
            if bd.enabled:
                ok &= ~np.asarray(bd.outside(pts, radii), bool)
        if not np.any(ok):
            names = ", ".join(f"{k} ({bd.name})" for k, bd in enumerate(sim.boundaries))
            problems.append(f"inlet {n}: no point of its region {region!r} (of "
                            f"{REGION_SAMPLES} tried, bounding radius {r:g} m) lies inside "
                            f"every boundary ({names}): it could never insert a particle")
    return problems


def validate_scene(sim: Any) -> None:
    """Refuse a scene that cannot run right, naming every problem in one error."""
    problems: list[str] = []
    b = sim.bodies
    if len(b) == 0:
        problems.append("the scene has no particles (sim.add_particles)" + (
            "; the inlets bring none before the first step (rate x every < 1 body): add "
            "particles, or raise the rate or every" if sim.inlets else ""))
    for name in ("position", "velocity", "angular_velocity", "orientation"):
        arr = getattr(b, name)
        bad = ~np.all(np.isfinite(arr), axis=1)
        if np.any(bad):
            problems.append(f"{name} is NaN or inf for particle id(s) {few(b.id[bad])}")
    problems += inlet_problems(sim)
    # every material pair that can meet needs a contact law
    particle, wall = pairs_that_can_meet(sim)
    brought = {sim._material_index(i.material, "") for i in sim.inlets}

    def label(k: int) -> str:
        only_inlet = k in brought and not np.any(b.material == k)
        return sim.materials[k].name + (" (brought by an inlet)" if only_inlet else "")

    missing = [f"{label(ia)}-{label(ib)}" for ia, ib in particle
               if (ia, ib) not in sim._contacts]
    for ia, k in wall:
        bd = sim.boundaries[k]
        ib = sim._material_index(bd.material, "")
        if (ia, ib) not in sim._contacts:
            pair = f"{label(ia)}-{bd.material.name} ({bd.name})"
            if pair not in missing:
                missing.append(pair)
    if missing:
        problems.append("no contact law for material pair(s) " + ", ".join(missing)
                        + "; set them with sim.contact(a, b, model=..., ...)")
    # particles outside a boundary
    if len(b):
        for k, bd in enumerate(sim.boundaries):
            if not bd.enabled:
                continue
            out = bd.outside(b.position, b.radius)
            if np.any(out):
                side = getattr(bd, "side", None)
                hint = (f" (particles belong {side} this closed mesh; set side= 'inside', "
                        "'outside' or 'both' to say otherwise)" if side else "")
                problems.append(f"{int(out.sum())} particle(s) lie outside boundary {k} "
                                f"({bd.name}): id(s) {few(b.id[out])}{hint}")
    # what runs but is most likely a slip of units or of a centre: warned about once per
    # scene (before a refusal too: a radius in mm read as m explains an overlap)
    from .plausibility import warn_plausibility

    warn_plausibility(sim, stacklevel=4)  # (sim.run's caller: _prepare, run, it)
    if problems:
        raise SceneError("scene check before the first step:\n  " + "\n  ".join(problems))


def check_period(sim: Any) -> None:
    """Each periodic length at least twice the contact search cell."""
    from .errors import ParameterError

    need = 2.0 * (2.0 * float(sim.elements.radius.max()) + sim.skin)
    for d in range(3):
        if 0.0 < sim.period[3 + d] < need:
            raise ParameterError(
                f"sim.set_periodic(): the period along {'xyz'[d]} is "
                f"{sim.period[3 + d]:.4g} m; it must be at least {need:.4g} m (twice "
                "the contact search range 2 r_max + skin) for nearest images to be unique")


def check_initial_overlaps(sim: Any, first_element: int = 0) -> None:
    """Refuse overlaps beyond ``overlap_tolerance`` (of the smaller radius) between
    particles and between particles and boundaries, all listed in one error. Only contacts
    of elements from ``first_element`` on are checked: after a run, those of the bodies
    added since (a settled bed's own overlaps are not initial)."""
    e, b, tol = sim.elements, sim.bodies, sim.overlap_tolerance
    problems = []
    c = sim.contacts
    if c.count and first_element < len(e):
        ratio = sim.backend.pair_overlaps()
        if first_element:  # the list holds j > i: a pair is new when j is
            ratio = np.where(c.key[:c.count] >= first_element, ratio, -np.inf)
        k = int(np.argmax(ratio))
        if ratio[k] > tol:
            i = int(np.searchsorted(c.start, k, side="right") - 1)
            j = int(c.key[k])
            problems.append(
                f"{int(np.sum(ratio > tol))} particle pair(s) overlap more than "
                f"overlap_tolerance={tol:g} of the smaller radius; worst: particles "
                f"{b.id[e.owner[i]]} and {b.id[e.owner[j]]} overlap by "
                f"{ratio[k]:.3g} of the radius")
    wc, w = sim.wall_contacts, sim.walls
    if wc.count and first_element < len(e):
        i = np.repeat(np.arange(len(e)), np.diff(wc.start))
        p = wc.key[:wc.count]
        ratio = sim.backend.entry_overlaps()
        if first_element:
            ratio = np.where(i >= first_element, ratio, -np.inf)
        k = int(np.argmax(ratio))
        if ratio[k] > tol:
            bd = sim.boundaries[w.owner[p[k]]]
            problems.append(
                f"{int(np.sum(ratio > tol))} particle(s) overlap a boundary more than "
                f"overlap_tolerance={tol:g} of the radius; worst: particle "
                f"{b.id[e.owner[i[k]]]} overlaps boundary {int(w.owner[p[k]])} ({bd.name}) "
                f"by {ratio[k]:.3g} of its radius")
    if problems:
        raise SceneError("initial overlap: " + "; ".join(problems))
