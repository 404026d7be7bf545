"""radau5 with the Lagrange formulation and no index steps the index-1 ODE (issue 32 item 4:
``Radau5.ode_by_default``); ``index=1`` still asks for the index-1 DAE. Both agree with scipy's
Radau on a stiff damped spring chain, and the ODE takes fewer steps than the DAE there."""
import numpy as np

import mbcomp
from mbcomp.simulation.setup import check_request
from mbcomp.solvers.radau import Radau5

CHAIN = mbcomp.load_model_file("models/spring_chain.py")


def test_the_default_is_the_ode_and_index_1_the_dae():
    assert Radau5.on_ode().problem == "ode" and Radau5.problem == "dae"
    stepper, index = check_request("radau5", "lagrange", None, None, 0.0, 1.0, "numeric")
    assert stepper is Radau5 and index == 1  # the request; simulate switches to the ODE (below)


def test_radau5_on_the_ode_agrees_with_scipy_and_the_dae_with_fewer_steps():
    opts = dict(t_end=0.2, rtol=1e-7, atol=1e-9, n_out=21)
    ode = mbcomp.simulate(CHAIN.build(N=4, c=1e6, d=1e5), method="radau5", **opts)
    dae = mbcomp.simulate(CHAIN.build(N=4, c=1e6, d=1e5), method="radau5", index=1, **opts)
    ref = mbcomp.simulate(CHAIN.build(N=4, c=1e6, d=1e5), method="Radau", rtol=1e-11, atol=1e-13, t_end=0.2, n_out=21)
    assert ode.status == dae.status == ref.status == "success"
    names = [n for n in ref.names if n.endswith(".phi") or n.endswith(".s")]
    assert names
    for n in names:
        assert np.max(np.abs(ode[n] - ref[n])) < 1e-5, n
        assert np.max(np.abs(dae[n] - ref[n])) < 1e-5, n
    # the ODE has no algebraic accelerations to converge: no more steps than the DAE
    assert ode.stats["steps"] <= dae.stats["steps"]
