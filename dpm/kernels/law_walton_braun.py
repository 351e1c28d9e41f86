"""Walton-Braun hysteretic spring: plastic loading, stiffer elastic unloading, no dashpot.

DPM thesis (Samiei 2012) §2.6.6, eqs. 2.47-2.52; Walton & Braun 1986 (J. Rheol. 30, 949):
    loading   (delta >= delta_max so far):  F_n = k_l delta,  delta_max <- delta
    otherwise (unloading and reloading):    F_n = max(0, k_ul (delta - delta_0))
    delta_0 = delta_max (1 - k_l / k_ul)    (plastic overlap; the two lines meet at delta_max)
so e = sqrt(k_l / k_ul) and the contact lasts pi/2 (sqrt(m*/k_l) + sqrt(m*/k_ul)).
The branch follows the largest overlap reached, not the sign of delta' (the thesis' eq.
2.47), so a partial unload followed by reloading retraces the unloading line.
Tangential as the linear spring-dashpot: k_t = kappa k_l, c_t = 2 zeta_t sqrt(m* k_l),
history and Coulomb limit mu F_n.

History: hist[k, h] = delta_max, hist[k, h + 1] = delta_0 (zeroed when the contact opens).
Slots: normal (k_l, k_ul); tangential :func:`.tangential.linear_tangential`.
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

from .config import inline_jit


@inline_jit
def walton_braun_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """Hysteretic normal force; q = (k_l, k_ul), history (d_max, d_0); k_n = k_l."""
    kl = q[0]
    kul = q[1]
    dmax = hist[k, h]
    if delta >= dmax:
        hist[k, h] = delta
        fn = kl * delta
        hist[k, h + 1] = delta * (1.0 - kl / kul)
    else:
        fn = kul * (delta - hist[k, h + 1])
        if fn < 0.0:
            fn = 0.0
    return fn, kl
