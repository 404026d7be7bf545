"""scipy's implicit methods get the formulation's Jacobian (:meth:`Formulation.jac`).

The seed's slotted disk (Example 5.5) spinning freely with stiff slider springs: its disk
angle grows without bound and nothing depends on it (a cyclic coordinate). scipy's own
finite differences adapt each column's step from the last Jacobian and, for that column,
let it grow until it overflowed: Radau stopped at t = 1.17 s and BDF at 15.9 s with "the
state became non-finite", and scipy's overflow warning reached the user. With the
formulation's Jacobian every implicit method runs, agrees with a tight DOP853 reference and
conserves what the physics conserves, and nothing of scipy's leaks out.
"""
import warnings

import numpy as np
import pytest

import mbcomp
from conftest import load_model

disk = load_model("models/textbook/ex5_5_slotted_disk.py")
STIFF = dict(k=1e5, theta_dot0=30.0)  # slider springs of ~316 rad/s on a disk turning at 30 rad/s
T_END = 2.0


@pytest.fixture(scope="module")
def reference():
    return mbcomp.simulate(disk.build(**STIFF), t_end=T_END, method="DOP853", rtol=1e-12, atol=1e-12, n_out=41)


# BDF at rtol 1e-9: at 1e-8 it runs too, but drifts 1.7e-5 of the energy the motion exchanges
# and the accuracy alarm says so (status "inaccurate": 6e-4 rad off after 2 s)
@pytest.mark.parametrize("method, rtol, agree", [("Radau", 1e-8, 1e-6), ("BDF", 1e-9, 1e-3), ("LSODA", 1e-8, 1e-3)])
def test_implicit_scipy_methods_run_a_freely_spinning_shaft(method, rtol, agree, reference):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = mbcomp.simulate(disk.build(**STIFF), t_end=T_END, method=method, rtol=rtol, atol=rtol / 100, n_out=41)
    assert r.success, r.message
    assert not [w for w in caught if "scipy" in w.filename or "overflow" in str(w.message)]
    assert r.stats["njev"] > 0  # the Jacobian was asked for, and given
    assert r["theta"][-1] > 50.0  # the cyclic coordinate grew far from where it started
    assert np.max(np.abs(r["theta"] - reference["theta"])) < agree
    assert np.max(np.abs(r["rho1"] - reference["rho1"])) < agree
    # no friction, no drive: energy conserved
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-4 * np.max(np.abs(E))


def test_the_jacobian_is_the_derivative_of_the_right_hand_side():
    """Formulation.jac against central differences with a much larger step, at a state
    where the disk angle is large (the cyclic coordinate's column is zero up to rounding)."""
    from mbcomp.assembly.initialization import initialize
    from mbcomp.formulations import LagrangeIndex1

    s = mbcomp.assemble(disk.build(**STIFF))
    init = initialize(s)
    form = LagrangeIndex1(s)
    y = form.initial_state(0.0, init.q, init.u)
    y[0] = 1e4  # the disk angle after many turns
    J = form.jac(0.0, y)
    Jc = np.empty_like(J)
    for j in range(y.size):
        h = 1e-5 * max(1.0, abs(y[j]))
        e = np.zeros_like(y)
        e[j] = h
        Jc[:, j] = (form.fun(0.0, y + e) - form.fun(0.0, y - e)) / (2 * h)
    assert np.max(np.abs(J[:, 0])) < 1e-6 * np.abs(J).max()  # nothing depends on the angle (rounding only)
    np.testing.assert_allclose(J, Jc, rtol=1e-5, atol=1e-5 * np.abs(Jc).max())
