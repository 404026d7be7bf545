"""The hybrid layer: what a run does at events -- modes, impacts, unilateral contacts, friction.

A run is smooth between events; it is integrated in *segments*, each over one *active set*
(``{joint: mode}``: which stops are engaged, which contacts closed or open, which frictions
stick or slip). This layer says what holds in a segment (its *rows in force*) and what an
event does (an impulse, a switch of the active set, the end of the run). Bottom to top:

* :mod:`.active` -- the active set and what it makes: :func:`~.active.rows_in_force`, the
  one description every consumer reads, the system stepped over it
  (:func:`~.active.mode_system`), and the run's segments (:class:`~.active.SegmentStart`,
  :func:`~.active.segment_at`);
* :mod:`.contacts` -- unilateral contacts: their rows, gaps, pushes and impacts;
* :mod:`.stops` -- rows held on tree joints' own coordinates (end stops, stuck frictions):
  pushes, impacts, consistent states, the columns where they hold;
* :mod:`.friction` -- Coulomb friction sticking and slipping on a 1-DOF joint's axis;
* :mod:`.slip` -- contacts that slide: the friction along the slip, its work, its columns;
* :mod:`.events` -- event functions detected and located on a step's dense output
  (:meth:`~.events.Events.check`) and the action on them (:meth:`~.events.Events.act`,
  an :class:`~.events.Outcome` the driver starts the next segment from);
* :mod:`.steppers` -- which stepper a run with events takes (the C integrators watching the
  declared event rows in their loop, or one scipy step at a time).

It sits between the solvers and :mod:`mbcomp.simulation` (whose driver integrates the
segments and whose post-processing writes each output's columns over its segment's system)
and imports nothing above it; the constrained and impulse solves it calls are
:mod:`mbcomp.assembly.kkt` and :mod:`mbcomp.assembly.impacts`.
"""
