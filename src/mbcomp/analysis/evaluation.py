"""What evaluates the model during an analysis: the generated program unless asked otherwise.

A linearization evaluates the model a few hundred times at nearby states and a steady-state
search a few thousand; the generated Python program (:mod:`mbcomp.codegen`) does that 10-20x
faster than the numeric path for a trace of a few tens of milliseconds, and agrees with it to
rounding. A model that cannot be traced falls back to the numeric path with a warning naming
the component.

Examples
--------
>>> import mbcomp
>>> from mbcomp.analysis.evaluation import system_for
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
>>> rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system_for(m, None, "numeric").nu
1
"""
from __future__ import annotations

import warnings

from ..assembly.system import MultibodySystem, assemble

__all__ = ["BACKENDS", "system_for"]

#: what may evaluate the model (as for :func:`mbcomp.simulate`)
BACKENDS = ("python", "numeric", "c", "auto")


def system_for(model_or_system, params=None, backend="python"):
    """The assembled system, evaluated by a generated program unless ``backend="numeric"``.

    Parameters
    ----------
    model_or_system : Model or MultibodySystem
        A system that is already compiled (``system.backend != "numeric"``) is used as it is.
    params : dict, optional
        Runtime parameter values ``{"component.param": value}``.
    backend : {"python", "numeric", "c", "auto"}

    Returns
    -------
    MultibodySystem
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is unknown; use one of {', '.join(BACKENDS)}")
    if isinstance(model_or_system, MultibodySystem):
        system = model_or_system.with_params(params) if params else model_or_system
    else:
        system = assemble(model_or_system, params)
    if backend == "numeric" or system.backend != "numeric":
        return system
    from ..codegen import CodegenError, compile_system

    try:
        return compile_system(system, backend)
    except CodegenError as exc:
        warnings.warn(f"stability: the numeric path evaluates this model (slower): {exc}", stacklevel=3)
        return system
