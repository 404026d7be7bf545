"""No silent wrong result and no lost one (issue 30, items 3 and 7): a run either gives the
right answer, or says what went wrong with advice that helps and keeps what it computed."""
import numpy as np
import pytest

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

G = 9.81


def pendulum(phi0=1.0):
    """A point mass (1 kg) on a 1 m massless rod on a hinge, gravity -y."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=phi0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


@pytest.mark.parametrize("formulation,method", [("lagrange", "dop853"), ("dalembert", "DOP853")])
def test_a_1e9_s_run_keeps_what_it_reached_and_says_what_it_needs(formulation, method):
    """1e9 s of a pendulum with 501 outputs: 2e6 s between outputs. The compiled loop stopped
    at its own cap of 1e5 steps per call ("failed" at t = 1e4 s, advice: radau5, heavier light
    parts) and the result kept only t = 0. Now the run goes on until its budget, keeps the
    state it reached (energy conserved there) and says the run needs ~7e9 steps of ~0.14 s:
    the motion sets the steps, so only a shorter run helps."""
    r = mbcomp.simulate(pendulum(), t_end=1e9, n_out=501, formulation=formulation, method=method, max_wall_time=1.5)
    assert r.status == "budget"
    assert len(r.time) == 2 and r.time[1] > 10.0 and f"results up to t={r.time[1]:g} s are kept" in r.message
    E = r["energy.total"]
    assert abs(E[1] - E[0]) < 1e-4 * abs(E[0])
    assert "needs about" in r.message and "shorten t_end" in r.message and "radau5" not in r.message
    need = float(r.message.split("needs about ")[1].split(" steps")[0])
    assert 1e9 < need < 1e11                      # 1e9 s / 0.1 s: steps of the order of the motion's
