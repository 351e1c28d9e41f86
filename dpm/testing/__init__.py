"""Contract suites for plugin authors: check a new impact model, shape or boundary against
independent references before anyone runs a scene with it.

Each suite is a pytest class to subclass (its checks are ``test_*`` methods, so pytest
collects them in the subclass) and a plain function that raises :class:`ContractError`
(an ``AssertionError``) with what failed, by how much, and the tolerance::

    import dpm.testing

    class TestMyModel(dpm.testing.ImpactModelContract):
        model = "my_model"                      # registered name (or the class)
        params = {"stiffness": 500.0, "restitution": 0.6, "friction": 0.4}

    class TestPebble(dpm.testing.ShapeContract):
        shape = "pebble"
        params = {"radius": 1e-3}
        def inside(self, points):               # the ideal solid, in the shape frame
            return np.linalg.norm(points, axis=1) <= 1e-3

    class TestFunnel(dpm.testing.BoundaryContract):
        boundary = "funnel"
        params = {...}
        def surface(self):                      # dense points on its surface, and spacing
            return points, spacing

The checks and their references:

* impact model (:mod:`dpm.testing.impact`): no force without overlap (the law itself at
  zero and vanishing overlap, and a real two-sphere run before the spheres touch);
  momentum conserved in an oblique two-sphere impact with spin (to round-off, a bound
  stated in the check); head-on restitution measured in a real two-sphere dpm run equal
  to the model's stated restitution within ``restitution_tolerance``;
* shape (:mod:`dpm.testing.shape`): mass, centre of mass and inertia tensor against a
  Monte-Carlo sampled volume of the solid (tolerances of 5 standard errors of the
  estimate, from the sample count), and every element inside the solid;
* boundary (:mod:`dpm.testing.boundary`): the contact distance and normal that the
  engine's geometry functions give, against the nearest of dense surface points.

The methods whose name contains ``engine`` run a real simulation (one compiled step
module per law set, 30-120 s when the numba cache is cold); the others take seconds.
"""

from .boundary import BoundaryContract, check_boundary
from .errors import ContractError
from .impact import (
    ImpactModelContract,
    check_momentum,
    check_no_force_without_overlap,
    check_restitution,
)
from .shape import ShapeContract, check_shape

__all__ = [
    "BoundaryContract",
    "ContractError",
    "ImpactModelContract",
    "ShapeContract",
    "check_boundary",
    "check_momentum",
    "check_no_force_without_overlap",
    "check_restitution",
    "check_shape",
]
