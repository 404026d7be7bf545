"""The C engine (dop853/dopri5 over the compiled Lagrange program) against scipy's DOP853 on
the dense path, its energy conservation, and the Python continuation past a failed guard."""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import load_model, torque_pendulum

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="no C compiler")


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_engine_matches_the_dense_path_and_conserves_energy(method):
    """A 5-link pendulum for 3 s: the C engine's outputs agree with scipy's DOP853 on the
    numeric path (both to 1e-10) and the energy stays constant."""
    m = load_model("models/n_link_pendulum.py").build(N=5)
    kw = dict(t_end=3.0, rtol=1e-10, atol=1e-12, n_out=61)
    fast = mbcomp.simulate(m, method=method, backend="c", **kw)
    ref = mbcomp.simulate(m, method="DOP853", backend="numeric", **kw)
    assert fast.success and fast.stats["nfev"] > 0
    for name in ref.names:
        if name.endswith(".phi"):
            np.testing.assert_allclose(fast[name], ref[name], atol=1e-7)
    E = fast["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-7


def test_a_failed_guard_goes_on_in_python_with_the_same_motion():
    """A torque law with a branch on the speed: the program was traced on one branch, the
    engine stops where the other one starts and scipy's DOP853 goes on over the Python path;
    the motion is the numeric path's."""
    law = lambda t, phi, w: -0.3 if w > 0 else 0.3  # noqa: E731 - a Coulomb-like torque
    kw = dict(t_end=2.0, rtol=1e-9, atol=1e-11, n_out=41)
    fast = mbcomp.simulate(torque_pendulum(law), method="dop853", backend="c", **kw)
    ref = mbcomp.simulate(torque_pendulum(law), method="DOP853", backend="numeric", **kw)
    assert fast.success, fast.message
    np.testing.assert_allclose(fast["hinge.phi"], ref["hinge.phi"], atol=1e-6)
