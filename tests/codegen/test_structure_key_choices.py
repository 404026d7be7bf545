"""The structure cache keys on what the topology chose from parameter values
(codegen/structure_key.py, Topology.choices): a fixed start value that moves the cut joint
of a loop is another program (the programs of the first tree used to be reused: a warm run
of the second model went off the cold run by 0.6 rad in 0.5 s)."""
import numpy as np
import pytest

import mbcomp
from mbcomp import Guess
from mbcomp.codegen.structure_key import STRUCTURES, structure_key
from mbcomp.library import FixedTranslation, RigidBody, Revolute, World


def four_bar(fixed):
    """A four-bar of hinges ``j0..j3``: ``fixed`` the hinge whose start angle is fixed (the
    others' are guesses), which the spanning tree keeps."""
    m = mbcomp.Model()
    w = m.add("world", World())
    js = [m.add(f"j{i}", Revolute(phi0=0.1 if i == fixed else Guess(0.1))) for i in range(4)]
    for i in range(3):
        link = m.add(f"l{i}", FixedTranslation(r=(1.0, 0.0, 0.0)))
        body = m.add(f"b{i}", RigidBody(m=1.0, I=np.eye(3)))
        m.connect(js[i].frame_b, link.frame_a)
        m.connect(link.frame_a, body.frame_a)
        m.connect(link.frame_b, js[i + 1].frame_a)
    m.connect(w.frame_b, js[0].frame_a)
    m.connect(js[3].frame_b, w.frame_b)
    return m


def run(model):
    return mbcomp.simulate(model, t_end=0.5, n_out=6, rtol=1e-10, atol=1e-12, backend="python")


def test_a_fixed_start_that_moves_the_cut_joint_is_another_structure():
    a, b = mbcomp.assemble(four_bar(0)), mbcomp.assemble(four_bar(3))
    assert a.topology.cut != b.topology.cut
    assert structure_key(a, "python")[0] != structure_key(b, "python")[0]
    assert structure_key(mbcomp.assemble(four_bar(3)), "python")[0] == structure_key(b, "python")[0]


@pytest.mark.parametrize("first", [0, 3])
def test_a_warm_run_of_another_tree_is_the_cold_run(first):
    other = 3 - first
    STRUCTURES.clear()
    cold = run(four_bar(other))
    STRUCTURES.clear()
    run(four_bar(first))
    warm = run(four_bar(other))
    assert warm.system.stats.get("structure_cache") == "miss"
    assert warm.status == cold.status == "success"
    for name in ("j0.phi", "j1.phi", "j2.phi", "j3.phi"):
        assert np.max(np.abs(np.asarray(warm[name]) - np.asarray(cold[name]))) <= 1e-12, name
