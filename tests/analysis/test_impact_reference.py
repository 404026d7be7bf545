"""Work-precision against a model file's closed form (issue 22): the door against its stops.

``models/door.py``'s ``reference(t_end, **build_kw)`` chains the closed-form impacts of the
damped door; ``work_precision`` takes it for any build parameters and end time, so the
error measured after several impacts is the event location's plus the integration's."""
import numpy as np

import mbcomp
from mbcomp.analysis.workprecision import Combo, reference_values, work_precision

DOOR = "models/door.py"


def test_door_closed_form_agrees_with_a_tight_run():
    mod = mbcomp.load_model_file(DOOR)
    kw = dict(damping=1.0, w0=-3.0)
    t_end, values, how = reference_values(mod, build_kw=kw, t_end=8.0)
    assert t_end == 8.0 and how.startswith("closed form")
    res = mbcomp.simulate(mod.build(**kw), t_end=t_end, rtol=1e-11, atol=1e-13, n_out=2)
    ref = mod.reference(t_end=8.0, **kw)
    impacts = [x.time for x in res.events if x.kind == "impact"]
    assert len(impacts) == len(ref["impacts"]) == 3
    assert np.max(np.abs(np.subtract(impacts, ref["impacts"]))) < 1e-9
    for name, v in values.items():
        assert abs(res[name][-1] - v) < 1e-9, name
    # undamped: the closed form of the module notes (first impact at phi0/|w0|, rebound 0.6)
    undamped = reference_values(mod, t_end=3.0)[1]
    assert abs(undamped["hinge.phi"] - 1.2) < 1e-12 and undamped["hinge.w"] == 0.6


def test_door_work_precision_error_falls_with_the_tolerance():
    rows = work_precision(DOOR, [Combo("dop853", dict(method="dop853"))], tols=[1e-4, 1e-7, 1e-10],
                          build_kw=dict(damping=1.0, w0=-3.0), t_end=8.0, log=lambda line: None)
    err = [r["error"] for r in rows]
    assert all(r["status"] == "success" for r in rows)
    assert err[2] < 1e-8 and err[2] < err[1] < 1e-4
