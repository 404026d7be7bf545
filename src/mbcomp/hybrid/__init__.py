"""The hybrid layer: what a run does at events -- modes, impacts, unilateral contacts, friction.

A run is smooth between events; this layer says what holds in between (the rows in force of
the active set: which stops and contacts are closed, which frictions stick or slide) and
what happens at an event (an impulse, a switch of mode, the end of the run):

* :mod:`.modes` -- the modes of a run's joints and the system over a mode's rows;
* :mod:`.contacts` -- unilateral contacts: their rows, pushes, impacts and columns;
* :mod:`.friction` -- Coulomb friction sticking and slipping on a 1-DOF joint's axis;
* :mod:`.slip` -- sliding contacts: the friction along a slide's direction;
* :mod:`.events` -- zero crossings located on a step's dense output, and the actions.

It sits between the solvers and :mod:`mbcomp.simulation` (which drives the run and writes
the result's columns) and imports nothing above it.
"""
