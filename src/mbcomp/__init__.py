"""mbcomp: Modelica-style, object-oriented modelling and simulation of mechanisms.

Compose bodies, joints, force elements and drives into a :class:`Model`, then
:func:`simulate` it. The standard components live in :mod:`mbcomp.library`. A model file
(a ``.py`` file defining ``build(**params) -> Model``) loads with :func:`load_model`.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model()
>>> w = m.add("world", World())
>>> j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.5))
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> res = mbcomp.simulate(m, t_end=1.0)
>>> res.status
'success'
"""
import sys as _sys

from . import _aliases
from .errors import InitializationError, ModelError, SimulationError
from .modeling.component import Component, Flange, Frame, Guess, Param
from .modeling.model import Model
from .modeling.roles import (Body, Drive, FlangeConstraint, FlangeElement, FlangeInertia, FlangeSum, ForceElement,
                             FrameState, Ground, Joint)
from .modeling.shapes import Box, Cylinder, Grid, Helix, Mesh, Rod, Sphere

_aliases.install()  # old module paths (mbcomp.kinematics, mbcomp.jets, ...) stay importable

__all__ = [
    "Component", "Param", "Frame", "Flange", "Guess", "Model",
    "Ground", "Body", "Joint", "ForceElement", "FlangeElement", "Drive", "FrameState",
    "FlangeConstraint", "FlangeInertia", "FlangeSum",
    "ModelError", "InitializationError", "SimulationError",
    "Box", "Cylinder", "Sphere", "Mesh", "Helix", "Rod", "Grid",
    "assemble", "simulate", "Result", "equations", "linearize", "steady_states", "sweep",
    "load_model_file", "load_model", "export_fmu", "Input", "study", "Uniform", "Normal", "gradient",
    "fit", "batch", "load_urdf", "load_mjcf",
]


def __getattr__(name):  # lazy: keep "import mbcomp" light and free of cycles with mbcomp.library
    if name == "assemble":
        from .assembly.system import assemble
        return assemble
    if name == "simulate":
        if "mbcomp.simulation.driver" not in _sys.modules:  # the first time: start the C runtime's
            from .codegen.compiler import prepare_runtime  # build (where missing) before the imports

            prepare_runtime()
        from .simulation.driver import simulate
        return simulate
    if name == "Result":
        from .simulation.result import Result
        return Result
    if name == "equations":  # symbolic equations of motion (imports sympy)
        from .codegen.symbolic import equations
        return equations
    if name in ("load_model_file", "load_model"):  # model files: build(**params) -> Model
        from .modeling import loader
        return getattr(loader, name)
    if name == "load_urdf":  # a URDF robot as a Model of library components
        from .io.urdf import load_urdf
        return load_urdf
    if name == "load_mjcf":  # an MJCF (MuJoCo) model as a Model of library components
        from .io.mjcf import load_mjcf
        return load_mjcf
    if name == "Input":  # an external signal standing where a law is given
        from .modeling.inputs import Input
        return Input
    if name == "export_fmu":  # the model as an FMI FMU (needs a C compiler)
        from .export import export_fmu
        return export_fmu
    if name == "gradient":  # adjoint gradients of an objective of a run
        from .analysis.gradient import gradient
        return gradient
    if name == "batch":  # many parameter sets in one compiled call
        from .analysis.batch import batch
        return batch
    if name == "fit":  # parameter identification: least squares with the exact sensitivities
        from .analysis.fit import fit
        return fit
    if name in ("linearize", "steady_states", "sweep", "study", "Uniform", "Normal"):  # analyses, studies
        from . import analysis
        return getattr(analysis, name)
    if name in _SUBPACKAGES:  # mbcomp.codegen.compile_system(...) after a plain "import mbcomp"
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'mbcomp' has no attribute {name!r}")


_SUBPACKAGES = ("analysis", "assembly", "cli", "codegen", "export", "formulations", "geometry", "library",
                "modeling", "simulation", "solvers")

__version__ = "0.1.0"
