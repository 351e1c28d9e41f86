"""dpm-contrib-example: a Kelvin-Voigt contact law, the spherocylinder shape, the orbit
motion and a run-time hook that records orbiting boundaries into the run's HDF5 file."""

__version__ = "0.1.0"
