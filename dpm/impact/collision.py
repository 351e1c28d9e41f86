"""Dimensionless single-collision solutions of the non-linear normal laws.

The models use these to turn a restitution coefficient into their damping constant and to
give the contact duration for the time-step check. They are solved here by ODE integration
because the attractive force is cut off (F_n >= 0): with the cut-off no damping formula of
the literature gives the set restitution (see shared/seeds/ERRATA.md).

Scaling (head-on collision, m* x'' = -F, impact speed v, Hertz constant k = 4/3 E* sqrt(R*)):
    delta = d_s x,  t = tau s,  d_s = (m* v^2 / k)^(2/5),  tau = d_s / v
Tsuji-type damping (Hertz-Mindlin, c_n = sqrt(5) beta sqrt(k m*) delta^(1/4)):
    x'' = -max(0, x^(3/2) + sqrt(5) beta x^(1/4) x')        (e independent of v)
Brilliantov viscoelastic damping (F_n = k (delta^(3/2) + A delta^(1/2) delta')):
    x'' = -max(0, x^(1/2) (x + gamma x')),   gamma = A (k/m*)^(2/5) v^(1/5)
Both start at x = 0, x' = 1; the contact ends when the force falls to zero.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import threading
from functools import lru_cache
from pathlib import Path

from .._lazy import lazy_module
from ..errors import ParameterError

integrate = lazy_module("scipy.integrate")
optimize = lazy_module("scipy.optimize")

SQRT5 = math.sqrt(5.0)

_SOLVED: dict | None = None


def _solved_path() -> Path:
    """File of the solutions found so far, named by a hash of this module's source (a
    changed solver starts a new file), next to the step modules' cache."""
    from ..plan import cache_dir  # (dpm.plan imports the kernels: not at module load)

    digest = hashlib.sha1(Path(__file__).read_bytes()).hexdigest()[:16]
    return cache_dir().parent / f"collisions-{digest}.json"


def _solved() -> dict:
    global _SOLVED
    if _SOLVED is None:
        try:
            _SOLVED = json.loads(_solved_path().read_text())
        except (OSError, ValueError):
            _SOLVED = {}
        if not isinstance(_SOLVED, dict):
            _SOLVED = {}
    return _SOLVED


def remembered(fn):
    """Memoize a solution of one float argument in memory and on disk (the root
    finders call ``.solve``, the function itself, so only the answers are stored).

    A warm start then neither solves an ODE nor imports scipy (scipy.integrate and
    scipy.optimize are 38 MB of resident memory and 0.3 s). The values are exact: JSON
    writes floats by their shortest repr, which reads back to the same float. Writes are
    atomic (a process' own temporary file, then a rename); two processes writing at once
    may lose each other's new entries, which are then solved again.
    """

    @lru_cache(maxsize=512)
    @functools.wraps(fn)
    def wrapper(x: float):
        key = f"{fn.__name__}:{float(x)!r}"
        known = _solved().get(key)
        if known is not None:
            return tuple(known) if isinstance(known, list) else known
        value = fn(x)
        _solved()[key] = list(value) if isinstance(value, tuple) else value
        path = _solved_path()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f"{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
            tmp.write_text(json.dumps(_solved()))
            os.replace(tmp, path)
        except OSError:  # a read-only cache: solve again next time
            pass
        return value

    wrapper.solve = fn  # the solution itself, neither remembered nor looked up
    return wrapper


def _collide(force) -> tuple[float, float, float]:
    """Integrate x'' = -max(0, force(x, v)) from (0, 1); return (e, t_end, x_max)."""

    def rhs(t, y):
        x = max(y[0], 0.0)
        return [y[1], -max(force(x, y[1]), 0.0)]

    def released(t, y):  # the force falls to zero while the bodies separate
        return force(max(y[0], 0.0), y[1]) if y[1] < 0.0 else 1.0

    released.terminal = True
    released.direction = -1

    def apart(t, y):
        return y[0]

    apart.terminal = True
    apart.direction = -1

    def turn(t, y):
        return y[1]

    sol = integrate.solve_ivp(rhs, (0.0, 100.0), [0.0, 1.0], method="DOP853", rtol=1e-10,
                              atol=1e-13, events=(released, apart, turn), max_step=0.05)
    ends = [te[0] for te in sol.t_events[:2] if len(te)]
    if not ends:
        raise RuntimeError("the single-collision ODE did not end")
    k = 0 if len(sol.t_events[0]) and (not len(sol.t_events[1])
                                        or sol.t_events[0][0] <= sol.t_events[1][0]) else 1
    v_end = sol.y_events[k][0][1]
    x_max = sol.y_events[2][0][0] if len(sol.t_events[2]) else float("nan")
    return -v_end, float(sol.t_events[k][0]), float(x_max)


@remembered
def tsuji_collision(beta: float) -> tuple[float, float, float]:
    """(e, t_end/tau, x_max) of a Hertz contact with Tsuji damping ratio ``beta``."""
    g = SQRT5 * beta
    return _collide(lambda x, v: x**1.5 + g * x**0.25 * v)


@remembered
def brilliantov_collision(gamma: float) -> tuple[float, float, float]:
    """(e, t_end/tau, x_max) of a viscoelastic Hertz contact with ``gamma`` (see above)."""
    return _collide(lambda x, v: math.sqrt(x) * (x + gamma * v))


def _invert(fun, restitution: float, what: str) -> float:
    """The damping constant c >= 0 with fun(c)[0] = restitution (fun decreasing)."""
    if restitution >= 1.0:
        return 0.0
    target = math.log(restitution)
    hi = 0.5
    while math.log(fun(hi)[0]) > target:
        hi *= 2.0
        if hi > 1e4:
            raise ParameterError(f"restitution={restitution:g} is too small to reach with the "
                                 f"{what} damping")
    return optimize.brentq(lambda c: math.log(fun(c)[0]) - target, 0.0, hi, xtol=1e-13, rtol=1e-12)


@remembered
def tsuji_beta_for_restitution(restitution: float) -> float:
    """beta of the Tsuji damping that gives ``restitution`` with the cut-off (e.g. 0.5 ->
    0.2553, where the no-cut-off formula -ln e / sqrt(ln^2 e + pi^2) gives 0.2155)."""
    return _invert(tsuji_collision.solve, restitution, "Tsuji")


@remembered
def brilliantov_gamma_for_restitution(restitution: float) -> float:
    """gamma = A (k/m*)^(2/5) v^(1/5) that gives ``restitution`` (viscoelastic Hertz)."""
    return _invert(brilliantov_collision.solve, restitution, "viscoelastic")


def hertz_scales(meff: float, reff: float, estar: float, speed: float) -> tuple[float, float]:
    """(d_s, tau): overlap and time scales of a Hertz collision (see the module docstring)."""
    k = 4.0 / 3.0 * estar * math.sqrt(reff)
    speed = max(speed, 1e-12)
    ds = (meff * speed * speed / k) ** 0.4
    return ds, ds / speed
