"""The inertia check's kinematic pass takes the poses alone (``tree_pass(..., forces=False)``:
:meth:`FrameJet.pose_through`, :meth:`FrameJet.offset_pose`): the same poses, motion
subspaces and spatial inertias as the full pass, bit for bit, so the same mass matrix and the
same decisions -- on joints traversed either way, drives, rotors, a floating base, balls."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.recursive import _link_jets, mass_matrix, speed_columns, tree_links, tree_pass
from mbcomp.library import FixedTranslation, Inertia, Revolute, RigidBody, Torque, World

from conftest import load_model


def reversed_arm():
    """A two-link arm whose first hinge is connected frame_b to the world (the tree walks it
    backwards) and a rotor turning on the second hinge's axis."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j1 = m.add("j1", Revolute(n=(0, 0, 1), phi0=0.4, w0=1.0))
    a = m.add("a", FixedTranslation(r=(0.7, 0.1, 0.0)))
    b1 = m.add("b1", RigidBody(m=1.3, I=np.diag([0.1, 0.2, 0.3]), r_cm=(0.2, 0.05, 0.0)))
    j2 = m.add("j2", Revolute(n=(0.3, 0.0, 1.0), phi0=-0.2, w0=2.0))
    b2 = m.add("b2", RigidBody(m=0.6, I=np.diag([0.05, 0.04, 0.02]), r_cm=(0.3, 0.0, 0.1)))
    rotor = m.add("rotor", Inertia(J=0.02))
    tq = m.add("tq", Torque(tau=0.1))
    m.connect(j1.frame_b, w.frame_b)  # backwards: frame_a is the arm's side
    m.connect(j1.frame_a, a.frame_a)
    m.connect(a.frame_b, b1.frame_a)
    m.connect(b1.frame_a, j2.frame_a)
    m.connect(j2.frame_b, b2.frame_a)
    m.connect(rotor.flange, j2.axis)
    m.connect(tq.flange_b, j2.axis)
    return m


MODELS = {
    "reversed arm with a rotor": reversed_arm,
    "3-D chain (balls)": lambda: load_model("models/chain_3d.py").build(),
    "pendulum on a driven cart": lambda: load_model("models/textbook/ex3_1_pendulum_cart.py").build(),
    "spinning plate (free body)": lambda: load_model("models/textbook/ex3_3_spinning_plate.py").build(),
}


@pytest.mark.parametrize("name", MODELS)
def test_the_pose_pass_is_the_full_pass_bit_for_bit(name):
    s = mbcomp.assemble(MODELS[name]())
    rng = np.random.default_rng(7)
    q = s.normalize(s.default_q() + 0.2 * rng.standard_normal(s.nq))
    u = rng.standard_normal(s.nu)
    links = tree_links(s)
    full, pose = _link_jets(s, links, 0.3, q, u), _link_jets(s, links, 0.3, q, u, pose_only=True)
    for node, J in full[0].items():
        np.testing.assert_array_equal(J.R, pose[0][node].R)
        np.testing.assert_array_equal(J.r, pose[0][node].r)
        assert not np.any(pose[0][node].w) and not np.any(pose[0][node].a)  # no motion computed
    for x, y in zip(full[1], pose[1]):
        np.testing.assert_array_equal(x, y)
    a, b = tree_pass(s, 0.3, q, u, forces=True), tree_pass(s, 0.3, q, u, forces=False)
    for x, y in zip(a.I, b.I):
        np.testing.assert_array_equal(x, y)
    assert speed_columns(b, s.nu) is not None
    M = mass_matrix(b, s.nu)
    np.testing.assert_array_equal(M, mass_matrix(a, s.nu))
    # and it is the mass matrix: the dense evaluation's to rounding
    np.testing.assert_allclose(M, s.evaluate(0.3, q, u).M, rtol=1e-12, atol=1e-12 * np.abs(M).max())
    if name.startswith("reversed"):
        assert any(not e.forward for e in s.topology.tree) and len(s.topology.rotors) == 1
