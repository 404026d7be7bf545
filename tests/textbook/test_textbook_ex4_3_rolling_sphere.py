"""Seed Section 4.3, Example 3 (rolling sphere) and Section 4.4 (its classification).

Model: ``models/textbook/ex4_3_rolling_sphere.py`` (the library's ``RollingSphere``).

Book: ``r_cz = a``, ``r_cx' - theta_y' a = 0``, ``r_cy' + theta_x' a = 0``; three constraint
forces R_x, R_y, R_z; the two velocity conditions are nonholonomic (4.4). The book's
signs are right: no slip at A = c - a z means ``v_c + w x (-a z) = 0``, i.e.
``v_cx = a w_y`` and ``v_cy = -a w_x``.

Trust physics over print: Section 4.3 then counts "the number of DOFs of each body" as
6 minus the number of constraint equations, 6 - 3 = 3 for the ball. That is the number of
independent *velocities* (motion DOF); a nonholonomic condition does not remove a
*configuration* coordinate -- the ball can reach any position and orientation on the plane
(5 coordinates) by rolling around. ``mbcomp info`` reports both: 5 DOF and 2 nonholonomic
rows, motion DOF 3.
"""
import numpy as np
import pytest

import mbcomp
from conftest import ROOT, load_model
from mbcomp.cli import main

PATH = "models/textbook/ex4_3_rolling_sphere.py"
MODEL = load_model(PATH)
P = dict(m=1.0, a=0.1, g=9.81)


@pytest.fixture(scope="module")
def rolling():
    res = mbcomp.simulate(MODEL.build(), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=101)
    assert res.success, res.message
    return res


def test_book_constraint_equations_hold(rolling):
    r = rolling
    a = P["a"]
    np.testing.assert_allclose(r["r_cz"], a, atol=1e-12)  # r_cz = a
    # angular velocity components in world axes are the book's theta_x', theta_y'
    np.testing.assert_allclose(r["ball.ball.v.x"] - a * r["ball.ball.w.y"], 0.0, atol=1e-10)
    np.testing.assert_allclose(r["ball.ball.v.y"] + a * r["ball.ball.w.x"], 0.0, atol=1e-10)


def test_free_rolling_on_a_level_plane_is_uniform_and_forces_are_the_weight(rolling):
    """No horizontal force: the friction forces vanish (R_x = R_y = 0), R_z = m g, the
    centre moves uniformly and the spin about the vertical stays constant."""
    r = rolling
    np.testing.assert_allclose(r["r_cx"], 0.5 * r.time, atol=1e-9)
    np.testing.assert_allclose(r["r_cy"], 0.2 * r.time, atol=1e-9)
    np.testing.assert_allclose(r["ball.ball.w.z"], 3.0, atol=1e-9)
    np.testing.assert_allclose(r["R_z"], P["m"] * P["g"], rtol=1e-10)
    assert np.abs(r["R_x"]).max() < 1e-9 and np.abs(r["R_y"]).max() < 1e-9


def test_pushed_ball_accelerates_at_five_sevenths_and_friction_is_two_sevenths():
    """A force F at the centre: m a = F + R_x and (2/5) m a^2 (a_c / a) = -a R_x give
    a_c = (5/7) F / m and R_x = -(2/7) F -- the constraint force the book names."""
    F = 1.4
    res = mbcomp.simulate(MODEL.build(vx0=0.0, vy0=0.0, spin0=0.0, push=F), t_end=1.0, rtol=1e-10,
                          atol=1e-12, n_out=11)
    assert res.success, res.message
    np.testing.assert_allclose(res["r_cx"], 0.5 * (5 / 7) * F / P["m"] * res.time ** 2, atol=1e-9)
    np.testing.assert_allclose(res["R_x"], -(2 / 7) * F, rtol=1e-9)
    np.testing.assert_allclose(res["r_cy"], 0.0, atol=1e-12)


def test_info_counts_five_dof_and_two_nonholonomic_rows(capsys):
    assert main(["info", str(ROOT / PATH)]) == 0
    out = capsys.readouterr().out
    assert "degrees of freedom: 5 " in out
    assert "nonholonomic constraints (velocity level): 2; motion DOF 3" in out
    assert "ball.contact (1 holonomic + 2 nonholonomic rows)" in out
