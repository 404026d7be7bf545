"""Units of the result columns a joint makes itself (``assembly/column_units.py``): a
``CutForceAndTorque``'s ``force.*``/``torque.*`` (N, N m), as a tree edge and as a cut joint,
and a massless rod's ``f_rod`` (N); every unit a library class declares is one mbcomp reads
(an unreadable one would be dropped silently)."""
import numpy as np
import pytest

import mbcomp
import mbcomp.library as lib
from mbcomp.library import CutForceAndTorque, FixedTranslation, PointMass, Revolute, RigidBody, SphericalSpherical, World
from mbcomp.modeling.units import unit_exponents


def _hanging_bob(cut):
    """A bob (2 kg) at rest below a hinge, held through the sensor (``cut``: the sensor closes
    the loop and the bob floats, its start on the sensor's frame)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0.0, -9.81, 0.0)))
    j = m.add("j", Revolute())
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    sensor = m.add("cut", CutForceAndTorque(cut=cut))
    bob = m.add("bob", RigidBody(m=2.0, I=1e-2 * np.eye(3)), free=cut)
    m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, sensor.frame_a); m.connect(sensor.frame_b, bob.frame_a)
    return m


@pytest.mark.parametrize("cut", [False, True], ids=["tree_edge", "cut_joint"])
def test_a_cut_sensor_s_force_and_torque_columns_have_units(cut):
    params = {"bob.free.r0": (0.0, -1.0, 0.0)} if cut else None
    res = mbcomp.simulate(_hanging_bob(cut), t_end=0.2, n_out=5, params=params)
    for ax in "xyz":
        assert res.units[f"cut.force.{ax}"] == "N"
        assert res.units[f"cut.torque.{ax}"] == "N m"
    np.testing.assert_allclose(res["cut.force.y"], 2.0 * 9.81, rtol=1e-9)  # the columns carry the weight


def test_a_rod_s_tension_has_newtons():
    m = mbcomp.Model()
    world = m.add("world", World(g=(0.0, -9.81, 0.0)))
    ball = m.add("ball", PointMass(m=0.5), free=True)
    rod = m.add("rod", SphericalSpherical(L=0.7, cut=True))
    m.connect(world.frame_b, rod.frame_a); m.connect(rod.frame_b, ball.frame_a)
    res = mbcomp.simulate(m, t_end=0.1, n_out=3, params={"ball.free.r0": (0.0, -0.7, 0.0)})
    assert res.units["rod.f_rod"] == "N"
    np.testing.assert_allclose(res["rod.f_rod"], 0.5 * 9.81, rtol=1e-8)


@pytest.mark.parametrize("name", [n for n in lib.__all__ if getattr(getattr(lib, n), "output_units", None)])
def test_every_declared_output_unit_is_readable(name):
    for key, text in getattr(lib, name).output_units.items():
        assert unit_exponents(text) is not None, f"{name}.output_units[{key!r}] = {text!r} is no unit mbcomp reads"
