"""Bodies in and out: appending built shapes, removing by id, inlets and outlets.

Removal compacts bodies, elements and both contact lists (keys renumbered in order, so the
rows stay sorted and the history of the others survives); insertion appends and the lists
get empty rows; then one rebuild and a force evaluation at dt = 0 (the backend's
:meth:`population_changed`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .flow import Inlet, random_quaternions
from .motion import frames
from .plugins import call_hook
from .shapes.base import Shape
from .state import BoundaryTable


def filled(n: int, value, dtype) -> np.ndarray:
    """np.full(n, value), by np.zeros when value is 0: its pages then stay unmapped until
    written, so a field that stays 0 (the material of a one-material scene, the birth time
    of bodies placed at t = 0) costs no resident memory."""
    return np.zeros(n, dtype) if value == 0 else np.full(n, value, dtype)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product a (x) b of (N, 4) quaternions (w, x, y, z)."""
    a0, a1, a2, a3 = np.moveaxis(a, -1, 0)
    b0, b1, b2, b3 = np.moveaxis(np.broadcast_to(b, a.shape), -1, 0)
    return np.stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                     a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                     a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0], axis=-1)


def append_bodies(sim: Any, shape: Shape, imat: int, density: float, pos: np.ndarray,
                  vel: np.ndarray, ang: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Build ``len(pos)`` bodies of ``shape`` and append them with their elements; return
    their new ids (a copy: the bodies keep the array itself)."""
    n = len(pos)
    from ._memory import check_request

    call = f"sim.add_particles({type(shape).__name__})"
    check_request(call, n, n)  # (one element each: before anything is built)
    batch = shape.build(n, density)
    check_request(call, n, int(np.sum(batch.element_count)))  # (before the state grows)
    quat = quat_multiply(quat, np.asarray(batch.principal_rotation, float))
    first = len(sim.bodies)
    snapshot_forces(sim)
    ids = np.arange(sim._next_id, sim._next_id + n, dtype=np.int64)
    sim._next_id += n
    kind = getattr(shape, "name", "") or type(shape).__name__
    if kind not in sim.shape_names:
        sim.shape_names.append(kind)
    b = sim.bodies
    b.append(
        id=ids, position=pos, velocity=vel, angular_velocity=ang, orientation=quat,
        force=np.zeros((n, 3)), torque=np.zeros((n, 3)), mass=batch.mass,
        inertia=batch.inertia, invmass=1.0 / batch.mass, invinertia=1.0 / batch.inertia,
        radius=batch.bounding_radius, material=filled(n, imat, np.int64),
        shape=filled(n, sim.shape_names.index(kind), np.int64), birth=filled(n, sim.time, float))
    b.element_start = np.concatenate(
        [b.element_start, b.element_start[-1] + np.cumsum(batch.element_count)])
    owner = np.repeat(np.arange(first, first + n), batch.element_count)
    sim.elements.append(owner, batch.element_offset, batch.element_radius,
                        filled(len(owner), imat, np.int64))
    sim.energy.added(sim, slice(first, first + n))
    # the lists keep one (empty) row per new element: every contact keeps its history
    sim.contacts.resize_rows(len(sim.elements))
    sim.wall_contacts.resize_rows(len(sim.elements))
    sim._prepared = False
    sim._forces_valid = False
    return ids.copy()


def remove_bodies(sim: Any, ids) -> dict[str, np.ndarray]:
    """Remove the bodies with these ids; return their records (id, time, mass,
    residence_time, position, velocity). Contact history of the others is kept."""
    b, e = sim.bodies, sim.elements
    gone = np.isin(b.id, np.asarray(ids, np.int64))
    rec = {"id": b.id[gone].copy(), "time": np.full(int(gone.sum()), sim.time),
           "mass": b.mass[gone].copy(), "residence_time": sim.time - b.birth[gone],
           "position": b.position[gone].copy(), "velocity": b.velocity[gone].copy()}
    if not np.any(gone):
        return rec
    keep_b = ~gone
    keep_e = keep_b[e.owner]
    new_b = np.cumsum(keep_b) - 1
    new_e = np.cumsum(keep_e) - 1
    snapshot_forces(sim)
    sim.energy.taken(sim, gone)
    if sim._force_snapshot is not None:  # the bodies the removed ones touched
        partners = touching(sim, gone)
        sim._force_snapshot["touched"].append(b.id[partners])
    if len(sim.contacts.start) == len(e) + 1:  # the lists exist: drop the removed rows
        sim.contacts.keep_rows(keep_e, new_e, True)
        sim.wall_contacts.keep_rows(keep_e, new_e, False)
    if sim.backend.sim is sim:
        sim.backend.keep_bodies(keep_b)
    b.keep(keep_b)
    e.keep(keep_e, new_b)
    sim._checked_elements = int(np.sum(keep_e[:sim._checked_elements]))
    if sim._prepared:
        population_changed(sim)
    else:
        sim._forces_valid = False
    return rec


def touching(sim: Any, mask: np.ndarray, geometry: bool = False) -> np.ndarray:
    """Bodies (bool per row) with a touching contact to a body of ``mask``: by the
    contacts' touching flags of the last step, or (``geometry``) by the overlaps of the
    listed pairs now."""
    c, e = sim.contacts, sim.elements
    out = np.zeros(len(sim.bodies), bool)
    if len(c.start) != len(e) + 1 or c.count == 0:
        return out
    rows = np.repeat(np.arange(len(e)), np.diff(c.start))
    act = (sim.backend.pair_overlaps() > 0.0) if geometry else (c.active[:c.count] != 0)
    bi, bj = e.owner[rows[act]], e.owner[c.key[:c.count][act]]
    out[bi[mask[bj]]] = True
    out[bj[mask[bi]]] = True
    return out & ~mask


def snapshot_forces(sim: Any) -> None:
    """Before the first change of the population since the forces were last evaluated:
    keep every body's force and torque by id, so that the bodies the change does not touch
    go on with them (:func:`restore_forces`) and their trajectories stay as they would
    have been."""
    if sim._forces_valid and sim._force_snapshot is None:
        b = sim.bodies
        order = np.argsort(b.id, kind="stable")
        sim._force_snapshot = {"id": b.id[order].copy(), "force": b.force[order].copy(),
                               "torque": b.torque[order].copy(), "touched": []}


def restore_forces(sim: Any) -> None:
    """After the forces of a changed population were evaluated (dt = 0): the bodies that
    were there before and touch no added or removed body take back their forces of the
    last step (a fresh evaluation differs from it by the velocities that dashpots see:
    the integrator's predicted ones during a step, the current ones at dt = 0). Added
    bodies start the integrator's state (:meth:`Integrator.start_bodies`)."""
    snap = sim._force_snapshot
    sim._force_snapshot = None
    b = sim.bodies
    if snap is not None and len(b):
        pos = np.searchsorted(snap["id"], b.id)
        pos = np.minimum(pos, max(len(snap["id"]) - 1, 0))
        old = (snap["id"][pos] == b.id) if len(snap["id"]) else np.zeros(len(b), bool)
        keep = old & ~touching(sim, ~old, geometry=True)
        if snap["touched"]:
            keep &= ~np.isin(b.id, np.concatenate(snap["touched"]))
        b.force[keep] = snap["force"][pos[keep]]
        b.torque[keep] = snap["torque"][pos[keep]]
    new = np.flatnonzero(b.id >= sim._integrated_ids)
    if len(new):
        sim.integrator.start_bodies(sim, new)
    sim._integrated_ids = sim._next_id


def spheres_only(sim: Any) -> bool:
    """Every body one sphere element at its centre."""
    b, e = sim.bodies, sim.elements
    return bool(len(e) == len(b) and np.all(e.offset == 0.0)
                and np.array_equal(e.owner, np.arange(len(b))))


def share_sphere_arrays(sim: Any) -> None:
    """Every body a single sphere at its centre: its element's position, and its radius
    and material where they agree (they do for built-in spheres), are the body's own
    arrays, not copies (16 B per sphere less besides the position)."""
    b, e = sim.bodies, sim.elements
    e.position = b.position
    if np.array_equal(e.radius, b.radius):
        e.radius = b.radius
    if np.array_equal(e.material, b.material):
        e.material = b.material


def wait_for_inlets(sim: Any, nsteps: int) -> int:
    """An empty scene whose inlets start later: time advances by whole flow intervals,
    with nothing to compute, until a flow event brings the first bodies or ``nsteps``
    steps have passed; returns the steps skipped. The inlets are checked first (a region
    that could never take a particle is refused now, not after the wait). Output and
    checkpoints begin with the first bodies."""
    from .errors import SceneError
    from .scene_check import inlet_problems

    problems = inlet_problems(sim)
    if problems:
        raise SceneError("scene check before the first step:\n  " + "\n  ".join(problems))
    flow = sim.operations.flow
    flow.schedule(sim)
    skipped = 0
    while len(sim.bodies) == 0 and skipped < nsteps:
        n = min(nsteps - skipped, max(1, flow.next - sim.step_count))
        sim.step_count += n
        skipped += n
        if sim.step_count >= flow.next:
            flow.next += flow.every
            flow_event(sim)
    return skipped


def population_changed(sim: Any) -> None:
    """After bodies were inserted or removed during a run: the scene's form (fused or
    two-pass), shared sphere arrays, then the backend resizes, rebuilds and primes; the
    thread count follows the new size (a scene an inlet fills from a few bodies gets
    ``threads`` / ``DPM_THREADS`` once it is large enough)."""
    import numba

    numba.set_num_threads(sim.backend.thread_count(len(sim.elements)))
    sim.plan.spheres_only = spheres_only(sim)
    if sim.plan.spheres_only:
        share_sphere_arrays(sim)
    sim.backend.population_changed()
    restore_forces(sim)
    sim._forces_valid = True
    sim._update_boundary_loads()
    sim._prepared = True


def flow_event(sim: Any) -> None:
    """Outlets, then inlets, at the current time."""
    changed = False
    prepared = sim._prepared
    for k, outlet in enumerate(sim.outlets):
        if len(sim.bodies) == 0:
            break
        sel = outlet.select(sim.bodies.position)
        if np.any(sel):
            rec = remove_bodies(sim, sim.bodies.id[sel])
            outlet.record(rec)
            if sim._writer is not None:
                sim._writer.write_removed(rec, k)
            call_hook(sim._registry, "dpm_on_particles_removed", sim=sim, outlet=outlet,
                      records=rec)
    released = []
    for inlet in sim.inlets:
        # (a stream inlet: its carried bodies that crossed the face are released)
        if getattr(inlet, "stream", False) and inlet.due(sim.time):
            snapshot_forces(sim)
            ids = inlet.release(sim)
            if len(ids):
                changed = True
                released.append(ids)
                if sim._force_snapshot is not None:
                    sim._force_snapshot["touched"].append(ids)
        ids = insert(sim, inlet)
        if len(ids):
            changed = True
            call_hook(sim._registry, "dpm_on_particles_inserted", sim=sim, inlet=inlet,
                      ids=ids)
    if changed and prepared:
        population_changed(sim)
        if released:  # (their velocity changed: the integrator starts them afresh)
            sim.integrator.start_bodies(
                sim, np.flatnonzero(np.isin(sim.bodies.id, np.concatenate(released))))


def inlet_shape(sim: Any, name: str, params: dict) -> Shape:
    """The shape an inlet draws (a registered name and its parameters)."""
    cls = sim._registry.lookup("shape", name, "sim.add_inlet()")
    return cls(call="sim.add_inlet()", **params)


def insert(sim: Any, inlet: Inlet) -> np.ndarray:
    """Place what ``inlet`` owes now; return the new ids."""
    from scipy.spatial import cKDTree

    owed = inlet.owed(sim.time + inlet.every)  # what the coming interval brings
    by_mass = inlet.mass_rate is not None
    if (owed < 1.0 and not by_mass) or owed <= 0.0:
        return np.zeros(0, np.int64)
    b = sim.bodies
    tree = cKDTree(b.position) if len(b) else None
    rmax = float(b.radius.max()) if len(b) else 0.0
    if sim.walls is None or len(sim.walls.frame) != len(sim.boundaries):
        table = BoundaryTable(sim.boundaries, lambda m: sim._material_index(m, ""), 1.0)
        for k, bd in enumerate(sim.boundaries):
            table.frame[k] = frames(bd.motion, np.array([sim.time]))[0]
    else:
        table = sim.walls
    on = np.array([bd.enabled for bd in sim.boundaries], bool)[table.owner] \
        if len(table.owner) else np.zeros(0, bool)
    p_kind, p_par, p_owner = table.kind[on], table.par[on], table.owner[on]
    if len(p_kind):  # (the scene's kinds, plugin kinds included; cached on disk)
        from .plan import placement_module

        boundary_gaps = placement_module(sorted(set(p_kind.tolist()))).boundary_gaps
    imat = sim._material_index(inlet.material, "sim.add_inlet()")
    placed_pos: list[np.ndarray] = []
    placed_r: list[float] = []
    new_ids = []
    # bodies placed and not yet appended: consecutive draws of the same shape are appended
    # in one call (appending grows every state array: one body at a time cost O(N) each)
    pending: list[tuple[np.ndarray, np.ndarray]] = []
    pending_shape: list[Any] = [None, None, None]  # (key, shape, one body of it built)

    def flush() -> None:
        if pending:
            pos = np.array([p for p, _ in pending])
            quat = np.concatenate([q for _, q in pending])
            vel = np.broadcast_to(getattr(inlet, "carry_velocity", inlet.velocity),
                                  pos.shape).copy()
            ids = append_bodies(sim, pending_shape[1], imat, inlet.material.density, pos,
                                vel, np.zeros_like(pos), quat)
            inlet.placed(sim, ids)
            new_ids.append(ids)
            pending.clear()

    while (owed >= 1.0) if not by_mass else (owed > 0.0):
        name, params = inlet.draw()
        # (drawn values are numbers; the others are the inlet's own objects, the same at
        # every draw of one shape entry: compared by identity, never by a truncated repr)
        key = (name, tuple((k, v if isinstance(v, int | float | str) else id(v))
                           for k, v in sorted(params.items())))
        if key != pending_shape[0]:
            flush()
            sh = inlet_shape(sim, name, params)
            pending_shape[:] = [key, sh, sh.build(1, inlet.material.density)]
        batch = pending_shape[2]  # (its bounding radius and mass: the same for each draw)
        rb = float(batch.bounding_radius[0])
        cand = inlet.candidates(rb)
        ok = np.ones(len(cand), bool)
        if tree is not None:
            hits = tree.query_ball_point(cand, rb + rmax)
            sizes = np.fromiter(map(len, hits), np.int64, len(hits))
            if sizes.any():
                near = np.concatenate([h for h in hits if h]).astype(np.int64)
                k = np.repeat(np.arange(len(cand)), sizes)
                d = np.linalg.norm(b.position[near] - cand[k], axis=1)
                ok[k[d < rb + b.radius[near]]] = False
        if placed_pos:
            pp = np.asarray(placed_pos)
            d = np.linalg.norm(cand[:, None, :] - pp[None], axis=2)
            ok &= np.all(d >= rb + np.asarray(placed_r)[None], axis=1)
        pick = -1
        for k in np.flatnonzero(ok):  # the first candidate clear of every boundary
            if len(p_kind) == 0 or boundary_gaps(
                    cand[k:k + 1], np.array([rb]), table.frame, p_kind, p_par,
                    p_owner)[0] >= 0.0:
                pick = int(k)
                break
        if pick < 0:
            break  # the region is full for now: the rest stays owed
        p = cand[pick]
        q = (random_quaternions(inlet.rng, 1) if inlet.random_orientation
             else np.array([[1.0, 0, 0, 0]]))
        q = q / np.linalg.norm(q, axis=1)[:, None]  # (as add_particles does)
        pending.append((p, q))
        placed_pos.append(p)
        placed_r.append(rb)
        m = float(batch.mass[0])
        owed -= m if by_mass else 1.0
        inlet.inserted += 1
        inlet.inserted_mass += m
    flush()
    out = np.concatenate(new_ids) if new_ids else np.zeros(0, np.int64)
    inlet.ids.append(out)
    return out
