"""What ``Result.plot`` draws: glob patterns choose columns (exactly the matching ones, in
pattern order); a pattern matching nothing names similar columns; the default shows the
coordinates (a joint's angular speeds instead of its quaternion parts), the energy (the
balance when there is one) and the loop residual."""
import fnmatch

import matplotlib
import numpy as np
import pytest

import mbcomp
from mbcomp.library import FreeMotion, RigidBody, Spherical, World
from mbcomp.result import Result
from mbcomp.simulation.plotting import MAX_PANELS, select

from conftest import load_model

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def crank():
    return mbcomp.simulate(load_model("models/slider_crank.py").build(), t_end=0.05)


def labels(fig):
    import matplotlib.pyplot as plt

    out = [ax.get_ylabel() for ax in fig.axes]
    plt.close(fig)
    return out


def spherical_pendulum():
    """A 1 kg bob 1 m from a ball joint, started swinging about two axes."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("ball", Spherical(w0=(0.5, 0.0, 1.0)))
    bob = m.add("bob", RigidBody(m=1.0, r_cm=(1.0, 0, 0), I=np.eye(3) * 1e-3))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, bob.frame_a)
    return m


def test_default_plot_of_the_slider_crank(crank):
    assert crank.default_plot_names() == ["crank_joint.phi", "slider_joint.s", "pin.phi", "energy.total",
                                          "residual.position"]
    assert labels(crank.plot()) == crank.default_plot_names()


def test_default_plot_of_a_spherical_pendulum_shows_angular_speeds_not_quaternion_parts():
    res = mbcomp.simulate(spherical_pendulum(), t_end=0.05)
    assert res.stats["coordinates"] == ["ball.Q.w", "ball.Q.x", "ball.Q.y", "ball.Q.z"]
    assert res.default_plot_names() == ["ball.w.x", "ball.w.y", "ball.w.z", "energy.total"]  # no loop: no residual


def test_default_plot_of_a_free_body_shows_position_and_angular_speeds():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("free", FreeMotion(r0=(0, 1.0, 0), v0=(1.0, 0, 0), w0=(0, 0, 2.0)))
    body = m.add("body", RigidBody(m=1.0, I=np.eye(3)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, body.frame_a)
    res = mbcomp.simulate(m, t_end=0.05)
    assert res.default_plot_names() == ["free.r.x", "free.r.y", "free.r.z", "free.w.x", "free.w.y", "free.w.z",
                                        "energy.total"]


def test_default_plot_prefers_the_energy_balance():
    cols = {n: np.zeros(3) for n in ("hinge.phi", "hinge.w", "energy.total", "energy.balance", "residual.position")}
    res = Result([0.0, 1.0, 2.0], cols, stats={"coordinates": ["hinge.phi"]})
    assert res.default_plot_names() == ["hinge.phi", "energy.balance"]


def test_patterns_draw_exactly_the_matching_columns_in_pattern_order(crank):
    want = [n for n in crank.names if fnmatch.fnmatchcase(n, "crank_joint.*")]
    want += [n for n in crank.names if n.endswith(".tau.z") and n not in want]
    assert len(want) > 6 and "rod_joint.tau.z" in want and "crank_joint.tau.z" in want
    assert labels(crank.plot(["crank_joint.*", "*.tau.z"])) == want
    assert labels(crank.plot("energy.total")) == ["energy.total"]  # an exact name, given as a string
    assert labels(crank.plot(["pin.phi", "pin.ph?"])) == ["pin.phi"]  # each column once


def test_pattern_matching_nothing_lists_similar_columns(crank):
    with pytest.raises(ValueError) as exc:
        crank.plot(["crank_joint.phi", "crank_jiont.ph"])
    assert str(exc.value) == ("no column matches 'crank_jiont.ph'; similar: crank_joint.phi, crank_joint.w, "
                              "crank_joint.f.x, crank_joint.f.y, crank_joint.f.z, crank_joint.w.der, "
                              "crank_joint.tau.x, crank_joint.tau.y -> fix: give a column name or a glob such as "
                              "'crank_joint.*' (Result.names lists them)")


def test_too_many_columns_is_an_error_not_a_giant_figure(crank):
    assert len(crank.names) > MAX_PANELS
    with pytest.raises(ValueError, match=rf"the patterns \* match {len(crank.names)} columns, more than the "
                                         rf"{MAX_PANELS} panels of one plot -> fix: narrower patterns"):
        select(crank.names, "*")


def test_plot_writes_the_png(crank, tmp_path):
    path = tmp_path / "p.png"
    crank.plot(["slider_joint.s"], path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
