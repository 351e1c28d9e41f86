"""``dpm analyse run.h5 ...``: the common results of :mod:`dpm.analysis` as text."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown


def _options(words: list[str] | None, what: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for w in words or []:
        key, sep, value = w.partition("=")
        out[key.strip()] = value.strip() if sep else ""
    return out


def _vec(text: str, name: str) -> np.ndarray:
    try:
        v = np.array([float(t) for t in text.split(",")])
    except ValueError:
        raise ParameterError(f"{name}={text!r}: three comma-separated numbers") from None
    if v.shape != (3,):
        raise ParameterError(f"{name}={text!r}: three comma-separated numbers")
    return v


def _num(opts: dict[str, str], key: str, default: Any, kind: type = float) -> Any:
    if key not in opts or opts[key] == "":
        return default
    try:
        return kind(opts[key])
    except ValueError:
        raise ParameterError(f"{key}={opts[key]!r} is not a {kind.__name__}") from None


def _summary(run: Any) -> None:
    from .contacts import kinetic_energy

    print(f"{run.path}: {run.n_frames} frame(s)", end="")
    if run.n_frames:
        print(f", t = {run.times[0]:.6g} .. {run.times[-1]:.6g} s, steps "
              f"{run.steps[0]} .. {run.steps[-1]}")
        f = run.frame(-1)
        k = kinetic_energy(f)
        print(f"last frame: {len(f['id'])} particles, mass {float(np.sum(f['mass'])):.6g} kg, "
              f"kinetic energy {k['total']:.6g} J (rotational {k['rotational']:.6g} J)")
    else:
        print()
    n = len(run.removed.get("id", []))
    print(f"removed by outlets: {n} bodies" + (f", {float(np.sum(run.removed['mass'])):.6g} kg"
                                              if n else ""))
    print(f"thermo rows: {len(run.thermo.get('time', []))}")


#: the exit status after the reader of standard output went away (``dpm analyse ... |
#: head``): a shell's for a process ended by SIGPIPE, 128 + 13
BROKEN_PIPE_STATUS = 128 + int(getattr(signal, "SIGPIPE", 13))


def analyse(args: argparse.Namespace) -> int:
    """``dpm analyse``: the results asked for, as text on standard output. When the reader
    of the output goes away first (``dpm analyse run.h5 --thermo | head``) it stops
    quietly, as Unix tools do, with status :data:`BROKEN_PIPE_STATUS`."""
    try:
        status = _analyse(args)
        sys.stdout.flush()  # (inside: a broken pipe shows here, not at exit)
        return status
    except BrokenPipeError:
        # what is still buffered goes nowhere: Python's own flush at exit would complain
        # ("Exception ignored ... BrokenPipeError") and exit with status 120
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)
        except (OSError, ValueError):  # (a stdout without a file descriptor)
            pass
        return BROKEN_PIPE_STATUS


def flow_normal(axis: str, gravity: Any = (0.0, 0.0, -9.81)) -> np.ndarray:
    """The default normal of ``--flow x=|y=|z=``: along gravity where the plane lies across
    it (z= under gravity along -z: (0, 0, -1), so that falling mass counts positive), else
    the axis' own direction (+x, +y)."""
    k = "xyz".index(axis)
    g = np.asarray(gravity, float).reshape(3)
    n = np.zeros(3)
    n[k] = -1.0 if g[k] < 0.0 else 1.0
    return n


def _analyse(args: argparse.Namespace) -> int:
    from ..io.hdf5 import load
    from . import contacts, drum, mixing, residence
    from .thermo import format_table

    run = load(args.run, repair_xdmf=False)
    did = False
    if args.residence is not None:
        o = _options(args.residence, "residence")
        rt = residence.residence_times(run, outlet=_num(o, "outlet", None, int),
                                       mass_weighted=bool(_num(o, "mass", 0, int)))
        print(f"residence times: {rt}")
        if len(rt):
            edges, e = rt.E(bins=_num(o, "bins", 10, int))
            print(f"{'t [s]':>12} {'E [1/s]':>12} {'F':>8}")
            for a, b, v in zip(edges[:-1], edges[1:], e, strict=True):
                print(f"{0.5 * (a + b):12.6g} {v:12.6g} {float(rt.F(b)):8.4f}")
        did = True
    if args.flow is not None:
        o = _options(args.flow, "flow")
        bw = _num(o, "bin", None)
        if "outlet" in o:
            if bw is None:
                raise ParameterError("--flow outlet needs bin=SECONDS")
            s = residence.outlet_flow_rate(run, bw, outlet=_num(o, "outlet", None, int))
            print("mass flow rate out of the outlets [kg/s]")
        else:
            axes = [k for k in ("x", "y", "z") if k in o]
            if len(axes) != 1:
                raise ParameterError("--flow: give the plane as x=, y= or z= (or outlet)")
            point = np.zeros(3)
            idx = "xyz".index(axes[0])
            point[idx] = _num(o, axes[0], 0.0)
            if "normal" in o:
                normal = _vec(o["normal"], "normal")
            else:  # (the help's default: z=0.0 [normal=0,0,-1], falling mass positive)
                normal = flow_normal(axes[0], run.attrs.get("gravity", (0.0, 0.0, -9.81)))
            s = residence.plane_flow_rate(run, point, normal, bin_width=bw)
            print(f"mass flow rate through {axes[0]} = {point[idx]:g} along normal "
                  f"{shown(normal, digits=6)} [kg/s]")
        print(f"{'t [s]':>12} {'rate [kg/s]':>14}")
        for t, v in zip(s.time, s.value, strict=True):
            print(f"{t:12.6g} {v:14.6g}")
        did = True
    if args.energy:
        s = contacts.kinetic_energy_series(run)
        print(f"{'t [s]':>12} {'transl. [J]':>14} {'rot. [J]':>14} {'total [J]':>14}")
        for t, v in zip(s.time, s.value, strict=True):
            print(f"{t:12.6g} {v[0]:14.6g} {v[1]:14.6g} {v[2]:14.6g}")
        did = True
    if args.thermo:
        print(format_table(run.thermo) if run.thermo.get("time") is not None
              and len(run.thermo["time"]) else "no /thermo rows in this file")
        did = True
    if args.lacey is not None:
        o = _options(args.lacey, "lacey")
        cell = _num(o, "cell", None)
        if cell is None:
            raise ParameterError("--lacey needs cell=SIZE [m]")
        if "material" not in o and "below" not in o:
            raise ParameterError("--lacey needs material=K or below=ID for species A")
        mat, below = _num(o, "material", None, int), _num(o, "below", None, int)
        print(f"{'t [s]':>12} {'M':>8} {'cells':>6}")
        for k in range(run.n_frames):
            f = run.frame(k)
            is_a = f["material"] == mat if mat is not None else f["id"] < below
            lab = f["id"][is_a]
            r = mixing.lacey(f, lab, cell, min_count=_num(o, "min", 5, int))
            print(f"{f['time']:12.6g} {r['M']:8.4f} {r['cells']:6d}")
        did = True
    if args.coordination is not None:
        o = _options(args.coordination, "coordination")
        d = contacts.coordination_distribution(run, tol=_num(o, "tol", 1e-6),
                                               frame=_num(o, "frame", -1, int))
        print(f"coordination number: mean {d['mean']:.4g}; fraction with k contacts: "
              + ", ".join(f"{k}: {v:.3f}" for k, v in enumerate(d["fraction"]) if v > 0))
        did = True
    if args.drum is not None:
        o = _options(args.drum, "drum")
        if "radius" not in o or "axis" not in o:
            raise ParameterError("--drum needs radius=R and axis=X,Y,Z")
        point = _vec(o["point"], "point") if "point" in o else np.zeros(3)
        g = run.attrs.get("gravity", (0.0, 0.0, -9.81))
        ds = drum.drum_surface(run, point, _vec(o["axis"], "axis"), _num(o, "radius", 0.0),
                               frame=_num(o, "frame", -1, int),
                               method=o.get("method", "highest"),
                               gravity=g if np.linalg.norm(g) > 0 else (0.0, 0.0, -9.81))
        print(ds)
        did = True
    if args.picture is not None:
        from .picture import picture

        o = _options(args.picture, "picture")
        out = o.get("out", "frame.png")
        picture(run, frame=_num(o, "frame", -1, int), color=o.get("color", "speed"),
                view=o.get("view", "xz"), path=out)
        print(f"wrote {out}")
        did = True
    if not did:
        _summary(run)
    return 0
