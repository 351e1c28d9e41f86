"""Pictures of every built-in boundary kind, drawn from dpm's own geometry: each
boundary is built as ``sim.add_boundary`` builds it and triangulated by
:func:`dpm.io.surfaces.boundary_surface` (the triangles the XDMF output shows in
ParaView), then rendered offscreen with VTK.

    python docs/render/boundaries.py            # writes docs/images/boundaries/*.png
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

import dpm
from dpm.io.surfaces import boundary_surface
from dpm.plugins import registry

sys.path.insert(0, str(Path(__file__).parent))
from vtkscene import caption, polydata, render, spheres_actor, surface_actor  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "images" / "boundaries"
STEEL = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)

# a closed mesh: an octahedron (a hopper insert or an obstacle)
_OCTA_V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                   float) * 0.03
_OCTA_F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5],
                    [3, 1, 5], [0, 3, 5]])

#: (file name, kind, parameters, caption, extent of a plane's square, view direction)
CASES = [
    ("plane", "plane", dict(point=(0, 0, 0), normal=(0, 0, 1)),
     "plane: infinite, one-sided (drawn as a square)", 0.05, (1.0, -1.5, 1.0)),
    ("box", "box", dict(lower=(-0.03, -0.02, 0), upper=(0.03, 0.02, 0.04), open=("+z",)),
     "box with open=('+z',)", 0.05, (1.0, -1.6, 1.2)),
    ("wall", "wall", dict(center=(0, 0, 0), normal=(0, 0, 1), u=(1, 0, 0),
                          half_extents=(0.04, 0.025), thickness=0.004),
     "wall: plate, half_extents (a, b), thickness", 0.05, (1.0, -1.5, 1.0)),
    ("tube", "tube", dict(start=(0, 0, 0), axis=(0, 0, 1), length=0.06, radius=0.025,
                          caps="start"),
     "tube: radius 25 mm, caps='start'", 0.05, (1.0, -1.5, 1.1)),
    ("tube_cone", "tube", dict(start=(0, 0, 0), axis=(0, 0, 1), length=0.05,
                               radius_start=0.006, radius_end=0.03),
     "tube as a cone: radius_start, radius_end (a hopper)", 0.05, (1.0, -1.5, 0.7)),
    ("bend", "bend", dict(center=(0, 0, 0), axis=(0, 0, 1), start_direction=(1, 0, 0),
                          bend_radius=0.05, pipe_radius=0.012, angle=math.pi / 2),
     "bend: bend_radius 50 mm, pipe_radius 12 mm, 90 deg", 0.05, (0.6, 0.4, 1.4)),
    ("mesh", "mesh", dict(vertices=_OCTA_V, faces=_OCTA_F),
     "mesh: vertices + faces (or an STL/OBJ/PLY file)", 0.05, (1.0, -1.5, 0.8)),
    ("sieve", "sieve", dict(center=(0, 0, 0), normal=(0, 0, 1), half_extents=(0.04, 0.04),
                            hole=0.006, bar=0.003, thickness=0.001),
     "sieve: square holes 6 mm, bars 3 mm", 0.05, (0.8, -1.2, 1.6)),
    ("sieve_round", "sieve", dict(center=(0, 0, 0), normal=(0, 0, 1),
                                  half_extents=(0.04, 0.04), hole=0.008, bar=0.004,
                                  shape="round", thickness=0.001),
     "sieve: round holes 8 mm, bars 4 mm", 0.05, (0.8, -1.2, 1.6)),
    ("orifice_plate", "orifice_plate", dict(center=(0, 0, 0), normal=(0, 0, 1),
                                            hole=0.02, radius=0.045, thickness=0.003),
     "orifice_plate: round, hole 20 mm", 0.05, (0.8, -1.2, 1.4)),
    ("orifice_plate_slot", "orifice_plate", dict(center=(0, 0, 0), normal=(0, 0, 1),
                                                 shape="rectangle", hole=(0.01, 0.05),
                                                 half_extents=(0.04, 0.04), u=(1, 0, 0)),
     "orifice_plate: rectangle, a slot 10 x 50 mm", 0.05, (0.8, -1.2, 1.4)),
]


def draw(name, kind, params, text, extent, view, size=(360, 270)) -> Path:
    sim = dpm.Simulation(dt=1e-5)
    bd = sim.add_boundary(kind, material=STEEL, **params)
    v, f = boundary_surface(bd, extent=extent, centre=np.zeros(3))
    # containers drawn see-through, so that the ball inside shows
    opacity = 0.55 if name in ("box", "tube", "tube_cone", "bend") else 1.0
    actors = [surface_actor(polydata(v, f), color=(0.66, 0.70, 0.78), opacity=opacity,
                            edges=True)]
    # a 5 mm ball for scale, resting where the boundary's geometry says it touches
    ball = {"tube": (0.0, 0.0, 0.03), "tube_cone": (0.0, 0.0, 0.03),
            "bend": (0.05 * math.cos(0.6), 0.05 * math.sin(0.6), 0.0),
            "box": (0.0, 0.0, 0.005), "orifice_plate": (0.03, 0.0, 0.0065),
            "orifice_plate_slot": (0.025, 0.0, 0.005)}.get(name, None)
    if ball is not None:
        actors.append(spheres_actor(np.array([ball]), np.array([0.005]), np.array([1.0]),
                                    (0.0, 1.0), resolution=24))

    def camera(cam):
        d = np.asarray(view, float)
        d /= np.linalg.norm(d)
        fp = np.array(cam.GetFocalPoint())
        cam.SetPosition(*(fp + cam.GetDistance() * d))
        cam.SetViewUp(0.0, 0.0, 1.0)
        cam.Zoom(0.95)

    path = OUT / f"{name}.png"
    render(actors, path, size=size, camera=camera, overlays=[caption(text, 12)])
    return path


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    kinds = {c[1] for c in CASES}
    missing = set(registry().names("boundary")) - kinds
    if missing:
        raise SystemExit(f"no picture case for the boundary kinds {sorted(missing)}")
    for case in CASES:
        path = draw(*case)
        print(f"wrote {path.relative_to(OUT.parents[1])} ({path.stat().st_size // 1024} kB)")


if __name__ == "__main__":
    main()
