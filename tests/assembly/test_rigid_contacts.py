"""A contact whose two sides are one rigid link can never move and carries an undetermined
force (the hold and the floor share a held ball's weight in any proportion). It used to reach
numpy's solver with a shape error from inside the hybrid start (found by locking the bowling
ball's free joint); now the model is refused naming the contact and the fix, while the same
contact on a body with freedom runs (the control)."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import ContactFriction, FixedTranslation, FreeMotion, Revolute, RigidBody, SphereContact, World

R = 0.109


def ball_on_lane(hold):
    """A ball on a lane, joined to the world by ``hold`` (a free joint or a rigid offset)."""
    m = mbcomp.Model()
    world = m.add("world", World(g=(0, 0, -9.81)))
    h = m.add("hold", hold)
    ball = m.add("ball", RigidBody(m=7.0, I=0.4 * 7.0 * R * R * np.eye(3)))
    lane = m.add("lane", SphereContact(r=R, unilateral=True, friction=ContactFriction(0.2, 0.04)))
    m.connect(world.frame_b, h.frame_a)
    m.connect(h.frame_b, ball.frame_a)
    m.connect(world.frame_b, lane.frame_a)
    m.connect(lane.frame_b, ball.frame_a)
    return m


def test_a_ball_held_fixed_on_the_lane_is_refused_naming_the_contact():
    with pytest.raises(mbcomp.ModelError, match=r"lane: both frames this SphereContact joins are fixed to the "
                                                r"world.*undetermined.*give a body it touches freedom"):
        mbcomp.simulate(ball_on_lane(FixedTranslation(r=(0, 0, R))), t_end=0.1)


def test_locking_the_free_joint_of_a_ball_on_the_lane_is_refused_the_same_way():
    model = ball_on_lane(FreeMotion(r0=(0.0, 0.0, R), v0=(1.0, 0.0, 0.0)))
    with pytest.raises(mbcomp.ModelError, match=r"lane: both frames"):
        mbcomp.assemble(model.lock(["hold"]))


def test_a_contact_between_two_frames_of_one_moving_link_names_that_link():
    m = mbcomp.Model()
    world = m.add("world", World(g=(0, 0, -9.81)))
    j = m.add("j", Revolute(n=(0, 1, 0), phi0=0.3))
    arm = m.add("arm", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", RigidBody(m=1.0, I=0.01 * np.eye(3)))
    c = m.add("c", SphereContact(r=0.05, unilateral=True))
    m.connect(world.frame_b, j.frame_a); m.connect(j.frame_b, arm.frame_a); m.connect(arm.frame_b, bob.frame_a)
    m.connect(j.frame_b, c.frame_a); m.connect(c.frame_b, bob.frame_a)
    with pytest.raises(mbcomp.ModelError, match=r"c: both frames .* one rigid link \(moved by j\)"):
        mbcomp.assemble(m)


def test_the_free_ball_on_the_lane_still_rolls_at_five_sevenths():
    """The control: the same contact with the ball free slides, then rolls at 5 v0 / 7."""
    res = mbcomp.simulate(ball_on_lane(FreeMotion(r0=(0.0, 0.0, R), v0=(1.0, 0.0, 0.0))), t_end=1.0,
                          rtol=1e-10, atol=1e-12, n_out=2)
    assert res.status == "success"
    assert abs(float(res["ball.v.x"][-1]) - 5.0 / 7.0) < 1e-8
