"""FMUs with events for models with kinematic loops against mbcomp.simulate.

The cases of tests/export/test_fmu_loop_events.py: the slider-crank (models/slider_crank.py)
whose slider rebounds off its lower stop (limits 0.45 .. 0.9 m, e = 0.5: three impacts through
the loop in 2.5 s), the four-bar (models/four_bar.py, gap 0.1 m) falling from rest onto its
crank's upper stop (2.5 rad, e = 0: it rests, the loop locked), released by a torque -2 t N m
on the crank and landing on its lower stop (1 rad), and the slider-crank again with the
importer's start value crank_joint.phi = 0.5 rad (the FMU moves the slider and the pin onto the
loop) against the model built with phi0 = 0.5. Each is exported (FMI 3.0 and 2.0) and run by
FMPy as Model Exchange (CVODE at rtol 1e-14) and as Co-Simulation (the FMU's DOP853 at 1e-12);
the reference is ``mbcomp.simulate(rtol=1e-12, atol=1e-14)``. Printed: mbcomp's and the FMU's
event instants, the largest event time difference (s), the largest state difference on mbcomp's
0.01 s grid (every coordinate and speed) and the largest loop residual from the FMU's states
(m: the closed-form geometry, at every output point). Needs FMPy and a C compiler.
Run: python bench/fmu_loop_events.py
"""
import pathlib
import sys
import tempfile

import numpy as np

import mbcomp
from mbcomp.export import export_fmu
from mbcomp.library import Torque

ROOT = pathlib.Path(__file__).resolve().parent.parent
SLIDER = {"slider_joint.limits": (0.45, 0.9), "slider_joint.restitution": 0.5}
CRANK = {"crank_joint.limits": (1.0, 2.5), "crank_joint.restitution": 0.0}
GAP = 0.1


def slider_crank(phi0=0.3):
    return mbcomp.load_model_file(ROOT / "models/slider_crank.py").build(phi0=phi0)


def four_bar():
    m = mbcomp.load_model_file(ROOT / "models/four_bar.py").build(gap=GAP, w0=0.0, phi0=np.pi / 2)
    pull = m.add("pull", Torque(tau=lambda t, phi, w: -2.0 * t))
    m.connect(m.components()["crank_joint"].axis, pull.flange_b)
    return m


def slider_gap(r):
    phi = r["crank_joint.phi"]
    return r["slider_joint.s"] - 0.2 * np.cos(phi) - np.sqrt(0.36 - (0.2 * np.sin(phi)) ** 2)


def four_bar_gap(r):
    L1, L2, L3, L4 = mbcomp.load_model_file(ROOT / "models/four_bar.py").lengths(GAP)
    a1 = r["crank_joint.phi"]
    a2 = a1 + r["coupler_joint.phi"]
    a3 = a2 + r["pin.phi"]
    return np.hypot(L2 * np.cos(a1) + L3 * np.cos(a2) - L4 * np.cos(a3) - L1,
                    L2 * np.sin(a1) + L3 * np.sin(a2) - L4 * np.sin(a3))


#: name: (model exported, parameters, end time (s), joint with the stop, loop residual, importer's starts,
#: reference model)
CASES = {
    "slider-crank": (slider_crank, SLIDER, 2.5, "slider_joint", slider_gap, None, slider_crank),
    "four-bar": (four_bar, CRANK, 3.0, "crank_joint", four_bar_gap, None, four_bar),
    "slider phi=0.5": (slider_crank, SLIDER, 2.5, "slider_joint", slider_gap, {"crank_joint.phi": 0.5},
                       lambda: slider_crank(phi0=0.5)),
}


def on_grid(r, res, var):
    return np.array([r[var][np.flatnonzero(np.abs(r["time"] - tk) < 1e-12)[-1]] for tk in res.time])


def main():
    import fmpy

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="fmu_loops_"))
    kind_name = {"ModelExchange": "ME", "CoSimulation": "CS"}
    print(f"{'model':14s} {'fmi':4s} {'kind':3s} {'instants mbcomp':>15s} {'FMU':>4s} {'max |dt| (s)':>13s} "
          f"{'max |dy|':>9s} {'loop (m)':>9s}")
    for name, (build, params, t_end, joint, gap, starts, ref) in CASES.items():
        res = mbcomp.simulate(ref(), params=params, t_end=t_end, rtol=1e-12, atol=1e-14, dt_out=0.01)
        want = np.unique([e.time for e in res.events])
        for fmi in ("3.0", "2.0"):
            path = tmp / f"{name.replace(' ', '_')}{fmi[0]}.fmu"
            info = export_fmu(build(), path, fmi=fmi, params=params, stop_time=t_end, derivatives=False)
            for kind in ("ModelExchange", "CoSimulation"):
                me = kind == "ModelExchange"
                r = fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=t_end, output_interval=0.01 if me else 1e-3,
                                      relative_tolerance=1e-14 if me else 1e-12, start_values=starts or {},
                                      output=info["states"] + [f"events.{joint}.time"])
                t = r[f"events.{joint}.time"]
                got = np.unique(t[t >= 0.0])
                err = np.max(np.min(np.abs(got[:, None] - want[None, :]), axis=1)) if len(got) else np.nan
                dy = max(np.max(np.abs(on_grid(r, res, v) - res[v])) for v in info["states"])
                loop = np.max(np.abs(gap(r)))
                print(f"{name:14s} {fmi:4s} {kind_name[kind]:3s} {len(want):15d} {len(got):4d} {err:13.2e} {dy:9.2e} "
                      f"{loop:9.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
