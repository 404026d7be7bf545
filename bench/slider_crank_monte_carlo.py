"""Monte Carlo showcase: the slider-crank's peak pin force under mass and speed tolerances, on Dask.

``models/slider_crank.py`` (unpowered, gravity along -y: the crank is thrown upwards at
``crank_joint.w0``, stops short of the top and swings back) is run for 1 s per sample, with

* crank mass ``crank.m ~ Normal(1.0, 0.05)`` kg (5 % standard deviation),
* crank start speed ``crank_joint.w0 ~ Uniform(5.7, 6.3)`` rad/s (+-5 %),
* rod mass ``rod.m ~ Uniform(1.9, 2.1)`` kg (+-5 %),

1,000 samples drawn with seed 0 (:func:`mbcomp.study` draws them before sending, so every
executor runs the same values), all runtime parameters: the model is compiled once per worker
and each run changes only the parameter vector. The metric is the peak of the pin force's
magnitude ``|pin.f|`` (N, the force the rod exerts on the slider's pin) over the run.

Writes the table (one row per sample: the three parameters, ``peak_pin_force``, status,
message, CPU time) to ``--out`` and a chart to ``--plot`` (default
``docs/images/slider_crank_monte_carlo.png``): the peak force against each varied parameter,
coloured by the rod mass (the largest influence; against the rod mass, by the crank speed), and a histogram of the
peak force with its mean, standard deviation and 99th percentile. Prints those numbers, the
least-squares sensitivities dF/dp and the wall time.

Run: python bench/slider_crank_monte_carlo.py [--samples 1000] [--executor dask] [--out FILE.csv] [--plot FILE.png]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; threads only cost on a shared machine

import argparse  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
MODEL = str(ROOT / "models" / "slider_crank.py")
TOLERANCES = {
    "crank.m": mbcomp.Normal(1.0, 0.05),          # kg
    "crank_joint.w0": mbcomp.Uniform(5.7, 6.3),   # rad/s
    "rod.m": mbcomp.Uniform(1.9, 2.1),            # kg
}
LABELS = {"crank.m": "crank mass crank.m (kg)", "crank_joint.w0": "crank start speed crank_joint.w0 (rad/s)",
          "rod.m": "rod mass rod.m (kg)"}
T_END = 1.0  # s: the crank rises, stops and swings back


def peak_pin_force(res):
    """Peak magnitude of the pin force over the run (N)."""
    return float(np.max(np.sqrt(res["pin.f.x"] ** 2 + res["pin.f.y"] ** 2 + res["pin.f.z"] ** 2)))


def monte_carlo(samples=1000, seed=0, executor="dask", t_end=T_END, **options):
    """The study: one row per sample with the drawn parameters and ``peak_pin_force`` (N).

    Examples
    --------
    >>> s = monte_carlo(samples=4, executor=None)
    >>> s.columns[:4], list(s["status"])
    (['crank.m', 'crank_joint.w0', 'rod.m', 'peak_pin_force'], ['success', 'success', 'success', 'success'])
    """
    return mbcomp.study(MODEL, TOLERANCES, t_end=t_end, metrics={"peak_pin_force": peak_pin_force},
                        samples=samples, seed=seed, executor=executor, **options)


def summary(force):
    """``{"mean", "std", "p99"}`` of the peak forces (N; ``std`` with ddof=1)."""
    force = np.asarray(force, dtype=float)
    return dict(mean=float(force.mean()), std=float(force.std(ddof=1)), p99=float(np.percentile(force, 99)))


def chart(s, path):
    """Scatter of the peak force against each parameter and its histogram, saved to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = np.array([st == "success" for st in s["status"]])
    force = s["peak_pin_force"][ok]
    fig, axes = plt.subplots(2, 2, figsize=(11, 8.5))
    for ax, (x, by) in zip(axes.flat, [("crank.m", "rod.m"), ("crank_joint.w0", "rod.m"),
                                       ("rod.m", "crank_joint.w0")]):
        sc = ax.scatter(s[x][ok], force, c=s[by][ok], s=9, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=LABELS[by])
        ax.set_xlabel(LABELS[x])
        ax.set_ylabel("peak pin force |pin.f| (N)")
        ax.grid(alpha=0.3)
    st = summary(force)
    ax = axes[1, 1]
    ax.hist(force, bins=40, color="0.7", edgecolor="0.4")
    for value, style, label in [(st["mean"], "-", f"mean {st['mean']:.3f} N"),
                                (st["mean"] - st["std"], ":", f"mean -/+ std ({st['std']:.3f} N)"),
                                (st["mean"] + st["std"], ":", None),
                                (st["p99"], "--", f"99th percentile {st['p99']:.3f} N")]:
        ax.axvline(value, color="C3", linestyle=style, label=label)
    ax.set_xlabel("peak pin force |pin.f| (N)")
    ax.set_ylabel("samples")
    ax.legend(fontsize=8)
    fig.suptitle(f"Slider-crank, {len(s)} Monte Carlo samples (seed 0): peak pin force over {T_END:g} s "
                 f"under mass and speed tolerances", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def sensitivities(s):
    """Least-squares slopes dF/dp of the peak force on each parameter (N per unit of p)."""
    ok = np.array([st == "success" for st in s["status"]])
    X = np.column_stack([s[p][ok] for p in TOLERANCES] + [np.ones(int(ok.sum()))])
    coef, *_ = np.linalg.lstsq(X, s["peak_pin_force"][ok], rcond=None)
    return dict(zip(TOLERANCES, coef[:-1]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--executor", default="dask", help="'dask' (default), 'serial' or tcp://host:port")
    ap.add_argument("--out", default="slider_crank_monte_carlo.csv")
    ap.add_argument("--plot", default=str(ROOT / "docs" / "images" / "slider_crank_monte_carlo.png"))
    a = ap.parse_args(argv)

    t0 = time.perf_counter()
    s = monte_carlo(a.samples, a.seed, None if a.executor == "serial" else a.executor, progress=True)
    wall = time.perf_counter() - t0
    s.to_csv(a.out)
    pathlib.Path(a.plot).parent.mkdir(parents=True, exist_ok=True)
    chart(s, a.plot)
    st = summary(s["peak_pin_force"][[x == "success" for x in s["status"]]])
    print(f"{len(s)} samples, {len(s.failed)} failed, executor {s.stats['executor']} ({s.stats['workers']} workers), "
          f"wall {wall:.1f} s, CPU {np.sum(s['cpu_time']):.1f} s")
    print(f"peak pin force: mean {st['mean']:.3f} N, std {st['std']:.3f} N, 99th percentile {st['p99']:.3f} N")
    print("sensitivities: " + ", ".join(f"dF/d{p} = {v:.3f}" for p, v in sensitivities(s).items()))
    print(f"wrote {a.out} and {a.plot}")
    return 0 if not s.failed else 1


if __name__ == "__main__":
    raise SystemExit(main())
