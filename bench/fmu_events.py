"""FMUs with events against mbcomp.simulate: event times and states, per model, FMI version and interface.

Each model is exported (FMI 3.0 and 2.0) and run by FMPy as Model Exchange (FMPy's CVODE at
rtol 1e-14: its root finding locates the indicators, the FMU acts in Event Mode) and as
Co-Simulation (the FMU's own DOP853 at 1e-12, its events located on the dense output); the
reference is ``mbcomp.simulate(rtol=1e-12, atol=1e-14)``. Printed: mbcomp's and the FMU's
event counts (Co-Simulation reports the last event of each output step), the largest event
time difference (s; each FMU event against mbcomp's nearest) and the largest state
difference on mbcomp's 0.01 s grid. Also the Model Exchange error of the ball's 32nd impact at
CVODE's rtol 1e-10 .. 1e-14 (the importer's share). Needs FMPy and a C compiler.
Run: python bench/fmu_events.py
"""
import pathlib
import sys
import tempfile

import numpy as np

import mbcomp
from mbcomp.export import export_fmu
from mbcomp.library import FixedTranslation, Force, PointMass, Prismatic, Revolute, SlidingFriction, World

ROOT = pathlib.Path(__file__).resolve().parent.parent


def pendulum(limits=(0.0, 3.0), e=0.7, phi0=0.8):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("hinge", Revolute(phi0=phi0, w0=0.0, limits=limits, restitution=e))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def block(mu_s=0.3, mu_k=0.25, k=20.0, v0=2.0):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.0, v0=v0, friction=SlidingFriction(mu_s, mu_k, normal=2.0 * 9.81)))
    b = m.add("b", PointMass(m=2.0))
    f = m.add("pull", Force(f=lambda t, s, v: -k * s))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, f.flange_b)
    return m


def shaker():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -9.81)))
    s = m.add("s", Prismatic(n=(1, 0, 0), s0=0.5, v0=0.0, limits=(-1.0, 1.0), restitution=0.0))
    b = m.add("b", PointMass(m=2.0))
    f = m.add("push", Force(f=lambda t, s, v: 10.0 * np.cos(t)))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, f.flange_b)
    return m


#: name: (model, end time (s), Co-Simulation output interval (s), component, states)
MODELS = {
    "ball": (lambda: mbcomp.load_model_file(ROOT / "models/bouncing_ball.py").build(), 4.3, 2e-4, "ground",
             ["free.r.z", "free.v.z"]),
    "pendulum": (pendulum, 3.0, 1e-3, "hinge", ["hinge.phi", "hinge.w"]),
    "resting": (lambda: pendulum((0.3, 3.0), 0.5, 1.2), 2.5, 1e-4, "hinge", ["hinge.phi", "hinge.w"]),
    "door": (lambda: mbcomp.load_model_file(ROOT / "models/door.py").build(), 8.0, 1e-3, "hinge",
             ["hinge.phi", "hinge.w"]),
    "block": (block, 5.0, 1e-3, "s", ["s.s", "s.v"]),
    "shaker": (shaker, 8.0, 1e-3, "s", ["s.s", "s.v"]),
}


def run(fmpy, path, t_end, dt, comp, states, kind, tol=None):
    me = kind == "ModelExchange"
    return fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=t_end, output_interval=0.01 if me else dt,
                             relative_tolerance=tol or (1e-14 if me else 1e-12), output=states + [f"events.{comp}.time"])


def on_grid(r, res, var):
    return np.array([r[var][np.flatnonzero(np.abs(r["time"] - tk) < 1e-12)[-1]] for tk in res.time])


def main():
    import fmpy

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="fmu_events_"))
    print(f"{'model':9s} {'fmi':4s} {'kind':3s} {'events mbcomp':>13s} {'FMU':>4s} {'max |dt| (s)':>13s} "
          f"{'max |dy|':>9s}")
    for name, (build, t_end, dt, comp, states) in MODELS.items():
        res = mbcomp.simulate(build(), t_end=t_end, rtol=1e-12, atol=1e-14, dt_out=0.01)
        want = np.unique([e.time for e in res.events])
        for fmi in ("3.0", "2.0"):
            path = tmp / f"{name}{fmi[0]}.fmu"
            export_fmu(build(), path, fmi=fmi, stop_time=t_end)
            for kind in ("ModelExchange", "CoSimulation"):
                r = run(fmpy, path, t_end, dt, comp, states, kind)
                got = np.unique(r[f"events.{comp}.time"][r[f"events.{comp}.time"] >= 0.0])
                err = np.max(np.min(np.abs(got[:, None] - want[None, :]), axis=1)) if len(got) else np.nan
                dy = max(np.max(np.abs(on_grid(r, res, v) - res[v])) for v in states)
                print(f"{name:9s} {fmi:4s} {kind[:2]:3s} {len(want):13d} {len(got):4d} {err:13.2e} {dy:9.2e}")
    build, t_end, dt, comp, states = MODELS["ball"]
    res = mbcomp.simulate(build(), t_end=t_end, rtol=1e-12, atol=1e-14)
    last = [e.time for e in res.events if e.kind == "impact"][-1]
    print("\nthe ball's 32nd impact, Model Exchange (FMI 3.0) by FMPy's CVODE at rtol:")
    for tol in (1e-10, 1e-12, 1e-14):
        r = run(fmpy, tmp / "ball3.fmu", t_end, dt, comp, states, "ModelExchange", tol)
        got = np.unique(r["events.ground.time"][r["events.ground.time"] >= 0.0])
        print(f"  {tol:7.0e}: {abs(got[-1] - last):.2e} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
