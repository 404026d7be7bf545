"""What a run needs before it steps: a checked request, the system, the output times.

The driver (:func:`mbcomp.simulate`) accepts a model or an assembled system, a method name
(any of :data:`mbcomp.solvers.STEPPERS`), a formulation and a DAE index. This module turns
that request into a stepper class and the index to use, refusing a combination nothing can
step *before* anything is assembled (the formulation side of the check is
:func:`mbcomp.formulations.check`, the stepper side its declared capabilities), and resolves
the system to run: assembled from a model, with runtime parameters, traced into a generated
program when a backend other than ``"numeric"`` is asked for.

Examples
--------
>>> from mbcomp.simulation.setup import check_request, output_times
>>> stepper, index = check_request("radau5", "lagrange", None, None, 0.0, 1.0, "numeric")
>>> stepper.__name__, index
('Radau5', 1)
>>> check_request("genalpha", "lagrange", None, None, 0.0, 1.0, "numeric")
Traceback (most recent call last):
...
ValueError: method 'genalpha' uses a fixed step: give the step size h (s), e.g. h=1e-4
>>> output_times(0.0, 1.0, None, 0.25).tolist()
[0.0, 0.25, 0.5, 0.75, 1.0]
"""
from __future__ import annotations

import numpy as np

from ..assembly.system import MultibodySystem, assemble
from ..formulations import check
from ..solvers import STEPPERS

__all__ = ["ALL_METHODS", "BACKENDS", "check_request", "system_of", "output_times"]

#: every method name, scipy's ODE methods first
ALL_METHODS = tuple(STEPPERS)
BACKENDS = ("numeric", "python", "c", "auto")


def check_request(method, formulation, index, h, t_start, t_end, backend):
    """``(stepper class, index)`` for a request; a ``ValueError`` naming the fix otherwise.

    Parameters
    ----------
    method : str
        A key of :data:`mbcomp.solvers.STEPPERS`.
    formulation : str
        A name of :data:`mbcomp.formulations.FORMULATIONS`.
    index : {None, 1, 2, 3}
        Requested DAE index.
    h : float or None
        Step size (s), required by fixed-step methods.
    t_start, t_end : float
        Time span (s).
    backend : str
        One of :data:`BACKENDS`.
    """
    if method not in STEPPERS:
        raise ValueError(f"method {method!r} is unknown; use one of {', '.join(ALL_METHODS)}")
    stepper = STEPPERS[method]
    index = check(formulation, stepper.problem, index=index, method=method, max_index=stepper.max_index)
    if not stepper.adaptive and not h:
        raise ValueError(f"method {method!r} uses a fixed step: give the step size h (s), e.g. h=1e-4")
    if not t_end > t_start:
        raise ValueError(f"t_end ({t_end}) must be greater than t_start ({t_start})")
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is unknown; use 'numeric', 'python', 'c' or 'auto'")
    return stepper, index


#: what a run does at a singular position (the constraint Jacobian losing rank)
SINGULAR = ("stop", "pass")


def check_singular(singular, method, stepper, formulation, stabilization):
    """The stabilization to use for ``singular`` (:data:`SINGULAR`) with the ``method`` (its
    stepper class ``stepper``) and formulation asked for; a ``ValueError`` naming the fix for a combination that cannot pass
    a singular position.

    With ``"pass"``: the Lagrange index-1 ODE projects (Baumgarte's terms divide by the
    vanishing eigenvalue of ``A M^-1 A^T``: on the N-four-bar the motion left the exact one
    by 29 rad within 12 s) -- the default stabilization becomes ``"projection"`` and an explicit
    ``"baumgarte"`` is refused; radau5 and IDA are refused (their Newton matrix is singular
    at the passage: the step size collapses there)."""
    if singular not in SINGULAR:
        raise ValueError(f"singular={singular!r} is unknown; use 'stop' (end the run at a singular position) or "
                         "'pass' (go through it and record the passage in res.stats['singular_passages'])")
    if singular == "stop":
        return "baumgarte" if stabilization is None else stabilization
    if stepper.problem == "dae":
        raise ValueError(f"singular='pass' does not work with method {method!r}: its Newton matrix is "
                         "singular where the constraint Jacobian loses rank -> use formulation='dalembert', "
                         "method='genalpha', or the Lagrange form with an ODE method (e.g. method='dop853')")
    if formulation == "lagrange" and stepper.problem == "ode" and stabilization == "baumgarte":
        raise ValueError("singular='pass' with stabilization='baumgarte': the Baumgarte terms blow up where the "
                         "constraint Jacobian loses rank -> use stabilization='projection' (the default with "
                         "singular='pass') or formulation='dalembert'")
    return "projection" if stabilization is None else stabilization


def system_of(model, params, backend):
    """The system to run: ``model`` assembled (or an assembled system, with ``params``
    applied), traced into a generated program unless ``backend`` is ``"numeric"`` or it
    already runs one."""
    if isinstance(model, MultibodySystem):
        system = model.with_params(params) if params else model
    else:
        system = assemble(model, params)
    if backend != "numeric" and system.backend == "numeric":
        from ..codegen import compile_system

        if backend != "auto":
            return compile_system(system, backend, lazy=True)
        from ..codegen import CodegenError

        try:
            return compile_system(system, backend, lazy=True)
        except CodegenError as exc:  # a law that cannot be traced: the numeric path, said once
            import warnings

            warnings.warn(f"mbcomp: running on the numeric evaluation (slower): {exc}", RuntimeWarning, stacklevel=3)
    return system


def output_times(t_start, t_end, n_out, dt_out):
    """Output grid (s): a step ``dt_out`` (not past ``t_end``), else ``n_out`` points
    (default 501)."""
    if dt_out is not None:
        t_out = np.arange(t_start, t_end + 0.5 * dt_out, dt_out)
        t_out[-1] = min(t_out[-1], t_end)
        return t_out
    return np.linspace(t_start, t_end, n_out or 501)
