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

History: hist[k, 6] = delta_max, hist[k, 7] = delta_0 (zeroed when the contact opens).
pair_params row: [k_l, k_ul, mu, kappa, zeta_t, (rolling), rolling model, mu_r]
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb


@inline_jit
def walton_braun(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    kl = p[0]
    kul = p[1]
    dmax = hist[k, 6]
    if delta >= dmax:
        hist[k, 6] = delta
        fn = kl * delta
        hist[k, 7] = delta * (1.0 - kl / kul)
    else:
        fn = kul * (delta - hist[k, 7])
        if fn < 0.0:
            fn = 0.0
    ftx, fty, ftz = spring_coulomb(p[3] * kl, 2.0 * p[4] * math.sqrt(meff * kl), p[2], fn,
                                   vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
