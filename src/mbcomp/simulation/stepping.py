"""One integration: the stepper, the kept outputs, and what happens after every accepted step.

:class:`Run` holds the state of one integration of a formulation by a stepper class: the
stepper now stepping (a new one after a restart), the outputs kept so far (``[q, u]`` at
the output times), the counters. After every accepted step the driver calls the run's
hooks in order (:func:`mbcomp.simulation.driver.hooks_for` makes them), each a :class:`StepHook`:

1. :class:`Monitoring` -- the run monitors (:mod:`mbcomp.simulation.monitors`), before the
   step's outputs are kept;
2. :class:`KeepOutputs` -- interpolate the step's outputs from its dense output (projected
   when the formulation projects); then, in a run with sensitivities stepped with it,
   :class:`~mbcomp.simulation.sensitivity.Sensitivities` (they read the step's dense output
   before a projection moves its end);
3. :class:`Projection` -- move the state back onto the constraint manifold; the stepper
   continues from it or restarts (:meth:`mbcomp.solvers.base.Stepper.reset_state`);
4. :class:`~mbcomp.simulation.rows.RowChoice` -- when the kept constraint rows lose rank
   and others do not, keep those and restart the stepper;
5. :class:`Repartition` -- when the formulation must choose its coordinates again, restart
   the stepper from the state written in the new ones;
6. :class:`Progress` -- the progress bar;

and the driver's extra hooks after them: the stiffness hint
(:class:`~mbcomp.simulation.stiffness.StiffnessWatch`, explicit methods) and a
:class:`Budget` (``max_wall_time``, ``max_steps``).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.formulations import build
>>> from mbcomp.solvers import STEPPERS
>>> from mbcomp.simulation.stepping import KeepOutputs, Repartition, Run
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=1.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> form = build("lagrange", "ode", mbcomp.assemble(m))
>>> run = Run(form, STEPPERS["RK45"], np.linspace(0.0, 1.0, 3), np.zeros(2), rtol=1e-10, atol=1e-12)
>>> hooks = [KeepOutputs(), Repartition()]    # the driver's hooks_for for this run
>>> _ = run.start()
>>> while not run.done:
...     if run.advance():
...         for hook in hooks:
...             hook(run)
>>> np.round(np.array(run.ys)[:, 0], 6).tolist()    # s = -g t^2 / 2 at t = 0, 0.5, 1
[0.0, -1.22625, -4.905]
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import SimulationError
from ..solvers import STEPPERS
from .monitors import StepEnd

__all__ = ["Run", "StepHook", "Monitoring", "KeepOutputs", "Projection", "Repartition", "Progress", "Budget",
           "BudgetSpent"]


class Run:
    """The state of one integration.

    Parameters
    ----------
    form : Formulation
    stepper : type
        A :class:`~mbcomp.solvers.base.Stepper` class whose ``problem`` is ``form.problem``.
    t_out : ndarray
        Output times (s); the run ends at ``t_out[-1]``.
    y0 : ndarray
        Start state of the formulation (projected first when it projects).
    rtol, atol, max_step, h
        Stepper options (``h``: the first or fixed step, s).

    Attributes
    ----------
    stepper : Stepper
        The stepper now stepping; ``steppers`` lists every one made (restarts).
    ys : list of ndarray
        ``[q, u]`` at ``t_out[:len(ys)]``.
    t_prev : float
        Start of the last step (s).
    stats : dict
        ``steps`` (step attempts), ``restarts`` (by repartition), ``projections``.
    """

    def __init__(self, form, stepper, t_out, y0, *, rtol=1e-6, atol=1e-8, max_step=np.inf, h=None):
        self._forms = {}
        self.form, self.stepper_class, self.t_out = form, stepper, t_out
        self.options = dict(rtol=rtol, atol=atol, first_step=h, max_step=max_step)
        self.projects = bool(form.projects)
        t0 = t_out[0]
        self.t_prev = t0
        y = form.project(t0, y0) if self.projects else y0
        self.ys = [np.array(form.full(t0, y), dtype=float)]
        self.stats = dict(steps=0, restarts=0, projections=0)
        self.steppers = []
        self.stepper = None
        self._y_start = y
        self._dense = None
        self._end = None
        self.hooks = []  # what is done after every accepted step (set by the driver: mbcomp.simulation.driver.hooks_for)

    def start(self, t=None, y=None):
        """Make a new stepper at ``(t, y)`` (default: the run's start)."""
        t = self.t_out[0] if t is None else t
        y = self._y_start if y is None else y
        opts = dict(self.options, t_eval=self.t_out) if self.stepper_class.needs_outputs else self.options
        self.stepper = self.stepper_class(self.form, t, y, self.t_out[-1], **opts)
        self.steppers.append(self.stepper)
        return self.stepper

    @property
    def done(self):
        """Every output kept, or the stepper stopped."""
        return len(self.ys) >= len(self.t_out) or self.stepper.status != "running"

    @property
    def t(self):
        """Time reached (s): the end of the last accepted step."""
        return self.stepper.t if self.stepper is not None else self.t_out[0]

    @property
    def t_kept(self):
        """Time of the last output kept (s)."""
        return self.t_out[len(self.ys) - 1]

    def advance(self):
        """One step; ``True`` when it moved (its hooks are due), ``SimulationError`` when the
        stepper failed (its message names the cause)."""
        s = self.stepper
        if s.go_on_by is not None:  # the stepper asks another to go on from its state (auto -> radau5)
            s = self._hand_over(s)
        self.t_prev = s.t
        msg = s.step()
        if s.status == "failed":
            raise SimulationError(msg)
        self.stats["steps"] += 1
        self._dense = None
        return s.t != self.t_prev

    def _hand_over(self, s):
        """A new stepper of the kind ``s.go_on_by`` names, going on from ``s``'s state (the
        ODE variant of a DAE solver on an ODE form), the run's outputs and options as before."""
        nxt = STEPPERS[s.go_on_by]
        if self.form.problem == "ode" and hasattr(nxt, "on_ode"):
            nxt = nxt.on_ode()
        self.stepper_class = nxt
        return self.start(s.t, s.y)

    def step_end(self):
        """The :class:`~mbcomp.simulation.monitors.StepEnd` of the stepper's current state,
        made once per state: the run monitors and the choice of kept rows share its unmasked
        evaluation (a projection in between makes a new one)."""
        s = self.stepper
        key = (id(s), s.t, s.y.tobytes())
        if self._end is None or self._end[0] != key:
            self._end = (key, StepEnd(self.form.system, s.t, self.form.full(s.t, s.y)))
        return self._end[1]

    def step_dense(self):
        """The stepper's dense output ``y(t)`` inside the last step (made once per step)."""
        if self._dense is None:
            self._dense = self.stepper.dense_output()
        return self._dense

    def dense(self):
        """``[q, u](t)`` inside the last step."""
        d, full = self.step_dense(), self.form.full
        return lambda tt: full(tt, d(tt))

    def keep_until(self, t, qu):
        """Keep the outputs at output times up to ``t`` (s) from ``qu(t) -> [q, u]`` (projected
        when the formulation projects): a step cut at an event inside it. Every state is taken
        from ``qu`` before any is projected: ``qu`` reads the step's dense output in the
        formulation's coordinates, and a projection's ``initial_state`` may choose them again
        (D'Alembert's independent speeds: the outputs after the first were read over the wrong
        speeds, 6.5 J of a ladder's 28 J missing)."""
        form = self.form
        k0 = len(self.ys)
        times = self.t_out[k0: max(k0, int(np.searchsorted(self.t_out, t, side="right")))]
        for tk, y in [(tk, np.array(qu(tk), dtype=float)) for tk in times]:
            if self.projects:
                y = form.full(tk, form.project(tk, form.initial_state(tk, y[: form.nq], y[form.nq:])))
            self.ys.append(np.array(y, dtype=float))

    def begin_segment(self, form, t, y):
        """Integrate on from ``t`` (s) in a new segment: ``form`` (over the new active set of a
        hybrid run, :class:`mbcomp.hybrid.events.Outcome`) from its state ``y``, a new stepper."""
        self.form, self.projects = form, bool(form.projects)
        self.start(t, y)
        self.t_prev = t

    def end_at(self, t, state):
        """End the run at ``t`` (s), inside the output grid: ``state`` (``[q, u]``) is its last
        output (the outputs up to ``t`` kept first, :meth:`keep_until`)."""
        if self.t_out[len(self.ys) - 1] < t:
            self.t_out = np.append(self.t_out[: len(self.ys)], t)
            self.ys.append(np.array(state, float))
        else:
            self.t_out = self.t_out[: len(self.ys)]

    def trim(self, t):
        """Forget outputs after ``t`` (s); the start is always kept."""
        while len(self.ys) > 1 and self.t_out[len(self.ys) - 1] > t:
            self.ys.pop()

    @property
    def form(self):
        """The formulation now integrated (a change of mode at an event sets a new one)."""
        return self._form

    @form.setter
    def form(self, form):
        self._forms[id(form)] = form
        self._form = form

    @property
    def nfev(self):
        """Evaluations of every formulation the run has integrated (a run with events
        rebuilds its formulation at each change of mode)."""
        return sum(f.nfev for f in self._forms.values())

    def counters(self):
        """The run's work: ``steps``, ``restarts``, ``projections``, and the steppers' counters
        summed over restarts (``njev``, ``nlu_integrator``, ``nreject`` and ``nnewton`` where
        the steppers count them)."""
        out = dict(self.stats)
        total = {}
        for s in self.steppers:
            for key, val in s.stats.items():
                if key != "stiff_from":
                    total[key] = total.get(key, 0) + int(val)
        stiff = [s.stats["stiff_from"] for s in self.steppers if "stiff_from" in s.stats]
        if stiff:  # the time (s) from which the "auto" method went on by its stiff method
            out["stiff_from"] = min(stiff)
        out["restarts"] += total.get("restarts", 0)
        if "stretches" in total:  # a compiled stepper: one driver step is a stretch of its own steps
            out["steps"] += total["nsteps"] - total["stretches"] - total.get("python_steps", 0)
            out["stretches"] = total["stretches"]
            out["projections"] += total.get("c_projections", 0)  # made in the C loop
        out["njev"] = total.get("njev", 0)
        out["nlu_integrator"] = total.get("nlu", 0)
        out.update({key: total[key] for key in ("nreject", "nnewton", "python_steps") if key in total})
        return out


class StepHook:
    """Something done after every accepted step (``hook(run)``); ``close()`` when the run ends."""

    def __call__(self, run):  # pragma: no cover - abstract
        raise NotImplementedError

    def close(self):
        """Release what the hook holds (the progress bar)."""

    def stats(self):
        """What the hook reports in the result's ``stats`` (none by default)."""
        return {}


class Monitoring(StepHook):
    """The run monitors check the step's end state and its dense output."""

    def __init__(self, monitors):
        self.monitors = monitors

    def __call__(self, run):
        end = run.step_end()
        for m in self.monitors:
            m.check(end, run.t_prev, run.dense())


class KeepOutputs(StepHook):
    """Interpolate the outputs inside the step (projected when the formulation projects)."""

    def __call__(self, run):
        form, t_out, ys, t = run.form, run.t_out, run.ys, run.stepper.t
        given = run.stepper.step_outputs() if not run.projects else None
        if given is not None:  # the integrator's own states at the output times: kept at once
            ts, Ys = given
            k0, k1 = len(ys), int(np.searchsorted(t_out, t, side="right"))
            idx = np.searchsorted(ts, t_out[k0:k1])
            if idx.size and idx[-1] < len(ts) and np.array_equal(ts[idx], t_out[k0:k1]):
                ys.extend(form.full_many(t_out[k0:k1], Ys[idx]).astype(float))
        while len(ys) < len(t_out) and t_out[len(ys)] <= t:
            tk = t_out[len(ys)]
            yk = run.step_dense()(tk)
            ys.append(np.array(form.full(tk, projected_output(run, tk, yk) if run.projects else yk), dtype=float))


#: an output's projection moving the state by more than this many times the tolerance is refused
OUTPUT_PROJECTION_LIMIT = 1e3


def projected_output(run, t, y):
    """The dense-output state ``y`` at output time ``t`` projected onto the constraints -- or
    ``y`` itself where the projection would move it by more than
    :data:`OUTPUT_PROJECTION_LIMIT` times ``atol + rtol |y|`` (counted in
    ``stats["refused_projections"]``). The dense output is accurate to the tolerance (the
    Cardan shafts' within 2 tolerances, the driven slider-crank's 90), so a correction far
    beyond it is a Newton step along a nearly singular direction (an output 6e-4 s after a
    four-bar's flat position went 0.07 J off in energy, the passage itself and the steps
    unharmed). The Cardan runs' outputs sat 1e9 tolerances off while the compiled loop
    projected its steps with the drive's values of another time; it no longer does
    (:meth:`mbcomp.codegen.evaluator.ProgramEvaluator.integrator`)."""
    yp = run.form.project(t, y)
    scale = run.options["atol"] + run.options["rtol"] * np.abs(y)
    if np.max(np.abs(yp - y) / scale, initial=0.0) <= OUTPUT_PROJECTION_LIMIT:
        return yp
    run.stats["refused_projections"] = run.stats.get("refused_projections", 0) + 1
    return y


class Projection(StepHook):
    """Move the state back onto the constraint manifold; the stepper continues from it."""

    def __call__(self, run):
        s = run.stepper
        s.reset_state(run.form.project(s.t, s.y))
        run.stats["projections"] += 1


class Repartition(StepHook):
    """Restart from the state written in newly chosen coordinates, when the formulation asks."""

    def __call__(self, run):
        s = run.stepper
        if run.form.needs_repartition(s.t, s.y):
            y = run.form.repartition(s.t, s.y)
            if y is not None:  # new coordinates: the stepper's history is in the old ones
                run.start(s.t, y)
                run.stats["restarts"] += 1


class Progress(StepHook):
    """A progress bar (tqdm) in simulated seconds, shown when the run lasts over two seconds.

    The bar (and tqdm, ~0.1 s to import) is made at the first step after those two seconds
    of wall time, starting at the simulated time reached by then: a short run never imports
    tqdm.
    """

    #: wall time (s) before the bar appears
    delay = 2.0

    def __init__(self, t0, t1):
        self.t0, self.total = float(t0), float(t1 - t0)
        self.started = time.time()
        self.bar = None

    def __call__(self, run):
        if self.bar is not None:
            self.bar.update(float(run.stepper.t - run.t_prev))
        elif time.time() - self.started >= self.delay:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=self.total, initial=float(run.stepper.t) - self.t0, unit="s sim", leave=False,
                            disable=None, bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]")
            self.bar.start_t = self.started  # elapsed and remaining time count from the run's start
            self.bar.refresh()

    def close(self):
        if self.bar is not None:
            self.bar.close()


class BudgetSpent(Exception):
    """A run's wall-time or step budget ran out (raised by :class:`Budget`; the driver ends
    the run with status ``"budget"`` and keeps every output)."""


class Budget(StepHook):
    """Ends the run when its wall time (s, from the hook's creation) or its step count (the
    integrator's steps, :meth:`Run.counters`) reaches the budget. Checked after every
    driver step: a compiled stepper's stretch (up to 16 output intervals in one C call) may
    overshoot the budget by one stretch, a run acting on its impacts in C by up to
    ``IMPACT_STRETCHES`` (8) of them (:mod:`mbcomp.hybrid.steppers`).

    Parameters
    ----------
    max_wall_time : float or None
        Seconds of wall time.
    max_steps : int or None
        Integrator steps (accepted and rejected attempts as each stepper counts them).
    """

    def __init__(self, max_wall_time=None, max_steps=None):
        self.max_wall_time, self.max_steps = max_wall_time, max_steps
        self.started = time.perf_counter()

    def __call__(self, run):
        if self.max_wall_time is not None:
            spent = time.perf_counter() - self.started
            if spent >= self.max_wall_time:
                raise BudgetSpent(f"the wall-time budget of {self.max_wall_time:g} s ran out at t={run.t:g} s "
                                  f"(of {run.t_out[-1]:g} s; {spent:.3g} s spent)")
        if self.max_steps is not None:
            steps = run.counters()["steps"]
            if steps >= self.max_steps:
                raise BudgetSpent(f"the step budget of {self.max_steps} steps ran out at t={run.t:g} s "
                                  f"(of {run.t_out[-1]:g} s)")
