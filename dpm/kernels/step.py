"""One DEM step and the many-step loop, composed from the other kernels.

Order of a step (:func:`run_steps`):

1. ``pre_force``   integrator part before the forces (e.g. half kick + drift)
2. element world positions from body position and quaternion
3. neighbour list rebuilt when an element moved more than skin/2 (history merged)
4. forces: gravity, element-element contacts (half list), element-plane contacts,
   rolling resistance; force and torque summed on the owner bodies, reaction on planes
5. ``post_force``  integrator part after the forces (e.g. second half kick)

:mod:`dpm.plan` copies this module for each scene with the block between the
``bindings`` markers rewritten: the contact laws the scene uses become ``law_0``,
``law_1``, ... and the integrator's ``pre_force``/``post_force`` are imported, so each
scene compiles (once, cached) a step that contains only what it needs.

Diagnostics (``diag``): [0] status (0 ok, 1 neighbour list overflow, 2 NaN, 3 overlap
beyond the limit), [1] steps done, [2] rebuilds, [3] pairs needed, [4] largest overlap /
radius seen, [5] element with that overlap, [6] active contacts in the last force evaluation.
"""
# ruff: noqa: I001  (the bindings block must stay between its markers)
import math

from .config import jit
from .neighbours import build_neighbour_list, max_displacement_sq
from .quaternion import rotate_vector
from .rolling import rolling_torque

# --- bindings begin (dpm.plan rewrites this block) ---
from .law_linear import linear_spring_dashpot as law_0
from .law_hertz_mindlin import hertz_mindlin as law_1
from .integrate_velocity_verlet import pre_force, post_force


@jit
def pair_force(model, p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Dispatch to the contact law ``model`` of this scene."""
    if model == 0:
        return law_0(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k)
    return law_1(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k)
# --- bindings end ---

STATUS_OK = 0
STATUS_OVERFLOW = 1
STATUS_NAN = 2
STATUS_OVERLAP = 3


@jit
def update_element_positions(b_pos, b_quat, e_owner, e_offset, e_pos, has_offsets):
    """x_e = X_b + R(q_b) offset_e (a copy of X_b for sphere-only scenes)."""
    for e in range(e_pos.shape[0]):
        b = e_owner[e]
        if has_offsets:
            ox, oy, oz = rotate_vector(b_quat, b, e_offset[e, 0], e_offset[e, 1], e_offset[e, 2])
            e_pos[e, 0] = b_pos[b, 0] + ox
            e_pos[e, 1] = b_pos[b, 1] + oy
            e_pos[e, 2] = b_pos[b, 2] + oz
        else:
            e_pos[e, 0] = b_pos[b, 0]
            e_pos[e, 1] = b_pos[b, 1]
            e_pos[e, 2] = b_pos[b, 2]


@jit
def compute_forces(dt, gravity, b_pos, b_vel, b_angvel, b_force, b_torque, b_mass, b_invmass,
                   e_owner, e_radius, e_mat, e_pos, nl_start, nl_j, nl_hist,
                   w_point, w_normal, w_vel, w_mat, w_force, w_hist, pair_model, pair_params,
                   diag):
    """Gravity plus all contact forces; returns the largest overlap / radius.

    ``dt`` only advances the tangential history (0 re-evaluates forces without doing so).
    """
    nb = b_pos.shape[0]
    for b in range(nb):
        m = b_mass[b]
        for d in range(3):
            b_force[b, d] = m * gravity[d]
            b_torque[b, d] = 0.0
    for w in range(w_force.shape[0]):
        for d in range(3):
            w_force[w, d] = 0.0
    worst = 0.0
    worst_e = -1
    active = 0
    ne = e_pos.shape[0]
    nh = nl_hist.shape[1]
    # element-element contacts
    for i in range(ne):
        xi = e_pos[i, 0]
        yi = e_pos[i, 1]
        zi = e_pos[i, 2]
        ri = e_radius[i]
        bi = e_owner[i]
        mi = e_mat[i]
        for kk in range(nl_start[i], nl_start[i + 1]):
            j = nl_j[kk]
            dx = xi - e_pos[j, 0]
            dy = yi - e_pos[j, 1]
            dz = zi - e_pos[j, 2]
            rs = ri + e_radius[j]
            d2 = dx * dx + dy * dy + dz * dz
            if d2 >= rs * rs:
                for c in range(nh):
                    nl_hist[kk, c] = 0.0
                continue
            bj = e_owner[j]
            ims = b_invmass[bi] + b_invmass[bj]
            if ims == 0.0:
                continue
            active += 1
            dist = math.sqrt(d2)
            nx = dx / dist
            ny = dy / dist
            nz = dz / dist
            delta = rs - dist
            rj = e_radius[j]
            ratio = delta / min(ri, rj)
            if ratio > worst:
                worst = ratio
                worst_e = i
            # contact point: middle of the overlap, on the line of centres
            a = ri - 0.5 * delta
            cx = xi - a * nx
            cy = yi - a * ny
            cz = zi - a * nz
            aix = cx - b_pos[bi, 0]
            aiy = cy - b_pos[bi, 1]
            aiz = cz - b_pos[bi, 2]
            ajx = cx - b_pos[bj, 0]
            ajy = cy - b_pos[bj, 1]
            ajz = cz - b_pos[bj, 2]
            # relative velocity of i with respect to j at the contact point
            vx = (b_vel[bi, 0] + b_angvel[bi, 1] * aiz - b_angvel[bi, 2] * aiy
                  - b_vel[bj, 0] - b_angvel[bj, 1] * ajz + b_angvel[bj, 2] * ajy)
            vy = (b_vel[bi, 1] + b_angvel[bi, 2] * aix - b_angvel[bi, 0] * aiz
                  - b_vel[bj, 1] - b_angvel[bj, 2] * ajx + b_angvel[bj, 0] * ajz)
            vz = (b_vel[bi, 2] + b_angvel[bi, 0] * aiy - b_angvel[bi, 1] * aix
                  - b_vel[bj, 2] - b_angvel[bj, 0] * ajy + b_angvel[bj, 1] * ajx)
            vn = vx * nx + vy * ny + vz * nz
            vtx = vx - vn * nx
            vty = vy - vn * ny
            vtz = vz - vn * nz
            mj = e_mat[j]
            p = pair_params[mi, mj]
            fn, ftx, fty, ftz = pair_force(pair_model[mi, mj], p, delta, -vn, vtx, vty, vtz,
                                           nx, ny, nz, 1.0 / ims, ri * rj / rs, dt, nl_hist, kk)
            fx = fn * nx + ftx
            fy = fn * ny + fty
            fz = fn * nz + ftz
            b_force[bi, 0] += fx
            b_force[bi, 1] += fy
            b_force[bi, 2] += fz
            b_force[bj, 0] -= fx
            b_force[bj, 1] -= fy
            b_force[bj, 2] -= fz
            b_torque[bi, 0] += aiy * fz - aiz * fy
            b_torque[bi, 1] += aiz * fx - aix * fz
            b_torque[bi, 2] += aix * fy - aiy * fx
            b_torque[bj, 0] -= ajy * fz - ajz * fy
            b_torque[bj, 1] -= ajz * fx - ajx * fz
            b_torque[bj, 2] -= ajx * fy - ajy * fx
            if p[6] != 0.0:
                tx, ty, tz = rolling_torque(p, fn, ri * rj / rs, 1.0 / ims,
                                            b_angvel[bi, 0] - b_angvel[bj, 0],
                                            b_angvel[bi, 1] - b_angvel[bj, 1],
                                            b_angvel[bi, 2] - b_angvel[bj, 2], dt, nl_hist, kk)
                b_torque[bi, 0] += tx
                b_torque[bi, 1] += ty
                b_torque[bi, 2] += tz
                b_torque[bj, 0] -= tx
                b_torque[bj, 1] -= ty
                b_torque[bj, 2] -= tz
    # element-plane contacts (one-sided: the normal points into the domain)
    nw = w_point.shape[0]
    for e in range(ne):
        r = e_radius[e]
        b = e_owner[e]
        for w in range(nw):
            hk = e * nw + w
            nx = w_normal[w, 0]
            ny = w_normal[w, 1]
            nz = w_normal[w, 2]
            dist = ((e_pos[e, 0] - w_point[w, 0]) * nx + (e_pos[e, 1] - w_point[w, 1]) * ny
                    + (e_pos[e, 2] - w_point[w, 2]) * nz)
            delta = r - dist
            if delta <= 0.0 or dist <= -r or b_invmass[b] == 0.0:
                for c in range(nh):
                    w_hist[hk, c] = 0.0
                continue
            active += 1
            ratio = delta / r
            if ratio > worst:
                worst = ratio
                worst_e = e
            a = r - 0.5 * delta
            ax = e_pos[e, 0] - a * nx - b_pos[b, 0]
            ay = e_pos[e, 1] - a * ny - b_pos[b, 1]
            az = e_pos[e, 2] - a * nz - b_pos[b, 2]
            vx = b_vel[b, 0] + b_angvel[b, 1] * az - b_angvel[b, 2] * ay - w_vel[w, 0]
            vy = b_vel[b, 1] + b_angvel[b, 2] * ax - b_angvel[b, 0] * az - w_vel[w, 1]
            vz = b_vel[b, 2] + b_angvel[b, 0] * ay - b_angvel[b, 1] * ax - w_vel[w, 2]
            vn = vx * nx + vy * ny + vz * nz
            vtx = vx - vn * nx
            vty = vy - vn * ny
            vtz = vz - vn * nz
            me = e_mat[e]
            mw = w_mat[w]
            p = pair_params[me, mw]
            fn, ftx, fty, ftz = pair_force(pair_model[me, mw], p, delta, -vn, vtx, vty, vtz,
                                           nx, ny, nz, b_mass[b], r, dt, w_hist, hk)
            fx = fn * nx + ftx
            fy = fn * ny + fty
            fz = fn * nz + ftz
            b_force[b, 0] += fx
            b_force[b, 1] += fy
            b_force[b, 2] += fz
            w_force[w, 0] -= fx
            w_force[w, 1] -= fy
            w_force[w, 2] -= fz
            b_torque[b, 0] += ay * fz - az * fy
            b_torque[b, 1] += az * fx - ax * fz
            b_torque[b, 2] += ax * fy - ay * fx
            if p[6] != 0.0:
                tx, ty, tz = rolling_torque(p, fn, r, b_mass[b], b_angvel[b, 0],
                                            b_angvel[b, 1], b_angvel[b, 2], dt, w_hist, hk)
                b_torque[b, 0] += tx
                b_torque[b, 1] += ty
                b_torque[b, 2] += tz
    diag[6] = active
    if worst > diag[4]:
        diag[4] = worst
        diag[5] = worst_e
    return worst


@jit
def run_steps(nsteps, dt, gravity, skin, max_overlap,
              b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_mass, b_invmass,
              b_invinertia, e_owner, e_offset, e_radius, e_mat, e_pos, e_ref, has_offsets,
              nl_start, nl_j, nl_hist, new_start, new_j, new_hist,
              w_point, w_normal, w_vel, w_mat, w_force, w_hist, pair_model, pair_params, diag):
    """Advance ``nsteps`` steps; stop early with a status in ``diag[0]``.

    On a neighbour-list overflow the step stops after ``pre_force``; the caller grows the
    buffers and calls :func:`finish_step` (with ``resume=True`` semantics) before going on.
    """
    diag[0] = STATUS_OK
    diag[1] = 0
    for s in range(nsteps):
        pre_force(b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass, b_invinertia, dt)
        finish_step(dt, gravity, skin, max_overlap, b_pos, b_vel, b_quat, b_angvel, b_force,
                    b_torque, b_mass, b_invmass, b_invinertia, e_owner, e_offset, e_radius,
                    e_mat, e_pos, e_ref, has_offsets, nl_start, nl_j, nl_hist, new_start,
                    new_j, new_hist, w_point, w_normal, w_vel, w_mat, w_force, w_hist,
                    pair_model, pair_params, diag)
        if diag[0] == STATUS_OK or diag[0] == STATUS_OVERLAP:
            diag[1] = s + 1
        if diag[0] != STATUS_OK:
            return


@jit
def finish_step(dt, gravity, skin, max_overlap, b_pos, b_vel, b_quat, b_angvel, b_force,
                b_torque, b_mass, b_invmass, b_invinertia, e_owner, e_offset, e_radius, e_mat,
                e_pos, e_ref, has_offsets, nl_start, nl_j, nl_hist, new_start, new_j, new_hist,
                w_point, w_normal, w_vel, w_mat, w_force, w_hist, pair_model, pair_params, diag):
    """Steps 2-5 of a step (everything after ``pre_force``); sets ``diag[0]`` on trouble."""
    update_element_positions(b_pos, b_quat, e_owner, e_offset, e_pos, has_offsets)
    d2 = max_displacement_sq(e_pos, e_ref)
    if d2 != d2:
        diag[0] = STATUS_NAN
        return
    if d2 > 0.25 * skin * skin:
        need = build_neighbour_list(e_pos, e_radius, e_owner, skin, nl_start, nl_j, nl_hist,
                                    new_start, new_j, new_hist)
        if need > new_j.shape[0]:
            diag[0] = STATUS_OVERFLOW
            diag[3] = need
            return
        for e in range(e_pos.shape[0]):
            for d in range(3):
                e_ref[e, d] = e_pos[e, d]
        diag[2] += 1
    worst = compute_forces(dt, gravity, b_pos, b_vel, b_angvel, b_force, b_torque, b_mass,
                           b_invmass, e_owner, e_radius, e_mat, e_pos, nl_start, nl_j,
                           nl_hist, w_point, w_normal, w_vel, w_mat, w_force, w_hist,
                           pair_model, pair_params, diag)
    post_force(b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass, b_invinertia, dt)
    if worst > max_overlap:
        diag[0] = STATUS_OVERLAP
