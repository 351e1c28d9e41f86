"""Post-processing of a loaded run (``dpm.load(path)``) or a live :class:`dpm.Simulation`.

Definitions and sources are in each function's docstring and in ``docs/analysis.md``:

- residence times: :func:`residence_times` (E(t), F(t), mean, variance);
- flow rates: :func:`plane_flow_rate`, :func:`outlet_flow_rate`, :func:`beverloo`,
  :func:`fit_beverloo`;
- fields: :func:`voxel_fields` (binning), :func:`coarse_grain` (Gaussian kernel),
  :meth:`Field.slice`;
- rotating drums: :func:`drum_surface`, :func:`angle_of_repose`;
- mixing: :func:`lacey`, :func:`lacey_index`;
- contacts and energy: :func:`coordination_numbers`, :func:`coordination_distribution`,
  :func:`force_distribution`, :func:`overlap_distribution`, :func:`kinetic_energy`,
  :func:`kinetic_energy_series`, :func:`energy_balance`;
- a log during runs: :class:`Thermo` (also written to ``/thermo`` of the output file);
- a picture of a frame: :func:`picture` (needs matplotlib, the ``plot`` extra).
"""

from ._common import Series, as_frame, frames_of
from .contacts import (
    coordination_distribution,
    coordination_numbers,
    energy_balance,
    force_distribution,
    kinetic_energy,
    kinetic_energy_series,
    overlap_distribution,
)
from .drum import DrumSurface, angle_of_repose, drum_surface
from .fields import Field, ball_points, coarse_grain, voxel_fields
from .mixing import lacey, lacey_index, species_mask
from .picture import picture
from .residence import (
    ResidenceTimes,
    beverloo,
    fit_beverloo,
    outlet_flow_rate,
    plane_flow_rate,
    removal_records,
    residence_times,
)
from .thermo import Thermo, format_table, thermo_row

__all__ = [
    "DrumSurface", "Field", "ResidenceTimes", "Series", "Thermo", "angle_of_repose",
    "as_frame", "ball_points", "beverloo", "coarse_grain", "coordination_distribution",
    "coordination_numbers", "drum_surface", "energy_balance", "fit_beverloo",
    "force_distribution",
    "format_table", "frames_of", "kinetic_energy", "kinetic_energy_series", "lacey",
    "lacey_index", "outlet_flow_rate", "overlap_distribution", "picture", "plane_flow_rate",
    "removal_records", "residence_times", "species_mask", "thermo_row", "voxel_fields",
]
