"""dpm's curves of the oblique Chung & Ooi tests beside rigid-body theory, as Markdown.

``python -m dpm.validation.curves`` prints, for CO4 (alumina, 3.9 m/s, mu = 0.092,
e = 0.98) and CO5 (steel, v_n = 5 m/s, mu = 0.3, e = 1), per impact: the contact point's
tangential restitution e_t = slip after / slip before and the spin after, for
``hertz_mindlin`` and ``hooke``, beside rigid-body Coulomb theory: sliding throughout
(e_t = 1 - 7/2 mu (1 + e) v_n / v_t) where the slip is large enough, else rolling
(e_t = 0; a rigid sphere ends rolling, a compliant one may reverse its slip). The
tables in ``docs/validation.md`` are its output; the paper's own curves were not
available to compare with.
"""

from __future__ import annotations

import math

from .chung_ooi import ALUMINA, STEEL, species
from .impacts import Impact, run_group

MODELS = ("hertz_mindlin", "hooke")


def rigid_et(vn: float, vt: float, e: float, mu: float) -> float:
    """Rigid sphere on a plane: slides throughout, or ends rolling (e_t = 0)."""
    return max(0.0, 1.0 - 3.5 * mu * (1.0 + e) * vn / vt)


def co4_table() -> str:
    radius, speed, mu, e = 0.0025, 3.9, 0.092, 0.98
    angles = tuple(range(5, 90, 5))
    imps = [Impact("wall", radius, speed * math.cos(math.radians(a)),
                   vt1=speed * math.sin(math.radians(a))) for a in angles]
    res = {m: run_group([species(ALUMINA, m, e, mu, speed, radius, False)], imps)
           for m in MODELS}
    head = ["angle [deg]", "e_t rigid"] + [f"e_t {m}" for m in MODELS] + \
        [f"w' [rad/s] {m}" for m in MODELS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k, (a, imp) in enumerate(zip(angles, imps, strict=True)):
        cells = [f"{a}", f"{rigid_et(imp.vn1, imp.vt1, e, mu):.4f}"]
        cells += [f"{(res[m][k].vt1 + res[m][k].surf1) / imp.vt1:.4f}" for m in MODELS]
        cells += [f"{res[m][k].w1:.1f}" for m in MODELS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def co5_table() -> str:
    radius, vn, mu, e = 1e-5, 5.0, 0.3, 1.0
    psis = (0.5, 1, 2, 3, 4, 5, 6, 7, 8, 10, 14, 20, 30)
    imps = [Impact("wall", radius, vn, vt1=p * mu * vn) for p in psis]
    res = {m: run_group([species(STEEL, m, e, mu, vn, radius, False)], imps)
           for m in MODELS}
    head = ["v_t/(mu v_n)", "slip'/(mu v_n) rigid"] + \
        [f"slip'/(mu v_n) {m}" for m in MODELS] + [f"R w'/(mu v_n) {m}" for m in MODELS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k, (p, imp) in enumerate(zip(psis, imps, strict=True)):
        cells = [f"{p}", f"{p * rigid_et(vn, imp.vt1, e, mu):.3f}"]
        cells += [f"{(res[m][k].vt1 + res[m][k].surf1) / (mu * vn):.3f}" for m in MODELS]
        cells += [f"{res[m][k].w1 * radius / (mu * vn):.3f}" for m in MODELS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    print("CO4, alumina (200 steps per contact)\n")
    print(co4_table())
    print("\nCO5, steel (200 steps per contact)\n")
    print(co5_table())


if __name__ == "__main__":
    main()
