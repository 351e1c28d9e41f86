"""Plausibility warnings before the first step: a scene that runs, but not as meant.

The scene check (:func:`dpm.scene_check.validate_scene`) refuses what cannot run; this
module warns (``UserWarning``, once per scene and problem) about what runs but is most
likely a slip of units or of a centre, each warning naming the value, what real scenes
have and the fix:

- a material of the scene (of a particle, of what an inlet brings, of a boundary) with
  Young's modulus below :data:`MIN_YOUNG` Pa: a modulus typed in GPa (``young=70`` for
  70 GPa is 70 Pa);
- a triangle mesh (:class:`dpm.boundaries.Mesh`) more than :data:`MESH_TOO_LARGE` times
  the largest particle's diameter across (a CAD file in mm read as m: ``scale=1e-3``
  missing) or smaller than :data:`MESH_TOO_SMALL` of it across (``scale=1e-3`` on a file
  in m);
- a :class:`dpm.Tube` turned by a :class:`dpm.Rotation` whose axis line does not meet the
  tube's own axis line (it lies more than :data:`ORBIT_TOLERANCE` of the tube's radius
  from it): the tube orbits that axis instead of turning in place (a drum's ``center``
  off its axis);
- a sphere, or an element of a cluster, larger than the box or tube it sits in (its
  diameter above the box's smallest inner size, or the tube's largest inner diameter, by
  more than the scene's ``overlap_tolerance`` allows: a sphere squeezed between two walls
  within the tolerance is meant), or an inlet bringing such spheres into one: a radius in
  mm read as m.

Each check is made so that the examples and the test scenes never meet it: a warning
that cries wolf is worse than none.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Hashable
from typing import Any

import numpy as np

from .errors import DpmError

#: Young's modulus [Pa] below which a material is taken for a modulus in the wrong unit:
#: the softest solids a granular scene holds (rubber 1e6 Pa, foams 1e5 Pa) and the
#: softened moduli DEM uses (down to 5e4 Pa: examples/grate.py's wood, Table 4.2 of its
#: source) lie above it; a modulus typed in GPa (0.01 to 1000 for real solids) below
MIN_YOUNG = 1e4
#: a mesh whose bounding box's largest side exceeds this many times the largest particle's
#: diameter is taken for a file in mm read as m (a drum 0.3 m across holding 4 mm beads
#: is 75 diameters across; the same drum read from mm, 75 000); the repository's examples
#: and tests reach 300
MESH_TOO_LARGE = 1e4
#: a mesh whose bounding box's largest side is below this fraction of the largest
#: particle's diameter is taken for a file scaled twice (``scale=1e-3`` on one in m: the
#: 0.3 m drum becomes 0.3 mm, 1/13 of a 4 mm bead); the examples' and tests' meshes are 2
#: diameters across at the least
MESH_TOO_SMALL = 0.1
#: a rotation's axis line farther than this fraction of a tube's radius from the tube's
#: axis line makes the tube orbit (1 % of the radius: more than rounding, less than any
#: drum built off its axis by a slip)
ORBIT_TOLERANCE = 1e-2
#: points sampled from each inlet region to find the containers it fills
_SAMPLES = 256

#: (scene, the keys of the problems already warned about): once per scene and problem
_WARNED: weakref.WeakKeyDictionary[Any, set[Hashable]] = weakref.WeakKeyDictionary()


def _length(x: float) -> str:
    """A length for a message, in the unit that reads best (m, mm or um)."""
    ax = abs(x)
    if ax != 0.0 and ax < 1e-3:
        return f"{x * 1e6:.3g} um"
    if ax != 0.0 and ax < 1.0:
        return f"{x * 1e3:.3g} mm"
    return f"{x:.3g} m"


def _boundary_label(k: int, bd: Any) -> str:
    file = getattr(bd, "params", {}).get("file")
    return f"boundary {k} ({bd.name}" + (f", file={str(file)!r})" if file else ")")


def young_problems(sim: Any) -> list[tuple[Hashable, str]]:
    """Materials of the scene's particles, inlets and boundaries softer than
    :data:`MIN_YOUNG`."""
    from .scene_check import material_counts

    used = [sim.materials[k] for k in sorted(material_counts(sim))]
    for bd in sim.boundaries:
        if all(bd.material is not m for m in used):
            used.append(bd.material)
    out = []
    for m in used:
        e = m.young
        if e is None or not e < MIN_YOUNG:
            continue
        # (no solid is stiffer than diamond, 1.2e12 Pa: above 1200 the number was MPa)
        unit, power = ("GPa", 9) if e <= 1200.0 else ("MPa", 6)
        out.append((("young", m.name), (
            f"Material({m.name!r}): young={e:g} Pa is softer than any solid: real "
            "materials range from about 1e6 Pa (rubber) over 1e9 Pa (plastics) to 5e10 to "
            "4e11 Pa (glass, metals), and softened DEM materials stay above "
            f"{MIN_YOUNG:g} Pa. young is in Pa: did you mean {e:g}e{power} ({unit})? Give "
            f"young={e:g}e{power} for {e:g} {unit}.")))
    return out


def largest_diameter(sim: Any) -> float:
    """The largest body's diameter [m] (bounding sphere) among the bodies present and
    those the inlets bring; 0 if none."""
    d = 2.0 * float(np.max(sim.bodies.radius, initial=0.0))
    for inlet in sim.inlets:
        try:
            d = max(d, 2.0 * float(inlet.largest_radius()))
        except DpmError:  # (the scene check names the inlet's problem)
            continue
    return d


def mesh_problems(sim: Any) -> list[tuple[Hashable, str]]:
    """Meshes far larger or far smaller than the particles (:data:`MESH_TOO_LARGE`,
    :data:`MESH_TOO_SMALL`)."""
    from .boundaries.mesh import Mesh

    meshes = [(k, bd) for k, bd in enumerate(sim.boundaries)
              if isinstance(bd, Mesh) and len(bd.vertices)]
    if not meshes:
        return []
    d = largest_diameter(sim)
    if not d > 0.0:
        return []
    out = []
    for k, bd in meshes:
        size = float(np.max(np.ptp(bd.vertices, axis=0)))
        scale = float(bd.params["scale"])
        ratio = size / d
        what = (f"{_boundary_label(k, bd)}: the mesh is {_length(size)} across (scale="
                f"{scale:g}), ")
        if ratio > MESH_TOO_LARGE:
            out.append((("mesh", k), what + (
                f"{ratio:.3g} times the largest particle's diameter ({_length(d)}; real "
                f"scenes stay below {MESH_TOO_LARGE:g} times): a file in mm read as m? "
                f"Give scale={scale * 1e-3:g} for a mesh in mm (scale=1e-3: mm to m, "
                "1e-2: cm to m).")))
        elif ratio < MESH_TOO_SMALL:
            out.append((("mesh", k), what + (
                f"1/{1.0 / ratio:.3g} of the largest particle's diameter ({_length(d)}): a "
                f"mesh scaled twice, or particle sizes not in m? Give scale={scale * 1e3:g} "
                "if the mesh is in m already (scale=1e-3 is for a file in mm), and radii "
                "in m.")))
    return out


def _point_line_distance(p: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> float:
    d = p - origin
    return float(np.linalg.norm(d - (d @ axis) * axis))


def _line_distance(p1: np.ndarray, a1: np.ndarray, p2: np.ndarray, a2: np.ndarray) -> float:
    """Shortest distance between the lines p1 + s a1 and p2 + t a2 (unit a1, a2)."""
    n = np.cross(a1, a2)
    nn = float(np.linalg.norm(n))
    if nn < 1e-9:  # parallel
        return _point_line_distance(p2, p1, a1)
    return abs(float((p2 - p1) @ n)) / nn


def orbit_problems(sim: Any) -> list[tuple[Hashable, str]]:
    """Tubes turned by a :class:`~dpm.motion.Rotation` about an axis line that misses the
    tube's own axis line (by more than :data:`ORBIT_TOLERANCE` of its radius)."""
    from .boundaries.tube import Tube
    from .motion import Rotation

    out = []
    for k, bd in enumerate(sim.boundaries):
        rot = bd.motion
        if not isinstance(bd, Tube) or not isinstance(rot, Rotation):
            continue
        radius = max(bd.r0, bd.r1)
        axis, centre = np.asarray(rot.axis, float), np.asarray(rot.pivot, float)
        gap = _line_distance(bd.start, bd.axis, centre, axis)
        if not gap > ORBIT_TOLERANCE * radius:
            continue
        parallel = abs(float(axis @ bd.axis)) > 1.0 - 1e-9
        on_axis = bd.start + ((centre - bd.start) @ bd.axis) * bd.axis
        fix = (f"center={_vector(on_axis)} (on the tube's axis)" if parallel
               else f"center={_vector(bd.start)} (the tube's start) and axis="
                    f"{_vector(bd.axis)}")
        out.append((("orbit", k), (
            f"{_boundary_label(k, bd)}: its Rotation turns it about an axis "
            f"{_vector(axis)} through {_vector(centre)}, which passes {_length(gap)} from "
            f"the tube's own axis (radius {_length(radius)}): the tube orbits that axis "
            f"instead of turning in place. Give the Rotation {fix}, or ignore this if the "
            "tube is meant to orbit.")))
    return out


def _vector(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{float(x):.6g}" for x in v) + ")"


def _containers(sim: Any) -> list[tuple[int, Any, float, str, Any]]:
    """(index, boundary, smallest inner size [m], what that size is, a function giving the
    mask of world points inside) of the boxes and tubes of the scene (a moving one where
    its motion has it now)."""
    from .boundaries.box import Box
    from .boundaries.tube import Tube
    from .motion import frames

    out = []
    for k, bd in enumerate(sim.boundaries):
        if not bd.enabled or not isinstance(bd, Box | Tube):
            continue
        if isinstance(bd, Box):
            closed = [d for d in range(3)
                      if f"-{'xyz'[d]}" in bd.faces and f"+{'xyz'[d]}" in bd.faces]
            if not closed:
                continue
            sizes = {d: float(bd.upper[d] - bd.lower[d]) for d in closed}
            axis = min(sizes, key=sizes.get)
            size, what = sizes[axis], f"its {'xyz'[axis]} side"

            def inside_own(p, bd=bd, closed=closed):
                return np.all((p[:, closed] > bd.lower[closed])
                              & (p[:, closed] < bd.upper[closed]), axis=1)
        else:
            size, what = 2.0 * (max(bd.r0, bd.r1) - bd.h), "its inner diameter"
            if bd.caps == "both" and bd.length - 2.0 * bd.h < size:
                size, what = bd.length - 2.0 * bd.h, "its inner length (both ends capped)"
            inside_own = bd.inside
        pose = None
        if bd.motion is not None:
            pose = frames(bd.motion, np.array([float(sim.time)]))[0]

        def inside(p, inside_own=inside_own, pose=pose):
            p = np.asarray(p, float).reshape(-1, 3)
            if pose is not None:  # world to the boundary's own frame: R^T (x - o)
                p = (p - pose[0:3]) @ pose[3:12].reshape(3, 3)
            return inside_own(p)

        out.append((k, bd, size, what, inside))
    return out


def _inlet_sphere_radius(inlet: Any) -> float:
    """The largest sphere an inlet brings (0 if its mix has other shapes only)."""
    r = 0.0
    for (cls, _low, high), f in zip(inlet.resolved, inlet.fractions, strict=True):
        if f > 0 and getattr(cls, "name", "") == "sphere" and "radius" in high:
            value = getattr(high["radius"], "high", high["radius"])
            r = max(r, float(np.max(value)))
    return r


def fit_problems(sim: Any) -> list[tuple[Hashable, str]]:
    """Spheres (and elements of clusters) larger than the box or tube their centre lies
    in, and inlets that bring such spheres into one."""
    conts = _containers(sim)
    if not conts:
        return []
    b, e = sim.bodies, sim.elements
    element_r = np.zeros(len(b))
    if len(e) and len(b):
        np.maximum.at(element_r, e.owner, e.radius)
    pos = np.asarray(b.position, float)
    finite = np.all(np.isfinite(pos), axis=1)
    inlet_r = [_inlet_sphere_radius(inlet) for inlet in sim.inlets]
    samples: dict[int, np.ndarray] = {}

    def sample(n: int) -> np.ndarray:
        """Points of inlet n's region (none where its region cannot be sampled)."""
        if n not in samples:
            rng = np.random.default_rng(n)
            try:
                pts = sim.inlets[n].region.sample(rng, _SAMPLES, np.zeros(_SAMPLES))
                samples[n] = np.asarray(pts, float).reshape(-1, 3)
            except (NotImplementedError, DpmError, ValueError):
                samples[n] = np.zeros((0, 3))
        return samples[n]

    # a sphere between two walls overlaps one of them by more than the tolerance allows
    # (of its radius) when d (1 - tol) > size: the scene check refuses it then; one
    # squeezed within the tolerance is meant
    fits = 1.0 - min(float(sim.overlap_tolerance), 0.5)
    out = []
    for k, bd, size, what, inside in conts:
        if not size > 0.0:
            continue
        label = _boundary_label(k, bd)
        big = finite & (2.0 * element_r * fits > size)
        if np.any(big):
            big[big] = inside(pos[big])
        if np.any(big):
            from .scene_check import few

            d = 2.0 * float(element_r[big].max())
            out.append((("fit", k), (
                f"{int(big.sum())} particle(s) lie in {label} but are larger than it: "
                f"diameter up to {_length(d)} (id(s) {few(b.id[big])}) against {what} of "
                f"{_length(size)}; they cannot fit. Are the sizes in m? (radius=2 is 2 m; "
                "2 mm is radius=2e-3)")))
        for n, r in enumerate(inlet_r):
            if 2.0 * r * fits > size and np.any(inside(sample(n))):
                out.append((("fit-inlet", n, k), (
                    f"inlet {n} brings spheres up to {_length(2.0 * r)} across into "
                    f"{label}, against {what} of {_length(size)}; they cannot fit. Are the "
                    "sizes in m? (radius=2 is 2 m; 2 mm is radius=2e-3)")))
    return out


def plausibility_problems(sim: Any) -> list[tuple[Hashable, str]]:
    """(key, sentence) of every plausibility problem of the scene as it is now."""
    return (young_problems(sim) + mesh_problems(sim) + orbit_problems(sim)
            + fit_problems(sim))


def warn_plausibility(sim: Any, stacklevel: int = 2) -> list[str]:
    """Issue a ``UserWarning`` for each plausibility problem of ``sim`` not warned about
    before for this scene; return the sentences issued. ``stacklevel`` as for
    :func:`warnings.warn`, counted from the caller of this function (1: that caller)."""
    try:
        seen = _WARNED.setdefault(sim, set())
    except TypeError:  # (a scene that cannot be weakly referenced: warn every time)
        seen = set()
    issued = []
    for key, message in plausibility_problems(sim):
        if key in seen:
            continue
        seen.add(key)
        warnings.warn(message, UserWarning, stacklevel=stacklevel + 1)
        issued.append(message)
    return issued


__all__ = ["MESH_TOO_LARGE", "MESH_TOO_SMALL", "MIN_YOUNG", "ORBIT_TOLERANCE",
           "plausibility_problems", "warn_plausibility"]
