"""External inputs (:class:`mbcomp.Input`): a signal standing where a law is given.

Reference: a 2 kg point mass on a 1 m massless rod turning about a vertical hinge (no
gravity), driven by a torque ``u(t)``: ``2 phi'' = u`` exactly. With ``u = sin t`` from rest,
``w = (1 - cos t) / 2`` and ``phi = (t - sin t) / 2``.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from conftest import turntable

BACKENDS = ["numeric", "python"] + (["c"] if c_compiler() else [])


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_input_drives_the_model_as_the_exact_motion(backend):
    r = mbcomp.simulate(turntable(mbcomp.Input("u", unit="N m")), t_end=3.0, n_out=31, backend=backend,
                        inputs={"u": np.sin})
    assert r.success, r.message
    t = r.time
    np.testing.assert_allclose(r["j.w"], (1 - np.cos(t)) / 2, atol=1e-7)
    np.testing.assert_allclose(r["j.phi"], (t - np.sin(t)) / 2, atol=1e-7)


# sin(3 t) tabulated every 0.1 s: each breakpoint is a kink the integrator steps onto, so the
# table's length sets the run's cost (201 points took 857 steps, 4 s of CPU per run; 21 take 180
# steps), not what is checked: the Input's interpolation against np.interp of the same table
TABLE_TIMES = np.linspace(0.0, 2.0, 21)
TABLE = (TABLE_TIMES, np.sin(3 * TABLE_TIMES))


@pytest.fixture(scope="module")
def written_in():
    """The reference for the table cases: the same law with the signal written in (one run
    serves every backend)."""
    return mbcomp.simulate(turntable(lambda t, phi, w: -5.0 * phi + np.interp(t, *TABLE)), t_end=2.0, n_out=21,
                           backend="numeric", rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_input_inside_a_law_and_a_table(backend, written_in):
    """An Input called inside a law of one's own (a spring plus the input), given as a table:
    against the same law with the signal written in."""
    u = mbcomp.Input("u2", unit="N m")
    law = turntable(lambda t, phi, w: -5.0 * phi + u(t))
    r = mbcomp.simulate(law, t_end=2.0, n_out=21, backend=backend, inputs={"u2": TABLE}, rtol=1e-10, atol=1e-12)
    assert r.success, r.message
    np.testing.assert_allclose(r["j.phi"], written_in["j.phi"], atol=1e-8)
    assert np.ptp(written_in["j.phi"]) > 1e-2  # the input moves the table (the comparison is not of zeros)


def test_an_input_not_given_keeps_its_start_value():
    r = mbcomp.simulate(turntable(mbcomp.Input("u3", start=4.0)), t_end=1.0, n_out=11)
    np.testing.assert_allclose(r["j.w"], 2.0 * r.time, atol=1e-9)  # 4 N m on 2 kg m^2


def test_bad_inputs_say_what_to_fix():
    m = turntable(mbcomp.Input("u4"))
    with pytest.raises(ValueError, match=r"inputs \['torqeu'\]: no Input of the model has that name"):
        mbcomp.simulate(m, t_end=1.0, inputs={"torqeu": 1.0})
    with pytest.raises(ValueError, match="strictly increasing times"):
        mbcomp.simulate(m, t_end=1.0, inputs={"u4": ([0.0, 0.0], [1.0, 2.0])})
    with pytest.raises(ValueError, match="Input name '1x'"):
        mbcomp.Input("1x")
