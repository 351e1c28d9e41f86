"""Residence time distributions and mass flow rates (through a plane, out of an outlet)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown
from ._common import Series, frames_of, is_run, is_sim, mass_of, unit


def removal_records(source: Any, outlet: int | None = None) -> dict[str, np.ndarray]:
    """The removal records (id, time, mass, residence_time, position, velocity, outlet) of
    a run (``run.removed``), a Simulation (``sim.outlets[k].records``, with ``outlet`` = k)
    or a dict of such arrays. ``outlet``: keep only that outlet's records; ``None``: all
    outlets (records of the escape guard, outlet -1, are left out)."""
    if is_run(source):
        rec = dict(source.removed)
    elif is_sim(source):
        parts = []
        for k, o in enumerate(source.outlets):
            r = dict(o.records)
            r["outlet"] = np.full(len(r["mass"]), k, "i4")
            parts.append(r)
        if not parts:
            return {"time": np.zeros(0), "mass": np.zeros(0), "residence_time": np.zeros(0),
                    "id": np.zeros(0, "i8"), "outlet": np.zeros(0, "i4")}
        rec = {k: np.concatenate([np.asarray(p[k]) for p in parts]) for k in parts[0]}
    elif isinstance(source, dict):
        rec = {k: np.asarray(v) for k, v in source.items()}
    else:
        raise ParameterError(f"expected a run, a Simulation or a dict of removal records, got "
                             f"{type(source).__name__}")
    if not rec or "time" not in rec:
        return {"time": np.zeros(0), "mass": np.zeros(0), "residence_time": np.zeros(0),
                "id": np.zeros(0, "i8"), "outlet": np.zeros(0, "i4")}
    if "outlet" in rec:
        keep = rec["outlet"] >= 0 if outlet is None else rec["outlet"] == outlet
        rec = {k: v[keep] for k, v in rec.items()}
    elif outlet not in (None, 0):
        raise ParameterError(f"outlet={outlet!r}: the records carry no outlet index")
    return rec


@dataclass
class ResidenceTimes:
    """A residence time distribution: ``samples`` (sorted) [s] with ``weights`` (summing to
    1: equal, or the mass fractions), ``mean`` = sum w t, ``variance`` = sum w (t - mean)^2,
    and :meth:`E` / :meth:`F` (Danckwerts 1953)."""

    samples: np.ndarray
    weights: np.ndarray
    mean: float
    variance: float

    def __len__(self) -> int:
        return len(self.samples)

    def F(self, t: Any) -> np.ndarray:
        """Cumulative distribution F(t): the (mass) fraction of the exit stream that stayed
        at most t (a right-continuous step function of the samples)."""
        c = np.concatenate([[0.0], np.cumsum(self.weights)])
        c /= max(c[-1], 1e-300)  # exactly 1 past the last sample
        return c[np.searchsorted(self.samples, np.asarray(t, float), side="right")]

    def E(self, bins: int | np.ndarray = 30, range: tuple[float, float] | None = None
          ) -> tuple[np.ndarray, np.ndarray]:
        """Density E(t) [1/s] as a histogram: ``(edges, density)``, integral 1."""
        if len(self.samples) == 0:
            return np.zeros(1), np.zeros(0)
        density, edges = np.histogram(self.samples, bins=bins, range=range,
                                      weights=self.weights, density=True)
        return edges, density

    def __str__(self) -> str:
        q = np.interp([0.1, 0.5, 0.9], np.cumsum(self.weights) if len(self) else [0],
                      self.samples if len(self) else [0])
        return (f"{len(self)} bodies: mean {self.mean:.6g} s, variance {self.variance:.6g} "
                f"s^2 (std {np.sqrt(self.variance):.6g} s), t10 {q[0]:.6g} s, "
                f"t50 {q[1]:.6g} s, t90 {q[2]:.6g} s")


def residence_times(source: Any, outlet: int | None = None, mass_weighted: bool = False
                    ) -> ResidenceTimes:
    """Residence time distribution of the bodies removed by outlets.

    The residence time of a body is the time from its insertion (its ``birth``) to its
    removal, as the outlet records it (``residence_time``). E(t) dt is the fraction of the
    exit stream that stayed between t and t + dt, F(t) = int_0^t E the fraction that stayed
    at most t; the mean residence time is int t E dt and the variance
    int (t - mean)^2 E dt (Danckwerts, P. V. 1953, "Continuous flow systems: distribution of
    residence times", Chem. Eng. Sci. 2, 1-13). With ``mass_weighted`` each body counts
    with its mass (a mass-flow RTD), otherwise each body counts once.

    ``source``: a run (``dpm.load``), a Simulation or a dict of removal records;
    ``outlet``: one outlet's index, or None for all outlets.
    """
    rec = removal_records(source, outlet)
    t = np.asarray(rec["residence_time"], float)
    w = np.asarray(rec["mass"], float) if mass_weighted else np.ones(len(t))
    order = np.argsort(t, kind="stable")
    t, w = t[order], w[order]
    total = float(w.sum())
    if total <= 0:
        return ResidenceTimes(t, w, float("nan"), float("nan"))
    w = w / total
    mean = float(np.sum(w * t))
    return ResidenceTimes(t, w, mean, float(np.sum(w * (t - mean) ** 2)))


def _bin(times: np.ndarray, mass: np.ndarray, bin_width: float, t0: float, t1: float
         ) -> Series:
    if not bin_width > 0:
        raise ParameterError(f"bin_width={shown(bin_width)} must be > 0 [s]")
    n = max(int(np.ceil((t1 - t0) / bin_width - 1e-9)), 1)
    edges = t0 + bin_width * np.arange(n + 1)
    total, _ = np.histogram(times, bins=edges, weights=mass)
    return Series(0.5 * (edges[1:] + edges[:-1]), total / bin_width, "kg/s")


def outlet_flow_rate(source: Any, bin_width: float, outlet: int | None = None,
                     start: float | None = None, stop: float | None = None) -> Series:
    """Mass flow rate [kg/s] out of the outlets against time: the mass of the removal
    records in each bin of ``bin_width`` seconds divided by the width (from ``start``,
    default 0, to ``stop``, default the end of the bin of the last removal). Resolution:
    an outlet removes every ``outlet.every`` seconds, so bins should hold several of its
    intervals."""
    rec = removal_records(source, outlet)
    t = np.asarray(rec["time"], float)
    t0 = 0.0 if start is None else float(start)
    if stop is None:  # through the bin holding the last removal
        last = float(t.max()) if len(t) else t0
        t1 = t0 + bin_width * (np.floor((last - t0) / bin_width) + 1)
    else:
        t1 = float(stop)
    if t1 <= t0:
        t1 = t0 + bin_width
    return _bin(t, np.asarray(rec["mass"], float), bin_width, t0, t1)


def plane_flow_rate(run: Any, point: Any, normal: Any, bin_width: float | None = None,
                    frames: Any = None) -> Series:
    """Signed mass flow rate [kg/s] through the plane through ``point`` with ``normal``.

    A body crosses between consecutive frames when the signed distance s = (x - p).n of
    its centre changes sign (from s < 0 to s >= 0: +m, the other way: -m; bodies present
    in both frames, matched by id). The rate is the mass crossed per interval: per frame
    interval (time: the interval's end) or, with ``bin_width``, summed into bins of that
    width (crossings at the interval's end time) divided by the width. A body that crosses
    twice between two frames is not seen, and a body moved by a periodic wrap counts as a
    crossing: frames must be closer in time than a body takes to travel its own size.
    ``run``: a run or a list of frame dicts (each with time, id, position, mass).
    """
    p, n = np.asarray(point, float).reshape(3), unit(normal, "normal")
    times, mass_crossed = [], []
    prev = None
    for f in frames_of(run, frames):
        ids = np.asarray(f["id"])
        s = (np.asarray(f["position"], float) - p) @ n
        m = mass_of(f, len(ids))
        if prev is not None:
            pid, ps, prev_t = prev
            _, ia, ib = np.intersect1d(pid, ids, assume_unique=True, return_indices=True)
            up = (ps[ia] < 0) & (s[ib] >= 0)
            down = (ps[ia] >= 0) & (s[ib] < 0)
            times.append((prev_t, float(f["time"])))
            mass_crossed.append(float(m[ib][up].sum() - m[ib][down].sum()))
        prev = (ids, s, float(f["time"]))
    if not times:
        return Series(np.zeros(0), np.zeros(0), "kg/s")
    t = np.asarray(times)
    dm = np.asarray(mass_crossed)
    if bin_width is None:
        return Series(t[:, 1], dm / (t[:, 1] - t[:, 0]), "kg/s")
    return _bin(t[:, 1] - 1e-12 * max(abs(t[-1, 1]), 1.0), dm, bin_width, float(t[0, 0]),
                float(t[-1, 1]))



def beverloo(bulk_density: float, orifice: float, particle_diameter: float,
             g: float = 9.81, C: float = 0.58, k: float = 1.5) -> float:
    """The mass flow rate [kg/s] out of a flat-bottomed silo through a circular orifice
    by Beverloo's correlation, to compare a measured :func:`outlet_flow_rate` with:
    W = C rho_b sqrt(g) (D - k d)^(5/2), rho_b the bulk density, D the orifice diameter,
    d the particle diameter (Beverloo, W. A., Leniger, H. A., van de Velde, J. 1961, "The
    flow of granular solids through orifices", Chem. Eng. Sci. 15, 260-269; C ~ 0.55-0.65,
    k ~ 1.5 typical). Zero when the orifice is narrower than k d."""
    for name, v in (("bulk_density", bulk_density), ("orifice", orifice),
                    ("particle_diameter", particle_diameter), ("g", g)):
        if not v > 0:
            raise ParameterError(f"beverloo(): {name}={shown(v)} must be > 0")
    return float(C * bulk_density * np.sqrt(g) * max(orifice - k * particle_diameter, 0.0)
                 ** 2.5)


def fit_beverloo(orifices: Any, rates: Any, particle_diameter: float, bulk_density: float,
                 g: float = 9.81) -> tuple[float, float]:
    """(C, k) of Beverloo's correlation W = C rho_b sqrt(g) (D - k d)^(5/2) fitted to
    measured rates W [kg/s] at orifice diameters D [m] (at least two): W^(2/5) is linear in
    D, W^(2/5) = s (D - k d) with s = (C rho_b sqrt(g))^(2/5), so a least-squares line
    through (D, W^(2/5)) gives C = s^(5/2) / (rho_b sqrt(g)) and k = -intercept / (s d)
    (the usual way of fitting it; Nedderman 1992, Statics and Kinematics of Granular
    Materials, ch. 10)."""
    D = np.asarray(orifices, float).reshape(-1)
    W = np.asarray(rates, float).reshape(-1)
    if D.shape != W.shape or len(D) < 2:
        raise ParameterError(f"fit_beverloo(): give at least two orifices with one rate each "
                             f"(got {len(D)} orifices, {len(W)} rates)")
    if not np.all(W > 0) or not np.all(D > 0):
        raise ParameterError(f"fit_beverloo(): orifices {D.tolist()} and rates {W.tolist()} "
                             "must be > 0")
    for name, v in (("particle_diameter", particle_diameter), ("bulk_density", bulk_density),
                    ("g", g)):
        if not v > 0:
            raise ParameterError(f"fit_beverloo(): {name}={shown(v)} must be > 0")
    s, intercept = np.polyfit(D, W ** 0.4, 1)
    if not s > 0:
        raise ParameterError(f"fit_beverloo(): the rates {W.tolist()} do not grow with the "
                             f"orifice {D.tolist()}: no Beverloo fit")
    C = s ** 2.5 / (bulk_density * np.sqrt(g))
    return float(C), float(-intercept / (s * particle_diameter))
