"""Parameter identification on the slider-crank: recover the rod's mass, the rod's inertia and a
damper's rate from noisy measurements of the crank angle alone (:func:`mbcomp.fit`).

The model is ``models/slider_crank.py``'s mechanism (crank 0.2 m, rod 0.6 m, slider 0.5 kg,
gravity along -y, the crank thrown at 6 rad/s from 0.3 rad) with a rotational damper
``damper`` on the crank joint (torque ``d w``). The rod's moments about its own x and y axes
play no part in the plane motion; they are set equal to the in-plane one
(``I = m L^2 / 12`` on every axis) so that the fit may move ``rod.I[2, 2]`` anywhere in
``(0, 2 I)`` without breaking the triangle inequality of a real inertia.

The script

1. simulates the true model (``rod.m`` 2 kg, ``rod.I[2, 2]`` 0.06 kg m^2, ``damper.d``
   0.05 N m s/rad) for ``--t-end`` s at tight tolerances and samples the crank angle at
   ``--points`` times, adding Gaussian noise of ``--noise`` rad (seeded: ``--seed``);
2. fits the three parameters from a start 25 % off, with bounds keeping them physical;
3. prints the fitted values with their standard errors, the relative errors, how many standard
   errors each is off, the runs and the wall time.

``--csv FILE`` also writes the measurements, for the command line:
``mbcomp fit bench/fit_slider_crank.py --data FILE --param rod.m --param "rod.I[2, 2]"
--param damper.d --bounds rod.m=0.1:10 --bounds "rod.I[2, 2]=0.001:0.12"``.

The file is also a model file (``build``), which is what that command loads.

``--compare`` repeats the fit with scipy's forward differences of whole runs as the Jacobian
(plain runs, no sensitivities) and prints its runs, wall time and how far its values are from the
exact-Jacobian fit's.

Run: python bench/fit_slider_crank.py [--seed 0] [--noise 1e-3] [--t-end 3] [--points 301] [--csv meas.csv]
[--compare]
"""
import argparse
import pathlib
import time

import numpy as np

import mbcomp
from mbcomp.library import RotationalDamper

#: the project's slider-crank, the example's starting point
SLIDER_CRANK = mbcomp.load_model_file(pathlib.Path(__file__).resolve().parents[1] / "models" / "slider_crank.py")

#: the values the measurements are made with
TRUE = {"rod.m": 2.0, "rod.I[2, 2]": 0.06, "damper.d": 0.05}
#: where the fit starts (25 % off) and the bounds that keep it physical
START = {"rod.m": 1.5, "rod.I[2, 2]": 0.045, "damper.d": 0.0625}
BOUNDS = {"rod.m": (0.1, 10.0), "rod.I[2, 2]": (0.001, 0.12), "damper.d": (0.0, 1.0)}
SIMULATION = dict(t_end=3.0, rtol=1e-10, atol=1e-12)


def isotropic(m, L):
    """A link's inertia ``m L^2 / 12`` (kg m^2) on every axis: its in-plane moment free to move
    in a fit (the model's ``rod_inertia`` keeps the out-of-plane one at 1e-6 of it, and the
    triangle inequality stops ``I[2, 2]`` from rising above about 0.06)."""
    return np.eye(3) * m * L ** 2 / 12.0


def build(crank_length=0.2, rod_length=0.6, m_crank=1.0, m_rod=2.0, m_slider=0.5, d=0.05, phi0=0.3, w0=6.0):
    """``models/slider_crank.py`` (links with :func:`isotropic` inertias) with a damper of rate
    ``d`` (N m s/rad) on the crank joint."""
    m = SLIDER_CRANK.build(crank_length, rod_length, m_crank, m_rod, m_slider, phi0, w0, inertia=isotropic)
    damper = m.add("damper", RotationalDamper(d=d))
    m.connect(damper.flange_a, m["crank_joint"].support)
    m.connect(damper.flange_b, m["crank_joint"].axis)
    return m


def measurements(model, *, t_end=3.0, points=301, noise=1e-3, seed=0):
    """``{"time", "crank_angle"}``: the true model's crank angle (rad) at ``points`` times from
    0 to ``t_end`` (s), plus Gaussian noise of standard deviation ``noise`` (rad), seeded."""
    import mbcomp

    truth = mbcomp.simulate(model, t_end=t_end, n_out=points, rtol=1e-12, atol=1e-14,
                            params={"rod.m": TRUE["rod.m"], "rod.I": np.diag([0.06, 0.06, TRUE["rod.I[2, 2]"]]),
                                    "damper.d": TRUE["damper.d"]})
    rng = np.random.default_rng(seed)
    return {"time": truth.time, "crank_angle": truth["crank_angle"] + noise * rng.standard_normal(points)}


def main(argv=None):
    import mbcomp

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise", type=float, default=1e-3, help="standard deviation of the angle noise (rad)")
    ap.add_argument("--t-end", dest="t_end", type=float, default=3.0)
    ap.add_argument("--points", type=int, default=301)
    ap.add_argument("--csv", help="also write the measurements to this CSV file")
    ap.add_argument("--compare", action="store_true", help="also fit with forward differences of whole runs")
    args = ap.parse_args(argv)

    model = mbcomp.assemble(build())
    data = measurements(model, t_end=args.t_end, points=args.points, noise=args.noise, seed=args.seed)
    if args.csv:
        np.savetxt(args.csv, np.column_stack([data["time"], data["crank_angle"]]), delimiter=",",
                   header="time,crank_angle", comments="", fmt="%.12g")
        print(f"wrote {args.csv}")
    wall = time.perf_counter()
    f = mbcomp.fit(model, data, dict(START), bounds=BOUNDS)
    wall = time.perf_counter() - wall
    print(f"{args.points} angles over {args.t_end:g} s, noise {args.noise:g} rad (seed {args.seed}); "
          f"{f.runs} runs, {wall:.2f} s; {f.message}")
    print(f.table())
    print(f"{'parameter':<12}  {'true':>8}  {'error':>9}  {'error/std':>9}")
    for p in f.params:
        err = f[p] - TRUE[p]
        print(f"{p:<12}  {TRUE[p]:8.4g}  {err / TRUE[p]:9.3%}  {err / f.std_errors[f.params.index(p)]:9.2f}")
    rms = float(np.sqrt(np.mean(f.residual["crank_angle"] ** 2)))
    print(f"rms residual {rms:.3g} rad (noise {args.noise:g} rad)")
    if args.compare:
        differenced(model, data, f)
    return f


def differenced(model, data, exact):
    """The same fit with scipy's forward differences of whole runs (no sensitivities) as the
    Jacobian: runs, wall time and the difference from the exact-Jacobian fit."""
    import mbcomp
    from scipy.optimize import least_squares

    runs = []

    def residual(x):
        runs.append(1)
        params = {"rod.m": x[0], "rod.I": np.diag([0.06, 0.06, x[1]]), "damper.d": x[2]}
        res = mbcomp.simulate(model, t_end=data["time"][-1], n_out=len(data["time"]), params=params,
                              **{k: SIMULATION[k] for k in ("rtol", "atol")})
        return res["crank_angle"] - data["crank_angle"]

    names = list(START)
    lo, hi = np.array([BOUNDS[p][0] for p in names]), np.array([BOUNDS[p][1] for p in names])
    wall = time.perf_counter()
    opt = least_squares(residual, np.array([START[p] for p in names]), bounds=(lo, hi), method="trf",
                        x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12)
    wall = time.perf_counter() - wall
    print(f"forward differences of whole runs: {len(runs)} runs, {wall:.2f} s; {opt.message}")
    for p, v in zip(names, opt.x):
        print(f"  {p:<12} {v:14.8g}  (exact-Jacobian fit {exact[p]:.8g}: {v / exact[p] - 1:+.1e} relative)")


if __name__ == "__main__":
    main()
