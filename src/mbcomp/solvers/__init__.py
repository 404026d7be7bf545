"""Integrators behind one stepping interface (:class:`~mbcomp.solvers.base.Stepper`).

``STEPPERS`` maps every method name :func:`mbcomp.simulate` accepts to its stepper class:
scipy's ODE integrators (``RK23, RK45, DOP853, Radau, BDF, LSODA``, wrapped by
:mod:`mbcomp.solvers.scipy_adapter`) and mbcomp's DAE solvers (``SOLVERS``: ``radau5``,
``ida``, ``genalpha``) and the explicit methods run in C over the compiled engine
(``COMPILED_STEPPERS``: ``dop853``, ``dopri5``). Every class declares what it can do (``implicit``, ``adaptive``,
``one_step``, ``max_index``, the ``problem`` kind it steps), so the driver checks a request
against the declaration and steps every solver alike, instead of special-casing names.

Examples
--------
>>> from mbcomp.solvers import SOLVERS, STEPPERS
>>> sorted(SOLVERS)
['genalpha', 'ida', 'radau5']
>>> SOLVERS["genalpha"].capabilities()["max_index"]
3
>>> [name for name, cls in STEPPERS.items() if not cls.one_step]   # their history cannot be projected
['BDF', 'LSODA', 'ida']
"""
from .base import MechanicalDAE, SemiExplicitDAE, StepFailure, Stepper
from .genalpha import GeneralizedAlpha
from .ida import IDA
from .radau import Radau5
from .compiled_rk import COMPILED_STEPPERS, CompiledRK
from .scipy_adapter import SCIPY_STEPPERS, ScipyStepper

#: mbcomp's own DAE solvers
SOLVERS = {"radau5": Radau5, "ida": IDA, "genalpha": GeneralizedAlpha}

#: every method name -> its stepper class (scipy's ODE methods first, then the C ones)
STEPPERS = {**SCIPY_STEPPERS, **COMPILED_STEPPERS, **SOLVERS}

__all__ = ["Stepper", "SemiExplicitDAE", "MechanicalDAE", "StepFailure", "Radau5", "IDA", "GeneralizedAlpha",
           "ScipyStepper", "CompiledRK", "SOLVERS", "SCIPY_STEPPERS", "COMPILED_STEPPERS", "STEPPERS"]
