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
>>> output_times(0.0, 1.0, None, 0.3).tolist(), output_times(0.0, 1.0, None, 5.0).tolist()
([0.0, 0.3, 0.6, 0.8999999999999999, 1.0], [0.0, 1.0])
"""
from __future__ import annotations

import numpy as np

from ..assembly.system import MultibodySystem, assemble
from ..formulations import check
from ..solvers import STEPPERS

__all__ = ["ALL_METHODS", "BACKENDS", "check_request", "check_numbers", "check_model", "system_of", "output_times"]

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
    already runs one.

    A system passed in is never the one run: the run works on its own copy (same topology,
    parameter values and program), as initialization chooses the constraint rows kept
    (``row_mask``) and a run may choose them again; the caller's system is left as it was.

    A C backend's shared pieces (the runtime, the thin call's extension) start compiling first,
    on threads, where this machine has not built them yet: the compiler works while the model
    is assembled and traced (:func:`~mbcomp.codegen.compiler.prepare_runtime`)."""
    if backend in ("auto", "c") and getattr(model, "backend", "numeric") in ("numeric", "c"):
        from ..codegen.compiler import prepare_runtime

        prepare_runtime()
    if isinstance(model, MultibodySystem):
        try:
            system = model.with_params(params or {})
        except Exception as exc:  # a law given in params that its program cannot hold: numeric, said once
            from ..codegen import CodegenError

            if not isinstance(exc, CodegenError):
                raise
            import warnings

            warnings.warn(f"mbcomp: running on the numeric evaluation (slower): {exc}", RuntimeWarning, stacklevel=3)
            system = model.with_evaluator(None).with_params(params)
    else:
        system = assemble(model, params)
    if backend != "numeric" and system.backend == "numeric":
        from ..codegen import compile_system

        if backend != "auto":
            return compile_system(system, backend, lazy=True, reuse=True)
        from ..codegen import CodegenError

        try:
            return compile_system(system, backend, lazy=True, reuse=True)
        except CodegenError as exc:  # a law that cannot be traced: the numeric path, said once
            import warnings

            warnings.warn(f"mbcomp: running on the numeric evaluation (slower): {exc}", RuntimeWarning, stacklevel=3)
    return system


def _positive(name, value, fix, allow_inf=False):
    """A ``ValueError`` naming ``name`` and the fix unless ``value`` is a positive number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}={value!r} is not a number -> {fix}") from None
    if not v > 0 or (np.isinf(v) and not allow_inf) or np.isnan(v):
        raise ValueError(f"{name}={value!r} must be a positive{'' if allow_inf else ', finite'} number -> {fix}")
    return v


def check_numbers(*, t_start, t_end, rtol, atol, alpha, beta, n_out, dt_out, max_step, h, max_wall_time, max_steps):
    """A ``ValueError`` naming the argument and the fix for a number :func:`mbcomp.simulate`
    cannot honour (before anything is assembled): non-finite times, tolerances that are not
    positive (``rtol`` at least the rounding unit), negative Baumgarte gains, an output grid
    of fewer than two points or a non-positive step, non-positive step bounds and budgets.

    Examples
    --------
    >>> check_numbers(t_start=0.0, t_end=1.0, rtol=-1e-6, atol=1e-9, alpha=10.0, beta=10.0, n_out=None,
    ...               dt_out=None, max_step=np.inf, h=None, max_wall_time=None, max_steps=None)
    Traceback (most recent call last):
    ...
    ValueError: rtol=-1e-06 must be a positive, finite number -> give a relative tolerance such as rtol=1e-8
    """
    for name, v in (("t_start", t_start), ("t_end", t_end)):
        if not np.isfinite(_positive(name, abs(float(v)) + 1.0, "give a finite time in s")):
            raise ValueError(f"{name}={v!r} must be finite (s)")
    _positive("rtol", rtol, "give a relative tolerance such as rtol=1e-8")
    if rtol < 100 * np.finfo(float).eps:
        raise ValueError(f"rtol={rtol!r} is below what double precision can deliver (about 2.2e-14) -> "
                         "give rtol >= 1e-13")
    for i, a in enumerate(np.atleast_1d(np.asarray(atol, dtype=object))):
        _positive("atol" if np.ndim(atol) == 0 else f"atol[{i}]", a, "give an absolute tolerance such as atol=1e-10")
    for name, v in (("alpha", alpha), ("beta", beta)):
        if not (isinstance(v, (int, float, np.floating, np.integer)) and np.isfinite(v) and v >= 0):
            raise ValueError(f"the Baumgarte gain {name}={v!r} must be a finite number >= 0 (1/s): a negative gain "
                             f"drives the constraint error up instead of down -> give e.g. {name}=10.0, or "
                             "stabilization='projection'")
    if n_out is not None and (isinstance(n_out, bool) or not isinstance(n_out, (int, np.integer)) or n_out < 2):
        raise ValueError(f"n_out={n_out!r} must be an integer >= 2 (the start and t_end are always output) -> "
                         "give e.g. n_out=501, or dt_out= a step in s")
    if dt_out is not None:
        _positive("dt_out", dt_out, "give the output step in s, e.g. dt_out=0.01")
    _positive("max_step", max_step, "give the largest step in s, or leave it out (no bound)", allow_inf=True)
    if h is not None:
        _positive("h", h, "give the (first) step size in s, e.g. h=1e-4")
    if max_wall_time is not None:
        _positive("max_wall_time", max_wall_time, "give the wall-time budget in s, e.g. max_wall_time=60")
    if max_steps is not None and (isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer))
                                  or max_steps < 1):
        raise ValueError(f"max_steps={max_steps!r} must be a positive integer -> give e.g. max_steps=100000")


def check_events(events):
    """The user's event functions as a tuple, each checked: a callable ``f(t, y)`` (``y = [q,
    u]``) whose ``direction`` (if set) is -1, 0 or +1 and whose ``terminal`` (if set) is a
    bool or a count >= 0 (scipy's convention); a ``ValueError``/``TypeError`` naming the event
    and the fix otherwise.

    Examples
    --------
    >>> def ground(t, y):
    ...     return y[0]
    >>> ground.terminal = True
    >>> check_events([ground])[0] is ground
    True
    >>> try:
    ...     check_events([lambda t: 0.0])
    ... except TypeError as exc:
    ...     print(str(exc).split(";")[0])
    event <lambda> takes 1 positional argument(s)
    """
    import inspect

    if events is None:
        return ()
    if callable(events) or isinstance(events, (str, bytes)) or not hasattr(events, "__iter__"):
        raise TypeError(f"events={events!r} must be a list of event functions f(t, y) -> fix: events=[f]")
    out = tuple(events)
    for i, f in enumerate(out):
        name = getattr(f, "__name__", f"events[{i}]")
        if not callable(f):
            raise TypeError(f"events[{i}]={f!r} is not a function -> fix: give functions f(t, y) returning a number "
                            "that crosses zero at the event (scipy's convention)")
        try:
            sig = inspect.signature(f)
        except (TypeError, ValueError):
            sig = None
        if sig is not None:
            params = list(sig.parameters.values())
            positional = [q for q in params if q.kind in (q.POSITIONAL_ONLY, q.POSITIONAL_OR_KEYWORD)]
            if not any(q.kind == q.VAR_POSITIONAL for q in params) and len(positional) < 2:
                raise TypeError(f"event {name} takes {len(positional)} positional argument(s); an event function is "
                                f"called as {name}(t, y) with y = [q, u] -> fix: def {name}(t, y): ...")
        direction = getattr(f, "direction", 0)
        if direction not in (-1, 0, 1):
            raise ValueError(f"event {name}: direction={direction!r} must be -1 (falling through zero), +1 (rising) "
                             "or 0 (both)")
        terminal = getattr(f, "terminal", False)
        if not (isinstance(terminal, (bool, np.bool_)) or (isinstance(terminal, (int, np.integer)) and terminal >= 0)):
            raise ValueError(f"event {name}: terminal={terminal!r} must be True/False or a count >= 0 of crossings "
                             "after which the run ends")
    return out


def check_model(model):
    """A ``TypeError`` naming what was given and the fix unless ``model`` is a
    :class:`~mbcomp.Model` or an assembled system."""
    from ..modeling.model import Model

    if isinstance(model, (Model, MultibodySystem)):
        return
    import os

    if isinstance(model, (str, os.PathLike)):
        raise TypeError(f"simulate() takes a Model, not the path {str(model)!r} -> load the file and build its "
                        f"model first: mbcomp.simulate(mbcomp.load_model_file({str(model)!r}).build(), ...), or run "
                        f"'mbcomp simulate {model}' from a shell")
    if callable(getattr(model, "build", None)):
        raise TypeError(f"simulate() takes a Model, not {type(model).__name__} {getattr(model, '__name__', '')!r} "
                        "-> call its build() and pass the model it returns: mbcomp.simulate(mod.build(), ...)")
    raise TypeError(f"simulate() takes an mbcomp.Model (or an assembled system), not {type(model).__name__} "
                    f"{model!r:.60} -> build the model with mbcomp.Model() and pass it")


def output_times(t_start, t_end, n_out, dt_out):
    """Output grid (s): a step ``dt_out`` from ``t_start``, else ``n_out`` points (default
    501); ``t_end`` is always the last point (after a shorter last interval when ``dt_out``
    does not divide the span; alone with the start when ``dt_out`` is longer than the run)."""
    if dt_out is not None:
        n = int(np.floor((t_end - t_start) / dt_out * (1.0 + 1e-12)))
        t_out = t_start + dt_out * np.arange(n + 1)
        t_out = t_out[t_out < t_end - 1e-9 * dt_out]
        return np.append(t_out, t_end)
    return np.linspace(t_start, t_end, n_out or 501)
