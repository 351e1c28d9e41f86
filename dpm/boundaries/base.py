"""Base class of boundaries."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..kernels.boundary_geometry import PAR_WIDTH, PLANE
from ..material import Material
from ..parameters import Parameter, declared_repr, validate


@dataclass
class Primitives:
    """A boundary's contact geometry for the kernels, in its own frame (the world frame at
    t = 0): ``kind`` (n,), ``par`` (n, PAR_WIDTH) as in :mod:`dpm.kernels.boundary_geometry`,
    ``ids`` (n, 4) triangle vertex ids and feature flags, ``lower``/``upper`` (n, 3) each
    primitive's bounding box (inf where unbounded), ``extent`` the largest distance of the
    geometry from the origin (inf if unbounded)."""

    kind: np.ndarray
    par: np.ndarray
    ids: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    extent: float

    @classmethod
    def build(cls, rows: list[tuple[int, list[float], tuple[np.ndarray, np.ndarray]]],
              ids: np.ndarray | None = None) -> Primitives:
        """From (kind, par values, (lower, upper)) rows."""
        n = len(rows)
        par = np.zeros((n, PAR_WIDTH))
        kind = np.zeros(n, np.int64)
        lower = np.zeros((n, 3))
        upper = np.zeros((n, 3))
        for k, (kd, values, (lo, hi)) in enumerate(rows):
            kind[k] = kd
            par[k, :len(values)] = values
            lower[k] = lo
            upper[k] = hi
        corners = np.concatenate([lower, upper]) if n else np.zeros((1, 3))
        extent = float(np.max(np.linalg.norm(corners, axis=1)))
        return cls(kind, par, np.zeros((n, 4), np.int64) if ids is None else ids, lower,
                   upper, extent if np.isfinite(extent) else math.inf)


class Boundary:
    """A boundary: subclass, declare ``parameters``, and give its contact geometry.

    A boundary is made of primitives (planes, finite walls, surfaces of revolution, torus
    segments, triangles, sieve plates; :mod:`dpm.kernels.boundary_geometry`) returned by
    :meth:`primitives` in the boundary's own frame, which is the world frame at t = 0 and
    then moves by the boundary's ``motion`` (:mod:`dpm.motion`). A boundary made only of
    one-sided planes may return them from :meth:`planes` instead.

    ``force`` [N] and ``torque`` [N m] are the total contact force and torque that the
    particles exert on it in the last step; the torque is taken about ``torque_point``
    (the motion's pivot, e.g. a drum's axis; the origin if the motion has none), so that
    ``power()`` = torque . omega + force . v gives the drive's power draw.
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = {}
    #: whether open ends of this boundary can be joined to another piece's (then give
    #: :meth:`pipe_ends`; :func:`dpm.boundaries.joints.join_pipe_ends` fills ``joined``)
    joinable_ends: ClassVar[bool] = False
    #: False while switched off (:meth:`dpm.Simulation.switch_off`, :mod:`dpm.switches`)
    enabled: bool = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        # help(), inspect.signature and the docs list the declared parameters (with units
        # and ranges in the docstring) though __init__ takes them as **params
        super().__init_subclass__(**kwargs)
        from ..motion import Motion
        from .signature import document, keyword

        document(cls, leading=(keyword("material", ann=Material, positional=True),
                               keyword("call", None, str | None, positional=True)),
                 trailing=(keyword("motion", None, Motion | None),),
                 extra=(("material", "Material", "the boundary's material (required)"),
                        ("motion", "Motion or None", "prescribed motion of its frame "
                         "(dpm.Rotation, dpm.Oscillation, ...; default None: at rest)"),
                        ("call", "str or None", "the call named in error messages")))

    def __init__(self, material: Material, call: str | None = None, motion: Any = None,
                 **params: Any) -> None:
        call = call or f"{type(self).__name__}()"
        if not isinstance(material, Material):
            from ..errors import ParameterError

            raise ParameterError(f"{call}: material={material!r} must be a dpm.Material")
        if motion is not None:
            from ..motion import Motion

            if not isinstance(motion, Motion):
                from ..errors import ParameterError

                raise ParameterError(f"{call}: motion={motion!r} must be a dpm.Motion "
                                     "(dpm.Rotation, dpm.Oscillation, ...)")
        self.material = material
        self.motion = motion
        self.params = validate(call, self.parameters, params)
        self.force = np.zeros(3)
        self.torque = np.zeros(3)
        #: velocity of the frame origin and angular velocity at the last step (for power)
        self.velocity = np.zeros(3)
        self.angular_velocity = np.zeros(3)
        #: simulated time [s] of the load above
        self.load_time = 0.0
        #: work [J] the boundary has done on the particles since the first step (its
        #: drive's energy input; 0 for a boundary at rest)
        self.work = 0.0

    def __repr__(self) -> str:
        """``Tube(material='steel', length=1, radius=0.05, motion=Rotation(...))``: the
        material's name, the declared parameters given (required ones and those that
        differ from their default) and the motion."""
        material = getattr(self, "material", None)
        lead = [f"material={material.name!r}"] if isinstance(material, Material) else []
        motion = getattr(self, "motion", None)
        trail = [f"motion={motion!r}"] if motion is not None else []
        if not getattr(self, "enabled", True):
            trail.append("enabled=False")
        return declared_repr(type(self).__name__, self.parameters,
                             getattr(self, "params", {}), lead, trail)

    def record_load(self, time: float, force: np.ndarray, torque: np.ndarray,
                    velocity: np.ndarray, angular_velocity: np.ndarray) -> None:
        """Store the load of the last step (the run loop calls it after each kernel call):
        force [N] and torque about :attr:`torque_point` [N m] that the particles exert,
        the frame's origin velocity and angular velocity, at simulated time ``time``."""
        self.load_time = float(time)
        self.force = force
        self.torque = torque
        self.velocity = velocity
        self.angular_velocity = angular_velocity

    @property
    def torque_point(self) -> np.ndarray:
        p = getattr(self.motion, "pivot", None)
        return np.zeros(3) if p is None else np.asarray(p, float)

    def power(self) -> float:
        """Power [W] the particles draw from the boundary's drive in the last step
        (-(F . v_pivot + T . omega): positive when the drive works on the particles)."""
        from ..motion import frames

        t = self.load_time
        if self.motion is None:
            return 0.0
        fr = frames(self.motion, np.array([t]))[0]
        v_pivot = fr[12:15] + np.cross(fr[15:18], self.torque_point - fr[0:3])
        return -float(self.force @ v_pivot + self.torque @ fr[15:18])

    def pipe_ends(self) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """(name, centre, outward unit axis, radius) of each open end that can be joined
        (boundaries with ``joinable_ends``); none by default."""
        return []

    def volume(self) -> float:
        """Volume of the boundary's material [m3] (0 for infinitely thin or unbounded
        boundaries). Boundaries move by prescribed motions, so they need no inertia."""
        return 0.0

    def primitives(self) -> Primitives:
        """The contact geometry in the boundary's frame (default: :meth:`planes`)."""
        pts, nrm = self.planes()
        rows = [(PLANE, [*p, *n], (np.full(3, -np.inf), np.full(3, np.inf)))
                for p, n in zip(pts, nrm, strict=True)]
        return Primitives.build(rows)

    def planes(self) -> tuple[np.ndarray, np.ndarray]:
        """(points (k, 3), unit normals (k, 3)) of the planes, normals into the domain."""
        return np.zeros((0, 3)), np.zeros((0, 3))

    def outside(self, position: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """Mask of particles whose centre lies on the wrong side of this boundary (planes:
        behind one; boundaries touched from both sides: none)."""
        pts, nrm = self.planes()
        if len(pts) == 0:
            return np.zeros(len(position), bool)
        d = np.einsum("nkj,kj->nk", position[:, None, :] - pts[None], nrm)
        return np.any(d < 0.0, axis=1)
