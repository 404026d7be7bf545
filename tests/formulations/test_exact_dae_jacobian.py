"""Exact Jacobians of the multiplier DAE forms and of the generalized-alpha matrix (issue 31
item 1): :mod:`mbcomp.codegen.dae_jacobian` differentiates the traced evaluation with the
accelerations, multipliers (and GGL's ``eta``) as extra inputs.

Checks: every form's ``d fun / dy`` against the sympy-exact one built from
:func:`mbcomp.equations` (``M``, ``f``, ``C``, ``Phi``, ``cb`` of the same kept rows) on a
double pendulum and the slider-crank loop; the generalized-alpha ``K`` and ``Ct`` likewise;
Taylor tests (the central-difference error of ``J d`` falls as ``h^2`` over three decades) on
the slider-crank for every form and on a quaternion chain through ``increment``; the forms
take the program where one runs and count it, the numeric backend differences; radau5, IDA
and generalized-alpha runs with the exact matrices follow the runs with differenced ones.
"""
import numpy as np
import pytest
import sympy as sp

import mbcomp
from conftest import double_pendulum
from conftest import load_model
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import compile_system
from mbcomp.codegen.dae_jacobian import DAEJacobianCode
from mbcomp.codegen.toolchain import c_compiler
from mbcomp.formulations import DAlembert
from mbcomp.formulations.dae import GGL, Index1, Index3, Mechanical
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

slider_crank = load_model("models/slider_crank.py")
chain_3d = load_model("models/chain_3d.py")
BACKENDS = ["python", pytest.param("c", marks=pytest.mark.skipif(c_compiler() is None, reason="no C compiler"))]
FORMS = {"index1": Index1, "ggl": GGL, "index3": Index3}




MODELS = {"double_pendulum": double_pendulum, "slider_crank": slider_crank.build}


def _form(build, name, backend):
    s = mbcomp.assemble(build())
    init = initialize(s)
    form = FORMS[name](compile_system(s, backend))
    y = form.initial_state(0.0, init.q, init.u)
    # off the constraint manifold and off the consistent a, lam: every term of the residual acts
    return form, y + 0.05 * np.sin(1.3 * np.arange(y.size) + 0.4)


def _sympy_residual(eqs, name, alpha=10.0, beta=10.0):
    """The form's residual in sympy from the symbolic equations (angles and sliders only:
    ``dq/dt = u``), with symbols for ``a``, ``lam``, ``eta``; and its state."""
    q, u = sp.Matrix(eqs.q), sp.Matrix(eqs.u)
    nu, mh = len(u), eqs.C.shape[0]
    a = sp.Matrix(sp.symbols(f"a0:{nu}"))
    lam = sp.Matrix(sp.symbols(f"lam0:{mh}")) if mh else sp.zeros(0, 1)
    C = eqs.C if mh else sp.zeros(0, nu)
    dyn = eqs.f - eqs.M * a - C.T * lam
    Phi = eqs.Phi if mh else sp.zeros(0, 1)
    Phid = C * u
    if name == "index3":
        return sp.Matrix.vstack(u, a, dyn, -Phi), list(q) + list(u) + list(a) + list(lam)
    if name == "ggl":
        eta = sp.Matrix(sp.symbols(f"eta0:{mh}")) if mh else sp.zeros(0, 1)
        return (sp.Matrix.vstack(u - C.T * eta, a, dyn, -Phid, -Phi),
                list(q) + list(u) + list(a) + list(lam) + list(eta))
    cb = eqs.cb if mh else sp.zeros(0, 1)
    return (sp.Matrix.vstack(u, a, dyn, -(C * a + cb + 2 * alpha * Phid + beta ** 2 * Phi)),
            list(q) + list(u) + list(a) + list(lam))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list(FORMS))
@pytest.mark.parametrize("which", list(MODELS))
def test_every_form_s_jacobian_is_sympy_exact(which, name, backend):
    eqs = mbcomp.equations(MODELS[which]())
    form, y = _form(MODELS[which], name, backend)
    F, syms = _sympy_residual(eqs, name)
    assert len(syms) == form.n
    at = {s: sp.Rational(repr(float(v))) for s, v in zip(syms, y)}
    ref = np.array(F.jacobian(syms).subs(at).evalf(30), dtype=float)
    # the residual itself agrees (same rows, same signs), then its derivative
    np.testing.assert_allclose(form.fun(0.0, y), np.array(F.subs(at).evalf(30), dtype=float).ravel(),
                               rtol=1e-12, atol=1e-12)
    J = form.jac(0.0, y)
    assert form.run_stats() == {"jac_exact": 1, "jac_differences": 0}
    np.testing.assert_allclose(J, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list(FORMS))
def test_taylor_every_form_s_central_difference_error_falls_as_h_squared(name, backend):
    form, y = _form(slider_crank.build, name, backend)
    J = form.jac(0.0, y)
    d = np.random.default_rng(5).standard_normal(y.size)
    hs = [3e-2, 3e-3, 3e-4, 3e-5]  # three decades in the asymptotic range, above rounding
    err = [np.abs((form.fun(0.0, y + h * d) - form.fun(0.0, y - h * d)) / (2 * h) - J @ d).max() for h in hs]
    rates = np.log10(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(rates > 1.9) and np.all(rates < 2.1), (err, rates)


def _mechanical(build, backend):
    s = mbcomp.assemble(build())
    init = initialize(s)
    form = Mechanical(compile_system(s, backend))
    y = form.initial_state(0.0, init.q, init.u)
    nq, nu = form.nq, form.nu
    q, u = init.q, init.u + 0.2 * np.cos(np.arange(nu))
    udot = y[nq + nu:nq + 2 * nu] + 0.3 * np.sin(np.arange(nu) + 1.0)
    lam = y[nq + 3 * nu:] + 0.7
    return form, q, u, udot, lam


@pytest.mark.parametrize("backend", BACKENDS)
def test_generalized_alpha_tangents_are_sympy_exact_on_the_slider_crank(backend):
    eqs = mbcomp.equations(slider_crank.build())
    form, q, u, udot, lam = _mechanical(slider_crank.build, backend)
    qs, us = list(eqs.q), list(eqs.u)
    r = eqs.M * sp.Matrix(udot.tolist()) + eqs.C.T * sp.Matrix(lam.tolist()) - eqs.f
    at = {s: sp.Rational(repr(float(v))) for s, v in zip(qs + us, list(q) + list(u))}
    K_ref = np.array(r.jacobian(qs).subs(at).evalf(30), dtype=float)  # dq/dt = u: increment is q + dq
    Ct_ref = -np.array(eqs.f.jacobian(us).subs(at).evalf(30), dtype=float)
    K, Ct = form.tangents(0.0, q, u, udot, lam)
    np.testing.assert_allclose(K, K_ref, rtol=1e-11, atol=1e-11 * np.abs(K_ref).max())
    np.testing.assert_allclose(Ct, Ct_ref, rtol=1e-11, atol=1e-11 * np.abs(Ct_ref).max())
    assert form.run_stats() == {"jac_exact": 1, "jac_differences": 0}


@pytest.mark.parametrize("backend", BACKENDS)
def test_taylor_generalized_alpha_stiffness_through_quaternion_increments(backend):
    """Ball joints (quaternions, nq = 4/3 nu): ``K`` is the derivative along ``increment``,
    the speed-space move the Newton iteration makes."""
    form, q, u, udot, lam = _mechanical(lambda: chain_3d.build(N=3), backend)
    assert form.nq > form.nu
    K, Ct = form.tangents(0.0, q, u, udot, lam)

    def r(qq, uu):
        M, f, _, C = form.dynamics(0.0, qq, uu)
        return M @ udot + C.T @ lam - f

    d = np.random.default_rng(7).standard_normal(form.nu)
    hs = [1e-2, 1e-3, 1e-4, 1e-5]
    eK = [np.abs((r(form.increment(q, h * d), u) - r(form.increment(q, -h * d), u)) / (2 * h) - K @ d).max()
          for h in hs]
    eC = [np.abs((r(q, u + h * d) - r(q, u - h * d)) / (2 * h) - Ct @ d).max() for h in hs]  # dr/du = -df/du
    rates = np.log10(np.array(eK[:-1]) / np.array(eK[1:]))
    assert np.all(rates > 1.9) and np.all(rates < 2.1), (eK, rates)
    # f is quadratic in the speeds (gyroscopic and centripetal terms): central differences
    # of it are exact up to rounding at every h
    assert max(eC) < 1e-9 * (1.0 + np.abs(Ct).max()), eC


def test_the_numeric_backend_differences_and_counts_it():
    s = mbcomp.assemble(slider_crank.build())
    init = initialize(s)
    num = Index3(s)
    y = num.initial_state(0.0, init.q, init.u)
    assert not num.exact_jac
    Jd = num.jac(0.0, y)
    assert num.run_stats() == {"jac_exact": 0, "jac_differences": 1}
    form = Index3(compile_system(mbcomp.assemble(slider_crank.build()), "python"))
    initialize(form.system)
    assert form.exact_jac
    J = form.jac(0.0, y)
    # the exact Jacobian against the differences: agree to the differences' own error
    np.testing.assert_allclose(J, Jd, rtol=1e-6, atol=1e-6 * np.abs(J).max())
    assert np.abs(J - Jd).max() > 0.0  # and they are not the same numbers (no differencing here)


def test_no_exact_matrix_where_an_entry_is_not_finite():
    s = mbcomp.assemble(double_pendulum())
    jac = DAEJacobianCode.build(s, "index3", "python").bind(s)
    y = np.array([0.7, -0.4, 1.3, -0.8, 0.1, 0.2])
    assert np.isfinite(jac(0.0, y)).all()
    y[2] = 1e160  # squares to infinity in the centripetal terms: no exact Jacobian there
    assert jac(0.0, y) is None


RUNS = [("radau5", 1, {}), ("radau5", 2, {}), ("radau5", 3, {}), ("ida", 1, {}), ("ida", 2, {}),
        ("genalpha", 3, {"h": 5e-4}), ("BDF", None, {"formulation": "dalembert"}),
        ("Radau", None, {"formulation": "dalembert"})]
COLUMNS = ("crank_joint.phi", "slider_joint.s", "crank_joint.w")


@pytest.fixture(scope="module")
def reference():
    """The slider-crank's motion to 1e-12 (DOP853 on the Lagrange form)."""
    return mbcomp.simulate(slider_crank.build(), t_end=1.0, rtol=1e-12, atol=1e-14, n_out=11)


@pytest.mark.parametrize("method, index, kw", RUNS, ids=[f"{m}-{i or 'dalembert'}" for m, i, _ in RUNS])
def test_runs_with_exact_matrices_are_as_accurate_as_runs_with_differenced_ones(method, index, kw, reference):
    """The Newton matrix changes the iteration, not the equations: against the exact motion,
    the run with exact matrices is as accurate as the run with differenced ones (numeric
    backend) -- the error control, not the matrix, decides the error."""
    opts = dict(t_end=1.0, method=method, index=index, rtol=1e-7, atol=1e-9, n_out=11, **kw)
    exact = mbcomp.simulate(slider_crank.build(), backend="python", **opts)
    diff = mbcomp.simulate(slider_crank.build(), backend="numeric", **opts)
    assert exact.success and diff.success
    assert exact.stats["jac_exact"] > 0 and exact.stats["jac_differences"] == 0
    assert diff.stats.get("jac_exact", 0) == 0
    for col in COLUMNS:
        e_exact = np.abs(exact[col] - reference[col]).max()
        e_diff = np.abs(diff[col] - reference[col]).max()
        assert e_exact <= 3.0 * e_diff + 1e-7, (col, e_exact, e_diff)
        if method == "genalpha":  # fixed steps: the same discrete equations, solved to Newton's tolerance,
            # so the two runs differ by far less than the method's own error
            assert np.abs(exact[col] - diff[col]).max() <= 0.01 * e_diff, (col, e_diff)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("which", ["slider_crank", "andrews"])
def test_taylor_dalembert_jacobian_through_the_dependent_speeds(which, backend):
    """D'Alembert's ``d fun / d[q, v]`` (chain rule through the speeds the loop determines):
    the central-difference error falls as ``h^2``, and the matrix is the one ``jac`` gives."""
    build = slider_crank.build if which == "slider_crank" else load_model("models/andrews.py").build
    s = compile_system(mbcomp.assemble(build()), backend)
    init = initialize(s)
    form = DAlembert(s)
    y = form.initial_state(0.0, init.q, init.u)
    y = y + 0.01 * np.sin(np.arange(y.size) + 0.3)  # off the loop: the dependent speeds move with q
    J = form.jac(0.0, y)
    assert form.run_stats()["jac_exact"] == 1 and form.run_stats()["jac_differences"] == 0
    d = np.random.default_rng(11).standard_normal(y.size)
    hs = [1e-2, 1e-3, 1e-4, 1e-5]
    err = [np.abs((form.fun(0.0, y + h * d) - form.fun(0.0, y - h * d)) / (2 * h) - J @ d).max() for h in hs]
    rates = np.log10(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(rates > 1.9) and np.all(rates < 2.1), (err, rates)


def test_dalembert_on_the_numeric_backend_differences():
    s = mbcomp.assemble(slider_crank.build())
    init = initialize(s)
    form = DAlembert(s)
    y = form.initial_state(0.0, init.q, init.u)
    np.testing.assert_array_equal(form.jac(0.0, y), form.difference_columns(0.0, y, range(y.size)))
    assert form.run_stats()["jac_differences"] == 1 and form.run_stats()["jac_exact"] == 0


def _driven_crank():
    """The slider-crank with its crank angle prescribed: the drive's (s, v, a) are per-call
    inputs of the evaluation the Jacobian program differentiates."""
    m = slider_crank.build()
    d = m.add("drive", PrescribedMotion(s="0.3 + 6*t + 0.5*sin(3*t)"))
    m.connect(m["crank_joint"].axis, d.flange_b)
    return m


MORE = {"driven_crank": _driven_crank, "bicycle": lambda: load_model("models/bicycle.py").build(),
        "chain_3d": lambda: chain_3d.build(N=2)}


@pytest.mark.parametrize("name", list(FORMS))
@pytest.mark.parametrize("which", list(MORE))
def test_drives_velocity_rows_and_quaternions_against_careful_differences(which, name):
    """A drive (per-call inputs), nonholonomic rows (``B``, ``Psi``) and quaternion rates:
    the exact matrix against five-point central differences (error ~h^4, 1e-12 here)."""
    form, y = _form(MORE[which], name, "python")
    t = 0.37
    J = form.jac(t, y)
    assert form.run_stats()["jac_exact"] == 1
    ref = np.empty_like(J)
    for j in range(y.size):
        h = 1e-3 * max(1.0, abs(y[j]))
        f = [form.fun(t, y + k * h * np.eye(y.size)[j]) for k in (-2, -1, 1, 2)]
        ref[:, j] = (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)
    np.testing.assert_allclose(J, ref, rtol=0, atol=1e-8 * np.abs(ref).max())


def test_above_the_size_cap_the_forms_difference():
    """Above MAX_SPEEDS speeds no program is made (its size grows as nu^3): differences."""
    from mbcomp.codegen.dae_jacobian import MAX_SPEEDS

    chain = load_model("models/n_link_pendulum.py")
    s = compile_system(mbcomp.assemble(chain.build(N=MAX_SPEEDS + 1)), "python")
    init = initialize(s)
    form = Index3(s)
    assert not form.exact_jac
    y = form.initial_state(0.0, init.q, init.u)
    form.jac(0.0, y)
    assert form.run_stats() == {"jac_exact": 0, "jac_differences": 1}
