"""Formulations: reductions of the assembled system to something a stepper can step.

Every formulation is a :class:`Formulation` (:mod:`.base`). ODE forms: :class:`LagrangeIndex1`
(multipliers at index 1, :mod:`.lagrange`) and :class:`DAlembert` (projection onto
independent speeds, :mod:`.dalembert`). DAE forms (:mod:`.dae`): index 1, GGL (index 2),
index 3 and the second-order mechanical form. :func:`build` chooses one for a request
(:mod:`.choice`), :func:`check` refuses a request nothing can step.

Examples
--------
>>> from mbcomp.formulations import FORMULATIONS, build
>>> FORMULATIONS
('lagrange', 'dalembert')
"""
from .base import Formulation
from .choice import FORMULATIONS, build, check, stepper_for
from .dalembert import DAlembert
from .lagrange import LagrangeIndex1

__all__ = ["Formulation", "LagrangeIndex1", "DAlembert", "build", "check", "stepper_for", "FORMULATIONS"]
