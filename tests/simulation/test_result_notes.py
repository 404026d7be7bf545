"""Joints speak for their own results (Joint.result_notes); the framework never does.

A rolling contact is bilateral: it holds the ball on the plane whatever the normal force.
When a vertical push at the ball's centre exceeds its weight, the contact pulls (N < 0):
the result says from when a real ball would lift off -- a note written by the contact
(library/contact.py), which the post-processing only collects.
"""
import inspect

import numpy as np

import mbcomp
import mbcomp.simulation.postprocess as postprocess
from mbcomp.library import RollingSphere, World, WorldForce
from mbcomp.modeling.roles import Joint

M, G, T0 = 0.5, 9.81, 0.455  # the push equals the weight at T0 (s)


def pushed_ball():
    """A ball resting on the ground, pushed up at its centre by F = m g t / T0 (N)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    ball = m.add("ball", RollingSphere(r=0.1, m=M))
    push = m.add("push", WorldForce(f=lambda t, frame: (0.0, 0.0, M * G * t / T0)))
    m.connect(w.frame_b, ball.plane)
    m.connect(ball.center, push.frame_b)
    return m


def test_a_contact_that_pulls_says_from_when_a_real_one_would_lift_off():
    res = mbcomp.simulate(pushed_ball(), t_end=1.0, n_out=101, rtol=1e-10, atol=1e-12)
    assert res.success
    # the ball stays on the plane: N = m g - F(t), negative after T0
    np.testing.assert_allclose(res["ball.contact.N"], M * G * (1.0 - res.time / T0), atol=1e-8)
    assert res.message == ("reached t_end; ball.contact.N < 0 from t = 0.46 s: the contact pulls the body onto "
                           "the plane there (contacts are bilateral; a real wheel or ball would lift off)")


def test_no_note_while_the_contact_presses():
    res = mbcomp.simulate(pushed_ball(), t_end=0.4, n_out=41)
    assert res.success and res.message == "reached t_end"
    assert res["ball.contact.N"].min() > 0.0


def test_joints_have_no_notes_by_default_and_the_framework_writes_none():
    assert Joint().result_notes("j", np.zeros(3), {"N": -np.ones(3)}) == []  # only a contact knows what N means
    assert "wheel or ball" not in inspect.getsource(postprocess)  # the words are the contact's
