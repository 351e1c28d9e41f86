"""Coordination numbers, force and overlap distributions, kinetic energy and the energy
balance."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..measures import kinetic_energy as _kinetic_energy
from ._common import Series, as_frame, frames_of, is_sim, mass_of, radius_of


def coordination_numbers(source: Any, tol: float = 1e-6, frame: int = -1) -> np.ndarray:
    """Contacts of each body: the pairs whose centres are closer than (r_i + r_j)(1 + tol)
    (found with a k-d tree, ``scipy.spatial.cKDTree``). Spheres only (clustered bodies are
    taken as their bounding sphere); periodic images are not searched. The mean
    coordination number Z = 2 (pairs) / N is a classic measure of a packing's
    mechanical state (e.g. Z = 6 on a simple-cubic lattice, 12 on a close packing;
    Bernal & Mason 1960, Nature 188, 910-911)."""
    from scipy.spatial import cKDTree

    f = as_frame(source, frame)
    x = np.asarray(f["position"], float)
    n = len(x)
    r = radius_of(f, n)
    out = np.zeros(n, np.int64)
    if n < 2:
        return out
    pairs = cKDTree(x).query_pairs(2.0 * float(r.max()) * (1 + tol), output_type="ndarray")
    if len(pairs) == 0:
        return out
    i, j = pairs[:, 0], pairs[:, 1]
    d = np.linalg.norm(x[i] - x[j], axis=1)
    touch = d < (r[i] + r[j]) * (1 + tol)
    return np.bincount(np.concatenate([i[touch], j[touch]]), minlength=n)


def coordination_distribution(source: Any, tol: float = 1e-6, frame: int = -1
                              ) -> dict[str, Any]:
    """The distribution of :func:`coordination_numbers`: ``mean`` Z and ``fraction[k]``,
    the fraction of bodies with k contacts."""
    z = coordination_numbers(source, tol, frame)
    frac = np.bincount(z) / max(len(z), 1) if len(z) else np.zeros(1)
    return {"mean": float(z.mean()) if len(z) else float("nan"), "fraction": frac}


def force_distribution(source: Any, bins: int = 30, subtract_gravity: bool = True
                       ) -> dict[str, np.ndarray]:
    """Distribution of the body force magnitudes ``|F| / <|F|>`` of a live Simulation (or of a
    namespace with ``force``, ``mass``): the net contact force on each body (the force sum
    less m g with ``subtract_gravity``; the gravity of the simulation). This is not the
    distribution of single contact forces (those are :func:`dpm.io.contacts.pair_forces`
    of a live Simulation, or ``run.contacts(k)`` of a run written with ``contacts=True``):
    it is a proxy with the same exponential-like tail in a static packing (the single-contact
    distribution P(f) ~ exp(-beta f) is that of Mueth, Jaeger & Nagel 1998, Phys. Rev. E
    57, 3164; Radjai et al. 1996, Phys. Rev. Lett. 77, 274). Returns ``edges``,
    ``density`` (of the normalised force), ``mean`` [N] and ``values`` (normalised)."""
    b = source.bodies if is_sim(source) else source
    force = np.asarray(b.force, float)
    if subtract_gravity and is_sim(source):
        force = force - np.asarray(b.mass, float)[:, None] * np.asarray(source.gravity)
    mag = np.linalg.norm(force, axis=1)
    mean = float(mag.mean()) if len(mag) else float("nan")
    if not mean > 0:
        return {"edges": np.zeros(1), "density": np.zeros(0), "mean": mean,
                "values": np.zeros(0)}
    vals = mag / mean
    density, edges = np.histogram(vals, bins=bins, density=True)
    return {"edges": edges, "density": density, "mean": np.asarray(mean), "values": vals}


def overlap_distribution(sim: Any, bins: int = 30) -> dict[str, np.ndarray]:
    """Distribution of the overlaps / smaller radius of the touching particle pairs of a
    live Simulation (``sim.backend.pair_overlaps()``; particle-boundary entries are left
    out). For a Hertz law the normal force goes as overlap^1.5, so this is the force
    distribution seen through the law. Returns ``edges``, ``density``, ``values``."""
    ov = np.asarray(sim.backend.pair_overlaps(), float)
    ov = ov[ov > 0]
    if len(ov) == 0:
        return {"edges": np.zeros(1), "density": np.zeros(0), "values": ov}
    density, edges = np.histogram(ov, bins=bins, density=True)
    return {"edges": edges, "density": density, "values": ov}


def kinetic_energy(source: Any, frame: int = -1) -> dict[str, float]:
    """Translational (sum 1/2 m v.v) and rotational (sum 1/2 I_k w_k^2, body frame)
    kinetic energy [J] of one frame, with ``total``, through
    :func:`dpm.measures.kinetic_energy`. The HDF5 frame stores no inertia: it is taken as
    that of a solid sphere, I = 2/5 m r^2 (exact for spheres; for clustered bodies the
    bounding radius makes it an estimate). A Simulation's own inertia is used."""
    f = as_frame(source, frame)
    n = len(f["position"])
    m = mass_of(f, n)
    v = np.asarray(f.get("velocity", np.zeros((n, 3))), float)
    w = np.asarray(f.get("angular_velocity", np.zeros((n, 3))), float)
    q = np.asarray(f.get("orientation", np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))), float)
    if "inertia" in f:
        inertia = np.asarray(f["inertia"], float)
    else:
        inertia = np.repeat((0.4 * m * radius_of(f, n) ** 2)[:, None], 3, axis=1)
    trans = 0.5 * float(np.sum(m * np.einsum("ij,ij->i", v, v)))
    total = _kinetic_energy(SimpleNamespace(mass=m, velocity=v, orientation=q,
                                            angular_velocity=w, inertia=inertia))
    return {"translational": trans, "rotational": total - trans, "total": total}


def kinetic_energy_series(source: Any, frames: Any = None) -> Series:
    """:func:`kinetic_energy` of every frame: value columns translational, rotational,
    total [J]."""
    t, e = [], []
    for f in frames_of(source, frames):
        k = kinetic_energy(f)
        t.append(float(f.get("time", len(t))))
        e.append((k["translational"], k["rotational"], k["total"]))
    return Series(np.asarray(t), np.asarray(e).reshape(-1, 3), "J")


def energy_balance(sim: Any) -> dict[str, Any]:
    """The energy book of a live Simulation (``sim.energy.balance(sim)``: initial, work
    done by the boundaries, inserted, removed, current mechanical energy, dissipated
    D = initial + work + inserted - removed - current [J]) with the kinetic energies
    (``translational``, ``rotational``) and the work of each boundary
    (``boundary_work``, ``bd.work`` [J], in the order of ``sim.boundaries``)."""
    if not is_sim(sim):
        raise ParameterError("energy_balance() needs a live Simulation; a run file has the "
                             "/thermo table (dpm.analysis.Thermo) instead")
    out: dict[str, Any] = dict(sim.energy.balance(sim))
    k = kinetic_energy(sim)
    out["translational"], out["rotational"] = k["translational"], k["rotational"]
    out["boundary_work"] = [float(bd.work) for bd in sim.boundaries]
    return out
