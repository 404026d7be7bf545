"""The ``mbcomp`` command line: one module per command, a shared model loader."""
from .main import load_model_file, main, parse_sweep, parse_value

__all__ = ["main", "load_model_file", "parse_value", "parse_sweep"]
