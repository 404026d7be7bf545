"""Slider-crank (closed loop): energy, constraint drift, and an independent 1-DOF derivation.

The independent reference: with the loop solved by hand (rod angle psi from
sin(psi) = -Lc sin(phi) / Lr), the mechanism has kinetic energy T = J(phi) phidot^2 / 2 and
potential V(phi); Lagrange's equation J phi'' + J'/2 phi'^2 + V' = 0 is derived here with
sympy and integrated with scipy at tight tolerance.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model

sc = load_model("models/slider_crank.py")
P = dict(crank_length=0.2, rod_length=0.6, m_crank=1.0, m_rod=2.0, m_slider=0.5, phi0=0.3, w0=6.0)
T_END = 2.0


def reference(t_eval, **over):
    par = {**P, **over}
    Lc, Lr, mc, mr, ms = (par[k] for k in ("crank_length", "rod_length", "m_crank", "m_rod", "m_slider"))
    g = 9.81
    phi, phid = sp.symbols("phi phid")
    psi = sp.asin(-Lc * sp.sin(phi) / Lr)
    tip = sp.Matrix([Lc * sp.cos(phi), Lc * sp.sin(phi)])
    rod_cm = tip + Lr / 2 * sp.Matrix([sp.cos(psi), sp.sin(psi)])
    x_s = tip[0] + Lr * sp.cos(psi)
    crank_cm = tip / 2

    def vel2(p):
        return sum((sp.diff(c, phi) * phid) ** 2 for c in p)

    psid = sp.diff(psi, phi) * phid
    T = (mc / 2 * vel2(crank_cm) + mc * Lc ** 2 / 24 * phid ** 2 + mr / 2 * vel2(rod_cm)
         + mr * Lr ** 2 / 24 * psid ** 2 + ms / 2 * (sp.diff(x_s, phi) * phid) ** 2)
    V = g * (mc * crank_cm[1] + mr * rod_cm[1])
    J = sp.diff(T, phid, 2)
    acc = -(sp.diff(J, phi) / 2 * phid ** 2 + sp.diff(V, phi)) / J
    f_acc = sp.lambdify((phi, phid), acc)
    sol = solve_ivp(lambda t, y: [y[1], f_acc(y[0], y[1])], (0, t_eval[-1]), [par["phi0"], par["w0"]],
                    t_eval=t_eval, rtol=1e-12, atol=1e-12, method="DOP853")
    return sol.y[0], sp.lambdify(phi, x_s)(sol.y[0])


@pytest.mark.parametrize("stab", ["none", "baumgarte", "projection"])
def test_slider_crank_matches_independent_lagrange(stab):
    res = mbcomp.simulate(sc.build(**P), t_end=T_END, rtol=1e-9, atol=1e-11, stabilization=stab, n_out=201)
    assert res.success, res.message
    phi_ref, x_ref = reference(res.time)
    np.testing.assert_allclose(res["crank_angle"], phi_ref, atol=2e-6)
    np.testing.assert_allclose(res["slider_position"], x_ref, atol=1e-6)
    E = res["energy.total"]
    assert np.abs(E - E[0]).max() < 1e-6 * (np.abs(res["energy.kinetic"]).max() + 1.0)
    drift = res["residual.position"].max()
    bound = {"none": 1e-6, "baumgarte": 1e-8, "projection": 1e-11}[stab]
    assert drift < bound, f"{stab}: position residual {drift:g}"


def test_summary_reports_one_dof_and_dropped_rows():
    system = mbcomp.assemble(sc.build())
    text = system.summary()
    assert "degrees of freedom: 1 " in text
    assert "rod_joint.tilt_1" in text  # the out-of-plane rows of the planar loop are redundant


def test_baumgarte_bounds_drift_that_grows_without_it():
    """Over a longer run at loose tolerance the unstabilized index-1 form drifts; Baumgarte keeps
    the residual bounded orders of magnitude lower (the classic reason for stabilization)."""
    kw = dict(t_end=4.0, rtol=1e-5, atol=1e-7, n_out=81, method="RK45")  # RK45's loose error drives the drift
    plain = mbcomp.simulate(sc.build(), stabilization="none", **kw)
    stab = mbcomp.simulate(sc.build(), stabilization="baumgarte", **kw)
    proj = mbcomp.simulate(sc.build(), stabilization="projection", **kw)
    d_plain = plain["residual.position"]
    assert d_plain[-1] > 10 * d_plain[5]  # it grows
    assert stab["residual.position"].max() < 0.05 * d_plain.max()
    assert proj["residual.position"].max() < 1e-10


def test_massless_rod_is_legal_where_its_motion_is_determined():
    """A massless connecting rod (m = 0, I = 0): its motion is fixed by crank and slider, so the
    reduced mass matrix stays positive definite and the result matches the reference with m_rod = 0."""
    res = mbcomp.simulate(sc.build(**{**P, "m_rod": 0.0}), t_end=1.0, rtol=1e-9, atol=1e-11, n_out=51)
    assert res.success, res.message
    phi_ref, x_ref = reference(res.time, m_rod=0.0)
    np.testing.assert_allclose(res["crank_angle"], phi_ref, atol=2e-6)
    np.testing.assert_allclose(res["slider_position"], x_ref, atol=1e-6)
