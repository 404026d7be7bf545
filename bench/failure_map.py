"""Where methods fail: every formulation x solver on four hard cases, charted and tabulated.

(a) drift: the seed's Example 6.5 pendulum with the rod as a loop-closing constraint
    (coordinates r, theta and a cut pin), 1000 s: energy and constraint drift per method;
(b) stiffness: Andrews' squeezing mechanism (spring c0 = 4530 N/m on 1e-2 kg bodies), to
    t = 0.03 s at rtol 1e-6: steps, evaluations, CPU and error against the published solution;
(c) singularity: a four-bar whose ground link is shortened by ``gap`` from the change-point
    geometry, so it passes ``gap`` from its flat position (gap = 0: through it);
(d) Baumgarte: the slider-crank with alpha = beta from 0 to 1e4 1/s, explicit and implicit;
(e) impacts, a hinge stop: the door (models/door.py, damped, pushed shut at 3 rad/s) against
    its stops, 8 s at rtol 1e-6 and 1e-9: impact times and the state at the end against the
    closed form (``door.reference``): what event location costs and how far it limits accuracy;
(f) impacts, a bouncing ball (models/bouncing_ball.py, when it is there): impact times
    against ``t0 + 2 t0 e (1 - e^k) / (1 - e)`` and the rest at the Zeno point ``t_inf`` (5 s).

Each run records its status and the library's message: a failure must be a status with a
cause (singular position, Newton failure, step-size collapse, divergence), never a numpy
traceback and never a silently wrong answer. Writes bench/failure_map.csv and
bench/failure_map.png and prints one table per case.

Run: python bench/failure_map.py [--cases a,b,c,d,e,f] [--t-pendulum 1000] [--executor processes|dask|tcp://...]

A run of some cases keeps the other cases' rows of bench/failure_map.csv; the chart of (a)-(d)
is drawn when all four ran, (e)-(f)'s chart (bench/failure_map_events.png) when either ran.

Every run is one picklable task (its model file is loaded where it runs), so the map runs on
any executor of :mod:`mbcomp.analysis.parallel`, with the same rows as the serial run.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; see bench/scaling.py
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import csv  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent

import mbcomp  # noqa: E402

COMBOS = {
    "ODE i1 none / DOP853": dict(method="DOP853", stabilization="none"),
    "ODE i1 Baumgarte / DOP853": dict(method="DOP853", stabilization="baumgarte"),
    "ODE i1 projection / DOP853": dict(method="DOP853", stabilization="projection"),
    "ODE i1 projection / Radau": dict(method="Radau", stabilization="projection"),
    "D'Alembert / DOP853": dict(formulation="dalembert", method="DOP853"),
    "DAE i1 Baumgarte / radau5": dict(method="radau5", index=1, stabilization="baumgarte"),
    "DAE i1 none / radau5": dict(method="radau5", index=1, stabilization="none"),
    "DAE i2 GGL / radau5": dict(method="radau5", index=2, stabilization="none"),
    "DAE i3 / radau5": dict(method="radau5", index=3, stabilization="none"),
    "DAE i2 GGL / IDA": dict(method="ida", index=2, stabilization="none"),
    "DAE i3 / gen-alpha": dict(method="genalpha", index=3, stabilization="none"),
}
ROWS = []
#: where each case's model comes from (a model file, loaded in the process that runs the task)
FILES = {"a": "models/textbook/ex6_5_pendulum.py", "b": "models/andrews.py", "c": "models/four_bar.py",
         "d": "models/slider_crank.py", "e": "models/door.py", "f": "models/bouncing_ball.py"}


def task(case, label, build, t_end, opts, extra=None, n_out=201):
    """One run of the map as a picklable tuple (the model is built where it runs)."""
    return (case, label, build, t_end, opts, extra or {}, n_out)


def run_task(spec):
    """The row of one run: :func:`task`'s tuple, simulated on the python backend; the
    published error for Andrews (case b), the crank's end angle for the four-bar (case c)."""
    case, label, build, t_end, opts, extra, n_out = spec
    model = mbcomp.load_model_file(ROOT / FILES[case]).build(**build)
    kw = dict(backend="python", n_out=n_out)
    kw.update(opts)
    c0 = time.process_time()
    try:
        res = mbcomp.simulate(model, t_end=t_end, **kw)
    except Exception as exc:  # noqa: BLE001 - a refused request is a row of the map too
        return dict(case=case, combo=label, status="refused", message=f"{type(exc).__name__}: {exc}",
                    cpu_s=time.process_time() - c0, **extra)
    E = res["energy.total"]
    row = dict(case=case, combo=label, status=res.status, message=res.message, cpu_s=time.process_time() - c0,
               t_reached=float(res.time[-1]), steps=res.stats.get("steps"), nfev=res.stats.get("nfev"),
               energy_drift=float(np.nanmax(np.abs(E - E[0]))) if len(E) else np.nan,
               residual=float(np.nanmax(res["residual.position"])), sigma_min=res.stats.get("min_constraint_sigma"),
               **extra)
    if case == "b" and res.success:
        ref = mbcomp.load_model_file(ROOT / FILES["b"]).REFERENCE["values"]
        row["error"] = max(abs(res[n][-1] - v) / abs(v) for n, v in ref.items())
    if case == "c" and res.success:
        row["crank_end"] = float(res["crank_angle"][-1])
    if case in ("e", "f"):
        row.update(impact_errors(case, build, t_end, res))
    return row


def impact_errors(case, build, t_end, res):
    """Case (e)/(f)'s columns: ``impacts`` (how many), ``t_err`` (s: max |t_impact - exact|
    over the impacts both have), ``state_err`` (door: max |phi - exact| (rad), |w - exact|
    (rad/s) at the end; ball: |t_rest - t_inf| (s)), ``events_evals``."""
    times = [x.time for x in res.events if x.kind == "impact"]
    out = dict(impacts=len(times), event_evals=res.stats.get("event_evaluations"))
    if case == "e":
        ref = mbcomp.load_model_file(ROOT / FILES["e"]).reference(t_end=t_end, **build)
        exact = ref["impacts"]
        if res.success:
            out["state_err"] = max(abs(float(res[n][-1]) - v) for n, v in ref["values"].items())
    else:
        p = dict(h0=1.0, restitution=0.8, g=9.81, **build)
        e, t0 = p["restitution"], np.sqrt(2 * p["h0"] / p["g"])
        exact = [t0 + 2 * t0 * e * (1 - e**k) / (1 - e) for k in range(len(times))]
        rest = [x.time for x in res.events if x.kind == "rest"]
        out["state_err"] = abs(rest[0] - t0 * (1 + 2 * e / (1 - e))) if rest else np.nan
    n = min(len(times), len(exact))
    out["t_err"] = float(np.max(np.abs(np.subtract(times[:n], exact[:n])))) if n else np.nan
    out["impacts_exact"] = len(exact)
    return out


def show(case, keys):
    rows = [r for r in ROWS if r["case"] == case]
    print(f"\n--- case {case} ---")
    head = "".join(f"{k:>13}" for k in keys)
    print(f"{'combination':<30}{head}  status / message")
    for r in rows:
        vals = "".join(f"{_fmt(r.get(k)):>13}" for k in keys)
        msg = "" if r["status"] == "success" else f"  {r['status']}: {r['message'][:110]}"
        print(f"{r['combo']:<30}{vals}{msg or '  success'}")


def _fmt(v):
    if v is None:
        return "-"
    if isinstance(v, float):
        return "nan" if v != v else f"{v:.3g}"
    return str(v)


def case_a(t_end):
    tasks = []
    for label, opts in COMBOS.items():
        o = dict(opts, rtol=1e-6, atol=1e-8)
        if opts["method"] == "genalpha":
            o["h"] = 2e-3
        tasks.append(task("a", label, {"rod": "constraint"}, t_end, o, n_out=101))
    return tasks


def case_b():
    tasks = []
    for label, opts in {**COMBOS, "ODE i1 Baumgarte / RK45": dict(method="RK45", stabilization="baumgarte"),
                        "D'Alembert / LSODA": dict(formulation="dalembert", method="LSODA")}.items():
        o = dict(opts, rtol=1e-6, atol=1e-8)
        if opts["method"] == "genalpha":
            o["h"] = 1e-5
        tasks.append(task("b", label, {}, 0.03, o, n_out=2))
    return tasks


def case_c():
    tasks = []
    for gap in (1e-2, 1e-4, 1e-8, 1e-12, 0.0):
        for label in ("ODE i1 Baumgarte / DOP853", "ODE i1 projection / DOP853", "ODE i1 projection / Radau",
                      "D'Alembert / DOP853", "DAE i3 / radau5", "DAE i2 GGL / IDA", "DAE i3 / gen-alpha"):
            o = dict(COMBOS[label], rtol=1e-8, atol=1e-10)
            if o["method"] == "genalpha":
                o["h"] = 1e-4
            tasks.append(task("c", label, {"gap": gap}, 0.5, o, extra=dict(gap=gap), n_out=51))
    return tasks


def case_d():
    tasks = []
    for ab in (0.0, 1.0, 10.0, 100.0, 1e3, 1e4):
        for method in ("RK45", "DOP853", "Radau"):
            o = dict(method=method, stabilization="baumgarte" if ab else "none", alpha=ab, beta=ab,
                     rtol=1e-6, atol=1e-8)
            tasks.append(task("d", f"Baumgarte a=b={ab:g} / {method}", {}, 10.0, o, extra=dict(alpha=ab), n_out=101))
    return tasks


def case_e():
    tasks = []
    for rtol in (1e-6, 1e-9):
        for label, opts in COMBOS.items():
            o = dict(opts, rtol=rtol, atol=rtol * 1e-2)
            if opts["method"] == "genalpha":
                o["h"] = 1e-3 if rtol > 1e-8 else 1e-4
            tasks.append(task("e", label, dict(damping=1.0, w0=-3.0), 8.0, o, extra=dict(rtol=rtol), n_out=2))
    return tasks


def case_f():
    if not (ROOT / FILES["f"]).exists():
        print("case f: models/bouncing_ball.py is not there yet: skipped")
        return []
    tasks = []
    for rtol in (1e-6, 1e-9):
        for label, opts in COMBOS.items():
            o = dict(opts, rtol=rtol, atol=rtol * 1e-2)
            if opts["method"] == "genalpha":
                o["h"] = 1e-3 if rtol > 1e-8 else 1e-4
            tasks.append(task("f", label, {}, 5.0, o, extra=dict(rtol=rtol), n_out=2))
    return tasks


#: what each case's table shows
KEYS = {"a": ["cpu_s", "steps", "energy_drift", "residual", "t_reached"],
        "b": ["cpu_s", "steps", "nfev", "error", "residual"],
        "c": ["gap", "cpu_s", "sigma_min", "energy_drift", "crank_end"],
        "d": ["alpha", "cpu_s", "steps", "nfev", "residual", "energy_drift"],
        "e": ["rtol", "cpu_s", "steps", "impacts", "t_err", "state_err", "event_evals"],
        "f": ["rtol", "cpu_s", "steps", "impacts", "t_err", "state_err", "event_evals"]}


def chart_events():
    """(e)/(f): impact-time error against CPU time per combination, one panel per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = [c for c in "ef" if any(r["case"] == c for r in ROWS)]
    fig, axes = plt.subplots(1, len(cases), figsize=(7 * len(cases), 5.2), squeeze=False)
    titles = {"e": "(e) door against its stops: max |t_impact - exact|",
              "f": "(f) bouncing ball: max |t_impact - exact|"}
    for ax, c in zip(axes[0], cases):
        rows = [r for r in ROWS if r["case"] == c and r["status"] not in ("failed", "refused")
                and r.get("t_err", np.nan) == r.get("t_err", np.nan)]
        for k, combo in enumerate(dict.fromkeys(r["combo"] for r in rows)):
            rr = sorted((r for r in rows if r["combo"] == combo), key=lambda r: -r["rtol"])
            ax.loglog([r["cpu_s"] for r in rr], [max(r["t_err"], 1e-16) for r in rr], "-o", color=f"C{k % 10}",
                      ms=4, label=combo)
        bad = [r["combo"] for r in ROWS if r["case"] == c and r["status"] in ("failed", "refused")]
        ax.set(xlabel="CPU s (rtol 1e-6 -> 1e-9; the first run includes compiling)", ylabel="s",
               title=titles[c] + (f"\nfailed/refused: {len(bad)} runs (not plotted)" if bad else ""))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(HERE / "failure_map_events.png", dpi=110)



def chart():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(13, 9))
    ok = {"success": "o", "failed": "x", "refused": "s"}
    a = [r for r in ROWS if r["case"] == "a"]
    for r in a:
        ax[0, 0].scatter(r.get("energy_drift", np.nan), r.get("residual", np.nan), marker=ok[r["status"]], s=40)
        ax[0, 0].annotate(r["combo"], (r.get("energy_drift", np.nan), r.get("residual", np.nan)), fontsize=6)
    ax[0, 0].set(xscale="log", yscale="log", xlabel="max |E - E0| (J)", ylabel="max position residual",
                 title="(a) pendulum with a loop-closing rod: drift over the run")
    b = [r for r in ROWS if r["case"] == "b" and r.get("nfev")]
    ax[0, 1].barh([r["combo"] for r in b], [r["cpu_s"] for r in b],
                  color=["C0" if r["status"] == "success" else "C3" for r in b])
    ax[0, 1].set(xscale="log", xlabel="CPU s to t = 0.03 at rtol 1e-6", title="(b) Andrews (stiff spring)")
    ax[0, 1].tick_params(axis="y", labelsize=6)
    c = [r for r in ROWS if r["case"] == "c"]
    combos = list(dict.fromkeys(r["combo"] for r in c))
    gaps = sorted({r["gap"] for r in c}, reverse=True)
    grid = np.array([[{"success": 1, "failed": 0, "refused": -1}[next(r["status"] for r in c if r["combo"] == k
                                                                       and r["gap"] == g)] for g in gaps]
                     for k in combos])
    ax[1, 0].imshow(grid, cmap="RdYlGn", vmin=-1, vmax=1, aspect="auto")
    ax[1, 0].set_xticks(range(len(gaps)), [f"{g:g}" for g in gaps])
    ax[1, 0].set_yticks(range(len(combos)), combos, fontsize=6)
    ax[1, 0].set(xlabel="gap to the flat position (m)", title="(c) four-bar: green ran, red reported a failure")
    d = [r for r in ROWS if r["case"] == "d"]
    for method, col in (("RK45", "C0"), ("DOP853", "C1"), ("Radau", "C2")):
        rr = [r for r in d if r["combo"].endswith(method) and r.get("nfev")]
        x = [max(r["alpha"], 0.1) for r in rr]
        ax[1, 1].loglog(x, [r["nfev"] for r in rr], "-o", color=col, label=f"{method}: f-evals")
        ax[1, 1].loglog(x, [max(r["residual"], 1e-16) * 1e12 for r in rr], ":^", color=col,
                        label=f"{method}: residual x 1e12")
    ax[1, 1].set(xlabel="alpha = beta (1/s) (0 plotted at 0.1)", title="(d) slider-crank, 10 s: Baumgarte sweep")
    ax[1, 1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "failure_map.png", dpi=110)


def main(argv=None):
    from mbcomp.analysis.parallel import executor_of, map_on

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="a,b,c,d,e,f")
    ap.add_argument("--t-pendulum", type=float, default=1000.0)
    ap.add_argument("--executor", default=None,
                    help="serial (default), processes, dask or tcp://host:port: where the runs go")
    ap.add_argument("--workers", type=int, default=None, help="processes of --executor processes")
    args = ap.parse_args(argv)
    cases = args.cases.split(",")
    makers = {"a": lambda: case_a(args.t_pendulum), "b": case_b, "c": case_c, "d": case_d, "e": case_e,
              "f": case_f}
    tasks = [t for c in "abcdef" if c in cases for t in makers[c]()]
    executor, owned = executor_of(args.executor, args.workers)
    try:
        ROWS.extend(map_on(executor, run_task, tasks, progress=True))
    finally:
        if owned:
            executor.shutdown()
    for c in "abcdef":
        if c in cases:
            show(c, KEYS[c])
    rows = kept_rows(cases) + ROWS
    keys = sorted({k for r in rows for k in r}, key=lambda k: (k not in ("case", "combo", "status"), k))
    with open(HERE / "failure_map.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    wrote = ["bench/failure_map.csv"]
    if {"a", "b", "c", "d"} <= set(cases):
        chart()
        wrote.append("bench/failure_map.png")
    if {"e", "f"} & set(cases) and any(r["case"] in "ef" for r in ROWS):
        chart_events()
        wrote.append("bench/failure_map_events.png")
    print("\nwrote " + " and ".join(wrote))


def kept_rows(cases):
    """The rows of the cases not run now, from the last bench/failure_map.csv (a run of some
    cases updates theirs and keeps the others')."""
    path = HERE / "failure_map.csv"
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return [r for r in csv.DictReader(fh) if r["case"] not in cases]


if __name__ == "__main__":
    main()
