"""A law that branches on the time or a state cannot be held by an FMU's program (issue 33 item
4): the export refuses it, naming the law and its line; a smooth law of the same model exports
and runs through the states the branching one would have failed at, as ``mbcomp.simulate`` does.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import torque_pendulum

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from mbcomp.export import export_fmu  # noqa: E402


def on_the_angle(t, phi, w):
    if phi > 0.0:  # the pendulum starts at 0.5 rad and swings through 0: the other branch
        return 1.0
    return -1.0


def after_a_while(t, phi, w):
    return 0.5 if t > 1.0 else 0.0


def clipped(t, phi, w):
    return min(0.3, 5.0 * abs(w))


#: each law, the text of its deciding line, and what shows the motion took its other branch
LAWS = [(on_the_angle, "phi > 0.0", lambda r: r["hinge.phi"].min() < 0.0),
        (after_a_while, "t > 1.0", lambda r: r.time[-1] > 1.0),
        (clipped, "min(", lambda r: 5.0 * np.abs(r["hinge.w"]).max() > 0.3)]


@pytest.mark.parametrize("law, line, other_branch", LAWS, ids=[x[0].__name__ for x in LAWS])
def test_a_law_branching_on_the_time_or_a_state_is_refused_naming_it(law, line, other_branch, tmp_path):
    with pytest.raises(ValueError) as err:
        export_fmu(torque_pendulum(law), tmp_path / "m.fmu")
    msg = str(err.value)
    lineno = law.__code__.co_firstlineno + next(k for k, src in enumerate(
        open(__file__).read().splitlines()[law.__code__.co_firstlineno - 1:]) if line in src)
    assert "motor.tau" in msg and f"test_fmu_laws.py:{lineno}" in msg and "np.tanh" in msg, msg
    assert not (tmp_path / "m.fmu").exists()
    # mbcomp.simulate follows both branches (a guard that fails leaves the program for the
    # numeric path, or traces the other branch), where the FMU's one branch would have failed
    res = mbcomp.simulate(torque_pendulum(law), t_end=2.0, n_out=201)
    assert res.success and other_branch(res)


def test_a_smooth_law_exports_and_runs_through_the_sign_changes_as_simulate(tmp_path):
    def smooth(t, phi, w):
        return -0.4 * np.tanh(w / 0.05) + 0.1 * abs(phi)

    path = tmp_path / "smooth.fmu"
    export_fmu(torque_pendulum(smooth), path, derivatives=False)
    ref = mbcomp.simulate(torque_pendulum(smooth), t_end=3.0, n_out=101, rtol=1e-11, atol=1e-13)
    assert np.ptp(np.sign(ref["hinge.w"])) == 2  # w changes sign: the tanh's both sides are taken
    r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=3.0, output=["hinge.phi"],
                          relative_tolerance=1e-10, output_interval=0.03)
    assert float(np.max(np.abs(np.interp(ref.time, r["time"], r["hinge.phi"]) - ref["hinge.phi"]))) < 1e-7
