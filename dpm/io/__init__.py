"""Input and output: HDF5 runs (+ XDMF for ParaView) and TOML scene files."""

from .hdf5 import Run, Writer, load
from .xdmf import write_xdmf

__all__ = ["Run", "Writer", "load", "write_xdmf"]
