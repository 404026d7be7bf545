"""Exact Jacobians against finite differences on stiff runs (issue 31 item 1): steps,
Jacobian evaluations, residual evaluations and time of the implicit methods, before (every
Jacobian differenced) and after (the exact programs of :mod:`mbcomp.codegen.dae_jacobian`
and :mod:`mbcomp.codegen.jacobian`).

Models:

* ``andrews``: Andrews' squeezer (``models/andrews.py``), 7 angles, 6 loop rows, to t = 0.03 s;
* ``spring chain``: a planar pendulum chain of N links whose bobs slide on their links against
  stiff springs (c = 1e6 N/m, m = 1 kg: ~1000 1/s against the pendulum's ~3 1/s), its last
  bob tied to the ground by a soft spring, to t = 1 s (an open tree: no constraint rows);
* ``flyball governor``: Watt's governor (:func:`flyball_governor`, built here from library
  parts): a shaft spinning at 10 rad/s, two ball arms, two links, a sleeve on a stiff spring
  (1e5 N/m, 0.5 kg: ~450 1/s); two loops, 4 kept rows, 2 degrees of freedom, to t = 1 s.

Methods: radau5 at index 3 and 1, IDA at index 1 and 2 (GGL), generalized-alpha (index 3,
fixed h), scipy's Radau and BDF on the Lagrange index-1 ODE, and BDF on D'Alembert's ODE. "Before" is the same call
with the evaluator's exact programs switched off (``ProgramEvaluator.dae_jacobian`` and
``lagrange_jac`` answer None, so every form takes its difference path: the C call that
differences the residual over q and u for the DAE forms, IDA's own difference quotients,
genalpha's differences of ``dynamics``, forward differences of ``fun`` for scipy).

Each run is on a system compiled once (C backend; the programs come from the cache after a
warm-up run); the time is the median CPU time of ``simulate`` over ``--repeats`` runs (the
process's CPU time: on a machine shared with other work, wall time measures the others too). The
last column is the largest error of the final angles against a run at rtol 1e-12 (DOP853 on
the Lagrange form), divided by the run's rtol.

Run: python bench/stiff_jacobians.py [--repeats 3] [--n 10] [--model governor] [--only ida]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import pathlib  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "models"))

import mbcomp  # noqa: E402
from mbcomp.codegen import compile_system  # noqa: E402
from mbcomp.codegen.evaluator import ProgramEvaluator  # noqa: E402
from mbcomp import Guess  # noqa: E402
from mbcomp.library import (FixedTranslation, Prismatic, Revolute, RigidBody,  # noqa: E402
                            TranslationalSpringDamper, World)

import andrews  # noqa: E402


def spring_chain(N=4, c=1e6, m=1.0, L=0.5):
    """``models/spring_chain.py``: N pendulum links (revolute), each bob sliding on its link
    against a spring of rate ``c`` (N/m, damper 1 N s/m); the last bob tied to the ground by a
    soft spring (100 N/m)."""
    import spring_chain as chain  # models/ is on sys.path (above)

    return chain.build(N=N, c=c, d=1.0, m=m, L=L)


def flyball_governor(c=1e5, arm=0.3, link=0.15, m_ball=1.0, m_sleeve=0.5, w0=10.0, theta0=0.5):
    """Watt's flyball governor: a vertical shaft spinning at ``w0`` (rad/s) carries two arms
    hinged at its top (balls of ``m_ball`` at their ends, start angle ``theta0`` from the
    shaft) whose midpoints are tied by links to a sleeve sliding on the shaft against a stiff
    spring (rate ``c``, N/m): two loops closed at the sleeve, 6 coordinates, 2 degrees of freedom."""
    mod = mbcomp.Model()
    w = mod.add("world", World(g=(0, -9.81, 0)))
    shaft_j = mod.add("shaft_joint", Revolute(n=(0, 1, 0), w0=w0))
    shaft = mod.add("shaft", RigidBody(m=2.0, r_cm=(0, 0.2, 0), I=np.diag([0.01, 0.002, 0.01])))
    top = mod.add("top", FixedTranslation(r=(0, 0.4, 0)))
    mod.connect(w.frame_b, shaft_j.frame_a)
    mod.connect(shaft_j.frame_b, shaft.frame_a)
    mod.connect(shaft_j.frame_b, top.frame_a)
    # where the links meet the axis at the start (the sleeve's start guess)
    px, py = 0.5 * arm * np.sin(theta0), 0.4 - 0.5 * arm * np.cos(theta0)
    ys = py - np.sqrt(link ** 2 - px ** 2)
    psi0 = -np.arctan2(px, py - ys) - theta0  # the link's angle relative to its arm
    sleeve_j = mod.add("sleeve_joint", Prismatic(n=(0, 1, 0), s0=Guess(ys)))
    sleeve = mod.add("sleeve", RigidBody(m=m_sleeve, I=np.diag([1e-3, 2e-3, 1e-3])))
    spring = mod.add("spring", TranslationalSpringDamper(c=c, d=5.0, s_rel0=ys + 0.01))
    mod.connect(shaft_j.frame_b, sleeve_j.frame_a)
    mod.connect(sleeve_j.frame_b, sleeve.frame_a)
    mod.connect(sleeve_j.support, spring.flange_a)
    mod.connect(sleeve_j.axis, spring.flange_b)
    for k, side in ((1, 1.0), (2, -1.0)):
        arm_j = mod.add(f"arm{k}_joint", Revolute(n=(0, 0, 1), phi0=side * theta0, w0=0.0))
        ball = mod.add(f"ball{k}", RigidBody(m=m_ball, r_cm=(0, -arm, 0), I=np.diag([1e-3, 1e-3, 1e-3])))
        mid = mod.add(f"arm{k}_mid", FixedTranslation(r=(0, -0.5 * arm, 0)))
        link_j = mod.add(f"link{k}_joint", Revolute(n=(0, 0, 1), phi0=Guess(side * psi0)))
        rod = mod.add(f"link{k}", RigidBody(m=0.1, r_cm=(0, -0.5 * link, 0), I=np.diag([1e-4, 1e-5, 1e-4])))
        end = mod.add(f"link{k}_end", FixedTranslation(r=(0, -link, 0)))
        pin = mod.add(f"pin{k}", Revolute(n=(0, 0, 1)))
        mod.connect(top.frame_b, arm_j.frame_a)
        mod.connect(arm_j.frame_b, ball.frame_a)
        mod.connect(arm_j.frame_b, mid.frame_a)
        mod.connect(mid.frame_b, link_j.frame_a)
        mod.connect(link_j.frame_b, rod.frame_a)
        mod.connect(link_j.frame_b, end.frame_a)
        mod.connect(end.frame_b, pin.frame_a)
        mod.connect(sleeve_j.frame_b, pin.frame_b)
    return mod


#: the reference runs: DOP853 on the Lagrange form; for the governor, whose DOP853 run stops at
#: t = 0.83 s calling a position singular that the implicit runs pass far from it (and on which
#: radau5 at index 1 and 2 fails at the start below rtol 1e-10, with or without exact
#: Jacobians), scipy's Radau on the Lagrange form
REFERENCE = dict(rtol=1e-12, atol=1e-14)


def cases(n_links):
    """``(name, build, options, genalpha's h, compared columns, reference options)``."""
    return [
        ("andrews", andrews.build, dict(t_end=0.03, rtol=1e-6, atol=1e-8), 1e-5,
         ["hinge_O.phi", "hinge_F.phi", "hinge_B.phi"], REFERENCE),
        (f"spring chain N={n_links}", lambda: spring_chain(n_links), dict(t_end=1.0, rtol=1e-6, atol=1e-8), 1e-4,
         [f"j{k}.phi" for k in range(n_links)], REFERENCE),
        ("flyball governor", flyball_governor, dict(t_end=1.0, rtol=1e-6, atol=1e-8), 1e-4,
         ["arm1_joint.phi", "shaft_joint.phi", "sleeve_joint.s"], dict(method="Radau", rtol=1e-11, atol=1e-13)),
    ]


METHODS = [("radau5", dict(method="radau5", index=3)), ("radau5 index 1", dict(method="radau5", index=1)),
           ("ida index 1", dict(method="ida", index=1)), ("ida index 2", dict(method="ida", index=2)),
           ("genalpha", dict(method="genalpha", index=3)),
           ("scipy Radau", dict(method="Radau")), ("scipy BDF", dict(method="BDF")),
           ("BDF dalembert", dict(method="BDF", formulation="dalembert"))]


@contextlib.contextmanager
def differences_only():
    """The evaluator's exact Jacobian programs switched off: every form differences."""
    saved = ProgramEvaluator.dae_jacobian, ProgramEvaluator.lagrange_jac, ProgramEvaluator.lagrange_jacobian
    ProgramEvaluator.dae_jacobian = lambda self, form: None
    ProgramEvaluator.lagrange_jac = lambda self, t, y, alpha, beta: None
    ProgramEvaluator.lagrange_jacobian = lambda self: None  # what LagrangeIndex1.jac keeps per row mask
    try:
        yield
    finally:
        ProgramEvaluator.dae_jacobian, ProgramEvaluator.lagrange_jac, ProgramEvaluator.lagrange_jacobian = saved


def run(system, opts, repeats):
    res = mbcomp.simulate(system, n_out=2, **opts)  # warm-up: programs traced, compiled, cached
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        res = mbcomp.simulate(system, n_out=2, **opts)
        times.append(time.process_time() - t0)
    return res, statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--n", type=int, default=10, help="links of the spring chain")
    ap.add_argument("--only", default=None, help="run only the methods whose label contains this")
    ap.add_argument("--model", default=None, help="run only the models whose name contains this")
    args = ap.parse_args()
    head = (f"{'model':<18} {'method':<15} {'steps':>11} {'Jacobians':>11} {'fun evals':>13} {'CPU (ms)':>15} "
            f"{'speed-up':>8} {'exact/diff':>10} {'error / rtol':>13}")
    print(head)
    print("-" * len(head))
    for name, build, base, h, cols, reference in cases(args.n):
        if args.model and args.model not in name:
            continue
        system = compile_system(mbcomp.assemble(build()), "c")
        ref = mbcomp.simulate(system, n_out=2, **dict(base, **reference))
        for label, extra in METHODS:
            if args.only and args.only not in label:
                continue
            opts = dict(base, **extra)
            if extra["method"] == "genalpha":
                opts["h"] = h
            try:
                with differences_only():
                    rb, tb = run(system, opts, args.repeats)
                ra, ta = run(system, opts, args.repeats)
            except Exception as exc:  # noqa: BLE001 - a row that cannot run says why
                print(f"{name:<18} {label:<15} failed: {type(exc).__name__}: {str(exc)[:80]}")
                continue
            sb, sa = rb.stats, ra.stats
            eb, ea = (max(float(np.abs(r[c][-1] - ref[c][-1])) for c in cols) / opts["rtol"] for r in (rb, ra))
            used = f"{sa.get('jac_exact', '-')}/{sa.get('jac_differences', '-')}"
            if extra["method"] in ("Radau", "BDF") and "formulation" not in extra:
                used = "lagrange_jac"  # the Lagrange form's program (codegen/jacobian.py)
            print(f"{name:<18} {label:<15} {sb['steps']:>5}->{sa['steps']:<5} {sb['njev']:>5}->{sa['njev']:<5} "
                  f"{sb['nfev']:>6}->{sa['nfev']:<6} {1e3 * tb:>7.1f}->{1e3 * ta:<7.1f} {tb / ta:>8.2f} "
                  f"{used:>10} {eb:>6.2g}->{ea:<6.2g}" + ("" if ra.success and rb.success else f"  ({rb.status}/{ra.status})"))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
