"""Methods that break down say so: a result status with the cause, results kept up to it.

The four-bar's singular positions are in tests/mechanisms/test_four_bar.py; here the solver-level
failures of bench/failure_map.py: a generalized-alpha step too long for Andrews' stiff
spring (Newton diverges), a mechanism driven unstable until its state overflows, and the
reports every failed result carries.
"""
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from conftest import load_model, torque_pendulum
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

AND = load_model("models/andrews.py")


def test_generalized_alpha_with_too_long_a_step_reports_newton_divergence():
    """h = 1 ms on Andrews (spring period ~1 ms, accelerations 1e4-1e6 rad/s^2): Newton diverges
    near the end. The result says so, names the step size as the fix, and keeps the steps it
    took, which are on the constraint manifold (index 3 holds Phi = 0 at every step)."""
    res = mbcomp.simulate(AND.build(), t_end=0.03, method="genalpha", h=1e-3, backend="python", n_out=31)
    assert res.status == "failed"
    assert "generalized-alpha: Newton failed to converge" in res.message
    assert "smaller step size" in res.message
    assert 0.0 < res.time[-1] < 0.03
    assert np.all(np.isfinite(res["beta"]))
    assert np.max(res["residual.position"]) < 1e-8
    # the same method with a step 100x shorter is robust and accurate to its order (2)
    ok = mbcomp.simulate(AND.build(), t_end=0.03, method="genalpha", h=1e-5, backend="python", n_out=2)
    assert ok.success, ok.message
    ref = AND.REFERENCE["values"]
    assert max(abs(ok[n][-1] - v) / abs(v) for n, v in ref.items()) < 1e-3


def pumped_pendulum():
    """A pendulum whose hinge torque grows with the square of its speed (tau = w |w|, N m):
    with the bob's inertia 1 kg m^2, phi'' = w |w| - g sin(phi) blows up in finite time, so
    no integrator can pass it."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute(phi0=0.0, w0=1.0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=lambda t, phi, w: w * abs(w)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m


@pytest.mark.parametrize("method", ["RK45", "radau5"])
def test_a_diverging_run_is_a_failed_result_not_an_overflow(method):
    res = mbcomp.simulate(pumped_pendulum(), t_end=3.0, method=method, n_out=301)
    assert res.status == "failed"
    assert any(w in res.message for w in ("non-finite", "diverged", "collapsed", "overflow")), res.message
    assert np.all(np.isfinite(res["hinge.phi"]))
    # the blow-up time of phi'' = w|w| - g sin(phi), phi(0) = 0, w(0) = 1, found independently
    blow = lambda t, y: y[1] - 1e6  # noqa: E731
    blow.terminal = True
    sol = solve_ivp(lambda t, y: [y[1], y[1] * abs(y[1]) - 9.81 * np.sin(y[0])], (0, 3), [0.0, 1.0],
                    events=blow, rtol=1e-10, atol=1e-12)
    t_blow = sol.t_events[0][0]
    assert res.time[-1] <= t_blow + 1e-3 and res.time[-1] > t_blow - 0.05
    assert res["hinge.w"][-1] > 10.0  # it really was blowing up: the failure is the physics, reported


def test_every_failed_result_keeps_time_and_stats():
    res = mbcomp.simulate(AND.build(), t_end=0.03, method="genalpha", h=1e-3, backend="python", n_out=31)
    assert res.stats["steps"] > 0 and res.stats["nfev"] > 0 and "cpu_time" in res.stats
    assert len(res.time) == len(res["beta"]) and res.time[-1] < 0.03


@pytest.mark.parametrize("exc, says", [
    ("CodegenError('cannot load the compiled library x.so: bad ELF -> fix: delete it')",
     r"the generated program could not be used at t=0\.25\d*: cannot load the compiled library x\.so: bad ELF -> fix"),
    ("OSError('undefined symbol: mbrt_foo')",
     r"mbcomp's own code raised OSError at t=0\.25\d*: undefined symbol: mbrt_foo \(no component's law .* report it"),
])
def test_a_failure_in_mbcomps_own_code_is_not_blamed_on_a_law(monkeypatch, exc, says):
    """An exception with no component's or user's code in its traceback (a compiled library
    that cannot be loaded, mbcomp's own bug) ends the run with what failed and whose it is --
    not "the model: ? raised ... -> fix the law" -- and keeps the results before it."""
    import mbcomp.formulations.lagrange as lagrange
    from mbcomp.codegen import CodegenError

    # a function of mbcomp's own (its code in mbcomp's sources) that raises from t = 0.25 s
    src = (f"def fun(self, t, y, _fun=_fun):\n    if t >= 0.25:\n        raise {exc}\n    return _fun(self, t, y)\n")
    scope = {"_fun": lagrange.LagrangeIndex1.fun, "CodegenError": CodegenError}
    exec(compile(src, lagrange.__file__, "exec"), scope)
    monkeypatch.setattr(lagrange.LagrangeIndex1, "fun", scope["fun"])
    res = mbcomp.simulate(torque_pendulum(lambda t, phi, w: 0.0), t_end=1.0, n_out=11, method="RK45",
                         backend="numeric")
    assert res.status == "failed"
    assert re.match(says, res.message), res.message
    assert "fix the law" not in res.message and "are kept" in res.message
    assert 0.1 < res.time[-1] < 0.25 + 1e-12


def test_a_compiled_library_that_cannot_be_loaded_says_which_file_and_the_fix(tmp_path):
    from mbcomp.codegen import CodegenError
    from mbcomp.codegen.toolchain import load_library

    cut = tmp_path / "mbcomp_cut_short.so"
    cut.write_bytes(b"\x7fELF not a library")
    with pytest.raises(CodegenError, match=r"cannot load the compiled library .*mbcomp_cut_short\.so: .* -> fix: delete it"):
        load_library(str(cut))
