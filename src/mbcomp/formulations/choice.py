"""Which formulation steps a request: the one place that knows formulation names and DAE indices.

A request names a formulation (``"lagrange"`` or ``"dalembert"``), the problem kind its
stepper can step (``"ode"``, ``"dae"`` or ``"mechanical"``, see :mod:`mbcomp.solvers.base`)
and, for DAE steppers, the index at which the constraints are kept:

=============  ============  =====  =====================================================
formulation    problem       index  formulation built
=============  ============  =====  =====================================================
lagrange       ode           1      :class:`~mbcomp.formulations.LagrangeIndex1`
dalembert      ode           --     :class:`~mbcomp.formulations.DAlembert`
lagrange       dae           1      :class:`~mbcomp.formulations.dae.Index1`
lagrange       dae           2      :class:`~mbcomp.formulations.dae.GGL`
lagrange       dae           3      :class:`~mbcomp.formulations.dae.Index3`
lagrange       mechanical    3      :class:`~mbcomp.formulations.dae.Mechanical`
=============  ============  =====  =====================================================

Any other combination is refused by :func:`check` with a message naming the fix.

Examples
--------
>>> from mbcomp.formulations import check
>>> check("lagrange", "dae"), check("lagrange", "mechanical"), check("dalembert", "ode")
(1, 3, None)
>>> check("lagrange", "ode", index=2, method="RK45")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: method 'RK45' integrates ODEs: the index-2 form is a DAE -> use method='radau5' (index 1-3), ...
"""
from __future__ import annotations

from .dae import DAE_FORMS, Mechanical
from .dalembert import DAlembert
from .lagrange import LagrangeIndex1

__all__ = ["FORMULATIONS", "PROBLEMS", "check", "build", "stepper_for"]

FORMULATIONS = ("lagrange", "dalembert")
PROBLEMS = ("ode", "dae", "mechanical")


def check(formulation, problem, *, index=None, method=None, max_index=None):
    """The DAE index to use for a request; a ``ValueError`` naming the fix when nothing can step it.

    Cheap (no system needed): the driver calls it before assembling the model.

    Parameters
    ----------
    formulation : {"lagrange", "dalembert"}
    problem : {"ode", "dae", "mechanical"}
        What the chosen stepper steps (its ``problem``; ``"ode"`` for scipy's methods).
    index : {1, 2, 3}, optional
        Requested DAE index; by default 1 (3 for the mechanical form).
    method : str, optional
        The stepper's name, for the messages only.
    max_index : int, optional
        The highest index the stepper handles (DAE steppers' ``max_index``).

    Returns
    -------
    int or None
        The index to report: 1 for the index-1 ODE, ``None`` for D'Alembert (no multipliers).

    Raises
    ------
    ValueError
        Unknown formulation, problem or index, or a combination no formulation provides.
    """
    name = f"method {method!r}" if method else "this stepper"
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation {formulation!r} is unknown; use one of {', '.join(FORMULATIONS)}")
    if problem not in PROBLEMS:
        raise ValueError(f"problem {problem!r} is unknown; use one of {', '.join(PROBLEMS)}")
    if index not in (None, 1, 2, 3):
        raise ValueError(f"index={index!r} is unknown; use 1 (acceleration level), 2 (GGL) or 3 (position level)")
    if problem == "ode":
        if index not in (None, 1):
            raise ValueError(f"{name} integrates ODEs: the index-{index} form is a DAE -> use "
                             "method='radau5' (index 1-3), 'ida' (index 1-2) or 'genalpha' (index 3)")
        return 1 if formulation == "lagrange" else None
    if formulation == "dalembert":
        raise ValueError(f"formulation='dalembert' is an ODE in the independent speeds; {name} is a DAE "
                         "solver -> use a scipy method (RK45, DOP853, Radau, BDF, LSODA) or formulation='lagrange'")
    if index is None:
        index = 3 if problem == "mechanical" else 1
    if max_index is not None and index > max_index:
        raise ValueError(f"{name} handles DAEs of index <= {max_index}; index={index} was requested "
                         f"-> use index<={max_index} or method='radau5' (index 1-3)")
    if problem == "mechanical" and index != 3:
        raise ValueError(f"{name} steps the index-3 (position-level) form only -> use index=3")
    return index


def stepper_for(stepper, formulation, index):
    """The stepper class to run ``formulation`` with: ``stepper`` itself, or for a DAE solver
    that declares ``ode_by_default`` (``radau5``) and the Lagrange formulation with no
    ``index`` asked for, its ODE variant (``stepper.on_ode()``: the index-1 ODE ``[q, u]``,
    smaller and, measured, faster than the index-1 DAE; see
    :attr:`mbcomp.solvers.radau.Radau5.ode_by_default`).

    Examples
    --------
    >>> from mbcomp.formulations import stepper_for
    >>> from mbcomp.solvers import STEPPERS
    >>> [stepper_for(STEPPERS["radau5"], "lagrange", i).problem for i in (None, 1)]
    ['ode', 'dae']
    """
    if index is None and formulation == "lagrange" and getattr(stepper, "ode_by_default", False):
        return stepper.on_ode()
    return stepper


def build(formulation, problem, system, *, index=None, stabilization="baumgarte", alpha=10.0, beta=10.0,
          independent=None, method=None, max_index=None, singular="stop"):
    """The formulation that reduces ``system`` to a problem of kind ``problem`` (see the table above).

    Parameters
    ----------
    formulation, problem, index, method, max_index
        As for :func:`check` (which is applied first).
    system : MultibodySystem
        Assembled and consistently initialized.
    stabilization : {"baumgarte", "projection", "none"}
        Lagrange at index 1 (ODE or DAE) only; the other forms keep the constraints themselves.
    alpha, beta : float
        Baumgarte parameters (1/s).
    independent : list of str, optional
        D'Alembert only: speed names to start with as independent.
    singular : {"stop", "pass"}
        Lagrange at index 1 as an ODE: how the multipliers are solved near a singular
        position (see :class:`LagrangeIndex1`).

    Returns
    -------
    Formulation

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.formulations import build
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=1.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> [type(build("lagrange", p, system, index=i)).__name__ for p, i in (("ode", 1), ("dae", 2), ("mechanical", 3))]
    ['LagrangeIndex1', 'GGL', 'Mechanical']
    """
    index = check(formulation, problem, index=index, method=method, max_index=max_index)
    if formulation == "dalembert":
        return DAlembert(system, independent=independent)
    if problem == "ode":
        return LagrangeIndex1(system, stabilization, alpha, beta, singular=singular)
    if problem == "mechanical":
        return Mechanical(system)
    if index == 1:
        return DAE_FORMS[1](system, stabilization, alpha, beta)
    return DAE_FORMS[index](system)
