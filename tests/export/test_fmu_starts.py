"""Start values an importer sets on a state are honoured by mbcomp's consistent initialization
inside the FMU (issue 33 item 4): the value set is kept, the model's guesses move to close the
loop, the model's other fixed starts stay; a start the constraints cannot meet is an error naming
it. Checked against ``mbcomp.simulate`` of the model built with that start value.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler

from conftest import load_model

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from mbcomp.export import export_fmu  # noqa: E402

VERSIONS = ["3.0", "2.0"]
VARS = ["crank_joint.phi", "rod_joint.phi", "slider_joint.s", "crank_joint.w"]


@pytest.fixture(scope="module")
def crank_fmus(tmp_path_factory):
    root = tmp_path_factory.mktemp("starts")
    built = {}

    def get(fmi):
        if fmi not in built:
            built[fmi] = root / f"slider_crank_{fmi[0]}.fmu"
            export_fmu(load_model("models/slider_crank.py").build(), built[fmi], fmi=fmi, derivatives=False)
        return built[fmi]
    return get


def max_diff(r, ref, var):
    return float(np.max(np.abs(np.interp(ref.time, r["time"], r[var]) - ref[var])))


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("how", ["state", "start parameter"])
def test_a_start_set_on_a_state_is_kept_and_the_loop_closed_as_mbcomp_does(fmi, how, crank_fmus):
    """``crank_joint.phi = 1.0`` set as FMPy's ``start_values`` (the state itself, or the FMU's
    ``start.crank_joint.phi`` parameter): the crank starts at exactly 1.0 rad (a minimum-norm
    projection of every coordinate moved it to 0.938 rad), the rod and the slider where the loop
    closes, the crank's fixed rate kept; the motion is mbcomp's from ``phi0=1.0``."""
    path = crank_fmus(fmi)
    name = "crank_joint.phi" if how == "state" else "start.crank_joint.phi"
    ref = mbcomp.simulate(load_model("models/slider_crank.py").build(phi0=1.0), t_end=2.0, n_out=101, rtol=1e-11,
                          atol=1e-13)
    assert abs(ref["crank_joint.phi"][0] - 1.0) == 0.0
    for fmi_type, agree in (("ModelExchange", 1e-5), ("CoSimulation", 1e-7)):
        r = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=2.0, start_values={name: 1.0},
                              output=VARS, relative_tolerance=1e-10, output_interval=0.02)
        assert r["crank_joint.phi"][0] == 1.0 and r["crank_joint.w"][0] == ref["crank_joint.w"][0]
        for var in VARS:
            assert abs(r[var][0] - ref[var][0]) < 1e-10, (fmi_type, var, r[var][0], ref[var][0])
            # the agreement of test_fmu's runs (angles in rad), relative to a variable's size (the
            # crank's rate reaches 9.8 rad/s)
            assert max_diff(r, ref, var) < agree * max(1.0, np.abs(ref[var]).max()), (fmi_type, var)


@pytest.mark.parametrize("fmi", VERSIONS)
def test_starts_the_loop_cannot_meet_are_refused_naming_them(fmi, crank_fmus, capfd):
    """The crank at 1.0 rad and the slider 5 m out: a 0.6 m rod cannot join them. The FMU says so
    at initialization, naming both values, instead of starting with an open loop."""
    path = crank_fmus(fmi)
    with pytest.raises(Exception, match="ExitInitializationMode"):
        fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=1.0, debug_logging=True,
                          start_values={"crank_joint.phi": 1.0, "slider_joint.s": 5.0}, output=VARS)
    out = capfd.readouterr()
    text = out.out + out.err
    assert "crank_joint.phi = 1" in text and "slider_joint.s = 5" in text and "cannot all hold" in text, text
