"""Per-contact data of the current state, for the output (``sim.output(..., fields=...,
contacts=True)``, docs/output-format.md): touching contacts per body, the touching element
pairs with their forces, and the derived rotation matrices of the bodies.

Everything here reads the state and changes nothing. The touching contacts are the entries
of the contact lists (:class:`dpm.state.Contacts`, :class:`dpm.state.WallContacts`) whose
``active`` flag the last force evaluation set. A pair's force is the force row the two-pass
force form stores for it; the fused pass of sphere scenes keeps no rows, so there the
scene's own contact pass (the two-pass step module's ``contact_pass``, the same law and
geometry code) evaluates the touching pairs again at ``dt = 0`` on copies of the contact
history, flags and rows: the history is not advanced and nothing of the state is written.
At ``dt = 0`` the normal force and the force of every sticking contact are those of the
step; a sliding contact's tangential force has the same magnitude (mu F_n) and its
direction may differ by the dashpot's share.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: the per-particle fields ``sim.output(fields=...)`` may add: name -> (width, dtype)
PARTICLE_FIELDS = {"force": (3, "f8"), "torque": (3, "f8"), "contact_count": (0, "i4"),
                   "rotation": (9, "f8")}
#: per-contact datasets of ``/contacts`` (one row per touching element pair):
#: name -> (shape of a row, dtype)
CONTACT_FIELDS = {"id": ((2,), "i8"), "ends": ((2, 3), "f8"), "point": ((3,), "f8"),
                  "force": ((3,), "f8"), "normal_force": ((), "f8"), "overlap": ((), "f8")}


def _entries(lst: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row element, key, touching flag) of every entry of a CSR contact list."""
    n = lst.count
    rows = np.repeat(np.arange(len(lst.start) - 1), np.diff(lst.start))
    return rows, np.asarray(lst.key[:n], np.int64), lst.active[:n] != 0


def contact_counts(sim: Any) -> np.ndarray:
    """Touching contacts of each body (rows of ``sim.bodies``): element pairs, counted for
    both bodies, and element-boundary entries, from the lists' touching flags."""
    owner = sim.elements.owner
    nb = len(sim.bodies)
    rows, keys, act = _entries(sim.contacts)
    count = np.bincount(owner[rows[act]], minlength=nb)
    count += np.bincount(owner[keys[act]], minlength=nb)
    wrows, _, wact = _entries(sim.wall_contacts)
    count += np.bincount(owner[wrows[wact]], minlength=nb)
    return count[:nb].astype(np.int32)


def rotation_columns(q: np.ndarray) -> np.ndarray:
    """(n, 9) rotation matrices of the unit quaternions ``q`` (n, 4) (w, x, y, z), column
    after column (VTK's order of a tensor's components): ``out[:, 3 j:3 j + 3]`` is the
    body's principal axis j in world coordinates."""
    q = np.asarray(q, float)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
                     2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
                     2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)],
                    axis=1)


def _rows_hold_forces(sim: Any) -> bool:
    """Whether the pairs' force rows hold the forces of the last evaluation: the CPU
    backend's two-pass form (the fused pass stores rows only for pairs across chunks)."""
    c = sim.contacts
    return (sim.backend.force_rows_current() and not sim.integrator.implicit and c.rows
            and len(c.force) >= c.count)


def _evaluated_rows(sim: Any) -> np.ndarray:
    """Force rows (count, 9) of every listed pair from the scene's contact pass at
    ``dt = 0``, on copies of the history, flags and rows (the state is not changed)."""
    from ..backends import records as rec

    b, e, c, wc, w, plan = (sim.bodies, sim.elements, sim.contacts, sim.wall_contacts,
                            sim.walls, sim.plan)
    n, m = c.count, wc.count
    # the velocities the forces saw (the integrator's prediction), else the state's
    seen = sim.backend.force_velocities()
    vf, wf = seen if seen is not None else (None, None)
    if vf is None or wf is None or vf.shape != b.velocity.shape or wf.shape != vf.shape:
        vf, wf = b.velocity, b.angular_velocity
    ctl = rec.SceneConstants(np.asarray(sim.gravity, float), float(sim.skin or 0.0),
                             sim.max_overlap, not plan.spheres_only, 0,
                             plan.spheres_only and not sim.sphere_orientation,
                             plan.pair_model, plan.pair_params, sim.period,
                             len(b) - b.ghosts, float(getattr(plan, "reach", 0.0)))
    bodies = rec.BodyArrays(b.position, b.velocity, b.orientation, b.angular_velocity,
                            b.force.copy(), b.torque.copy(), b.mass, b.invmass,
                            b.invinertia, vf, wf, np.zeros((len(b), 0)), b.element_start)
    elems = rec.ElementArrays(e.owner, e.offset, e.radius, e.material, e.position,
                              e.reference, np.zeros(len(e)), np.zeros(len(e), np.int32))
    rows = np.zeros((n, 9))
    pairs = rec.PairList(c.start, c.key, c.history[:n].copy(), c.active[:n].copy(), rows,
                         c.t_start, c.t_pair)
    walls = rec.WallList(wc.start, wc.key, wc.history[:m].copy(), wc.active[:m].copy(),
                         np.zeros((m, wc.FORCE_WIDTH)), wc.tag[:m].copy())
    bnd = rec.BoundaryArrays(w.kind, w.par, w.owner, w.material, w.ids, w.frame,
                             w.frame_ref, w.extent, w.load.copy(), w.grid_int, w.grid_flt,
                             w.cell_start, w.cell_items, w.prim_cells)
    # (the two-pass module in the form the run's thread count takes: a clustered scene's
    # own, not a second module to compile)
    import numba

    plan.module(False, numba.get_num_threads() == 1).contact_pass(0.0, ctl, bodies, elems,
                                                                  pairs, walls, bnd)
    return rows


def pair_forces(sim: Any, evaluate: bool | None = None) -> dict[str, np.ndarray]:
    """The touching element pairs of the current state and their forces.

    Returns ``i``, ``j`` (element indices, i < j), ``body_i``, ``body_j`` (rows of
    ``sim.bodies``), ``force`` (C, 3) on body i from body j [N], ``normal`` (C, 3) unit
    normal from j to i, ``point`` (C, 3) contact point (middle of the overlap on the line
    of centres) [m], ``overlap`` (C,) [m] and ``shift`` (C, 3), the periodic image offset
    of j (its image is at ``position[j] + shift``). ``evaluate``: None takes the stored
    force rows where they hold the forces (see the module docstring) and evaluates the law
    otherwise; True always evaluates; False always reads the rows."""
    e, c = sim.elements, sim.contacts
    rows, keys, act = _entries(c)
    i, j = rows[act], keys[act]
    if evaluate is None:
        evaluate = not _rows_hold_forces(sim)
    if len(i) == 0:
        force = np.zeros((0, 3))
    elif evaluate:
        force = _evaluated_rows(sim)[act, :3]
    else:
        force = c.force[:c.count][act, :3]
    xi, xj = e.position[i], e.position[j]
    d = xi - xj
    shift = np.zeros_like(d)
    period = np.asarray(sim.period, float)[3:6]
    periodic = period > 0
    if periodic.any():  # the nearest image of j (dpm.kernels.neighbours.minimum_image)
        length = np.where(periodic, period, 1.0)
        d = np.where(periodic, d - length * np.floor(d / length + 0.5), d)
        shift = (xi - d) - xj
    dist = np.linalg.norm(d, axis=1)
    normal = d / np.maximum(dist, 1e-300)[:, None]
    ri, rj = e.radius[i], e.radius[j]
    overlap = ri + rj - dist
    point = xi - (ri - 0.5 * overlap)[:, None] * normal
    return {"i": i, "j": j, "body_i": e.owner[i], "body_j": e.owner[j], "force": force,
            "normal": normal, "point": point, "overlap": overlap, "shift": shift}


def contact_rows(sim: Any) -> dict[str, np.ndarray]:
    """One frame of ``/contacts`` (:data:`CONTACT_FIELDS`): per touching element pair the
    body ids, the two body centres (j's nearest periodic image) as a line's ends, the
    contact point, the force on body i, the normal force F . n (> 0 pushes the bodies
    apart) and the overlap."""
    p = pair_forces(sim)
    b = sim.bodies
    bi, bj = p["body_i"], p["body_j"]
    ends = np.stack([b.position[bi], b.position[bj] + p["shift"]], axis=1)
    return {"id": np.stack([b.id[bi], b.id[bj]], axis=1).reshape(-1, 2),
            "ends": ends.reshape(-1, 2, 3), "point": p["point"], "force": p["force"],
            "normal_force": np.einsum("ij,ij->i", p["force"], p["normal"]),
            "overlap": p["overlap"]}


def particle_values(sim: Any, name: str) -> np.ndarray:
    """This frame's values of the optional per-particle field ``name``
    (:data:`PARTICLE_FIELDS`)."""
    b = sim.bodies
    if name == "contact_count":
        return contact_counts(sim)
    if name == "rotation":
        return rotation_columns(b.orientation)
    return getattr(b, name)
