"""Nested models, aliases, runtime parameters, CSV and plot output."""
import csv

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World


def link(length, mass, phi0):
    """A reusable assembly: hinge + massless rod + point mass, exposing frame_a and tip."""
    sub = mbcomp.Model()
    j = sub.add("joint", Revolute(n=(0, 0, 1), phi0=phi0, w0=0.0))
    rod = sub.add("rod", FixedTranslation(r=(0, -length, 0)))
    bob = sub.add("bob", PointMass(m=mass))
    sub.connect(j.frame_b, rod.frame_a)
    sub.connect(rod.frame_b, bob.frame_a)
    sub.expose("frame_a", j.frame_a)
    sub.expose("tip", rod.frame_b)
    sub.alias("angle", "joint.phi")
    return sub


def double_pendulum(l1=1.0, l2=0.7, m1=1.0, m2=0.6, th1=0.8, th2=-0.4):
    m = mbcomp.Model()
    w = m.add("world", World())
    a = m.add("upper", link(l1, m1, th1))
    b = m.add("lower", link(l2, m2, th2))
    m.connect(w.frame_b, a.frame_a)
    m.connect(a.tip, b.frame_a)
    m.alias("theta1", "upper.joint.phi")
    return m


def reference(t, l1=1.0, l2=0.7, m1=1.0, m2=0.6, th1=0.8, th2=-0.4, g=9.81):
    """Classic double pendulum with absolute angles a1, a2 from the downward vertical."""
    def rhs(_, y):
        a1, a2, w1, w2 = y
        d = a1 - a2
        M = np.array([[(m1 + m2) * l1, m2 * l2 * np.cos(d)], [l1 * np.cos(d), l2]])
        b = np.array([-m2 * l2 * w2 ** 2 * np.sin(d) - (m1 + m2) * g * np.sin(a1),
                      l1 * w1 ** 2 * np.sin(d) - g * np.sin(a2)])
        return [w1, w2, *np.linalg.solve(M, b)]

    s = solve_ivp(rhs, (0, t[-1]), [th1, th1 + th2, 0, 0], t_eval=t, rtol=1e-12, atol=1e-12, method="DOP853")
    return s.y[0], s.y[1]


def test_nested_assemblies_match_double_pendulum_equations():
    res = mbcomp.simulate(double_pendulum(), t_end=3.0, rtol=1e-10, atol=1e-12, n_out=151)
    a1, a2 = reference(res.time)
    np.testing.assert_allclose(res["theta1"], a1, atol=1e-7)
    np.testing.assert_allclose(res["upper.angle"], a1, atol=1e-7)  # alias inside the sub-model
    np.testing.assert_allclose(res["upper.joint.phi"] + res["lower.joint.phi"], a2, atol=1e-7)
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-8


def test_runtime_parameters_equal_a_rebuilt_model_without_rederiving():
    base = mbcomp.assemble(double_pendulum())
    heavier = base.with_params({"lower.bob.m": 1.5})
    assert heavier.topology is base.topology  # nothing re-derived
    r1 = mbcomp.simulate(heavier, t_end=1.0, rtol=1e-10, atol=1e-12, n_out=21)
    r2 = mbcomp.simulate(double_pendulum(m2=1.5), t_end=1.0, rtol=1e-10, atol=1e-12, n_out=21)
    np.testing.assert_allclose(r1["theta1"], r2["theta1"], atol=1e-12)
    a1, _ = reference(r1.time, m2=1.5)
    np.testing.assert_allclose(r1["theta1"], a1, atol=1e-7)
    with pytest.raises(mbcomp.ModelError, match="lower.bob.m"):
        base.with_params({"lower.bob.m": -1.0})


def test_csv_and_plot_carry_the_series(tmp_path):
    res = mbcomp.simulate(double_pendulum(), t_end=0.5, n_out=11)
    path = res.to_csv(tmp_path / "out.csv")
    with open(path) as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    assert header[0] == "time" and "theta1" in header and "upper.joint.phi" in header
    data = np.array(rows[1:], float)
    assert data.shape == (11, len(header))
    np.testing.assert_allclose(data[:, header.index("theta1")], res["theta1"], rtol=1e-11)
    np.testing.assert_allclose(data[:, header.index("energy.total")], res["energy.total"], rtol=1e-11)
    fig = res.plot(["theta1", "energy.total"], path=tmp_path / "out.png")
    line = fig.axes[0].lines[0]
    np.testing.assert_allclose(line.get_ydata(), res["theta1"])
    assert (tmp_path / "out.png").stat().st_size > 5000


def test_unknown_variable_names_similar_ones():
    res = mbcomp.simulate(double_pendulum(), t_end=0.1, n_out=3)
    with pytest.raises(KeyError, match="upper"):
        res["upper.joint.psi"]


def test_derived_outputs_compose_through_nested_models():
    """``Model.output``: the lower bob's absolute angle, built from the lower link's own
    sub-model output (its tip height) and an outer output, equals the reference a2; a
    failing user function is reported in the message and every other result is kept."""
    m = double_pendulum()
    m["lower"].output("bob_height", lambda y: y - 0.0, "bob.r.y")
    m.output("a2", lambda p1, p2: p1 + p2, "upper.joint.phi", "lower.joint.phi")
    m.output("broken", lambda p: p[:3], "upper.joint.phi")
    res = mbcomp.simulate(m, t_end=2.0, rtol=1e-10, atol=1e-12, n_out=101)
    a1, a2 = reference(res.time)
    np.testing.assert_allclose(res["a2"], a2, atol=1e-7)
    np.testing.assert_allclose(res["lower.bob_height"], -np.cos(a1) - 0.7 * np.cos(a2), atol=1e-7)
    assert "output 'broken' failed" in res.message and "broken" not in res
    assert res.status == "success"
