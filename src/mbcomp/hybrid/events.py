"""Events in a run: zero crossings located on the dense output, actions, modes, chattering.

After every accepted step :class:`Events` evaluates every event function at the step's end
(the start's values are kept from the step before) and, where one changed sign in its
declared direction, locates the root on the stepper's dense output by Brent's method to
``|dt| <= min(1e-12, rtol / 1000) max(1, |t|)`` (:mod:`mbcomp.solvers.locate`, shared with the
singularity monitors). Several roots in one step are taken
earliest first:

* a user's event (``simulate(..., events=[f])``, scipy's convention: ``f(t, y)`` with
  ``y = [q, u]`` in ``system.q_names + system.u_names``, attributes ``terminal`` (bool or a
  count) and ``direction``) is recorded; a terminal one ends the run there with status
  ``"success"`` and the message ``"event <name> at t=..."``, the event's state the last output;
* a component's event (:meth:`mbcomp.modeling.modes.Modes.events`) gets the component's
  action (:mod:`mbcomp.modeling.events`): an impact (the impulse equations,
  :func:`mbcomp.hybrid.stops.impact_speeds`), a switch of mode, or the end of the run;
* an engaged row's push (its multiplier) falling through zero is the component's
  ``"release"`` event.

The run is integrated in *segments* (:func:`mbcomp.simulation.driver.integrate`), as scipy's
``solve_ivp`` and diffrax do: after every accepted step the driver asks :meth:`Events.check`
for the first event in the step that acts (detect, locate); it keeps the outputs up to the
event from the step's dense output (:meth:`mbcomp.simulation.stepping.Run.keep_until`), then
:meth:`Events.act` acts (an impulse, a switch of mode, the end of the run) and returns an
:class:`Outcome`: the run's end, or the next segment -- the state moved onto the new active
set's rows (:func:`~mbcomp.hybrid.stops.consistent`) and the formulation built over its
system -- from which the driver starts a new stepper. The events never touch the run.

An impact whose rebound would rise less than :data:`REST_HEIGHT` times ``atol`` above the
limit settles in the engaged mode (a ball at rest), and so does a component whose impacts
come ever closer in time (:data:`CHATTER` intervals each shorter than the one before: a Zeno
accumulation) if it has a resting mode (``Modes.rest``); without one the run fails naming it.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=1.0)); b = m.add("b", PointMass(m=1.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> def ground(t, y):
...     return y[0]
>>> ground.terminal, ground.direction = True, -1
>>> r = mbcomp.simulate(m, t_end=2.0, rtol=1e-10, atol=1e-12, events=[ground])
>>> r.status, bool(abs(r.events[0].time - np.sqrt(2 / 9.81)) < 1e-9), r.message
('success', True, 'event ground at t=0.451523640986 s')
"""
from __future__ import annotations

import numpy as np

from ..assembly.kkt import accelerations
from ..errors import SimulationError
from ..modeling.events import ContactRow, End, Impact, SlipSpeed, Switch
from .contacts import (contact_impact, contact_pushes, contact_rows, event_value, inward_gap_acceleration,
                       touching_at_start)
from ..solvers.locate import return_root, root, time_tolerance
from ..assembly.conservation import impulse_work
from .active import (SegmentStart, mode_rows, mode_system, open_joints, rows_in_force, slipping_joints, start_modes,
                     with_mode_forces)
from .outcomes import Cut, EventRecord, Outcome
from .stops import consistent, impact_speeds, row_push, row_values
from .slip import SPIN_SPAN, SPIN_TURNS, SlideEvents, tangent_rows, with_slip_friction
from .c_loop import CLoop
from .friction import row_events

__all__ = ["EventRecord", "Events", "Cut", "Outcome", "REST_HEIGHT", "CHATTER", "BURST", "BURST_SPAN",
           "SPIN_TURNS", "SPIN_SPAN"]

#: an impact whose rebound rises less than this times ``atol`` (m or rad) settles engaged
REST_HEIGHT = 10.0
#: this many successive shrinking intervals between a component's impacts are chattering
CHATTER = 30
#: this many events of one component within BURST_SPAN max(1, |t|) seconds are chattering (an error naming it)
BURST, BURST_SPAN = 60, 1e-9


def _crossed(g0, g1, direction):
    if direction <= 0 and g0 >= 0.0 > g1:
        return True
    return direction >= 0 and g0 <= 0.0 < g1


class Events(CLoop, SlideEvents):
    """The events of one run (see the module notes).

    Parameters
    ----------
    system : MultibodySystem
        Initialized (the modes' systems are variants of it).
    make_form : callable
        ``make_form(system) -> Formulation``: the run's formulation over a mode's system.
    user : list of callables
        scipy-style event functions ``f(t, y)``, ``y = [q, u]``.
    rtol, atol : float
        The run's tolerances (location tolerance; the resting threshold).
    """

    def __init__(self, system, make_form, user=(), rtol=1e-8, atol=1e-10):
        self.system, self.make_form = system, make_form
        self.modes = start_modes(system)
        self.user = list(user)
        self.user_left = [_terminal_count(f) for f in self.user]
        self.rtol, self.atol = rtol, atol
        self.records = []
        self._systems, self._hits = {}, {}
        self._g0 = None
        self._fresh = self._last = None  # the event just handled (its function starts at zero)
        self._c_keys, self._checked = [], set()  # the events the C loop watches (c_watch); (joint, mode) checked
        self.stats = dict(events=0, event_evaluations=0, mode_changes=0)
        self.slip_dirs = {}  # {sliding contact: the unit direction (tangent coordinates) its slide started with}
        self.segments = []  # [SegmentStart]: the run's start and every event's next segment (the columns)
        self._slip_keys, self._gap_keys, self._before, self._slip_peak = set(), set(), None, {}
        self.slide_worked, self.work_log, self._worked_to = 0.0, [], None  # the sliding friction's work (J)

    @property
    def active(self):
        """Whether there is anything to watch."""
        return bool(self.modes or self.user)

    def system_now(self, modes=None, dirs=None):
        """The system of ``modes`` (default: the current ones) and sliding contacts' start
        directions ``dirs`` (default: the current ones), made once per set of both."""
        modes = self.modes if modes is None else modes
        dirs = self.slip_dirs if dirs is None else dirs
        sliding = slipping_joints(self.system, modes)
        key = (tuple(sorted(modes.items())), tuple((n, tuple(dirs.get(n, ()))) for n in sliding))
        if key not in self._systems:
            if len(self._systems) > 256:  # many slides, each with its direction: keep the cache small
                self._systems.clear()
            self._systems[key] = with_slip_friction(with_mode_forces(mode_system(self.system, modes), modes),
                                                    self.system, modes, dirs)
        return self._systems[key]

    # --- the event functions ---------------------------------------------------------------
    def _functions(self):
        """``{key: direction}`` of every event function in the current modes."""
        out = {}
        sysm = self.system
        for name, mode in self.modes.items():
            e = sysm.edge(name)
            qj = np.zeros(e.q.stop - e.q.start)
            declared = self._declared(name, mode)
            for ev_name, _, direction in declared.events(qj, np.zeros(e.u.stop - e.u.start), mode):
                out[("joint", name, ev_name)] = direction
            for row in declared.rows(mode):
                out.update(dict.fromkeys(row_events(name, row, 0.0), -1))
        for i, f in enumerate(self.user):
            if self.user_left[i] != 0:
                out[("user", i, getattr(f, "__name__", f"event{i}"))] = float(getattr(f, "direction", 0.0))
        return out

    def values(self, t, qu):
        """``{key: value}`` of every event function at ``(t, [q, u])``."""
        self.stats["event_evaluations"] += 1
        sysm = self.system
        q, u = sysm.normalize(qu[: sysm.nq]), qu[sysm.nq: sysm.nq + sysm.nu]
        out = {}
        rows = None
        for name, mode in self.modes.items():
            e = sysm.edge(name)
            declared = self._declared(name, mode)
            for ev_name, value, _ in declared.events(q[e.q], u[e.u], mode):
                if isinstance(value, SlipSpeed):  # a slide's speed along its start direction
                    self._slip_keys.add(("joint", name, ev_name))
                    v_t = tangent_rows(sysm, name, t, q, u)[1]
                    self._slip_peak[name] = max(self._slip_peak.get(name, 0.0), float(np.linalg.norm(v_t)))
                    out[("joint", name, ev_name)] = float(v_t @ self.slip_dirs[name])
                else:
                    if isinstance(value, ContactRow):  # an open contact's gap (m)
                        self._gap_keys.add(("joint", name, ev_name))
                    out[("joint", name, ev_name)] = event_value(sysm, name, value, t, q, u)
            if declared.rows(mode):
                rows = self._pushes(t, q, u) if rows is None else rows
                out.update(rows[name])
        for i, f in enumerate(self.user):
            if self.user_left[i] != 0:
                out[("user", i, getattr(f, "__name__", f"event{i}"))] = float(f(t, np.concatenate((q, u))))
        return out

    def _pushes(self, t, q, u):
        """``{joint: {("release", joint, row): push}}`` of the engaged rows (N or N m)."""
        held = mode_rows(self.system, self.modes)
        out = contact_pushes(self.system, self.system_now(), self.modes, t, q, u)  # a closed contact's normal row
        if not held:
            return out
        first = self.system_now().evaluate(t, q, u).Phi.size - len(held)  # the rows are appended
        push = row_push(self.system_now(), t, q, u, first, len(held))
        for (name, row, _, _), p in zip(held, push):
            out.setdefault(name, {}).update(row_events(name, row, float(p)))
        return out

    def arm(self, t, qu):
        """Take the event functions' values at the start of the next step."""
        self._g0 = self.values(t, qu)

    # --- after a step ----------------------------------------------------------------------
    def check(self, run):
        """Detect and locate the events in the last accepted step of ``run`` (read only): the
        first that acts, a :class:`Cut` (the step's other hooks are then not due; the driver
        keeps the outputs up to it and calls :meth:`act`), or None. Events that do not act (a
        user's non-terminal event, an impact not closing) are recorded on the way."""
        if getattr(run.stepper, "watched_step", False):  # the C loop watched this stretch
            return self._located(run)
        dense_y = run.step_dense()
        full = run.form.full

        def qu(tt):
            return full(tt, dense_y(tt))

        t0, t1 = run.t_prev, run.stepper.t
        if self._g0 is None:  # the steps before were watched in C
            self._g0 = self.values(t0, qu(t0))
        g1 = self.values(t1, full(t1, run.stepper.y))
        dirs = self._functions()
        hits = []
        fresh, self._fresh = self._fresh, None
        for key, d in dirs.items():
            a, b = self._g0.get(key), g1.get(key)
            if a is None or b is None:
                continue
            if key == fresh and d != 0 and d * b > 0:  # left its zero at t0 and came back in this step
                hits.append((self._returned(key, qu, t0, t1, d), key))
            elif _crossed(a, b, d):
                hits.append((self._locate(key, qu, t0, t1, a, b), key))
        self._not_inside(t0, t1, g1, hits)
        for t_e, key in sorted(hits):
            self._slide_work(run, qu, t_e)
            cut = self._decide(key, t_e, qu)
            if cut is not None:
                return cut
        self._slide_work(run, qu, t1)
        self._g0 = g1
        return None

    def _not_inside(self, t0, t1, g1, hits):
        """Fail where an open contact's gap was below zero through a whole step ``[t0, t1]``
        (values ``g1`` at its end; ``hits``: the crossings found in it): the body passed into
        what it touches without the touch event (the gap falling through zero) firing."""
        depth = REST_HEIGHT * self.atol
        for key in self._gap_keys & set(g1):
            if g1[key] < -depth and self._g0.get(key, 0.0) < -depth and key not in {k for _, k in hits}:
                raise SimulationError(f"{key[1]}: open, it is {-g1[key]:.3g} m inside what it touches at t={t1:.9g} "
                                      f"s (and was at t={t0:.9g} s) without having touched it: the body passes "
                                      "through -> report this model: the run lost the contact's touch-down")

    def _located(self, run):
        """:meth:`check` of a stretch the C loop watched: the event it located (the stretch
        ends there) decided as in Python; one that does not act lets the stepper's next step
        go past it on the Python path."""
        self.take_c_impacts(getattr(run.stepper, "impacts_done", ()))  # acted on in the C loop
        self._fresh, self._g0 = None, None
        hit = run.stepper.hit
        if hit is None:
            return None
        which, t_e = hit
        qu = run.dense()
        cut = self._decide(self._c_keys[which], t_e, qu)
        if cut is None:
            run.stepper.step_python_once()
        return cut

    def _locate(self, key, qu, t0, t1, g0, g1):
        """The root of event function ``key`` in ``[t0, t1]`` (s) on the step's dense output
        (:func:`mbcomp.solvers.locate.root`)."""
        return root(lambda tt: self.values(tt, qu(tt))[key], t0, t1, g0, g1, tol=time_tolerance(t1, self.rtol))

    def _returned(self, key, qu, t0, t1, d):
        """The return through zero of event function ``key``, which left it at ``t0`` (the
        event just handled) and is back on its far side at ``t1``: Brent's root between the
        function's extreme on the leaving side and ``t1`` (``t0`` when it never left;
        :func:`mbcomp.solvers.locate.return_root`)."""
        return return_root(lambda tt: self.values(tt, qu(tt))[key], t0, t1, d, tol=time_tolerance(t1, self.rtol))

    def _decide(self, key, t_e, qu):
        """The :class:`Cut` of event ``key`` at ``t_e`` if it acts, else None (recorded if it
        is a user's)."""
        kind, who, name = key
        if kind == "user":
            self.records.append(EventRecord(t_e, "user", name, "user", {}))
            self.stats["events"] += 1
            if self.user_left[who] > 0:
                self.user_left[who] -= 1
                if self.user_left[who] == 0:
                    return Cut(t_e, qu, key, np.array(qu(t_e), float))
            return None
        comp, p = self.system.edge(who).comp, self.system.P[who]
        action = comp.modes(p).action("release" if kind == "release" else name, self.modes[who])
        state = qu(t_e)
        self._before = np.array(state, float)
        if key in self._slip_keys:
            turn = self._turns(who, t_e, state)
            if turn is not None:
                return Cut(t_e, qu, key, state, turn=turn)
        if isinstance(action, Impact) and not self._approaching(who, action, state, t_e):
            if key != self._last:
                return None
            # back at the limit right after leaving it, too slow to tell apart: at rest there
            action = Switch(comp.modes(p).rest(name, self.modes[who]) or self.modes[who])
        if action is None:
            return None
        return Cut(t_e, qu, key, state, action)

    def act(self, cut):
        """Act on the event ``cut`` (:meth:`check`; the driver has kept the outputs up to it):
        the :class:`Outcome` -- the run's end, or the next segment over the new active set."""
        (kind, who, name), t_e, state, action = cut.key, cut.t, cut.state, cut.action
        if kind == "user":
            return Outcome(t_e, state, message=f"event {name} at t={t_e:.12g} s")
        nq = self.system.nq
        if cut.turn is not None:  # a plane slide turned: it slides on along the new direction
            self.slip_dirs = {**self.slip_dirs, who: cut.turn}
            self._record(t_e, who, name, "turn", {"mode": self.modes[who], "energy_loss": 0.0})
            return self._segment(t_e, state[:nq], state[nq:], dict(self.modes))
        if isinstance(action, End):
            self._record(t_e, who, name, "end", {"reason": action.reason})
            return Outcome(t_e, np.array(state, float), message=f"{who}: {action.reason} (event {name} at t={t_e:.12g} s)")
        modes = dict(self.modes)
        q, u = state[:nq], state[nq:]
        if isinstance(action, Switch):
            modes[who] = action.mode
            self._record(t_e, who, name, "release" if kind == "release" else "switch",
                         {"mode": action.mode, "energy_loss": 0.0})
        elif isinstance(action, Impact):
            u, settle = self._impact(t_e, who, name, action, q, u)
            if settle is not None:
                modes[who] = settle
        out = self._segment(t_e, q, u, modes)
        self._fresh = self._last = cut.key
        return out

    # --- for the sensitivities' jumps (mbcomp.simulation.sensitivity) -------------------------
    def event_value(self, key, t, qu):
        """The value of event function ``key`` (a :attr:`Cut.key`) at ``(t, [q, u])`` in the
        current modes."""
        return float(self.values(t, np.asarray(qu, float))[key])

    def reset(self, cut, qu, before, after):
        """``[q, u]`` right after the action of ``cut`` from the state ``qu`` before it, as
        :meth:`act` made it: an impact's impulse map over the system of the active set
        ``before`` (the action read again from this run's parameters: a twin's restitution,
        :meth:`twin`), then the state made consistent with the active set ``after``. Nothing is
        recorded and the modes stay."""
        (kind, who, name), action = cut.key, cut.action
        nq, t = self.system.nq, float(cut.t)
        q, u = np.asarray(qu[:nq], float), np.asarray(qu[nq:], float)
        if isinstance(action, Impact):
            action = self.system.edge(who).comp.modes(self.system.P[who]).action(name, before[who])
            u = self._impact_map(t, who, action, q, u, before)[0]
        q, u = consistent(self.system_now(after), t, q, u)
        return np.concatenate((q, u))

    def twin(self, params):
        """Events like these (the same modes and slide directions) over a numeric copy of the
        system with ``params`` (``{"component.param": value}``) changed: where the
        sensitivities read the event functions and actions at perturbed parameters."""
        other = Events(self.system.with_evaluator(None).with_params(params), self.make_form, self.user, self.rtol,
                       self.atol)
        other.modes, other.slip_dirs = dict(self.modes), dict(self.slip_dirs)
        return other

    def holds_rows(self):
        """Whether the current active set holds rows or applies forces of its own (an engaged
        stop, a stuck or slipping friction, a sliding contact): the system stepped then is not
        the assembled one with rows only taken out."""
        rows = rows_in_force(self.system, self.modes)
        return bool(rows.held or rows.sliding or rows.forces)

    def _impact_map(self, t, who, action, q, u, modes):
        """``(u+, kinetic energy lost (J), normal speed after (m/s) or None)`` of an impact of
        ``who`` (action ``action``) at ``(t, q, u-)`` over the system of the active set ``modes``
        before it (its rows hold through the impact): a contact touching down on its own rows
        (:func:`~mbcomp.hybrid.contacts.contact_impact`; the speed after is its normal row's),
        a joint on the rows of its engaged mode (:func:`~mbcomp.hybrid.stops.impact_speeds`;
        None). The one impulse map of :meth:`act` and of :meth:`reset`."""
        before = self.system_now(modes)
        if not self.system.edge(who).comp.tree_edge:
            row = _contact_row(self.system, who, action.engage)
            u_plus, _, loss, after = contact_impact(before, who, t, q, u, action.restitution, row,
                                                    friction=self._cone(who, action.engage))
            return u_plus, loss, after
        rows = list(mode_rows(self.system, {who: action.engage}))
        u_plus, _, loss = impact_speeds(before, t, q, u, rows, action.restitution)
        return u_plus, loss, None

    def _approaching(self, who, action, state, t=0.0):
        """Whether the impact's rows close (a negative speed along them) at ``state``."""
        if not self.system.edge(who).comp.tree_edge:  # a contact: its normal row's rate
            row = _contact_row(self.system, who, action.engage)
            nq = self.system.nq
            return contact_rows(self.system, who, t, state[:nq], state[nq:], row).speed < 0.0
        rows = mode_rows(self.system, {who: action.engage})
        _, speed, _ = row_values(self.system, rows, state[: self.system.nq], state[self.system.nq:])
        return bool(np.any(speed < 0.0))

    def _record(self, t, who, name, kind, detail):
        self.records.append(EventRecord(float(t), who, name, kind, detail))
        self.stats["events"] += 1
        burst = [r for r in self.records[-BURST:] if r.component == who]
        if len(burst) == BURST and burst[-1].time - burst[0].time <= BURST_SPAN * max(1.0, abs(t)):
            modes = sorted({str(r.detail.get("mode")) for r in burst if r.detail.get("mode") is not None})
            raise SimulationError(
                f"chattering: {who} changed mode {BURST} times within {burst[-1].time - burst[0].time:.3g} s at "
                f"t={t:.9g} s (events {', '.join(sorted({r.name for r in burst}))}; modes {', '.join(modes)}): its "
                "modes do not settle there -> look at what drives it at that instant (a load at the friction "
                "limit, a contact at the edge of lifting off), or loosen the model (a compliant contact, "
                "friction regularized by BearingFriction)")

    def _impact(self, t, who, name, action, q, u):
        """``(u+, mode to settle in or None)`` of an impact of ``who`` at event ``name``."""
        sysm, p = self.system, self.system.P[who]
        u_plus, loss, after0 = self._impact_map(t, who, action, q, u, self.modes)
        if not sysm.edge(who).comp.tree_edge:  # a contact touching down: its own rows
            row = _contact_row(sysm, who, action.engage)
            speed, after = [contact_rows(sysm, who, t, q, u, row).speed], [after0]

            def rests():
                return self._contact_rests(t, q, u_plus, who, row, after0)
        else:
            rows = list(mode_rows(sysm, {who: action.engage}))
            _, speed, _ = row_values(sysm, rows, q, u)
            _, after, _ = row_values(sysm, rows, q, u_plus)

            def rests():
                return self._rests(t, q, u_plus, rows, after)
        self._record(t, who, name, "impact", {"speed_before": float(speed[0]), "speed_after": float(after[0]),
                                              "energy_loss": loss, "restitution": action.restitution,
                                              "drive_work": impulse_work(self.system_now(), t, q, u, u_plus, loss)})
        hits = self._hits.setdefault(who, [])
        hits.append(t)
        settle = None
        if action.restitution == 0.0 or rests():
            settle = action.engage
        elif _chattering(hits):
            settle = sysm.edge(who).comp.modes(p).rest(name, self.modes[who])
            span = hits[-1] - hits[-CHATTER - 1]
            if settle is None:
                raise SimulationError(f"chattering: {who} hit {name!r} {len(hits)} times, the last {CHATTER} in "
                                      f"{span:.3g} s, ever faster (a Zeno accumulation at about t={t:.9g} s) and "
                                      f"has no resting mode -> give {who}'s modes a rest, or damp the motion")
        if settle is not None:  # the rebound's energy goes with it: counted when the state is made consistent
            self._record(t, who, name, "engage" if action.restitution == 0.0 else "rest",
                         {"mode": settle, "energy_loss": 0.0})
            self.stats["mode_changes"] += 1
        return u_plus, settle

    def _rests(self, t, q, u_plus, rows, after):
        """Whether the rebound (speeds ``after`` on ``rows``) would rise less than
        :data:`REST_HEIGHT` ``atol`` against the acceleration pressing into the rows."""
        sysm = self.system_now()
        ud, _ = accelerations(sysm.evaluate(t, q, u_plus))
        _, _, C = row_values(self.system, rows, q, u_plus)
        acc = C @ ud
        return bool(np.all(acc < 0.0) and np.all(after ** 2 <= -2.0 * acc * REST_HEIGHT * self.atol))

    def _contact_rests(self, t, q, u_plus, who, row, after):
        """Whether contact ``who``'s rebound (its normal speed ``after``, m/s) would rise less
        than :data:`REST_HEIGHT` ``atol`` against its gap's acceleration in flight."""
        sysm = self.system_now()
        ud, _ = accelerations(sysm.evaluate(t, q, u_plus))
        cr = contact_rows(self.system, who, t, q, u_plus, row)
        acc = float(cr.C[0] @ ud + cr.bias[0])
        return acc < 0.0 and after ** 2 <= -2.0 * acc * REST_HEIGHT * self.atol

    def _segment(self, t, q, u, modes):
        """The next segment, from ``t`` at ``(q, u)`` in ``modes`` (an :class:`Outcome`): the
        active set settled (contacts that would pull open, landings that slip slide, stuck
        frictions that cannot hold break away), the state made consistent with its rows, the
        formulation built over its system; the event functions armed there."""
        modes = self._sliding_now(t, q, u, self._open_pulling(t, q, u, modes))
        new, u0 = self.system_now(modes), u
        going_on = set(slipping_joints(self.system, self.modes)) & set(slipping_joints(self.system, modes))
        q, u = consistent(new, t, q, u)
        modes, new = self._break_away(t, q, u, modes)
        if any(p < 0.0 for d in self.pushes_in(new, modes, t, q, u).values() for p in d.values()):
            for n in sorted(n for n in modes if modes[n] != self.modes.get(n)):  # the log says it stays
                self._record(t, n, "pull", "release", {"mode": self.modes[n], "energy_loss": 0.0})
            modes, new = dict(self.modes), self.system_now()  # an engaged row that would pull: stay free
            q, u = consistent(new, t, q, u)
        self.slip_dirs = self._directions(t, q, u, modes, going_on)
        new = self.system_now(modes)
        self._let_go_outward(t, q, u, new, modes)
        self.modes = modes
        self.segments.append(SegmentStart(float(t), dict(modes), dict(self.slip_dirs), self._before,
                                          np.concatenate((q, u))))
        self._worked_to = t
        if self.records and "energy_loss" in self.records[-1].detail and self.records[-1].kind != "impact":
            M = new.evaluate(t, q, u0).M
            self.records[-1].detail["energy_loss"] = loss = float(0.5 * (u0 @ M @ u0 - u @ M @ u))
            self.records[-1].detail["drive_work"] = impulse_work(new, t, q, u0, u, loss)
        form = self.make_form(new)
        y0 = form.initial_state(t, q, u)
        self.arm(t, np.concatenate((q, u)))
        return Outcome(float(t), np.concatenate((q, u)), form, y0)

    def start(self, form, y0, t, q, u):
        """``(form, y0)``, the run's formulation and initial state at its start ``t``, or, when
        a stuck friction cannot hold there (:meth:`_break_away`), those of the mode it breaks
        away to; a contact touching there has its impact, engages (sliding if it slips) or
        lets go at once (:meth:`_touching_at_start`, :meth:`_sliding_now`, :meth:`_open_pulling`)."""
        u0 = u
        u, modes = self._touching_at_start(t, q, u)
        modes = self._sliding_now(t, q, u, self._open_pulling(t, q, u, self._rolling_at_start(t, q, u, modes)))
        going_on = set(slipping_joints(self.system, modes))  # a start with a slip speed
        if modes != self.modes:
            q, u = consistent(self.system_now(modes), t, q, u)
        modes, new = self._break_away(t, q, u, modes)
        self.slip_dirs = self._directions(t, q, u, modes, going_on)
        new = self.system_now(modes, self.slip_dirs)
        if modes != self.modes or form.system is not new or u is not u0:
            self.modes = modes
            q, u = consistent(new, t, q, u)
            self._let_go_outward(t, q, u, new, modes)
            form = self.make_form(new)
            y0 = form.initial_state(t, q, u)
        self.segments = [SegmentStart(float(t), dict(self.modes), dict(self.slip_dirs), None, np.concatenate((q, u)))]
        self.slide_worked, self.work_log, self._worked_to = 0.0, [(float(t), 0.0)], t
        return form, y0

    def _touching_at_start(self, t, q, u):
        """``(u, modes)`` at the start with the contacts that start open but touch (their gap
        within :data:`REST_HEIGHT` ``atol`` of zero, where their touch event could not fire:
        :func:`~mbcomp.hybrid.contacts.touching_at_start`, an error for one inside beyond it)
        and the stops that start free at a limit (:meth:`_stops_touching`): one closing has
        its impact now, one at rest there (its rebound too small, :meth:`_contact_rests`,
        :meth:`_rests`) engages, one leaving stays open."""
        modes = dict(self.modes)
        tol = REST_HEIGHT * self.atol
        for who, name, action, row, _, speed in (touching_at_start(self.system, self.modes, t, q, u, tol)
                                                 + self._stops_touching(t, q, u, tol)):
            if not isinstance(action, Impact):
                continue
            settle = None
            if speed < 0.0:
                u, settle = self._impact(t, who, name, action, q, u)
                self._fresh = self._last = ("joint", who, name)  # a rebound may come back in the first step
            elif (self._contact_rests(t, q, u, who, row, speed) if row is not None else
                  self._rests(t, q, u, mode_rows(self.system, {who: action.engage}), np.array([speed]))):
                settle = action.engage
                self._record(t, who, name, "engage", {"mode": settle, "energy_loss": 0.0})
            if settle is not None:
                modes[who] = settle
        return u, modes

    def _let_go_outward(self, t, q, u, sysm, modes):
        """Fail where a contact let go at ``t`` (a ``release`` recorded there, open in ``modes``,
        the system ``sysm``) would accelerate into what it touched
        (:func:`~mbcomp.hybrid.contacts.inward_gap_acceleration`): no mode is consistent there."""
        released = {r.component for r in self.records if r.time == t and r.kind == "release"}
        for n in sorted(released & set(open_joints(self.system, modes))):
            if self.system.edge(n).comp.tree_edge:
                continue
            a = inward_gap_acceleration(self.system, sysm, n, t, q, u)
            if a is not None:
                raise SimulationError(
                    f"{n}: let go at t={t:.9g} s, but open it accelerates into what it touches ({a:.3g} m/s^2) while "
                    "closed it would pull: its normal force fell to zero with its rolling rows still holding a "
                    "tangential load (rows that never slip need an unbounded friction coefficient there), so no "
                    "mode is consistent (a Painleve-like contradiction) -> give the contact Coulomb friction "
                    "(friction=ContactFriction(mu_s, mu_k)) so it slides before it lifts off")

    def _stops_touching(self, t, q, u, tol):
        """``[(joint, event, action, None, value, speed)]`` of the stops free at the start whose
        impact event's value (m or rad from the limit) is within ``tol`` of zero, ``speed``
        along the row it would engage (a start beyond a limit is a model problem: the stop's
        ``check_params``). At a limit exactly its event starts at zero and is located at the
        start, where an impact at speed 0 was dropped: the joint went through its stop."""
        out = []
        for who, mode in self.modes.items():
            e = self.system.edge(who)
            if not e.comp.tree_edge:
                continue
            declared = self._declared(who, mode)
            for name, value, _ in declared.events(q[e.q], u[e.u], mode):
                action = declared.action(name, mode)
                if isinstance(action, Impact) and abs(float(value)) <= tol:
                    _, speed, _ = row_values(self.system, mode_rows(self.system, {who: action.engage}), q, u)
                    out.append((who, name, action, None, float(value), float(speed[0])))
        return out

    def _break_away(self, t, q, u, modes):
        """``(modes, system)``: a stuck friction's row (:class:`~mbcomp.modeling.events.StickRow`)
        whose push is beyond its limit at ``(t, q, u)`` in ``modes`` breaks away at once to
        the mode its joint's ``Modes.action("break+" or "break-")`` names (recorded as a switch)."""
        for name, d in self.pushes_in(self.system_now(modes), modes, t, q, u).items():
            broken = sorted((v, key[2]) for key, v in d.items() if key[0] == "joint" and v < 0.0)
            if broken:
                action = self.system.edge(name).comp.modes(self.system.P[name]).action(broken[0][1], modes[name])
                modes = {**modes, name: action.mode}
                self._record(t, name, broken[0][1], "switch", {"mode": action.mode, "energy_loss": 0.0})
        return modes, self.system_now(modes)

    def _open_pulling(self, t, q, u, modes):
        """``modes`` with the contacts that were closed and would pull in them opened, the
        most pulling first, one at a time (a contact closing elsewhere may unload another
        one: the bicycle's front wheel landing lifts the rear one); each a ``"release"``."""
        if all(self.system.edge(n).comp.tree_edge for n in modes):  # no contacts
            return modes
        for _ in range(len(modes)):
            new = self.system_now(modes)
            qc, uc = consistent(new, t, q, u)
            pulls = sorted((p, n, key[2]) for n, d in contact_pushes(self.system, new, modes, t, qc, uc).items()
                           for key, p in d.items() if p < 0.0 and self.modes.get(n) == modes[n])
            if not pulls:
                break
            _, who, row = pulls[0]
            action = self.system.edge(who).comp.modes(self.system.P[who]).action("release", modes[who])
            if not isinstance(action, Switch):
                break
            modes = dict(modes, **{who: action.mode})
            self._record(t, who, row, "release", {"mode": action.mode, "energy_loss": 0.0})
        return modes

    def pushes_in(self, new, modes, t, q, u):
        """``{joint: {event key: push}}`` of the rows held in ``modes`` at ``(t, q, u)`` (empty when none is held)."""
        old, self.modes = self.modes, modes
        try:
            held = any(self.system.edge(n).comp.modes(self.system.P[n]).rows(m) for n, m in modes.items())
            return self._pushes(t, q, u) if held else {}
        finally:
            self.modes = old

def _contact_row(system, who, mode):
    """The holonomic row a contact holds in ``mode`` (its first :class:`ContactRow`)."""
    rows = [r for r in system.edge(who).comp.modes(system.P[who]).rows(mode) if isinstance(r, ContactRow)]
    return rows[0].name if rows else "normal"


def _chattering(hits):
    """Whether the last :data:`CHATTER` intervals between ``hits`` (s) each shrank."""
    if len(hits) < CHATTER + 2:
        return False
    d = np.diff(hits[-CHATTER - 2:])
    return bool(np.all(d[1:] < d[:-1]))


def _terminal_count(f):
    """scipy's ``terminal``: ``True`` -> 1, a count, ``False``/missing -> -1 (never)."""
    term = getattr(f, "terminal", False)
    if term is True:
        return 1
    return int(term) if term else -1
