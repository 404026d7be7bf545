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
    # a pendulum's state: DOP853's energy error grows about linearly with the time reached (1.3e-4
    # of E after ~1e5 s at the default rtol 1e-8); the bound is 1e-8 of E per second
    assert abs(E[1] - E[0]) < 1e-8 * r.time[1] * abs(E[0])
    assert "needs about" in r.message and "shorten t_end" in r.message and "radau5" not in r.message
    need = float(r.message.split("needs about ")[1].split(" steps")[0])
    assert 1e9 < need < 1e11                      # 1e9 s / 0.1 s: steps of the order of the motion's


def flat_times(w0, N=2, g=G, count=2):
    """Times (s) at which the N-four-bar (unit links and masses, cranks starting vertical at
    ``w0``) lies flat, theta = pi, 2 pi, ...: from its energy, theta'^2 = w0^2 + 2 g c (1 -
    sin theta) / J with c = (N + 1) / 2 + N, J = (N + 1) / 3 + N (models/n_four_bar.py)."""
    from scipy.integrate import quad

    c, J = (N + 1) / 2 + N, (N + 1) / 3 + N
    rate = lambda th: 1.0 / np.sqrt(w0 ** 2 + 2.0 * g * c * (1.0 - np.sin(th)) / J)  # noqa: E731
    return [quad(rate, np.pi / 2, k * np.pi)[0] for k in range(1, 1 + count)]


@pytest.mark.parametrize("formulation,method", [("dalembert", "DOP853"), ("dalembert", "dop853"),
                                                ("lagrange", "DOP853"), ("lagrange", "RK45")])
@pytest.mark.parametrize("w0, rtol", [(4.0, 1e-4), (8.0, 1e-3)])
def test_a_flat_position_crossed_within_one_step_stops_the_run(formulation, method, w0, rtol):
    """At loose tolerances a step of an explicit method spans a flat position of the N = 2
    four-bar (0.15 s -> 0.55 s across the flat at 0.328 s): sigma at both step ends was far
    from 0 and the run stopped at the second flat position (or none). The monitor looks inside
    each step on the dense output: the run stops at the first, at its closed-form time."""
    model = mbcomp.load_model_file("models/n_four_bar.py").build(N=2, w0=w0)
    r = mbcomp.simulate(model, t_end=1.5, formulation=formulation, method=method, rtol=rtol, atol=rtol)
    t1, t2 = flat_times(w0)
    assert r.status == "failed" and "singular position" in r.message
    t_stop = float(r.message.split("singular position at t=")[1].split(":")[0])
    assert abs(t_stop - t1) < 1e-3 < t2 - t1 and r.time[-1] <= t_stop


def driven_crank():
    """The slider-crank (crank 0.2 m, rod 0.6 m) with its crank angle prescribed,
    phi = 0.3 + 6 t + 0.5 sin(3 t): no degree of freedom left."""
    from mbcomp.library import PrescribedMotion

    m = mbcomp.load_model_file("models/slider_crank.py").build()
    d = m.add("drive", PrescribedMotion(s="0.3 + 6*t + 0.5*sin(3*t)"))
    m.connect(m["crank_joint"].axis, d.flange_b)
    return m


@pytest.mark.parametrize("formulation,method", [("lagrange", "dop853"), ("lagrange", "DOP853"),
                                                ("dalembert", "dop853"), ("dalembert", "DOP853")])
def test_outputs_of_a_driven_loop_are_projected_from_states_on_it(formulation, method):
    """With stabilization='projection' the compiled loop projected its steps with the drive's
    values of another time (set per call from Python): the dense states at the outputs sat up
    to 6e11 tolerances off the loop and only the output projection's Newton brought them back
    (an output guard refusing such moves had to be limited to singular='pass'). Now the
    outputs' projections move them by at most a few tolerances and none is refused; the slider
    follows the closed form x = r cos(phi) + sqrt(l^2 - r^2 sin(phi)^2)."""
    kw = dict(stabilization="projection") if formulation == "lagrange" else {}
    r = mbcomp.simulate(driven_crank(), t_end=2.0, n_out=201, formulation=formulation, method=method,
                        rtol=1e-10, atol=1e-12, **kw)
    assert r.status == "success", r.message
    assert r.stats.get("refused_projections", 0) == 0
    t = r.time
    phi = 0.3 + 6 * t + 0.5 * np.sin(3 * t)
    x = 0.2 * np.cos(phi) + np.sqrt(0.6 ** 2 - (0.2 * np.sin(phi)) ** 2)
    assert np.max(np.abs(r["slider_joint.s"] - x)) < 1e-9
