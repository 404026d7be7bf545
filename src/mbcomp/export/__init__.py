"""Exporting a composed model to run outside Python: :func:`export_fmu` writes an FMI FMU.

The FMU carries the model's generated C program (the same one ``mbcomp.simulate`` runs), the
parameter program in C, and a small FMI wrapper; it needs no Python, numpy or mbcomp to run.
"""
from .fmu import export_fmu

__all__ = ["export_fmu"]
