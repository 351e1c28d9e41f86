"""Drop test: a bead dropped on a plate bounces with the restitution of its contact law.

The elementary test of Hromnik (GPGPU DEM of a tumbling mill, sec. 6.1, Fig. 6.1): a
sphere dropped from rest on a plate rebounds, bounce after bounce, with the restitution
coefficient e of the contact model, so the rebound heights fall as h_k+1 / h_k = e^2
(h ~ v^2). Here one 3 mm glass bead (r = 3 mm, 2500 kg/m3) per impact model falls from
h0 = 0.1 m (centre above the touching height) on its own plate (a ``wall`` boundary of
its own material), side by side in one simulation, so the models run together. Every
model that takes a restitution is set to Hromnik's e = 0.658:

| model | set | restitution |
|---|---|---|
| linear_spring_dashpot | k_n = 2.8e5 N/m (contact ~0.1 ms) | e, any speed |
| hooke | E = 1e8 Pa (k_n = 4/3 E* R*) | e, any speed |
| maw_linear_spring | E = 1e9 Pa, impact_velocity = sqrt(2 g h0) | e, any speed |
| walton_braun | k_l = 2.8e5 N/m, k_ul = k_l / e^2 | e, any speed |
| hertz_mindlin | E = 1e9 Pa | e, any speed (Tsuji damping) |
| hertz_brilliantov | E = 1e9 Pa, dissipation A (e = 0.658 at sqrt(2 g h0)) | falls with the speed |

(``linear_cohesion`` is Hertz-Mindlin with an attraction: with cohesion its rebound is
lower than e by design, without it is Hertz-Mindlin; it is left out.)

The rebound height of flight k is read from any state in the air as
h = z - z_touch + v_z^2 / (2 g), exact for free flight (velocity Verlet integrates constant
gravity exactly); its median over the flight's samples is taken. For the speed-independent
models the ratio of successive heights is compared with e^2; for Brilliantov's model with
e(v)^2 at the impact speed v = sqrt(2 g h_k), e(v) solved here from the model's collision
ODE (m x'' = -k (x^3/2 + A x^1/2 x'), force cut at zero, k = 4/3 E* sqrt(r)) with scipy,
independently of dpm's own solver. At dt = 1 us (~100 steps per contact) two errors
remain: gravity acting during the contact lowers the ratio by about g T / v (0.1 % at the
first bounce, ~0.5 % at 0.17 m/s: the drift of Walton-Braun and Hertz-Mindlin), and the
dashpot of the linear laws jumps to c v at first touch, so where the first contact step
falls within dt moves e by up to ~2 zeta w0 dt (the +-0.5 % scatter of the linear laws).

    python examples/drop_test.py            # 6 bounces, 0.65 s simulated: ~20 s
    python examples/drop_test.py --quick    # 3 bounces: ~10 s once compiled

Writes ``drop_test.h5`` + ``.xdmf``, ``drop_test.json`` and ``drop_test.png`` into
``--output``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import dpm

G = 9.81
R = 3e-3
RHO = 2500.0
E_SET = 0.658          # Hromnik sec. 6.1
H0 = 0.1               # drop height of the centre above touching [m]
DT = 1e-6
PLATE_Z = 0.0
SPACING = 0.02
NU = 0.3
MASS = RHO * 4 / 3 * math.pi * R**3
K_LINEAR = MASS * (math.pi / 1e-4) ** 2        # a 0.1 ms contact
E_HERTZ = 1e9
V0 = math.sqrt(2 * G * H0)

SPEED_INDEPENDENT = ["linear_spring_dashpot", "hooke", "maw_linear_spring", "walton_braun",
                     "hertz_mindlin"]
MODELS = SPEED_INDEPENDENT + ["hertz_brilliantov"]


def brilliantov_restitution(v: float, A: float, k: float, m: float = MASS) -> float:
    """Restitution of a head-on impact at speed v under m x'' = -max(0, k (x^1.5 +
    A x^0.5 x')), solved by scipy (rtol 1e-10); the contact ends when the force returns
    to zero or the overlap to zero."""
    def rhs(_t, y):
        x, xd = y
        f = k * (max(x, 0.0) ** 1.5 + A * math.sqrt(max(x, 0.0)) * xd)
        return [xd, -max(f, 0.0) / m]

    def ends(_t, y):
        x, xd = y
        if xd >= 0:
            return 1.0
        return x ** 1.5 + A * math.sqrt(max(x, 0.0)) * xd if x > 0 else x
    ends.terminal, ends.direction = True, -1
    t_scale = (m**2 / (k**2 * v)) ** 0.2 * 10
    sol = solve_ivp(rhs, (0.0, t_scale), [0.0, v], events=ends, rtol=1e-10, atol=1e-16,
                    max_step=t_scale / 2000)
    return -float(sol.y_events[0][0][1]) / v


def e_star(young_a: float, young_b: float, nu: float = NU) -> float:
    return 1.0 / ((1 - nu**2) / young_a + (1 - nu**2) / young_b)


def build() -> tuple[dpm.Simulation, dict]:
    """One bead per model above its own plate; returns the simulation and the model
    parameters (for the predictions)."""
    sim = dpm.Simulation(dt=DT, gravity=(0.0, 0.0, -G))
    k_hertz = 4 / 3 * e_star(E_HERTZ, E_HERTZ) * math.sqrt(R)
    # A of Brilliantov's law for e = E_SET at V0, from the ODE above
    A = brentq(lambda a: brilliantov_restitution(V0, a, k_hertz) - E_SET, 1e-9, 1e-3,
               xtol=1e-14)
    young = {"hooke": 1e8}
    params = {
        "linear_spring_dashpot": {"stiffness": K_LINEAR, "restitution": E_SET},
        "hooke": {"restitution": E_SET},
        "maw_linear_spring": {"restitution": E_SET, "impact_velocity": V0},
        "walton_braun": {"stiffness": K_LINEAR, "restitution": E_SET},
        "hertz_mindlin": {"restitution": E_SET},
        "hertz_brilliantov": {"dissipation": A},
    }
    beads, plates = [], []
    for name in MODELS:
        E = young.get(name, E_HERTZ)
        beads.append(dpm.Material(f"bead_{name}", density=RHO, young=E, poisson=NU))
        plates.append(dpm.Material(f"plate_{name}", density=7800.0, young=E, poisson=NU))
    # the beads never meet each other or another plate; laws are set for every pair all
    # the same (the scene check asks for them)
    for i, a in enumerate(beads):
        for b in beads[i:] + plates:
            sim.contact(a, b, model="linear_spring_dashpot", stiffness=K_LINEAR,
                        restitution=E_SET, friction=0.0)
    for name, bead, plate in zip(MODELS, beads, plates, strict=True):
        sim.contact(bead, plate, model=name, friction=0.0, **params[name])
    pos = []
    for k, (bead, plate) in enumerate(zip(beads, plates, strict=True)):
        x = k * SPACING
        sim.add_boundary("wall", material=plate, center=(x, 0.0, PLATE_Z),
                         normal=(0.0, 0.0, 1.0), u=(1.0, 0.0, 0.0),
                         half_extents=(0.4 * SPACING, 0.4 * SPACING))
        p = (x, 0.0, PLATE_Z + R + H0)
        pos.append(p)
        sim.add_particles("sphere", material=bead, radius=R, positions=np.array([p]))
    info = {"brilliantov_A_s": A, "k_hertz": k_hertz, "params": params,
            "young": {n: young.get(n, E_HERTZ) for n in MODELS}}
    return sim, info


def flight_heights(t: np.ndarray, z: np.ndarray, vz: np.ndarray) -> tuple[list, list]:
    """Rebound heights h_k (k = 0: the drop) and the times of the bounces, from samples."""
    z_touch = PLATE_Z + R
    energy = z - z_touch + vz**2 / (2 * G)
    air = z > z_touch
    # a bounce between samples i and i+1: falling (or touching) then rising
    bounce = np.nonzero(((vz[:-1] < 0) & (vz[1:] > 0)) | (~air[1:] & air[:-1]))[0] + 1
    bounce = bounce[np.insert(np.diff(bounce) > 2, 0, True)] if len(bounce) else bounce
    heights, times = [], []
    edges = np.concatenate([[0], bounce, [len(t)]])
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = np.arange(a, b)
        sel = sel[air[sel]]
        if len(sel) >= 3:
            heights.append(float(np.median(energy[sel])))
            times.append(float(t[a]))
    return heights, times


def picture(doc: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = ["-", "--", "-.", ":", (0, (5, 1)), "-"]
    for (name, m), ls in zip(doc["models"].items(), styles, strict=True):
        ax1.plot(doc["time"], np.asarray(m["z"]) * 1e3, linestyle=ls, lw=1, label=name)
    ax1.set_xlabel("time [s]")
    ax1.set_ylabel("centre height above touching [mm]")
    ax1.set_title(f"bead dropped from {H0 * 1e3:.0f} mm, e = {E_SET}", fontsize=9)
    ax1.legend(fontsize=7)
    markers = "os^vDx"
    for (name, m), mk in zip(doc["models"].items(), markers, strict=True):
        k = np.arange(1, len(m["ratio"]) + 1)
        ax2.plot(k, m["ratio"], mk, mfc="none", label=name)
    b = doc["models"]["hertz_brilliantov"]
    ax2.plot(np.arange(1, len(b["predicted_ratio"]) + 1), b["predicted_ratio"], "k+",
             ms=10, label="Brilliantov ODE e(v)^2")
    ax2.axhline(E_SET**2, color="0.4", lw=1, label="e^2")
    ax2.set_xlabel("bounce")
    ax2.set_ylabel("h_k / h_k-1")
    ax2.set_title("ratio of successive rebound heights", fontsize=9)
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="3 bounces instead of 6")
    p.add_argument("--output", default="drop_test_results", help="output folder")
    args = p.parse_args(argv)
    bounces = 3 if args.quick else 6
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    sim, info = build()
    # until the last bounce's flight is over (e constant)
    until = math.sqrt(2 * H0 / G) * (1 + 2 * sum(E_SET**k for k in range(1, bounces + 1)))
    sim.output(str(out / "drop_test.h5"), every=5e-3, overwrite=True)
    every = 1e-3
    ts, zs, vs = [], [], []
    t0 = time.perf_counter()
    while sim.time < until - 1e-12:
        sim.run(until=min(until, sim.time + every))
        ts.append(sim.time)
        zs.append(sim.bodies.position[:, 2].copy())
        vs.append(sim.bodies.velocity[:, 2].copy())
    wall = time.perf_counter() - t0
    steps = sim.step_count
    sim.close()
    t, z, vz = np.array(ts), np.array(zs), np.array(vs)
    doc = {"scene": "drop_test", "quick": args.quick, "restitution": E_SET, "h0_m": H0,
           "radius_m": R, "density": RHO, "dt_s": DT, "steps": steps, "wall_s": wall,
           "brilliantov_A_s": info["brilliantov_A_s"], "time": t.tolist(), "models": {}}
    dpm.notice(f"{len(MODELS)} beads, {steps} steps of {DT:g} s in {wall:.1f} s")
    dpm.notice(f"{'model':<23s} {'bounce':>6s} {'h [mm]':>9s} {'ratio':>8s} {'e^2':>8s} "
               f"{'predicted':>9s} {'rel.err':>8s}")
    for j, name in enumerate(MODELS):
        h, tb = flight_heights(t, z[:, j], vz[:, j])
        h = h[:bounces + 1]
        ratio = [h[k] / h[k - 1] for k in range(1, len(h))]
        if name == "hertz_brilliantov":
            pred = [brilliantov_restitution(math.sqrt(2 * G * h[k - 1]),
                                            info["brilliantov_A_s"], info["k_hertz"]) ** 2
                    for k in range(1, len(h))]
        else:
            pred = [E_SET**2] * len(ratio)
        err = [r / q - 1 for r, q in zip(ratio, pred, strict=True)]
        doc["models"][name] = {"heights_m": h, "bounce_times_s": tb[:len(h)],
                               "ratio": ratio, "predicted_ratio": pred, "rel_error": err,
                               "z": (z[:, j] - PLATE_Z - R).tolist(),
                               "speed_dependent": name not in SPEED_INDEPENDENT}
        for k, (r, q, e) in enumerate(zip(ratio, pred, err, strict=True)):
            dpm.notice(f"{name:<23s} {k + 1:6d} {h[k + 1] * 1e3:9.4f} {r:8.5f} {E_SET**2:8.5f} "
                       f"{q:9.5f} {e:+8.2%}")
    if dpm.is_root():  # (rank 0 writes: every rank holds the result)
        (out / "drop_test.json").write_text(json.dumps(doc))
        try:
            picture(doc, out / "drop_test.png")
        except ImportError:
            print("matplotlib is missing: no picture (pip install 'dpm-granular[plot]')")
    dpm.notice(f"output in {out}/")
    return doc


if __name__ == "__main__":
    main()
