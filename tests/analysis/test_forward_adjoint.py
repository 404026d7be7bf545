"""Forward sensitivities and the adjoint gradient agree (issue 31 item 6: to 1e-8 relative).

Two independent routes to ``d crank_angle(T) / dp``: :func:`mbcomp.simulate` with
``sensitivities=`` integrates ``S`` forward with the run (staggered, exact ``f_y``, ``f_p``),
:func:`mbcomp.gradient` integrates the adjoint backward (vector-Jacobian programs).
"""
import numpy as np
import pytest

import mbcomp

SLIDER = mbcomp.load_model_file("models/slider_crank.py").build
CHAIN = mbcomp.load_model_file("models/n_link_pendulum.py").build


@pytest.mark.parametrize("case", ["slider_crank", "chain"])
def test_forward_and_adjoint_gradients_agree(case):
    if case == "slider_crank":
        build, column = SLIDER, "crank_angle"
        params = ["rod.m", "crank.m", "slider.m", "rod.I[2, 2]", "crank_joint.phi0", "crank_joint.w0", "rod_tip.r[0]"]
    else:
        build, column = (lambda: CHAIN(N=4)), "joint4.phi"
        params = ["link1.m", "link3.m", "joint2.phi0", "world.g[1]"]
    grad = mbcomp.gradient(build(), {"terminal": column}, params, t_end=1.0, rtol=1e-10, atol=1e-12)
    res = mbcomp.simulate(build(), t_end=1.0, sensitivities=params, rtol=1e-10, atol=1e-12)
    forward = np.array([res.sensitivity(column, p)[-1] for p in params])
    assert np.all(np.abs(forward) > 1e-3)  # every parameter moves the objective: a real comparison
    np.testing.assert_allclose(grad.gradient, forward, rtol=1e-8, atol=0)
