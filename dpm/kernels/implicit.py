"""Implicit integration of sphere scenes: Newton-Raphson with block Gauss-Seidel.

The three implicit schemes of :mod:`dpm.integrators.implicit` share one form. With the
unknown acceleration a_{n+1} = F(x_{n+1}, v_{n+1}) / m + g,

    x_{n+1} = X* + beta dt^2 a_{n+1},        v_{n+1} = V* + gamma dt a_{n+1}

    scheme            X*                                        V*                       beta  gamma
    backward Euler    x_n + dt v_n                              v_n                      1     1
    Newmark-beta      x_n + dt v_n + dt^2/4 a_n                 v_n + dt/2 a_n           1/4   1/2
    (average acceleration, Newmark 1959)
    Numerov           2 x_n - x_{n-1} + dt^2/12 (10 a_n + a_{n-1})  (X* - x_n)/dt          1/12  3/8
                                                                + dt/24 (6 a_n - a_{n-1})

(Numerov: x_{n+1} = 2 x_n - x_{n-1} + dt^2/12 (a_{n+1} + 10 a_n + a_{n-1}), DPM thesis eq.
3.25; its velocity here is the fourth-order v_{n+1} = (x_{n+1} - x_n)/dt + dt/24 (7 a_{n+1}
+ 6 a_n - a_{n-1}) instead of the thesis' first-order backward difference, eq. 3.26.)
So v is a function of x: v(x) = V* + gamma/(beta dt) (x - X*), and x_{n+1} is the root of

    R_i(x) = m_i (x_i - X*_i) - beta dt^2 (F_i(x, v(x)) + m_i g) = 0      (rows scaled by m_i)

solved by Newton-Raphson, J dx = -R, x <- x + dx, with the Jacobian

    J = M - beta dt^2 dF/dx - gamma dt dF/dv

assembled from 3x3 blocks per touching contact (sparse: one block per contact, DPM thesis
§3.8.2; with rows scaled by m_i it is symmetric, see shared/seeds/ERRATA.md). For a contact
of normal n = (x_i - x_j)/d, overlap delta = r_i + r_j - d, normal force f_n(delta, delta'):

    B = beta dt^2 (k n n^T - f_n/d (I - n n^T)) + gamma dt c n n^T,
    k = df_n/d delta,  c = df_n/d delta'  (finite differences of the contact law)
    J_ii += B, J_jj += B, J_ij = J_ji -= B;   a plane contact adds its k, c part to J_ii.

The linear system is solved by block Gauss-Seidel sweeps (3x3 diagonal blocks inverted),
the Jacobian and residual are rebuilt every Newton iteration, and contacts are re-detected
at every iteration from a candidate list (pairs within a margin, built by the explicit
step's neighbour list builder and kept while no body moved more than half the margin), so
a contact that starts during a step acts during that step (DPM thesis §3.8.1).
Convergence: a full Newton correction with max |dx| below ``tol`` (absolute, metres) for
every body. A correction that raises the
residual sum_i |R_i / m_i|^2 (a contact or a dashpot cut-off switching inside the step
makes Newton cycle) is halved, up to 6 times (backtracking line search; each halving
counts as an iteration). Where even 1/64 of the step raises the residual, the residual
jumps there (the linear dashpot switches on with a jump c delta' at delta = 0, and a root
may not exist); the iterate is then accepted if the last correction is below
``stall_tol`` (counted in ``stats[4]``). A step that does not converge within
``max_iter`` iterations stops the run with status 5.

The contact laws are the scene's, composed from their parts in the bindings block that
:func:`dpm.plan.implicit_module` writes (``pair_force``; ``pair_normal`` for k and c).
Tangential forces and rolling torques come from the contact law at the
current iterate with the history of the step start; they enter the residual but not the
Jacobian (a fixed-point part of the iteration). Rotation is not solved implicitly: the
contacts see omega* = omega_n + dt T_n / I during the iterations, and after convergence
omega_{n+1} = omega_n + dt ((1 - theta) T_n + theta T_{n+1}) / I, q rotated exactly by
((1 - theta) omega_n + theta omega_{n+1}) dt (theta = 1 backward Euler, 1/2 otherwise: the
average torque of the thesis §3.8.5). Spheres only (one element per body at its centre).

Status codes returned in ``diag[0]``: 0 ok, 2 NaN, 3 overlap beyond the limit,
5 Newton did not converge, 6 candidate buffer overflow (``diag[3]`` = the size needed).
"""

import math

import numpy as np

# ruff: noqa: I001, F821  (the bindings block must stay between its markers; the names it
# binds are written into the generated module only)
from .config import inline_jit, step_jit as jit  # noqa: F401  (inline_jit: the bindings')
from .neighbours import build_neighbour_list
from .rigid_rotation import rotate_isotropic

# --- bindings begin (dpm.plan rewrites this block) ---
# (empty here: :func:`dpm.plan.implicit_module` writes the scene's contact laws:
# ``pair_row``, ``pair_force``, ``pair_normal``, ``ROLLING``; this file is only imported
# for its constants, its functions run from the generated module)
# --- bindings end ---

STATUS_OK = 0
STATUS_NAN = 2
STATUS_OVERLAP = 3
STATUS_NOT_CONVERGED = 5
STATUS_OVERFLOW = 6

BACKWARD_EULER = 0
NEWMARK = 1
NUMEROV = 2

@jit
def normal_derivatives(model, p, delta, ddelta, nx, ny, nz, meff, reff, dt, fn, scratch,
                       hist0, k):
    """(df_n/d delta, df_n/d delta') by forward differences of the law's normal part (and
    adhesion), on a throw-away copy of the contact's history at the step start (a
    hysteretic normal part then differentiates the branch it is on)."""
    h = 1e-7 * delta + 1e-300
    for c in range(scratch.shape[1]):
        scratch[0, c] = hist0[k, c]
    f1 = pair_normal(model, p, delta + h, ddelta, nx, ny, nz, meff, reff, dt, scratch, 0)
    kx = (f1 - fn) / h
    hv = 1e-7 * abs(ddelta) + 1e-9 * delta / max(dt, 1e-300) + 1e-300
    for c in range(scratch.shape[1]):
        scratch[0, c] = hist0[k, c]
    f2 = pair_normal(model, p, delta, ddelta + hv, nx, ny, nz, meff, reff, dt, scratch, 0)
    cv = (f2 - fn) / hv
    return max(kx, 0.0), max(cv, 0.0)


@jit
def candidate_pairs(x, radius, owner, margin, nl_start, nl_j, nl_hist, nl_active, t_start,
                    t_pair, period):
    """Pairs (i < j) with |x_i - x_j| < r_i + r_j + margin in the explicit step's half
    neighbour list (CSR, history merged; :func:`.neighbours.build_neighbour_list`, called
    here so that it is cached with this module); returns how many (above the capacity
    nothing is changed)."""
    return build_neighbour_list(x, radius, owner, margin, nl_start, nl_j, nl_hist, nl_active,
                                t_start, t_pair, period, x.shape[0])


@jit
def pair_rows(nl_start, pi):
    """pi[k] = i for the pairs k of element i (the CSR list expanded)."""
    for i in range(nl_start.shape[0] - 1):
        for k in range(nl_start[i], nl_start[i + 1]):
            pi[k] = i


@jit
def candidate_walls(x, radius, margin, w_point, w_normal, out_i, out_w):
    """Body-plane entries with -r - margin < distance < r + margin."""
    count = 0
    cap = out_i.shape[0]
    for i in range(x.shape[0]):
        for w in range(w_point.shape[0]):
            dist = ((x[i, 0] - w_point[w, 0]) * w_normal[w, 0]
                    + (x[i, 1] - w_point[w, 1]) * w_normal[w, 1]
                    + (x[i, 2] - w_point[w, 2]) * w_normal[w, 2])
            if -radius[i] - margin < dist < radius[i] + margin:
                if count < cap:
                    out_i[count] = i
                    out_w[count] = w
                count += 1
    return count


@jit
def sort_and_merge(ci, cj, count, nkey, old_key, old_hist, new_key, new_hist):
    """Sort the first ``count`` candidates by key i * nkey + j and carry the history of
    those already in the (sorted) old list."""
    keys = np.empty(count, np.int64)
    for k in range(count):
        keys[k] = ci[k] * nkey + cj[k]
    order = np.argsort(keys)
    ti = ci[:count].copy()
    tj = cj[:count].copy()
    nold = old_key.shape[0]
    for k in range(count):
        o = order[k]
        ci[k] = ti[o]
        cj[k] = tj[o]
        new_key[k] = keys[o]
        p = np.searchsorted(old_key, keys[o])
        if p < nold and old_key[p] == keys[o]:
            for c in range(new_hist.shape[1]):
                new_hist[k, c] = old_hist[p, c]
        else:
            for c in range(new_hist.shape[1]):
                new_hist[k, c] = 0.0


@jit
def evaluate(x, v, w, dt, beta_dt2, gamma_dt, radius, mass, mat, pair_model,
             pair_params, w_point, w_normal, w_mat, pi, pj, npair, p_hist0, p_hist, wi, ww, nwall,
             w_hist0, w_hist, force, torque, w_force, blk, blk_i, blk_j, diag, scratch, p_seen,
             w_seen):
    """Contact forces and torques at positions x, velocities v, angular velocities w
    (gravity not included); the Jacobian's blocks (6 entries of the symmetric 3x3 B per
    touching pair, listed in blk/blk_i/blk_j) and its diagonal blocks (``diag``, without
    the mass). Histories start from ``*_hist0`` and the updated ones go to ``*_hist``.
    ``p_seen[k]``/``w_seen[k]`` (kept over the Newton iterations of a step): the stiffness
    and damping coefficient (beta dt^2 k + gamma dt c) of a contact once it touched in this
    step; a candidate that touched before but not now keeps that block in the Jacobian (with
    zero force), so Newton does not cycle between the branches of a contact that sits at the
    edge of touching (it becomes a chord iteration with a stiffer Jacobian, which converges).
    Returns (touching pairs, largest overlap / radius)."""
    n = x.shape[0]
    for i in range(n):
        for d in range(3):
            force[i, d] = 0.0
            torque[i, d] = 0.0
        for c in range(6):
            diag[i, c] = 0.0
    for q in range(w_force.shape[0]):
        for d in range(3):
            w_force[q, d] = 0.0
    nh = p_hist.shape[1]
    nb = 0
    worst = 0.0
    for k in range(npair):
        i = pi[k]
        j = pj[k]
        dx = x[i, 0] - x[j, 0]
        dy = x[i, 1] - x[j, 1]
        dz = x[i, 2] - x[j, 2]
        ri = radius[i]
        rj = radius[j]
        rs = ri + rj
        d2 = dx * dx + dy * dy + dz * dz
        if d2 >= rs * rs:
            for c in range(nh):
                p_hist[k, c] = 0.0
            if p_seen[k] > 0.0:
                dist = math.sqrt(d2)
                nx = dx / dist
                ny = dy / dist
                nz = dz / dist
                e = p_seen[k]
                blk[nb, 0] = e * nx * nx
                blk[nb, 1] = e * ny * ny
                blk[nb, 2] = e * nz * nz
                blk[nb, 3] = e * nx * ny
                blk[nb, 4] = e * nx * nz
                blk[nb, 5] = e * ny * nz
                for c in range(6):
                    diag[i, c] += blk[nb, c]
                    diag[j, c] += blk[nb, c]
                blk_i[nb] = i
                blk_j[nb] = j
                nb += 1
            continue
        for c in range(nh):
            p_hist[k, c] = p_hist0[k, c]
        dist = math.sqrt(d2)
        nx = dx / dist
        ny = dy / dist
        nz = dz / dist
        delta = rs - dist
        worst = max(worst, delta / min(ri, rj))
        a = ri - 0.5 * delta
        aix = -a * nx
        aiy = -a * ny
        aiz = -a * nz
        b = rj - 0.5 * delta
        ajx = b * nx
        ajy = b * ny
        ajz = b * nz
        vx = (v[i, 0] + w[i, 1] * aiz - w[i, 2] * aiy - v[j, 0] - w[j, 1] * ajz + w[j, 2] * ajy)
        vy = (v[i, 1] + w[i, 2] * aix - w[i, 0] * aiz - v[j, 1] - w[j, 2] * ajx + w[j, 0] * ajz)
        vz = (v[i, 2] + w[i, 0] * aiy - w[i, 1] * aix - v[j, 2] - w[j, 0] * ajy + w[j, 1] * ajx)
        vn = vx * nx + vy * ny + vz * nz
        mi = mat[i]
        mj = mat[j]
        p = pair_row(pair_params, mi, mj)
        model = pair_model[mi, mj]
        meff = mass[i] * mass[j] / (mass[i] + mass[j])
        reff = ri * rj / rs
        fn, ftx, fty, ftz, rx, ry, rz = pair_force(
            model, p, delta, -vn, vx - vn * nx, vy - vn * ny, vz - vn * nz, nx, ny, nz, meff,
            reff, w[i, 0] - w[j, 0], w[i, 1] - w[j, 1], w[i, 2] - w[j, 2], dt, p_hist, k)
        fx = fn * nx + ftx
        fy = fn * ny + fty
        fz = fn * nz + ftz
        force[i, 0] += fx
        force[i, 1] += fy
        force[i, 2] += fz
        force[j, 0] -= fx
        force[j, 1] -= fy
        force[j, 2] -= fz
        torque[i, 0] += aiy * fz - aiz * fy
        torque[i, 1] += aiz * fx - aix * fz
        torque[i, 2] += aix * fy - aiy * fx
        torque[j, 0] -= ajy * fz - ajz * fy
        torque[j, 1] -= ajz * fx - ajx * fz
        torque[j, 2] -= ajx * fy - ajy * fx
        if ROLLING:
            torque[i, 0] += rx
            torque[i, 1] += ry
            torque[i, 2] += rz
            torque[j, 0] -= rx
            torque[j, 1] -= ry
            torque[j, 2] -= rz
        kx, cv = normal_derivatives(model, p, delta, -vn, nx, ny, nz, meff, reff, dt, fn,
                                    scratch, p_hist0, k)
        s = beta_dt2 * kx + gamma_dt * cv
        p_seen[k] = max(p_seen[k], s)
        g = beta_dt2 * fn / dist
        # B = s n n^T - g (I - n n^T) = (s + g) n n^T - g I
        e = s + g
        blk[nb, 0] = e * nx * nx - g
        blk[nb, 1] = e * ny * ny - g
        blk[nb, 2] = e * nz * nz - g
        blk[nb, 3] = e * nx * ny
        blk[nb, 4] = e * nx * nz
        blk[nb, 5] = e * ny * nz
        for c in range(6):
            diag[i, c] += blk[nb, c]
            diag[j, c] += blk[nb, c]
        blk_i[nb] = i
        blk_j[nb] = j
        nb += 1
    for k in range(nwall):
        i = wi[k]
        q = ww[k]
        nx = w_normal[q, 0]
        ny = w_normal[q, 1]
        nz = w_normal[q, 2]
        ri = radius[i]
        dist = ((x[i, 0] - w_point[q, 0]) * nx + (x[i, 1] - w_point[q, 1]) * ny
                + (x[i, 2] - w_point[q, 2]) * nz)
        delta = ri - dist
        if delta <= 0.0 or dist <= -ri:
            for c in range(nh):
                w_hist[k, c] = 0.0
            e = w_seen[k]
            if e > 0.0 and dist > -ri:
                diag[i, 0] += e * nx * nx
                diag[i, 1] += e * ny * ny
                diag[i, 2] += e * nz * nz
                diag[i, 3] += e * nx * ny
                diag[i, 4] += e * nx * nz
                diag[i, 5] += e * ny * nz
            continue
        for c in range(nh):
            w_hist[k, c] = w_hist0[k, c]
        worst = max(worst, delta / ri)
        a = ri - 0.5 * delta
        ax = -a * nx
        ay = -a * ny
        az = -a * nz
        vx = v[i, 0] + w[i, 1] * az - w[i, 2] * ay
        vy = v[i, 1] + w[i, 2] * ax - w[i, 0] * az
        vz = v[i, 2] + w[i, 0] * ay - w[i, 1] * ax
        vn = vx * nx + vy * ny + vz * nz
        mi = mat[i]
        mw = w_mat[q]
        p = pair_row(pair_params, mi, mw)
        model = pair_model[mi, mw]
        fn, ftx, fty, ftz, rx, ry, rz = pair_force(
            model, p, delta, -vn, vx - vn * nx, vy - vn * ny, vz - vn * nz, nx, ny, nz,
            mass[i], ri, w[i, 0], w[i, 1], w[i, 2], dt, w_hist, k)
        fx = fn * nx + ftx
        fy = fn * ny + fty
        fz = fn * nz + ftz
        force[i, 0] += fx
        force[i, 1] += fy
        force[i, 2] += fz
        w_force[q, 0] -= fx
        w_force[q, 1] -= fy
        w_force[q, 2] -= fz
        torque[i, 0] += ay * fz - az * fy
        torque[i, 1] += az * fx - ax * fz
        torque[i, 2] += ax * fy - ay * fx
        if ROLLING:  # (a fixed plane: the relative angular velocity is the body's)
            torque[i, 0] += rx
            torque[i, 1] += ry
            torque[i, 2] += rz
        kx, cv = normal_derivatives(model, p, delta, -vn, nx, ny, nz, mass[i], ri, dt, fn,
                                    scratch, w_hist0, k)
        s = beta_dt2 * kx + gamma_dt * cv
        w_seen[k] = max(w_seen[k], s)
        diag[i, 0] += s * nx * nx
        diag[i, 1] += s * ny * ny
        diag[i, 2] += s * nz * nz
        diag[i, 3] += s * nx * ny
        diag[i, 4] += s * nx * nz
        diag[i, 5] += s * ny * nz
    return nb, worst


@jit
def invert_sym3(a0, a1, a2, a3, a4, a5):
    """Inverse of the symmetric [[a0, a3, a4], [a3, a1, a5], [a4, a5, a2]] (6 entries)."""
    c0 = a1 * a2 - a5 * a5
    c1 = a0 * a2 - a4 * a4
    c2 = a0 * a1 - a3 * a3
    c3 = a4 * a5 - a3 * a2
    c4 = a3 * a5 - a4 * a1
    c5 = a3 * a4 - a0 * a5
    det = a0 * c0 + a3 * c3 + a4 * c4
    inv = 1.0 / det
    return c0 * inv, c1 * inv, c2 * inv, c3 * inv, c4 * inv, c5 * inv


@jit
def gauss_seidel(res, mass, diag, blk, blk_i, blk_j, nb, dx, ptr, adj, dinv, tol, max_sweeps):
    """Solve J dx = -res by block Gauss-Seidel; J = M + diag - (off-diagonal blocks).
    Returns the sweeps done."""
    n = res.shape[0]
    for i in range(n + 1):
        ptr[i] = 0
    for k in range(nb):
        ptr[blk_i[k] + 1] += 1
        ptr[blk_j[k] + 1] += 1
    for i in range(n):
        ptr[i + 1] += ptr[i]
    fill = ptr[:n].copy()
    for k in range(nb):
        adj[fill[blk_i[k]]] = k
        fill[blk_i[k]] += 1
        adj[fill[blk_j[k]]] = k
        fill[blk_j[k]] += 1
    for i in range(n):
        m = mass[i]
        d0, d1, d2, d3, d4, d5 = invert_sym3(m + diag[i, 0], m + diag[i, 1], m + diag[i, 2],
                                             diag[i, 3], diag[i, 4], diag[i, 5])
        dinv[i, 0] = d0
        dinv[i, 1] = d1
        dinv[i, 2] = d2
        dinv[i, 3] = d3
        dinv[i, 4] = d4
        dinv[i, 5] = d5
        for d in range(3):
            dx[i, d] = 0.0
    sweeps = 0
    while sweeps < max_sweeps:
        sweeps += 1
        change = 0.0
        for i in range(n):
            bx = -res[i, 0]
            by = -res[i, 1]
            bz = -res[i, 2]
            for s in range(ptr[i], ptr[i + 1]):
                k = adj[s]
                o = blk_j[k] if blk_i[k] == i else blk_i[k]
                ox = dx[o, 0]
                oy = dx[o, 1]
                oz = dx[o, 2]
                bx += blk[k, 0] * ox + blk[k, 3] * oy + blk[k, 4] * oz
                by += blk[k, 3] * ox + blk[k, 1] * oy + blk[k, 5] * oz
                bz += blk[k, 4] * ox + blk[k, 5] * oy + blk[k, 2] * oz
            nx_ = dinv[i, 0] * bx + dinv[i, 3] * by + dinv[i, 4] * bz
            ny_ = dinv[i, 3] * bx + dinv[i, 1] * by + dinv[i, 5] * bz
            nz_ = dinv[i, 4] * bx + dinv[i, 5] * by + dinv[i, 2] * bz
            change = max(change, abs(nx_ - dx[i, 0]), abs(ny_ - dx[i, 1]), abs(nz_ - dx[i, 2]))
            dx[i, 0] = nx_
            dx[i, 1] = ny_
            dx[i, 2] = nz_
        if change <= tol or nb == 0:
            break
    return sweeps


@jit
def implicit_steps(nsteps, scheme, dt, gravity, tol, stall_tol, max_iter, gs_tol, gs_max,
                   max_overlap, theta, x, v, q, w, force, torque, aux, radius, mass, inertia,
                   mat, pair_model, pair_params, w_point, w_normal, w_mat, w_force,
                   pi, pj, npair_arr, p_key, p_hist, wi, ww, nwall_arr, w_key, w_hist,
                   x_ref, margin, work, iwork, it_log, stats, diag):
    """Advance up to ``nsteps`` steps; stop early with a status in ``diag[0]``.

    ``force``/``torque`` hold F_n (contacts + gravity) and T_n on entry and F_{n+1}, T_{n+1}
    after. ``aux[:, 0:3]``, ``aux[:, 3:6]``: x_{n-1} and a_{n-1} (Numerov). Candidates
    (``pi``/``pj`` with history ``p_hist``, ``wi``/``ww`` with ``w_hist``) were built at
    ``x_ref`` with ``margin``; when a converged step moved a body more than margin/2 from
    ``x_ref``, the step returns with status 6 and ``diag[3] = -1`` (rebuild and redo).
    ``it_log[s]``: Newton iterations of step s. ``stats``: [0] iterations, [1] sweeps,
    [2] largest correction of the last iteration (m), [3] largest iteration count,
    [4] steps accepted at a residual jump (within ``stall_tol``, see below).
    """
    n = x.shape[0]
    beta = 1.0
    gamma = 1.0
    if scheme == NEWMARK:
        beta = 0.25
        gamma = 0.5
    elif scheme == NUMEROV:
        beta = 1.0 / 12.0
        gamma = 3.0 / 8.0
    bdt2 = beta * dt * dt
    gdt = gamma * dt
    npair = npair_arr[0]
    nwall = nwall_arr[0]
    # work arrays (n x 3 unless noted)
    xs = work[0]
    vs = work[1]
    xn = work[2]
    vn = work[3]
    res = work[4]
    fc = work[5]
    tc = work[6]
    dxv = work[7]
    ws = work[8]
    x_old = work[9]
    diagb = np.empty((n, 6))
    dinv = np.empty((n, 6))
    nbmax = max(npair, 1)
    blk = np.empty((nbmax, 6))
    blk_i = np.empty(nbmax, np.int64)
    blk_j = np.empty(nbmax, np.int64)
    ptr = np.empty(n + 1, np.int64)
    adj = np.empty(2 * nbmax, np.int64)
    p_hist_new = np.empty_like(p_hist)
    w_hist_new = np.empty_like(w_hist)
    scratch = np.zeros((1, p_hist.shape[1]))
    wfo = np.zeros((w_force.shape[0], 3))
    p_seen = np.zeros(max(npair, 1))
    w_seen = np.zeros(max(nwall, 1))
    diag[0] = STATUS_OK
    diag[1] = 0
    half = 0.5 * margin
    for s in range(nsteps):
        # predictors of the scheme, the angular velocity the contacts see
        for i in range(n):
            im = 1.0 / mass[i]
            ii = 1.0 / inertia[i]
            for d in range(3):
                a = force[i, d] * im
                if scheme == BACKWARD_EULER:
                    xs[i, d] = x[i, d] + dt * v[i, d]
                    vs[i, d] = v[i, d]
                elif scheme == NEWMARK:
                    xs[i, d] = x[i, d] + dt * v[i, d] + 0.25 * dt * dt * a
                    vs[i, d] = v[i, d] + 0.5 * dt * a
                else:
                    ap = aux[i, 3 + d]
                    xs[i, d] = 2.0 * x[i, d] - aux[i, d] + dt * dt / 12.0 * (10.0 * a + ap)
                    vs[i, d] = (xs[i, d] - x[i, d]) / dt + dt / 24.0 * (6.0 * a - ap)
                ws[i, d] = w[i, d] + dt * torque[i, d] * ii
                # first iterate: a_{n+1} = a_n
                xn[i, d] = xs[i, d] + bdt2 * a
                x_old[i, d] = x[i, d]
        p_seen[:] = 0.0
        w_seen[:] = 0.0
        converged = False
        it = 0
        last = 0.0
        worst = 0.0
        lam = 1.0
        rprev = np.inf
        while True:
            for i in range(n):
                for d in range(3):
                    vn[i, d] = vs[i, d] + gamma / (beta * dt) * (xn[i, d] - xs[i, d])
            nb, worst = evaluate(xn, vn, ws, dt, bdt2, gdt, radius, mass, mat, pair_model,
                                 pair_params, w_point, w_normal, w_mat, pi, pj, npair,
                                 p_hist, p_hist_new, wi, ww, nwall, w_hist, w_hist_new,
                                 fc, tc, wfo, blk, blk_i, blk_j, diagb, scratch, p_seen,
                                 w_seen)
            rnorm = 0.0
            for i in range(n):
                m = mass[i]
                for d in range(3):
                    r = m * (xn[i, d] - xs[i, d]) - bdt2 * (fc[i, d] + m * gravity[d])
                    res[i, d] = r
                    rnorm += (r / m) ** 2
            if it > 0 and lam == 1.0 and last <= tol:
                converged = True
                break
            if it >= max_iter:
                break
            if it > 0 and rnorm > rprev and lam <= 1.0 / 64.0 and last <= stall_tol:
                # no descent even along 1/64 of the Newton step: the residual jumps here
                # (the linear dashpot's force c delta' switches on at delta = 0 with a
                # jump, so there may be no root); accept a point within stall_tol
                stats[4] += 1
                converged = True
                break
            if it > 0 and rnorm > rprev and lam > 1.0 / 64.0:
                # backtracking line search: the full Newton step raised the residual (a
                # contact or a dashpot switching on or off inside the step): halve it
                lam *= 0.5
                for i in range(n):
                    for d in range(3):
                        xn[i, d] -= lam * dxv[i, d]
                it += 1
                continue
            it += 1
            stats[1] += gauss_seidel(res, mass, diagb, blk, blk_i, blk_j, nb, dxv, ptr, adj,
                                     dinv, gs_tol, gs_max)
            lam = 1.0
            rprev = rnorm
            last = 0.0
            for i in range(n):
                for d in range(3):
                    xn[i, d] += dxv[i, d]
                    last = max(last, abs(dxv[i, d]))
            if not last == last:
                diag[0] = STATUS_NAN
                return
        stats[0] += it
        stats[2] = last
        stats[3] = max(stats[3], it)
        if not converged:
            diag[0] = STATUS_NOT_CONVERGED
            diag[3] = it
            return
        # candidates still valid?
        moved = 0.0
        for i in range(n):
            dx = xn[i, 0] - x_ref[i, 0]
            dy = xn[i, 1] - x_ref[i, 1]
            dz = xn[i, 2] - x_ref[i, 2]
            moved = max(moved, dx * dx + dy * dy + dz * dz)
        if moved > half * half:
            diag[0] = STATUS_OVERFLOW
            diag[3] = -1.0
            return
        # accept: a_{n+1}, v_{n+1}, rotation
        for i in range(n):
            m = mass[i]
            ii = 1.0 / inertia[i]
            for d in range(3):
                fnew = fc[i, d] + m * gravity[d]
                a_new = fnew / m
                if scheme == NUMEROV:
                    aux[i, d] = x_old[i, d]
                    aux[i, 3 + d] = force[i, d] / m
                x[i, d] = xn[i, d]
                v[i, d] = vs[i, d] + gdt * a_new
                w0 = w[i, d]
                w1 = w0 + dt * ((1.0 - theta) * torque[i, d] + theta * tc[i, d]) * ii
                ws[i, d] = (1.0 - theta) * w0 + theta * w1
                w[i, d] = w1
                force[i, d] = fnew
                torque[i, d] = tc[i, d]
            q0, q1, q2, q3 = rotate_isotropic(q[i, 0], q[i, 1], q[i, 2], q[i, 3], ws[i, 0],
                                              ws[i, 1], ws[i, 2], dt)
            q[i, 0] = q0
            q[i, 1] = q1
            q[i, 2] = q2
            q[i, 3] = q3
        for k in range(npair):
            for c in range(p_hist.shape[1]):
                p_hist[k, c] = p_hist_new[k, c]
        for k in range(nwall):
            for c in range(w_hist.shape[1]):
                w_hist[k, c] = w_hist_new[k, c]
        for r in range(w_force.shape[0]):
            for d in range(3):
                w_force[r, d] = wfo[r, d]
        it_log[s] = it
        diag[1] = s + 1
        diag[6] = nb
        if worst > diag[4]:
            diag[4] = worst
        if worst > max_overlap:
            diag[0] = STATUS_OVERLAP
            return


@jit
def contact_forces(x, v, w, dt, radius, mass, mat, pair_model, pair_params, w_point,
                   w_normal, w_mat, pi, pj, npair, p_hist, wi, ww, nwall, w_hist, force, torque,
                   w_force):
    """Contact forces and torques at (x, v, w) with the histories unchanged (gravity not
    included); for the start of a run and the Numerov starter."""
    n = x.shape[0]
    nb = max(npair, 1)
    blk = np.empty((nb, 6))
    blk_i = np.empty(nb, np.int64)
    blk_j = np.empty(nb, np.int64)
    diagb = np.empty((n, 6))
    ph = np.empty_like(p_hist)
    wh = np.empty_like(w_hist)
    scratch = np.zeros((1, p_hist.shape[1]))
    evaluate(x, v, w, dt, 0.0, 0.0, radius, mass, mat, pair_model, pair_params,
             w_point, w_normal, w_mat, pi, pj, npair, p_hist, ph, wi, ww, nwall, w_hist, wh,
             force, torque, w_force, blk, blk_i, blk_j, diagb, scratch, np.zeros(max(npair, 1)),
             np.zeros(max(nwall, 1)))
