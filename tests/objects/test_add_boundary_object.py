"""A boundary built already is added as it is (issue #56: `add_boundary(dpm.boundaries.
Tube(...))` was refused as "unknown boundary <... object at 0x...>")."""

from __future__ import annotations

import pytest

import dpm
from dpm.boundaries import Box


def test_a_built_boundary_is_added_as_it_is():
    sim = dpm.Simulation(dt=1e-5)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    box = Box(glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.01))
    assert sim.add_boundary(box) is box
    assert sim.boundaries == [box] and glass in sim.materials
    with pytest.raises(dpm.ParameterError, match="added already"):
        sim.add_boundary(box)
    other = Box(glass, lower=(0, 0, 0), upper=(0.02, 0.02, 0.02))
    with pytest.raises(dpm.ParameterError, match="built already.*given also: material, open"):
        sim.add_boundary(other, glass, open=("+z",))
    with pytest.raises(dpm.ParameterError, match="material is required"):
        sim.add_boundary("box", lower=(0, 0, 0), upper=(1, 1, 1))
    with pytest.raises(dpm.ParameterError, match="kind=5"):
        sim.add_boundary(5, glass)
