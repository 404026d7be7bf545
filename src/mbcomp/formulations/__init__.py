"""Formulations: reductions of the assembled system to something a solver can step.

ODE forms: :class:`LagrangeIndex1` (multipliers at index 1) and :class:`DAlembert`
(projection onto independent speeds). DAE forms (:mod:`mbcomp.formulations.dae`): index 1,
GGL (index 2), index 3 and the second-order mechanical form.
"""
from .lagrange import DAlembert, LagrangeIndex1

__all__ = ["LagrangeIndex1", "DAlembert"]
