"""Integrators behind one stepping interface (:class:`~mbcomp.solvers.base.Stepper`).

``SOLVERS`` maps a method name to its class; every class declares what it can do
(``implicit``, ``adaptive``, ``max_index``, the ``problem`` kind it steps), so the driver
(:func:`mbcomp.simulate`) checks a request against the declaration instead of special-casing
names. scipy's integrators (``RK45`` ...) step the ODE forms and are listed in
:data:`mbcomp.simulation.METHODS`.

Examples
--------
>>> from mbcomp.solvers import SOLVERS
>>> sorted(SOLVERS)
['genalpha', 'ida', 'radau5']
>>> SOLVERS["genalpha"].capabilities()["max_index"]
3
"""
from .base import MechanicalDAE, SemiExplicitDAE, StepFailure, Stepper
from .genalpha import GeneralizedAlpha
from .ida import IDA
from .radau import Radau5

SOLVERS = {"radau5": Radau5, "ida": IDA, "genalpha": GeneralizedAlpha}

__all__ = ["Stepper", "SemiExplicitDAE", "MechanicalDAE", "StepFailure", "Radau5", "IDA", "GeneralizedAlpha",
           "SOLVERS"]
