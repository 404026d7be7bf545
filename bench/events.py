"""Event location: accuracy and cost per formulation x solver on cases with exact event times.

Three cases with closed-form event times (issue 22, item 6):

* **rotor**: a free rotor (J = 2 kg m^2, no gravity) from 0 at 1 rad/s between rigid stops at
  +-0.5 rad, restitution 0.8, 6 s: impacts at 0.5, 0.5 + 1/0.8, ... (4 impacts). The motion
  between impacts is linear in t, so every method integrates it exactly: the error is the
  location's alone (Brent on the dense output, ``min(1e-12, rtol/1000) max(1, |t|)``).
* **pendulum**: a 1 m pendulum (point mass, g = 9.81) released at 0.8 rad onto a stop at
  0 rad, restitution 0.7, 5 s (5 impacts): the first at the quarter period
  ``K(sin^2 0.4) / sqrt(g/l)``, then each rebound of amplitude ``theta_k`` with
  ``sin(theta_k / 2) = e^k sin 0.4`` returns after half its period ``2 K(sin^2(theta_k/2)) / sqrt(g/l)``.
  Here the integration error enters the impact times too.
* **ball**: a solid ball (m = 7 kg, r = 0.11 m, I = 2/5 m r^2) thrown along a level floor at
  v0 = 3 m/s with backspin w_b = 20 rad/s (``w0 = (0, -w_b, 0)``), Coulomb friction
  ``ContactFriction(0.3, 0.2)``, 1.5 s: it slides (``dv/dt = -mu_k g``, the slip speed
  ``v + r w_y`` falling at ``7/2 mu_k g``) until the event ``stick`` (a ``switch`` to the
  rolling mode ``closed``) at ``t* = (v0 + r w_b) / (3.5 mu_k g) = 0.757245 s``, then rolls at
  ``(5 v0 - 2 r w_b) / 7``. The sliding motion is quadratic in t, so the error is again the
  location's, on the numeric path a sliding contact runs on (see
  :mod:`mbcomp.hybrid.slip`).

Each formulation (lagrange, dalembert) x solver (dop853, dopri5 -- the C integrators: the stops'
events located and their rebounds acted on in the C loop over the Lagrange form, one step at a
time in Python otherwise --, radau5, ida, genalpha; and scipy's
DOP853, Radau, LSODA for comparison) runs at rtol 1e-6, 1e-9, 1e-12 (genalpha: fixed steps
h = 1e-2, 1e-3, 1e-4 s), and once more on an event-free counterpart for the cost ratio: the
rotor turning freely and the pendulum swinging freely (no stops), and for the ball the same
ball and frictional contact rolling from the start at its final rolling speed
``(5 v0 - 2 r w_b) / 7`` (``w_y = v / r``): the contact stays in its rolling mode (its
friction cone is watched but never left), so the run has no event and no sliding -- which
also means it runs on the compiled path, so the ball's ratio holds the numeric path's cost
as well as the events'. Columns: method, formulation, rtol (or h), max |t_event - t_exact|
(s) over the case's events (impacts; the ball's ``stick`` switches), steps, f-evals,
event-function evaluations, CPU s, and the event-free run's steps and CPU s with the ratio.
A refused combination (the DAE solvers take no D'Alembert ODE; genalpha no rolling
(nonholonomic) constraints) is a row saying so, and so is a combination left out of the default for its
cost (:data:`SLOW`, run with ``--slow``).

``f-evals`` sums the steppers' right-hand-side calls over every restart (an impact starts a
new stepper and formulation; ``res.stats["nfev"]`` counts only the last formulation's, so
this script reads the steppers' counters instead, see ``_count_all_evaluations``).

Writes bench/events.csv (a run of some ``--cases`` replaces their rows, keeping the other
cases') and prints the table.

``--actions`` instead times the stop pendulum of ``bench/peers.py --cases events`` (the default
call at rtol = atol = 1e-7, 101 outputs; the peer Pinocchio in a hand-written scipy DOP853 event
loop at 1e-8, ``peers/stop_pendulum.py``) with the impacts acted on in the C loop and with every
action in Python (``mbcomp.hybrid.steppers.C_IMPACTS``): CPU time of batches of 20 runs (one
3 ms run is too short to time alone on a shared machine), the median of 9 batches and of the
batches' ratios to the peer, in one process.

Run: python bench/events.py [--cases rotor,pendulum,ball] [--rtols 1e-6,1e-9,1e-12] [--slow]
     python bench/events.py --actions
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import csv  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.library import (ContactFriction, FixedTranslation, FreeMotion, PointMass, Revolute, RigidBody,  # noqa: E402
                            SphereContact, World)

HERE = pathlib.Path(__file__).resolve().parent
G = 9.81
SOLVERS = ["dop853", "dopri5", "radau5", "ida", "genalpha", "DOP853", "Radau", "LSODA"]
FORMULATIONS = ["lagrange", "dalembert"]
GENALPHA_H = {1e-3: 1e-2, 1e-6: 1e-2, 1e-9: 1e-3, 1e-12: 1e-4}


def rotor(events=True, e=0.8):
    """A rotor (J = 2 about z) from 0 at 1 rad/s, between stops at +-0.5 rad if ``events``."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    lim = dict(limits=(-0.5, 0.5), restitution=e) if events else {}
    j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=1.0, **lim))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, 2.0])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def rotor_times(n, e=0.8):
    t, speed, out = 0.5, 1.0, []
    for _ in range(n):
        out.append(t)
        speed *= e
        t += 1.0 / speed
    return np.array(out)


def pendulum(events=True, e=0.7, phi0=0.8):
    """A 1 m pendulum released at ``phi0`` onto a stop at 0 rad if ``events``."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    lim = dict(limits=(0.0, 3.0), restitution=e) if events else {}
    j = m.add("hinge", Revolute(phi0=phi0, w0=0.0, **lim))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def pendulum_times(n, e=0.7, phi0=0.8):
    """Impact times on the stop at the bottom: quarter period, then half periods of the rebounds."""
    from scipy.special import ellipk

    k0, om = np.sin(phi0 / 2), np.sqrt(G)
    t, out = ellipk(k0 ** 2) / om, []
    for k in range(n):
        out.append(t)
        t += 2 * ellipk((e ** (k + 1) * k0) ** 2) / om
    return np.array(out)


#: the ball case: kg, m, m/s, rad/s (backspin), static and kinetic friction
BALL = dict(m=7.0, r=0.11, v0=3.0, w_b=20.0, mu_s=0.3, mu_k=0.2)


def ball(events=True):
    """The ball thrown with backspin (:data:`BALL`, see the module notes); ``events=False``: its
    event-free counterpart, the same ball and contact rolling from the start at the final
    rolling speed ``(5 v0 - 2 r w_b) / 7``."""
    m, r, v0, w_b = BALL["m"], BALL["r"], BALL["v0"], BALL["w_b"]
    if not events:
        v0 = (5 * v0 - 2 * r * w_b) / 7
        w_b = -v0 / r  # rolling: w_y = v / r
    model = mbcomp.Model()
    w = model.add("world", World(g=(0, 0, -G)))
    free = model.add("free", FreeMotion(r0=(0, 0, r), v0=(v0, 0, 0), w0=(0, -w_b, 0)))
    body = model.add("ball", RigidBody(m=m, I=0.4 * m * r * r * np.eye(3)))
    floor = model.add("floor", SphereContact(r=r, unilateral=True,
                                             friction=ContactFriction(BALL["mu_s"], BALL["mu_k"])))
    model.connect(w.frame_b, free.frame_a)
    model.connect(free.frame_b, body.frame_a)
    model.connect(w.frame_b, floor.frame_a)
    model.connect(floor.frame_b, body.frame_a)
    return model


def ball_times(n):
    """The slide's end ``(v0 + r w_b) / (3.5 mu_k g)``; a further ``stick`` has no exact time
    (inf: it shows as an infinite error)."""
    t_star = (BALL["v0"] + BALL["r"] * BALL["w_b"]) / (3.5 * BALL["mu_k"] * G)
    return np.array([t_star] + [np.inf] * (n - 1))[:n]


def impacts(res):
    """Times (s) of the run's impacts."""
    return [x.time for x in res.events if x.kind == "impact"]


def stick_switches(res):
    """Times (s) of the run's slip-to-roll switches (event ``stick``)."""
    return [x.time for x in res.events if x.kind == "switch" and x.name == "stick"]


#: case: (build(events=...), exact event times(n), t_end s, the run's event times)
CASES = {"rotor": (rotor, rotor_times, 6.0, impacts), "pendulum": (pendulum, pendulum_times, 5.0, impacts),
         "ball": (ball, ball_times, 1.5, stick_switches)}

#: combinations left out of the default for their cost (CPU s measured on one core, 2 shared),
#: run with ``--slow``: (case, method, formulation, rtol) -> why
SLOW = {("ball", "Radau", "dalembert", 1e-12): "275 s: scipy's Radau on the sliding ball's numeric path "
                                                "(3080 steps, the D'Alembert form's Jacobian by differences)",
        ("ball", "Radau", "lagrange", 1e-12): "49 s alone, 64 s on a loaded machine: scipy's Radau on the "
                                               "sliding ball's numeric path (3022 steps)",
        ("ball", "radau5", "lagrange", 1e-12): "48 s alone, 64 s on a loaded machine: radau5 on the sliding "
                                                "ball's numeric path (2909 steps)"}


def _count_all_evaluations():
    """Report the steppers' right-hand-side calls summed over restarts as ``nfev_all``
    (``Run.counters`` sums the steppers' other counters, but ``nfev`` is the formulation's)."""
    from mbcomp.simulation.stepping import Run

    if getattr(Run.counters, "_all_nfev", False):
        return
    plain = Run.counters

    def counters(self):
        out = plain(self)
        out["nfev_all"] = sum(int(s.stats.get("nfev", 0)) for s in self.steppers)
        return out

    counters._all_nfev = True
    Run.counters = counters


def run(build, t_end, method, formulation, rtol):
    """``(result or None, cpu s, refusal message)`` of one run."""
    kw = dict(method=method, formulation=formulation, rtol=rtol, atol=rtol * 1e-2, n_out=2)
    if method == "genalpha":
        kw["h"] = GENALPHA_H.get(rtol, 1e-3)
    c0 = time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = mbcomp.simulate(build(), t_end=t_end, **kw)
    except Exception as exc:  # noqa: BLE001 - a refused combination is a row
        return None, time.process_time() - c0, f"{type(exc).__name__}: {exc}"
    return res, time.process_time() - c0, ""


_WARM = set()


def row(case, method, formulation, rtol, slow=False):
    build, exact_times, t_end, located = CASES[case]
    if not slow and (case, method, formulation, rtol) in SLOW:
        return dict(case=case, method=method, formulation=formulation, setting=f"{rtol:g}", status="skipped",
                    message=f"left out (--slow runs it): {SLOW[case, method, formulation, rtol]}")
    if (case, method, formulation) not in _WARM:  # the first run of a combination compiles and caches its program
        _WARM.add((case, method, formulation))
        run(build, t_end, method, formulation, 1e-3)
        run(lambda: build(events=False), t_end, method, formulation, 1e-3)
    res, cpu, refused = run(build, t_end, method, formulation, rtol)
    out = dict(case=case, method=method, formulation=formulation,
               setting=f"h={GENALPHA_H.get(rtol, 1e-3):g}" if method == "genalpha" else f"{rtol:g}")
    if res is None:
        return dict(out, status="refused", message=refused[:160])
    times = located(res)
    exact = exact_times(len(times))
    free, cpu_free, _ = run(lambda: build(events=False), t_end, method, formulation, rtol)
    st = res.stats
    out.update(status=res.status, events=len(times),
               max_dt=float(np.max(np.abs(np.array(times) - exact))) if times else np.nan,
               steps=st.get("steps"), fevals=st.get("nfev_all", st.get("nfev")),
               event_evals=st.get("event_evaluations"), cpu_s=cpu,
               steps_free=free.stats.get("steps") if free else None,
               fevals_free=free.stats.get("nfev_all") if free else None, cpu_free=cpu_free if free else None,
               message="" if res.status == "success" else res.message[:160])
    if free is not None and cpu_free > 0:
        out["cpu_ratio"] = cpu / cpu_free
    return out


def _fmt(v, spec):
    if v is None or (isinstance(v, float) and v != v):
        return "-"
    return format(v, spec)


def table(rows):
    head = (f"{'case':<9}{'method':<9}{'formulation':<12}{'rtol':>9}{'max|dt| s':>11}{'steps':>7}{'f-evals':>9}"
            f"{'ev-evals':>9}{'CPU s':>8}{'free steps':>11}{'free f-ev':>10}{'free CPU':>9}{'ratio':>7}")
    lines = [head, "-" * len(head)]
    for r in rows:
        if r["status"] in ("refused", "skipped"):
            lines.append(f"{r['case']:<9}{r['method']:<9}{r['formulation']:<12}{r['setting']:>9}  {r['status']}: "
                         f"{r['message'][:90]}")
            continue
        lines.append(f"{r['case']:<9}{r['method']:<9}{r['formulation']:<12}{r['setting']:>9}"
                     f"{_fmt(r['max_dt'], '11.1e')}{_fmt(r['steps'], '7d')}{_fmt(r['fevals'], '9d')}"
                     f"{_fmt(r['event_evals'], '9d')}{_fmt(r['cpu_s'], '8.3f')}{_fmt(r['steps_free'], '11d')}"
                     f"{_fmt(r['fevals_free'], '10d')}{_fmt(r['cpu_free'], '9.3f')}{_fmt(r.get('cpu_ratio'), '7.1f')}"
                     + ("" if r["status"] == "success" else f"  {r['status']}: {r['message'][:70]}"))
    return "\n".join(lines)


def _kept_rows(path, cases):
    """The rows of the CSV at ``path`` (if any) of cases other than ``cases``: a run of some
    cases replaces their rows and keeps the others'."""
    if not os.path.exists(path):
        return []
    with open(path, newline="") as fh:
        return [r for r in csv.DictReader(fh) if r.get("case") not in cases]


def actions_table(batches=9, runs=20):
    """The stop pendulum with the impacts in C, with the Python actions, and the Pinocchio peer:
    ``[(who, ms per run, ratio to the peer)]`` (medians over ``batches`` batches of ``runs``)."""
    import sys

    from mbcomp.hybrid import steppers

    sys.path.insert(0, str(HERE))
    from peers import stop_pendulum

    why = stop_pendulum.available()
    if why:
        return [("pinocchio + scipy event loop", why, None)]
    peer = stop_pendulum.build(e=0.7, phi0=0.8, t_end=5.0)

    def default_call():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return mbcomp.simulate(pendulum(e=0.7, phi0=0.8), t_end=5.0, rtol=1e-7, atol=1e-7, n_out=101)

    def per_run(f):
        c0 = time.process_time()
        for _ in range(runs):
            f()
        return (time.process_time() - c0) / runs

    who = {"mbcomp, impacts in C": True, "mbcomp, actions in Python": False}
    times = {k: [] for k in [*who, "pinocchio + scipy event loop"]}
    for flag in who.values():  # warm: the programs compiled and cached, scipy imported
        steppers.C_IMPACTS = flag
        default_call()
    peer.impact_times("DOP853", 1e-8, 1e-8)
    try:
        for _ in range(batches):
            for name, flag in who.items():
                steppers.C_IMPACTS = flag
                times[name].append(per_run(default_call))
            times["pinocchio + scipy event loop"].append(per_run(lambda: peer.impact_times("DOP853", 1e-8, 1e-8)))
    finally:
        steppers.C_IMPACTS = True
    base = np.array(times["pinocchio + scipy event loop"])
    return [(k, 1e3 * float(np.median(v)), float(np.median(np.array(v) / base))) for k, v in times.items()]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--rtols", default="1e-6,1e-9,1e-12")
    ap.add_argument("--methods", default=",".join(SOLVERS))
    ap.add_argument("--out", default=str(HERE / "events.csv"))
    ap.add_argument("--slow", action="store_true", help="also run the combinations of SLOW")
    ap.add_argument("--actions", action="store_true", help="the stop pendulum: impacts in C, actions in Python, "
                    "Pinocchio + scipy event loop (batches of runs)")
    args = ap.parse_args(argv)
    if args.actions:
        print(f"{'who':<32}{'ms per run':>12}{'ratio':>8}")
        for who, ms, ratio in actions_table():
            print(f"{who:<32}{ms:>12.3f}{ratio:>8.2f}" if ratio is not None else f"{who:<32}  {ms}")
        return
    _count_all_evaluations()
    rtols = [float(x) for x in args.rtols.split(",")]
    rows = []
    for case in args.cases.split(","):
        for method in args.methods.split(","):
            for formulation in FORMULATIONS:
                for rtol in rtols:
                    rows.append(row(case, method, formulation, rtol, slow=args.slow))
                    if rows[-1]["status"] == "refused":
                        break  # refused at one tolerance: refused at all
    print(table(rows))
    rows = _kept_rows(args.out, {r["case"] for r in rows}) + rows
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
