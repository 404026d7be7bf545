"""The result columns by the recursive algorithms (:mod:`mbcomp.assembly.outputs`) against
the dense route (full jets, the saddle-point solve, reactions on the Kane sums), on every
kind of model in models/; and a physical check of the reactions on a pendulum."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.outputs import output_values
from mbcomp.formulations import LagrangeIndex1
from mbcomp.kinematics import matrix_to_quat
from mbcomp.simulation.postprocess import _Columns, _sample

from conftest import load_model

MODELS = ["n_link_pendulum", "chain_3d", "four_bar", "slider_crank", "andrews", "bicycle", "rolling_disk"]


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("stabilization", ["baumgarte", "none"])
def test_recursive_columns_are_the_dense_columns(name, stabilization):
    """Every column (coordinates, rates, reactions, joints' own outputs, drive efforts, poses,
    energies, residuals, multipliers) agrees with the dense route at a perturbed state."""
    s = mbcomp.assemble(load_model(f"models/{name}.py").build())
    initialize(s)
    rng = np.random.default_rng(7)
    q = s.normalize(s.default_q() + 0.05 * rng.standard_normal(s.nq))
    u = rng.standard_normal(s.nu)
    form = LagrangeIndex1(s, stabilization=stabilization)
    dense = _Columns(1)
    _sample(s, form, dense, 0, 0.3, q, u)
    gains = form.output_gains()
    cols, rot = output_values(s, 0.3, q, u, *(gains or (0.0, 0.0)), baumgarte=gains is not None)
    assert set(cols) == set(dense.series), set(cols) ^ set(dense.series)
    for key, val in cols.items():
        ref = dense.series[key][0]
        if np.isnan(ref):
            assert np.isnan(val), key
            continue
        scale = 1.0 + max(abs(ref), 1.0 if key.startswith(("lambda", "energy")) else 0.0)
        assert abs(val - ref) <= 1e-9 * scale, (name, key, val, ref)
    for path, R in rot.items():
        np.testing.assert_allclose(matrix_to_quat(R), dense.quat[path][0], atol=1e-13, err_msg=path)


def test_pendulum_reaction_is_centripetal_plus_gravity():
    """A point mass m on a massless rod of length l released at angle phi with speed w: the
    hinge carries m (g cos(phi) + w^2 l) along the rod and m g sin(phi) across it is taken
    by the bob's acceleration, so the rod-direction force on the bob is the tension."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, World

    m_, l, phi, w = 2.0, 1.5, 0.4, 1.3
    m = mbcomp.Model()
    world = m.add("world", World())
    j = m.add("j", Revolute(n=(0, 0, 1)))
    rod = m.add("rod", FixedTranslation(r=(0, -l, 0)))
    bob = m.add("bob", PointMass(m=m_))
    m.connect(world.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    cols, _ = output_values(mbcomp.assemble(m), 0.0, np.array([phi]), np.array([w]))
    g = 9.81
    f = np.array([cols["j.f.x"], cols["j.f.y"], cols["j.f.z"]])   # on frame_b, in frame_b (rotated by phi)
    assert abs(f[1] - m_ * (g * np.cos(phi) + w ** 2 * l)) < 1e-12   # tension along the rod (+y of frame_b)
    assert abs(f[0]) < 1e-12 and abs(f[2]) < 1e-12                # a massless rod carries no shear
    assert abs(cols["j.w.der"] + g / l * np.sin(phi)) < 1e-12
    assert abs(cols["energy.kinetic"] - 0.5 * m_ * (w * l) ** 2) < 1e-12
