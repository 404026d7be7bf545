"""The C engine (dop853/dopri5 over the compiled Lagrange program) against scipy's DOP853 on
the dense path, its energy conservation, and the Python continuation past a failed guard."""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import compiled, load_model, torque_pendulum

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


# --------------------------------------------------------------------------- projection in C
def _projection_form(path):
    from mbcomp.assembly.initialization import initialize
    from mbcomp.formulations import build

    s = compiled(load_model(path).build())
    init = initialize(s, 0.0)
    form = build("lagrange", "ode", s, stabilization="projection")
    return s, form, form.project(0.0, form.initial_state(0.0, init.q, init.u))


@pytest.mark.parametrize("path", ["models/slider_crank.py", "models/four_bar.py"])
def test_the_c_projection_is_the_python_projection_after_every_step(path):
    """The engine projecting in C against the same runtime DOP853 driven from Python with
    callbacks (the formulation's ``fun`` and ``project``, what the Python driver does after
    each step): at rtol 1e-6 the projections move the state by up to 1e-5, and both runs take
    the same steps to the same states (1e-12), every accepted step projected."""
    import ctypes

    from mbcomp.codegen.engine import RuntimeStats

    s, form, y0 = _projection_form(path)
    eng = form.compiled_integrator()
    assert eng is not None and eng.projects
    n, t_out = y0.size, np.linspace(0.0, 0.5, 11)
    r = eng.integrate(8, 0.0, y0, 0.5, t_out, 1e-6, 1e-8)
    assert r.status == 0 and r.projections == r.naccept > 5

    rhs_t = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                             ctypes.POINTER(ctypes.c_double))
    step_t = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.POINTER(ctypes.c_double))
    moved = []

    def rhs(ctx, t, y, dy):
        np.ctypeslib.as_array(dy, (n,))[:] = form.fun(t, np.ctypeslib.as_array(y, (n,)).copy())
        return 0

    def step(ctx, t, y):
        a = np.ctypeslib.as_array(y, (n,))
        b = form.project(t, a.copy())
        moved.append(np.abs(b - a).max())
        a[:] = b
        return 0

    dll = eng.bound.code.dll  # the engine's library holds the runtime
    vp, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    dll.mbrt_dop853.argtypes = [rhs_t, step_t, vp, i, d, vp, d, d, vp, d, d, ctypes.c_long, vp, i, vp, vp, vp, vp]
    dll.mbrt_dop853.restype = i
    f, g = rhs_t(rhs), step_t(step)
    Y, nw, st = np.zeros((len(t_out), n)), ctypes.c_int(), RuntimeStats()
    work, atol = np.zeros(int(dll.mbcomp_work_size(8, n))), np.full(n, 1e-8)
    rc = dll.mbrt_dop853(f, g, None, n, 0.0, y0.ctypes.data, 0.5, 1e-6, atol.ctypes.data, 0.0, 0.0, 0,
                         t_out.ctypes.data, len(t_out), Y.ctypes.data, ctypes.byref(nw), work.ctypes.data,
                         ctypes.byref(st))
    assert rc == 0 and st.naccept == r.naccept and len(moved) == r.projections
    assert max(moved) > 1e-7  # the projections did move the state
    np.testing.assert_allclose(r.Y, Y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.y_last, form.project(0.5, Y[-1]), rtol=0, atol=1e-12)


def _run(path, method, **kw):
    """One run through the driver, returning it (its steppers' counters are kept)."""
    from mbcomp.assembly.initialization import initialize
    from mbcomp.formulations import build
    from mbcomp.simulation.driver import integrate
    from mbcomp.simulation.setup import output_times
    from mbcomp.simulation.stepping import Run
    from mbcomp.solvers import STEPPERS

    s = compiled(load_model(path).build())
    init = initialize(s, 0.0)
    form = build("lagrange", "ode", s, stabilization="projection")
    run = Run(form, STEPPERS[method], output_times(0.0, kw.pop("t_end"), kw.pop("n_out"), None),
              form.initial_state(0.0, init.q, init.u), **kw)
    status, message = integrate(run, [], False)
    assert status == "success", message
    return s, form, run


@pytest.mark.parametrize("path", ["models/slider_crank.py", "models/four_bar.py"])
def test_a_projection_run_in_c_is_the_python_driven_run(path):
    """stabilization="projection" with dop853: one C call per stretch, projected after every
    accepted step in C, against scipy's DOP853 driven (and projected) by the Python driver:
    the same motion to the tolerance, the constraints closed at every output."""
    kw = dict(t_end=1.0, n_out=101, rtol=1e-10, atol=1e-12)
    s, form, fast = _run(path, "dop853", **kw)
    _, _, ref = _run(path, "DOP853", **kw)
    st = fast.stepper.stats
    assert st["python_steps"] == 0 and st["c_projections"] == st["nsteps"] > 0 and st["stretches"] <= 8
    counts = fast.counters()  # what the result reports: the engine's steps and projections
    assert counts["steps"] == st["nsteps"] and counts["projections"] == fast.stats["projections"] + st["c_projections"]
    Y, R = np.array(fast.ys), np.array(ref.ys)
    np.testing.assert_allclose(Y, R, rtol=0, atol=1e-7 * (1 + np.abs(R).max()))
    for t, y in zip(fast.t_out, Y):
        ev = s.evaluate(t, y[: s.nq], y[s.nq:])
        assert np.linalg.norm(ev.Phi) < 1e-9 and np.abs(ev.Phid).max() < 1e-9


def test_a_projection_declined_in_c_goes_on_in_python(monkeypatch):
    """When the C projection cannot close (here: asked for |Phi| = 0 exactly, which Newton
    does not reach), the stretch ends at that step, the driver projects it in Python and the
    rest of the stretch is stepped in Python; the run is the Python-driven run's."""
    import mbcomp.formulations.lagrange as lagrange

    monkeypatch.setattr(lagrange, "POSITION_TOL", 0.0)
    kw = dict(t_end=0.5, n_out=21, rtol=1e-9, atol=1e-11)
    s, form, fast = _run("models/slider_crank.py", "dop853", **kw)
    monkeypatch.undo()
    _, _, ref = _run("models/slider_crank.py", "DOP853", **kw)
    st = fast.stepper.stats
    assert st["python_steps"] > 0 and st["stretches"] > 0
    np.testing.assert_allclose(np.array(fast.ys), np.array(ref.ys), rtol=0, atol=1e-6)


def test_quaternion_systems_project_in_c_too():
    """A 3-D chain of ball joints (quaternion coordinates) with projection: the engine
    normalizes and turns the quaternions as the joints do, after every step, and the run is
    the Python-driven one to the tolerance with unit quaternions at every output."""
    kw = dict(t_end=0.3, n_out=16, rtol=1e-9, atol=1e-11)
    s, form, fast = _run("models/chain_3d.py", "dop853", **kw)
    _, _, ref = _run("models/chain_3d.py", "DOP853", **kw)
    st = fast.stepper.stats
    assert form.projects and st["python_steps"] == 0 and st["c_projections"] == st["nsteps"] > 0
    Y, R = np.array(fast.ys), np.array(ref.ys)
    np.testing.assert_allclose(Y, R, rtol=0, atol=1e-6 * (1 + np.abs(R).max()))
    for k in range(0, 16, 4):
        np.testing.assert_allclose(np.linalg.norm(Y[:, k:k + 4], axis=1), 1.0, atol=1e-14)
