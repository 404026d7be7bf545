"""``simulate``: assemble, initialize, integrate, post-process -- and never lose the results.

The driver resolves a request to a stepper class (:data:`mbcomp.solvers.STEPPERS`: scipy's
``RK23, RK45, DOP853, Radau, BDF, LSODA`` for the ODE forms, mbcomp's ``radau5``, ``ida``,
``genalpha`` for the multiplier form kept as a DAE of index 1, 2 (GGL) or 3), builds the
formulation that stepper can step (:func:`mbcomp.formulations.build`) and steps it. Every
stepper is stepped alike: what happens after an accepted step (run monitors, outputs,
projection, repartition, progress bar) is a list of hooks (:mod:`mbcomp.simulation.stepping`),
and what a stepper can do is read from its declared capabilities, never from its name.

A run that cannot go on still returns a :class:`~mbcomp.simulation.result.Result` with the
results up to the last accepted step:

* ``status="failed"``: a stepper failed (its message names the cause), a run monitor found a
  singular position, or a component's law raised -- the message then names the component,
  the law, the time and the exception;
* ``status="budget"``: ``max_wall_time`` or ``max_steps`` ran out (the message says which);
* ``status="interrupted"``: Ctrl-C (``KeyboardInterrupt``) or ``SIGTERM`` during the
  integration (a SIGTERM handler is installed only while integrating, only in the main
  thread, and the previous one restored).

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("slide", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=1.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12)
>>> round(float(r["slide.s"][-1]), 6)   # free fall: -g t^2 / 2
-4.905
"""
from __future__ import annotations

import time as _time

import numpy as np

from ..codegen.graph import no_gc
from ..errors import SimulationError, SimulationInterrupted
from ..formulations import FORMULATIONS, build, stepper_for
from ..hybrid.contacts import initialize_in_modes
from ..hybrid.events import Events
from ..hybrid.steppers import stepwise, watching
from ..modeling.inputs import check_names, input_signals, signal_of
from ..solvers import SCIPY_STEPPERS, StepFailure
from .monitors import SingularPosition, evaluate_by_program, monitors_for
from .postprocess import postprocess
from .hybrid_columns import finish, segment_columns
from .error_estimate import with_estimate
from .result import Result
from .setup import (ALL_METHODS, check_events, check_model, check_numbers, check_request, check_singular,
                    output_times, system_of)
from .rows import RowChoice
from .stepping import Budget, BudgetSpent, KeepOutputs, Monitoring, Progress, Projection, Repartition, Run
from .stiffness import StiffnessWatch, system_laws
from .sensitivity import Sensitivities, check_sensitivities
from .endings import Terminated, interrupted_by, interruption, law_failure, raised_in_a_law, sigterm_interrupts, start_failure

__all__ = ["simulate", "METHODS", "FORMULATIONS", "ALL_METHODS"]


def __getattr__(name):
    """``METHODS``: scipy's ODE methods, name -> ``scipy.integrate`` class (every method:
    ``mbcomp.solvers.STEPPERS``); built once on first use, as it imports ``scipy.integrate``."""
    if name == "METHODS":
        methods = globals()["METHODS"] = {key: cls.method for key, cls in SCIPY_STEPPERS.items()}
        return methods
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def simulate(model, t_end=1.0, *, t_start=0.0, params=None, method="auto", rtol=1e-8, atol=1e-10,
             formulation="lagrange", stabilization=None, alpha=10.0, beta=10.0, n_out=None, dt_out=None,
             max_step=np.inf, progress=False, independent=None, index=None, h=None,
             backend="auto", singular="stop", inputs=None, max_wall_time=None, max_steps=None,
             body_momenta=False, events=None, error_estimate=False, sensitivities=None) -> Result:
    """Simulate a model: Lagrange multipliers at index 1, or D'Alembert projection to an ODE.

    Parameters
    ----------
    model : Model or MultibodySystem
    t_end, t_start : float
        Time span in s.
    params : dict, optional
        Runtime parameter values ``{"component.param": value}`` (nothing is re-derived).
    method : str
        ``"auto"`` (default): ``"dop853"`` until the C integrator finds the problem stiff
        (Hairer's test: 15 accepted steps held by the method's stability, not its accuracy),
        then from that step on (``stats["stiff_from"]`` says when) ``"radau5"`` with its loop in
        C for a state of at most 24 entries (a formulation that does not project), else scipy's
        ``LSODA`` with the exact Jacobian; ``"dop853"`` or ``"dopri5"``: Dormand-Prince 8(5,3) / 5(4) run in C over
        the compiled right-hand side (the whole stretch between outputs is one C call;
        scipy's ``DOP853``/``RK45`` over the Python right-hand side when there is no C
        program), a ``scipy.integrate.solve_ivp`` method name (ODE forms: Lagrange at index
        1 and D'Alembert), or a DAE solver of :mod:`mbcomp.solvers`: ``"radau5"`` (Radau IIA order
        5, index 1-3, index-aware error control), ``"ida"`` (SUNDIALS IDA, index 1 and 2) or
        ``"genalpha"`` (generalized-alpha, index 3, fixed step ``h``).
    rtol, atol : float
        Integrator tolerances (the Newton tolerance of ``genalpha``); the defaults keep long
        runs right to plotting accuracy for moderate motions: a 1 m pendulum released from
        1 rad is within 0.4 mm of its exact motion after 2,000 s (900 periods). The phase
        error grows with the swing (a pendulum's period depends on its amplitude): released
        from 3 rad the same call is 0.27 m off after 2,000 s with its energy exact to 1e-9 --
        an error no energy alarm can see; ``error_estimate=True`` measures it. A
        conservative run whose energy drifts more than ``rtol`` promises ends ``"inaccurate"``.
    index : {1, 2, 3}, optional
        Lagrange formulation with a DAE solver: the constraints at acceleration level (1),
        velocity level with position correction (2, GGL) or position level (3). Default 1
        (3 for ``genalpha``). scipy methods integrate the index-1 ODE only.
    h : float, optional
        Step size (s) of fixed-step methods (``genalpha``, required there); the first step
        of adaptive ones.
    backend : {"auto", "numeric", "python", "c"}
        ``"auto"`` (default): a generated program (:mod:`mbcomp.codegen`) in C when a
        compiler exists (cached on disk by structure), else in Python; a model whose laws
        cannot be traced runs on the numeric path with a warning naming the component.
        ``"numeric"`` evaluates the jets directly (no set-up cost); ``"python"``, ``"c"``
        force a program (:mod:`mbcomp.codegen`; linear in the bodies of a chain).
    formulation : {"lagrange", "dalembert"}
        ``"lagrange"``: multipliers, index 1 (:class:`~mbcomp.formulations.LagrangeIndex1`);
        ``"dalembert"``: projection onto independent speeds, a minimal ODE whose positions are
        corrected onto the constraint manifold after every step
        (:class:`~mbcomp.formulations.DAlembert`; ``stabilization`` does not apply).
    stabilization : {"baumgarte", "projection", "none"}, optional
        Constraint stabilization of the Lagrange formulation (see :mod:`mbcomp.formulations`);
        default ``"baumgarte"``, and ``"projection"`` with ``singular="pass"``.
    alpha, beta : float
        Baumgarte parameters (1/s).
    n_out, dt_out : int, float, optional
        Output grid: ``n_out`` points or a step ``dt_out`` (default 501 points).
    independent : list of str, optional
        D'Alembert only: speed names to start with as independent (re-chosen automatically
        when they become ill-conditioned).
    progress : bool
        Show a progress bar (tqdm) when the run lasts more than two seconds.
    inputs : dict, optional
        The model's external inputs (:class:`mbcomp.Input`) by name: a function of time
        ``f(t)``, a number, or a table ``(times, values)`` (linear interpolation); an input
        not given keeps its ``start`` value.
    singular : {"stop", "pass"}
        Where the constraint Jacobian loses rank (a flat four-bar): ``"stop"`` (default: past
        it the motion need not be unique) ends the run there, naming the time; ``"pass"`` goes
        on, positions and velocities continuous, recording each passage in
        ``stats["singular_passages"]`` (time, relative singular value, rank drop, joints).
    max_wall_time : float, optional
        Wall-time budget of the call (s, assembly, compilation and integration); when it runs
        out the run ends with status ``"budget"`` and the results computed so far.
    max_steps : int, optional
        Budget of integrator steps; the same.
    body_momenta : bool
        Also each body's momenta (``<body>.momentum.*``, ``<body>.angular_momentum.*``); the
        whole mechanism's are always columns.
    events : list of callables, optional
        Event functions ``f(t, y)`` of ``y = [q, u]`` (``system.q_names + u_names``), scipy's
        convention: ``f.terminal`` (bool or a count) ends the run at its root with status
        ``"success"``, ``f.direction`` (-1, 0, +1) filters the crossings. They and the
        components' own events (joint stops: ``Revolute(limits=..., restitution=...)``) are
        located on each step's dense output and recorded in ``res.events``
        (:mod:`mbcomp.hybrid.events`).
    error_estimate : bool
        Also run the same request at 100x tighter tolerances on the same output grid and
        report the difference (:mod:`mbcomp.simulation.error_estimate`): per column in
        ``res.stats["error_estimate"]``, the largest over the state in
        ``res.stats["global_error"]`` (and the column in ``"global_error_column"``). It sees
        the phase error that energy alarms cannot; it costs one more run (about 1.7x the
        first one's steps for dop853).
    sensitivities : list of str, optional
        Parameters to differentiate the motion with respect to: ``"component.param"``,
        ``"component.param[i]"`` (an array's entry) or a start value (``"crank_joint.phi0"``).
        The forward sensitivity equations are integrated with the run
        (:mod:`mbcomp.simulation.sensitivity`: staggered on its steps, exact derivatives from
        the generated programs, jumps at events); ``res.sensitivity(column, param)`` gives
        ``d column / d param`` at the output times for the coordinates, speeds and every
        column of the output program (reactions, energies, poses).

    Returns
    -------
    Result
        ``status`` ``"success"``, ``"inaccurate"`` (an accuracy alarm: see
        :mod:`mbcomp.simulation.accuracy`), ``"failed"`` or ``"budget"`` (``max_wall_time``
        or ``max_steps`` ran out); the results up to the last accepted step in every case.

    Raises
    ------
    SimulationInterrupted
        Ctrl-C (SIGINT) or SIGTERM during the integration: the partial result (status
        ``"interrupted"``, the results up to the last accepted step) is its ``.result``. It
        is a ``KeyboardInterrupt``, so a script stops instead of carrying on as if the run
        had finished.
    """
    check_model(model)
    check_numbers(t_start=t_start, t_end=t_end, rtol=rtol, atol=atol, alpha=alpha, beta=beta, n_out=n_out,
                  dt_out=dt_out, max_step=max_step, h=h, max_wall_time=max_wall_time, max_steps=max_steps)
    asked_index = index
    stepper, index = check_request(method, formulation, index, h, t_start, t_end, backend)
    events = check_events(events)
    stabilization = check_singular(singular, method, stepper, formulation, stabilization)
    stepper = stepper_for(stepper, formulation, asked_index)  # radau5: the index-1 ODE unless an index is asked for
    check_names(inputs or {})
    sensitivities = check_sensitivities(sensitivities)

    def run(rtol, atol, sensitivities=None):
        return _simulate(model, t_start=t_start, t_end=t_end, params=params, backend=backend,
                         formulation=formulation, stepper=stepper, index=index, stabilization=stabilization,
                         alpha=alpha, beta=beta, independent=independent, method=method, singular=singular,
                         rtol=rtol, atol=atol, n_out=n_out, dt_out=dt_out, max_step=max_step, h=h,
                         progress=progress, budget=Budget(max_wall_time, max_steps) if max_wall_time or max_steps
                         else None, body_momenta=body_momenta, events=events, sensitivities=sensitivities)

    with input_signals({name: signal_of(name, v) for name, v in (inputs or {}).items()}):
        res = run(rtol, atol, sensitivities)
        if error_estimate and res.status != "interrupted":
            with_estimate(res, run, rtol, atol)
    if res.status == "interrupted":
        raise SimulationInterrupted(res, interrupted_by(res.message), res.message)
    return res


def _simulate(model, *, t_start, t_end, params, backend, formulation, stepper, index, stabilization, alpha, beta,
              independent, method, singular, rtol, atol, n_out, dt_out, max_step, h, progress, budget,
              body_momenta, events=None, sensitivities=None):
    """:func:`simulate` once the request is checked and the inputs' signals are in place."""
    # setting up allocates many short-lived containers and makes no cycles that matter: a collection
    # of the oldest generation landing here walked every live object (~60 ms of a 1000-link call)
    with no_gc():
        system = system_of(model, params, backend)
        try:
            init = initialize_in_modes(system, t_start)  # a contact starting open: without its rows
            form = build(formulation, stepper.problem, system, index=index, stabilization=stabilization, alpha=alpha,
                         beta=beta, independent=independent, method=method, max_index=stepper.max_index,
                         singular=singular)
            y0 = form.initial_state(t_start, init.q, init.u)
        except Exception as exc:  # a law raising before the first step: say whose, there is nothing to keep
            if not raised_in_a_law(exc):
                raise
            raise SimulationError(start_failure(exc, t_start)) from exc
        if np.size(y0) == 0:  # every motion prescribed: nothing to integrate, the outputs are kinematics
            stepper = SCIPY_STEPPERS["RK45"]
            if form.problem != "ode":
                form = build("lagrange", "ode", system, stabilization=stabilization, alpha=alpha, beta=beta)
                y0 = form.initial_state(t_start, init.q, init.u)
        watcher = Events(system, lambda s: build(formulation, stepper.problem, s, index=index,
                                                 stabilization=stabilization, alpha=alpha, beta=beta,
                                                 independent=independent, method=method,
                                                 max_index=stepper.max_index, singular=singular),
                         events or (), rtol, atol)
        watcher = watcher if watcher.active else None
        if watcher is not None and system.nu <= EVENT_PROGRAM_SPEEDS:  # every act evaluates: by the program
            evaluate_by_program(system)
        if watcher is not None and watcher.system_now() is not system:  # the start modes hold other rows
            form = watcher.make_form(watcher.system_now())
            y0 = form.initial_state(t_start, init.q, init.u)
        if watcher is not None:  # a stuck friction that cannot hold at the start breaks away there
            form, y0 = watcher.start(form, y0, t_start, init.q, init.u)
        after = bool(sensitivities) and Sensitivities.after_the_run(form, watcher, stepper)
        stepped = bool(sensitivities) and not after  # a step's dense output carries them: one step at a time
        t_out = output_times(t_start, t_end, n_out, dt_out)
        offers = getattr(system.evaluator, "offers", None)  # asking every capability would wait for the program
        if watcher is None and offers is not None and offers("outputs"):  # its C build beside the program's
            system.evaluator.prepare_outputs(len(t_out), form.output_gains())  # and the integration
        run = Run(form, stepwise(stepper) if stepped else watching(stepper, watcher) if watcher else stepper,
                  t_out, y0, rtol=rtol, atol=atol, max_step=max_step, h=h)
        sens = None
        if sensitivities:
            sens = Sensitivities(form.system, sensitivities, t_start, run.ys[0], form.output_gains() or (0.0, 0.0),
                                 stepper.implicit, rtol, atol, events=watcher)
    monitors = monitors_for(system, atol, singular, getattr(init, "rows", None))
    wall0 = _time.perf_counter()
    watch = None if stepper.implicit else StiffnessWatch()
    status, message = integrate(run, monitors, progress, [x for x in (watch, budget) if x is not None], watcher,
                                None if after else sens)
    if after:
        sens.integrate_after(run)
    stats = run_stats(run, monitors, init, _time.perf_counter() - wall0, method=method, formulation=formulation,
                      index=index, rtol=rtol, atol=atol)
    if after:  # not a hook: its figures are added here
        stats.update(sens.stats())
    message = "; ".join([message] + why_slow(run, watch, status, stats))
    t_done = run.t_out[: len(run.ys)]
    if watcher is not None:
        stats.update(watcher.stats)
    Y = np.array(run.ys).reshape(len(run.ys), -1)
    added = {}
    with no_gc():
        res = postprocess(system, form, t_done, Y, status, message, stats, init, body_momenta,
                          fix=_mode_fix(system, watcher, t_done, Y, added))
    res.units.update(added)
    res = finish(res, watcher, np.array(run.ys).reshape(len(run.ys), -1))
    if sens is not None:
        res.sensitivities = sens.table(t_done, Y)
        if sens.stopped is not None:  # the states stand; the sensitivities after that time do not
            res.message += f"; the sensitivities end at t={sens.stopped[0]:.9g} s (NaN after): {sens.stopped[1]}"
    return res


def _mode_fix(system, watcher, t, Y, units):
    """The post-processing's ``fix`` of a run with modes (None without): the columns at the
    output times ``t`` computed over each output's segment's system
    (:func:`~mbcomp.simulation.hybrid_columns.segment_columns`; the added columns' units put in
    ``units``)."""
    if watcher is None:
        return None

    def fix(series):
        units.update(segment_columns(series, system, watcher.segments, t, Y, watcher.system_now))
    return fix


def why_slow(run, watch, status, stats):
    """Notes on what made a run slow: the stiffness hint (:class:`StiffnessWatch`, made now
    for a run cut short by a budget or a failure if it was not made yet), and most evaluations
    leaving the generated program for the numeric path (an untraced branch of a law)."""
    notes = []
    if watch is not None:
        if status in ("budget", "failed") and not watch.done:
            watch(run, now=True)
        if watch.note:
            notes.append(watch.note)
            stats["stiffness_hint"] = watch.note
    pace = _pace(run, status, stats)
    if pace:
        notes.append(pace)
    if stats.get("fallbacks", 0) > max(100, stats["nfev"] // 2):
        laws = system_laws(run.form.system)
        notes.append(f"{stats['fallbacks']} of {stats['nfev']} evaluations left the generated program for the "
                     + ("numeric path (a law's branch, if/abs/min on a state, the trace did not take; laws in "
                        f"{', '.join(laws)}) -> write the branch smoothly (e.g. tanh) or run with backend='numeric' "
                        "(no program to leave)" if laws else
                        "numeric path: its guards met nearly singular matrices (the model has no laws to branch) "
                        "-> the run spent its time near a singular position: look at min_constraint_sigma and the "
                        "residual columns"))
    return notes


def _keep_reached(run):
    """Keep the state a run cut short by its budget reached past its last output, as one more
    output at that time (a 1e9 s run with 2e6 s between outputs kept only t = 0)."""
    t = float(run.t)
    if len(run.ys) < len(run.t_out) and t > run.t_kept:
        y = np.asarray(run.form.full(t, run.stepper.y), float)
        if np.isfinite(y).all():
            run.t_out = np.append(run.t_out[: len(run.ys)], t)
            run.ys.append(y)


#: steps a run cut short has made before its pace is worth a note
PACE_STEPS = 100
#: a run with events on a system of at most this many speeds evaluates by its program from
#: the start (each impact, resting test and consistent state evaluates; the program's size is
#: O(N^2), its compile a fraction of a second here): the pendulum on a stop, 5 impacts, ~1 ms
EVENT_PROGRAM_SPEEDS = 24


def _pace(run, status, stats):
    """For a run cut short (a budget, a failure) after :data:`PACE_STEPS` steps: how many steps
    and how much wall time the whole span would take at its pace so far (a 1e9 s pendulum
    needs 7e9 steps of 0.14 s: no integrator and no output grid changes that), else None."""
    t0, t_end = float(run.t_out[0]), float(getattr(run.stepper, "t_bound", run.t_out[-1]))
    done, steps, wall = float(run.t) - t0, stats.get("steps", 0), stats.get("cpu_time", 0.0)
    if status not in ("budget", "failed") or steps < PACE_STEPS or not 0.0 < done < t_end - t0:
        return None
    need, seconds = (t_end - t0) / done * steps, (t_end - t0) / done * wall
    took = f"{seconds / 3600.0:.2g} h" if seconds >= 3600.0 else f"{seconds:.2g} s"
    return (f"at its pace so far (h={done / steps:.2g} s on average, {steps} steps to t={float(run.t):g} s) the "
            f"run needs about {need:.2g} steps and {took} of wall time to reach t_end={t_end:g} s -> shorten "
            "t_end or loosen rtol (the steps follow the motion: more or fewer output points change nothing)"
            + ("" if status == "budget" else ", and give max_wall_time= to keep what a long run reaches"))


def run_stats(run, monitors, init, seconds, **request):
    """The result's ``stats``: the run's counters (:meth:`Run.counters`), the formulation's
    evaluations and its own figures, the monitors', initialization's, the integration's
    ``cpu_time`` (``seconds``), what was asked (``request``: method, formulation, index) and,
    on a generated program, its ``fallbacks`` (evaluations whose guard failed: a law's branch
    or a singular solve, run on the numeric path)."""
    form = run.form
    stats = run.counters()
    stats.update(nfev=run.nfev, nlu=form.nlu + stats["nlu_integrator"], cpu_time=seconds, **request,
                 backend=form.system.backend, stabilization=form.stabilization,
                 projected_rows_dropped=list(init.dropped), init_iterations=init.iterations)
    stats.update(form.run_stats())
    if "fallbacks" in form.system.stats:  # evaluations a generated program handed to the numeric path
        stats["fallbacks"] = form.system.stats["fallbacks"]
    for m in monitors:
        stats.update(m.stats())
    for hook in run.hooks:
        stats.update(hook.stats())
    return stats


def hooks_for(run, monitors, progress, sensitivities=None):
    """The hooks of a run, in order: monitors (if any), outputs, the sensitivities (if asked:
    they read the step's dense output before a projection moves its end), projection (if the
    formulation projects), the choice of kept constraint rows (if rows were dropped:
    :class:`mbcomp.simulation.rows.RowChoice`), repartition, progress bar (if asked)."""
    hooks = [Monitoring(monitors)] if monitors else []
    hooks.append(KeepOutputs())
    if sensitivities is not None:
        hooks.append(sensitivities)
    if run.projects:
        hooks.append(Projection())
    mask = run.form.system.row_mask
    if mask is not None and not mask.all():
        hooks.append(RowChoice(run.form.system))
    hooks.append(Repartition())
    if progress:
        hooks.append(Progress(run.t_out[0], run.t_out[-1]))
    return hooks


def integrate(run, monitors, progress=False, extra=(), events=None, sensitivities=None):
    """Step ``run`` to its end; ``(status, message)``. Every way a run can stop early keeps
    the outputs of the accepted steps (see the module notes). ``extra`` hooks run after the
    usual ones: a :class:`~mbcomp.simulation.stepping.Budget` that runs out ends the run with
    ``"budget"``.

    With ``events`` (:class:`~mbcomp.hybrid.events.Events`) the run is integrated in
    segments: after every accepted step the events detect and locate the first event in it
    that acts (:meth:`~mbcomp.hybrid.events.Events.check`); the step is cut there (its hooks
    are not due), the outputs up to the event are kept from its dense output, the events act
    (:meth:`~mbcomp.hybrid.events.Events.act`: an impulse, a switch of mode, the end) and the
    next segment starts over the new active set with a new stepper -- or the run ends there
    with status ``"success"`` and the event's message.

    With ``sensitivities`` (:class:`~mbcomp.simulation.sensitivity.Sensitivities`) they are
    integrated over every accepted step right after its outputs are kept, and jump at every
    event's action."""
    hooks = run.hooks = hooks_for(run, monitors, progress, sensitivities) + list(extra)
    status, message = "success", "reached t_end"
    with sigterm_interrupts():
        try:
            run.start()
            if events is not None:
                events.arm(run.t, run.ys[0])
            while not run.done:
                if not run.advance():
                    continue
                cut = events.check(run) if events is not None else None
                if cut is None:
                    for hook in hooks:
                        hook(run)
                    continue
                run.keep_until(cut.t, cut.qu)  # the step's outputs up to the event
                jump = sensitivities.before_act(run, cut, events) if sensitivities is not None else None
                outcome = events.act(cut)
                if outcome.ends:
                    run.end_at(outcome.t, outcome.state)
                    message = outcome.message
                else:
                    run.begin_segment(outcome.form, outcome.t, outcome.y0)
                if sensitivities is not None:
                    sensitivities.after_act(run, jump, outcome, events)
        except BudgetSpent as exc:
            _keep_reached(run)
            status, message = "budget", f"{exc}; the results up to t={run.t_kept:g} s are kept"
        except SingularPosition as exc:  # results past the singular position are not valid
            run.trim(exc.t)
            status, message = "failed", str(exc)
        except (SimulationError, StepFailure) as exc:
            status, message = "failed", str(exc)
        except np.linalg.LinAlgError as exc:  # the framework's own solves, or a law's (then name the law)
            status, message = "failed", (law_failure(exc, run.t, run.t_kept) if raised_in_a_law(exc)
                                         else f"linear algebra failure: {exc}")
        except Exception as exc:  # noqa: BLE001 - a component's law raised: say who, keep the results
            status, message = "failed", law_failure(exc, run.t, run.t_kept)
        except KeyboardInterrupt:
            status, message = "interrupted", interruption("by Ctrl-C (KeyboardInterrupt)", run.t, run.t_kept)
        except Terminated:
            status, message = "interrupted", interruption("by SIGTERM", run.t, run.t_kept)
        finally:
            for hook in hooks:
                hook.close()
    return status, message
