"""Implicit integrators: backward Euler, Newmark-beta and Numerov, solved by Newton-Raphson
with block Gauss-Seidel on the sparse contact Jacobian (DPM thesis, Samiei 2012, ch. 3).

The equations, the Jacobian and the treatment of friction and rotation are in
:mod:`dpm.kernels.implicit` and docs/integrators.md. These classes pack the scene for the
kernels, keep the candidate contact list and its history between steps, and report the
Newton iterations of every step. The kernels are generated per scene by
:func:`dpm.plan.implicit_module` with the scene's contact laws composed from their parts,
as the explicit step's (any impact model works, rolling resistance included).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from .. import plan as _plan
from ..errors import SceneError
from ..kernels import implicit as K
from ..state import Contacts
from .base import Integrator

PLANE_KINDS = ("plane", "box")


class ImplicitIntegrator(Integrator):
    """Common machinery of the implicit schemes (see :mod:`dpm.kernels.implicit`).

    Attributes to tune after ``Simulation(...)`` (``sim.integrator.tolerance = ...``):

    - ``tolerance``: Newton stops when every body's correction is below
      ``tolerance`` x the smallest radius (default 1e-10);
    - ``stall_tolerance``: where no fraction of the Newton step lowers the residual (a
      force jump: the linear dashpot switches on with c delta' at delta = 0), the iterate
      is accepted if its correction is below this x the smallest radius (default 1e-4);
      such steps are counted in ``stats["stalled"]``;
    - ``max_iterations``: Newton iterations allowed per step (default 50); a step that
      needs more stops the run with :class:`dpm.UnstableRunError`;
    - ``gs_tolerance``: Gauss-Seidel stops when a sweep changes no correction by more than
      this fraction of the Newton tolerance (default 0.01); ``gs_max_sweeps`` (500).

    Reported: ``iterations`` (Newton iterations of each step of the last run call),
    ``last_iterations``, ``max_iterations_used`` and ``stats`` (steps, iterations,
    Gauss-Seidel sweeps, candidate rebuilds, largest iteration count).
    """

    implicit: ClassVar[bool] = True
    #: only used to compile the force evaluation of the first state (the backend's ``prime``)
    kernel_module = "dpm.kernels.integrate_velocity_verlet"
    #: unconditionally stable for linear contacts: one step per contact is accepted
    min_steps_per_contact = 1.0
    aux_columns = 6
    scheme: ClassVar[int] = K.BACKWARD_EULER
    #: weight of the end-of-step torque in the angular velocity update
    theta: ClassVar[float] = 0.5

    def __init__(self) -> None:
        self.tolerance = 1e-10
        self.stall_tolerance = 1e-4
        self.max_iterations = 50
        self.gs_tolerance = 0.01
        self.gs_max_sweeps = 500
        self.iterations = np.zeros(0, np.int64)
        self.last_iterations = 0
        self.max_iterations_used = 0
        self.stats = dict(steps=0, iterations=0, sweeps=0, rebuilds=0, max_iterations=0,
                          stalled=0)
        self._ready = False

    def __getstate__(self) -> dict[str, Any]:
        """A checkpoint keeps the packed scene and candidates; the kernels module is
        loaded again (from the plan's laws) at the next step."""
        state = self.__dict__.copy()
        state.pop("_K", None)
        return state

    # ------------------------------------------------------------------ scene packing
    def _setup(self, sim: Any) -> None:
        b, e = sim.bodies, sim.elements
        problems = []
        if not (len(e) == len(b) and np.all(e.offset == 0.0)
                and np.array_equal(e.owner, np.arange(len(b)))):
            problems.append("only sphere scenes (one element per body at its centre) are "
                            "supported; clustered bodies need an explicit integrator")
        if np.any(b.invmass == 0.0):
            problems.append("bodies of infinite mass are not supported")
        if getattr(sim, "inlets", None) or getattr(sim, "outlets", None):
            problems.append("inlets and outlets are not supported (the body count is fixed)")
        if np.any(getattr(sim, "period", np.zeros(6))[3:] > 0):
            problems.append("periodic faces are not supported")
        pts, nrm, mats, owners = [np.zeros((0, 3))], [np.zeros((0, 3))], [], []
        for k, bd in enumerate(sim.boundaries):
            if bd.name not in PLANE_KINDS:
                problems.append(f"boundary {k} ({bd.name}) is not supported; allowed: "
                                + ", ".join(PLANE_KINDS))
                continue
            if getattr(bd, "motion", None) is not None:
                problems.append(f"boundary {k} ({bd.name}) moves; only fixed planes are "
                                "supported")
            p, nv = bd.planes()
            pts.append(np.asarray(p, float))
            nrm.append(np.asarray(nv, float))
            mats += [sim.material_index(bd.material)] * len(p)
            owners += [k] * len(p)
        # the planes of every boundary, packed for the kernels (object form: bd.planes())
        self._w_point = np.ascontiguousarray(np.concatenate(pts))
        self._w_normal = np.ascontiguousarray(np.concatenate(nrm))
        self._w_mat = np.array(mats, np.int64)
        self._w_owner = np.array(owners, np.int64)
        self._w_force = np.zeros((len(mats), 3))
        if problems:
            raise SceneError(f"integrator {self.name!r}: " + "; ".join(problems))
        # the kernels with the scene's contact laws (the laws and tables of the step)
        self._K = _plan.implicit_module(sim.plan.laws)
        self._nh = int(sim.contacts.history_width)
        n = len(b)
        self._radius = np.ascontiguousarray(e.radius)
        self._inertia = np.ascontiguousarray(b.inertia[:, 0])
        self._rmin = float(self._radius.min())
        # candidate pairs: the explicit step's neighbour list (CSR, history merged)
        self._pairs = Contacts(n, 4 * n + 16)
        self._pairs.set_history_width(self._nh)
        self._owner = np.arange(n, dtype=e.owner.dtype)
        self._period = np.zeros(6)
        self._pi = np.zeros(0, np.int64)
        self._pj = np.zeros(0, np.int64)
        self._pkey = np.zeros(0, np.int64)
        self._phist = np.zeros((0, self._nh))
        self._wi = np.zeros(2 * n + 16, np.int64)
        self._ww = np.zeros(2 * n + 16, np.int64)
        self._wkey = np.zeros(0, np.int64)
        self._whist = np.zeros((0, self._nh))
        self._np = np.zeros(1, np.int64)
        self._nw = np.zeros(1, np.int64)
        self._xref = np.zeros((n, 3))
        self._work = np.zeros((10, n, 3))
        self._margin = 0.0
        self._ready = True

    def _rebuild(self, sim: Any) -> None:
        """Candidate pairs and plane entries within a margin of the current positions,
        with the tangential history of those that were candidates before."""
        b = sim.bodies
        x = b.position
        dt = sim.dt
        acc = np.linalg.norm(b.force * b.invmass[:, None], axis=1)
        step = float(np.max(np.linalg.norm(b.velocity, axis=1) * dt + 0.5 * acc * dt * dt,
                            initial=0.0))
        self._margin = max(0.2 * self._rmin, 4.0 * step)
        c = self._pairs
        while True:
            cnt = self._K.candidate_pairs(x, self._radius, self._owner, self._margin, c.start,
                                          c.key, c.history, c.active, c.t_start, c.t_pair,
                                          self._period)
            if cnt <= c.capacity:
                break
            c.grow(cnt)
        self._pi = np.empty(cnt, np.int64)
        self._K.pair_rows(c.start, self._pi)
        self._pj = c.key[:cnt].astype(np.int64)
        self._phist = c.history[:cnt]  # (a view: the steps update the list's history)
        self._np[0] = cnt
        nw = len(self._w_point)
        while True:
            cw = self._K.candidate_walls(x, self._radius, self._margin, self._w_point,
                                   self._w_normal, self._wi, self._ww)
            if cw <= len(self._wi):
                break
            self._wi = np.zeros(2 * cw, np.int64)
            self._ww = np.zeros(2 * cw, np.int64)
        key = np.zeros(cw, np.int64)
        hist = np.zeros((cw, self._nh))
        self._K.sort_and_merge(self._wi, self._ww, cw, max(nw, 1), self._wkey, self._whist, key,
                               hist)
        self._wkey, self._whist, self._nw[0] = key, hist, cw
        self._xref[:] = x
        self.stats["rebuilds"] += 1

    def _forces(self, sim: Any, x: np.ndarray, v: np.ndarray, w: np.ndarray) -> tuple:
        """(force incl. gravity, torque) at (x, v, w) without touching the histories."""
        b = sim.bodies
        f = np.zeros_like(x)
        t = np.zeros_like(x)
        wf = np.zeros((len(self._w_point), 3))
        self._K.contact_forces(x, v, w, sim.dt, self._radius, b.mass, b.material,
                               sim.plan.pair_model, sim.plan.pair_params, self._w_point,
                               self._w_normal, self._w_mat, self._pi, self._pj,
                               int(self._np[0]), self._phist, self._wi, self._ww,
                               int(self._nw[0]), self._whist, f, t, wf)
        f += b.mass[:, None] * sim.gravity
        return f, t, wf

    # ------------------------------------------------------------------ Integrator API
    def start(self, sim: Any) -> None:
        """Pack the scene, build the candidates, the forces of the first state (and the
        Numerov history)."""
        self._setup(sim)
        self._rebuild(sim)
        b = sim.bodies
        f, t, wf = self._forces(sim, b.position, b.velocity, b.angular_velocity)
        b.force[:] = f
        b.torque[:] = t
        self._w_force[:] = wf
        self._store_loads(sim)
        sim.backend.aux[:] = 0.0
        self._start_history(sim)

    def _store_loads(self, sim: Any) -> None:
        """Force of the particles on each boundary into the scene's boundary table (read
        by ``sim.boundaries[k].force``); the torque is left at zero."""
        w = sim.walls
        if w is None or not hasattr(w, "load"):
            return
        w.load[:] = 0.0
        for k in range(len(sim.boundaries)):
            w.load[k, :3] = self._w_force[self._w_owner == k].sum(axis=0)

    def _start_history(self, sim: Any) -> None:
        """Scheme-specific history (Numerov: x_{-1}, a_{-1})."""

    def advance(self, sim: Any, n: int) -> int:
        if not self._ready:
            self.start(sim)
        elif "_K" not in self.__dict__:  # restored from a checkpoint
            self._K = _plan.implicit_module(sim.plan.laws)
        b, d = sim.bodies, sim.backend.diag
        tol = self.tolerance * self._rmin
        log = np.zeros(n, np.int64)
        stats = np.zeros(5)
        done = 0
        d[4] = 0.0
        while done < n:
            d[0] = K.STATUS_OK
            self._K.implicit_steps(
                n - done, self.scheme, sim.dt, sim.gravity, tol,
                self.stall_tolerance * self._rmin, self.max_iterations,
                self.gs_tolerance * tol, self.gs_max_sweeps, sim.max_overlap, self.theta,
                b.position, b.velocity, b.orientation, b.angular_velocity, b.force, b.torque,
                sim.backend.aux, self._radius, b.mass, self._inertia, b.material,
                sim.plan.pair_model, sim.plan.pair_params, self._w_point, self._w_normal,
                self._w_mat, self._w_force,
                self._pi, self._pj, self._np, self._pkey, self._phist, self._wi, self._ww,
                self._nw, self._wkey, self._whist, self._xref, self._margin, self._work,
                np.zeros(1, np.int64), log[done:], stats, d)
            done += int(d[1])
            if d[0] == K.STATUS_OVERFLOW:
                self._rebuild(sim)
                continue
            break
        self._store_loads(sim)
        self.iterations = log[:done]
        self.stats["steps"] += done
        self.stats["iterations"] += int(stats[0])
        self.stats["sweeps"] += int(stats[1])
        self.stats["stalled"] += int(stats[4])
        self.stats["max_iterations"] = max(self.stats["max_iterations"], int(stats[3]))
        self.max_iterations_used = self.stats["max_iterations"]
        if done:
            self.last_iterations = int(log[done - 1])
        if d[0] == K.STATUS_NOT_CONVERGED:  # the run loop stops with this diagnosis
            self.failure = (f"{self.name}: Newton-Raphson did not converge within "
                            f"{self.max_iterations} iterations in the next step (largest "
                            f"correction {stats[2]:.3g} m, tolerance {tol:.3g} m)")
        d[1] = done
        return done


class BackwardEuler(ImplicitIntegrator):
    """Backward (implicit) Euler, first order, L-stable (DPM thesis §3.3.1, eqs. 3.2-3.3).

        v_{n+1} = v_n + dt a_{n+1},   x_{n+1} = x_n + dt v_{n+1}

    Numerically damped: an undamped contact loses energy (restitution below 1).
    """

    name = "backward_euler"
    order = 1
    scheme = K.BACKWARD_EULER
    theta = 1.0


class NewmarkBeta(ImplicitIntegrator):
    """Newmark-beta, average acceleration (beta = 1/4, gamma = 1/2; Newmark 1959; DPM
    thesis §3.3.3, eqs. 3.7-3.8): the trapezoidal rule, second order, A-stable, no
    numerical damping.

        v_{n+1} = v_n + dt (a_n + a_{n+1}) / 2
        x_{n+1} = x_n + dt v_n + dt^2 (a_n + a_{n+1}) / 4
    """

    name = "newmark_beta"
    order = 2
    scheme = K.NEWMARK


class Numerov(ImplicitIntegrator):
    """Numerov (Cowell, implicit Stormer), fourth order in position (DPM thesis §3.3.8,
    eq. 3.25), with the fourth-order velocity v_{n+1} = (x_{n+1} - x_n)/dt
    + dt/24 (7 a_{n+1} + 6 a_n - a_{n-1}).

        x_{n+1} = 2 x_n - x_{n-1} + dt^2/12 (a_{n+1} + 10 a_n + a_{n-1})

    Two-step: x_{-1}, a_{-1} come from a backward RK4 integration over one step (4
    substeps) at the start, so the start does not spoil the order. Stable for
    omega dt < sqrt(6) (undamped linear contact): it is not A-stable, one step per contact
    (omega dt = pi) is already beyond its limit; at least 1.3 steps per contact.
    """

    name = "numerov"
    order = 4
    scheme = K.NUMEROV
    min_steps_per_contact = 1.3

    def _start_history(self, sim: Any) -> None:
        b = sim.bodies
        w = b.angular_velocity
        m = b.mass[:, None]

        def acc(x, v):
            return self._forces(sim, x, v, w)[0] / m

        x, v = b.position.copy(), b.velocity.copy()
        h = -sim.dt / 4
        for _ in range(4):
            k1x, k1v = v, acc(x, v)
            k2x, k2v = v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v)
            k3x, k3v = v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v)
            k4x, k4v = v + h * k3v, acc(x + h * k3x, v + h * k3v)
            x = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        sim.backend.aux[:, 0:3] = x
        sim.backend.aux[:, 3:6] = acc(x, v)

