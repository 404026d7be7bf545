"""The ``mbcomp`` command line: one module per command, a shared model loader.

Examples
--------
>>> from mbcomp.cli import parse_sweep
>>> parse_sweep("omega=5:8:4")[1].tolist()
[5.0, 6.0, 7.0, 8.0]
"""
from .main import load_model_file, main, parse_sweep, parse_value

__all__ = ["main", "load_model_file", "parse_value", "parse_sweep"]
