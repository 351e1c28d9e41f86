"""Hertz-Mindlin contact law with Tsuji-type damping (as in LIGGGHTS ``hertz``/``history``).

Normal (Hertz 1882; damping Tsuji et al. 1992, Antypov & Elliott 2011):
    a      = sqrt(R* delta)
    k_n    = 4/3 E* a           F_n = max(0, k_n delta + c_n delta')
    S_n    = 2 E* a             c_n = 2 sqrt(5/6) beta sqrt(S_n m*)
Tangential (Mindlin 1949, no-slip stiffness):
    k_t    = 8 G* a             c_t = 2 sqrt(5/6) beta sqrt(k_t m*)
    spring with history and Coulomb limit mu F_n (:func:`.tangential.spring_coulomb`)
beta is solved in the object layer so that the restitution with the attractive force cut
off is the one set (:func:`dpm.impact.collision.tsuji_beta_for_restitution`).

Sliding: the spring alone is limited to mu F_n (k_t |s| > mu F_n shortens it to
s mu F_n / (k_t |s|), as in LIGGGHTS ``tangential history``; it is never lengthened), and
spring plus dashpot, -(k_t s + c_t v_t), are limited to mu F_n. (LAMMPS' older form stores
s = -(F_t + c_t v_t)/k_t; with k_t and c_t growing with the overlap the stored spring then
pulls the force below the limit while the contact slides: an oblique impact far in the
sliding regime, tan(psi) = 8 x the sticking limit, lost 11 % of its friction impulse at
e = 0.5. Resetting it to s = -F_t/k_t instead loads the spring with the dashpot's share of
the force, energy it gives back: :mod:`.tangential`.)

Slots: normal (E*, beta); tangential :func:`.tangential.mindlin_tsuji_tangential`
(G*, beta, mu): the two share the slot beta.
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

import math

from .config import inline_jit

SQRT_5_6 = math.sqrt(5.0 / 6.0)


@inline_jit
def hertz_tsuji_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """F_n = max(0, 4/3 E* a d + 2 sqrt(5/6) beta sqrt(2 E* a m*) d'), a = sqrt(R* d);
    q = (E*, beta); k_n = S_n = 2 E* a."""
    a = math.sqrt(reff * delta)
    kn = 4.0 / 3.0 * q[0] * a
    sn = 2.0 * q[0] * a
    cn = 2.0 * SQRT_5_6 * q[1] * math.sqrt(sn * meff)
    fn = kn * delta + cn * ddelta
    if fn < 0.0:
        fn = 0.0
    return fn, sn
