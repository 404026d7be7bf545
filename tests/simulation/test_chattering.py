"""Chattering at one instant (issue 22, item 1): detected and reported with the component named.

A rotor whose torque is +1 N m in mode ``up`` and -1 N m in mode ``down``, switching where its
angle crosses 0.5 rad, started at 0.5 rad at rest: each mode drives it straight back across
the switching surface (a Filippov sliding mode), so the modes switch without time passing.
The run must stop there with a ``chattering`` failure naming the joint, its event and its
modes -- not loop. The same rotor started below the surface instead swings through it in a
bang-bang oscillation of constant amplitude, which is no chattering: it first crosses at
``t1 = sqrt(2 J d / tau)`` (``d`` = 0.1 rad below) and then every ``2 t1``, its energy
balance closing with the modes' work.
"""
import numpy as np

import mbcomp
from mbcomp.library import Revolute, RigidBody, World
from mbcomp.modeling.events import Switch
from mbcomp.modeling.modes import Modes
from mbcomp.hybrid.events import BURST


class UpDown(Modes):
    """+1 N m in mode 'up' and -1 N m in mode 'down', switching where phi crosses 0.5 rad."""

    has_force = True

    def events(self, q, u, mode):
        return [("cross", 0.5 - q[0] if mode == "up" else q[0] - 0.5, -1)]

    def action(self, name, mode):
        return Switch("down" if mode == "up" else "up")

    def force(self, mode):
        return 1.0 if mode == "up" else -1.0


class BangBang(Revolute):
    """A rotor axis driven by +1 N m in mode 'up' and -1 N m in mode 'down', switching where
    phi crosses 0.5 rad."""

    def modes(self, p):
        return UpDown("up")

    # its mode force does work: declared as the stick-slip frictions declare theirs (the run
    # books a mode force's work, -F ds per mode, in energy.dissipated: mbcomp.hybrid.friction)
    dissipative = True

    def conserves_energy(self, p):
        return False

    def outputs(self, a, b, p, lam):
        return {**super().outputs(a, b, p, lam), "power": 0.0}


def rotor(phi0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("axis", BangBang(n=(0, 0, 1), phi0=phi0, w0=0.0))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, 2.0])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def test_switching_without_time_passing_is_reported_as_chattering():
    res = mbcomp.simulate(rotor(0.5), t_end=1.0)
    assert res.status == "failed"
    assert res.message.startswith(f"chattering: axis changed mode {BURST} times within")
    assert "events cross; modes down, up" in res.message
    assert len(res.events) == BURST and res.events[-1].time - res.events[0].time <= 1e-9


def test_bang_bang_oscillation_is_no_chattering():
    """From 0.4 rad at rest (J = 2, tau = 1): the surface is reached at ``sqrt(2 J 0.1)``, and
    every later crossing two such times apart (decelerate, come back)."""
    res = mbcomp.simulate(rotor(0.4), t_end=5.0, rtol=1e-10, atol=1e-12)
    assert res.status == "success" and np.max(np.abs(res["energy.balance"])) < 1e-9
    t1 = np.sqrt(2 * 2.0 * 0.1)
    times = np.array([e.time for e in res.events])
    assert len(times) == int((5.0 - t1) // (2 * t1)) + 1
    assert np.max(np.abs(times - (t1 + 2 * t1 * np.arange(len(times))))) < 1e-9
