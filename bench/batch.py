"""Batches: :func:`mbcomp.batch` against :func:`mbcomp.simulate` calls and MuJoCo's ``rollout``.

1. **5-link pendulum** (``models/n_link_pendulum.py``, N = 5, 10 s, rtol 1e-6, atol 1e-8, the
   default 501 output points): ``--runs`` start states, every hinge's start angle drawn from
   U(-0.3, 0.3) rad (seed 0), at rest.

   * ``batch``: one :func:`mbcomp.batch` call (threads = cores), the median wall time of
     ``--repeat`` calls, split into its Python part (per-run consistent initialization and
     parameter program, or waiting for the worker processes that make the starts where the
     batch chose them) and its C calls (which overlap; their threads' CPU time beside);
   * ``simulate``: one :func:`mbcomp.simulate` call per run on the model (what a user loop
     does), wall time of all of them (once); the first 20 runs are compared with the batch's
     (the largest difference of any state, which the tests hold to 1e-12);
   * ``mujoco rollout``: the same pendulum in MuJoCo (``bench/peers/mujoco_pendulum.py``), RK4
     (MuJoCo's most accurate integrator for a smooth model) with ``mujoco.rollout.rollout`` on
     one ``MjData`` per core, in chunks of 100 runs into one preallocated state array. Its time
     step is *matched in accuracy*: the error of each method is the largest deviation of any
     hinge angle (rad), over the output grid (every 0.02 s), from a reference batch at rtol
     1e-12 on the first 20 runs; the step chosen is the largest of 0.02 / k s (k = 1, 2, 4, 5,
     6, 8, 10, 16, 20, 40: the output times stay steps) whose error is at most the batch's.

2. **slider-crank** (``models/slider_crank.py``, a closed loop: consistent initialization per
   run, which MuJoCo's soft equality constraints cannot hold exactly, so no MuJoCo row), 10 s,
   rtol 1e-6, atol 1e-8: crank start angle U(0, 2 pi) rad, start rate U(2, 8) rad/s, rod mass
   U(1.5, 2.5) kg; batch against simulate calls as above, and a batch whose initialization
   evaluates the loop's Newton closure with the compiled evaluation program
   (``initialization="program"``: starts equal to rounding, not bit for bit). The error column
   is the largest deviation of the crank and pin angles from a batch at rtol 1e-12 (first 20
   runs).

Timing: the machine has 2 cores shared with other work, whose load changes by the minute, so the
batch and the simulate calls are interleaved: each of ``--repeat`` rounds times the batch on all
runs, then ``simulate`` on every ``repeat``-th run (scaled to all runs); the table gives medians
and the median of the per-round ratios, in wall time and in CPU time of this process and its children
(all threads, and the worker processes a batch forks for the starts: a batch's CPU time counts
both cores' work, so the CPU ratio is the work saved and the wall ratio adds the overlap). MuJoCo is timed after, its ratio against the batch's
median.

Run: python bench/batch.py [--runs 1000] [--repeat 3] [--t-end 10]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import pathlib  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
PENDULUM = mbcomp.load_model_file(HERE.parent / "models" / "n_link_pendulum.py").build
SLIDER = mbcomp.load_model_file(HERE.parent / "models" / "slider_crank.py").build
N = 5
TOL = dict(rtol=1e-6, atol=1e-8)
SAMPLE = 20  # runs whose error is measured against the reference
STEPS_PER_OUTPUT = (1, 2, 4, 5, 6, 8, 10, 16, 20, 40)
OUT_DT = 0.02


def pendulum_table(runs):
    rng = np.random.default_rng(0)
    phi = rng.uniform(-0.3, 0.3, (runs, N))
    return {f"joint{k + 1}.phi0": phi[:, k] for k in range(N)}, phi


def slider_table(runs):
    rng = np.random.default_rng(0)
    return {"crank_joint.phi0": rng.uniform(0.0, 2 * np.pi, runs), "crank_joint.w0": rng.uniform(2.0, 8.0, runs),
            "rod.m": rng.uniform(1.5, 2.5, runs)}


def cpu_time():
    """CPU seconds of this process's threads and of its children that ended (the batch's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def interleaved(model, table, t_end, rounds, names, variants=(("batch", {}),)):
    """Timings under a shared machine's changing load: each round times every batch variant on
    all runs, then ``simulate`` on every ``rounds``-th run (scaled to all runs). Returns
    ``{method: (median wall s, median cpu s, median per-round wall ratio to the first batch,
    the same for cpu)}``, the last result of each variant, and the largest state difference
    between simulate and the first variant on the runs simulated of the first SAMPLE."""
    runs = len(next(iter(table.values())))
    for _, kw in variants:  # compile / load once
        mbcomp.batch(model, {k: v[:2] for k, v in table.items()}, t_end=t_end, **TOL, **kw)
    mbcomp.simulate(model, t_end=t_end, params={k: v[0] for k, v in table.items()}, **TOL)
    times, results, diff = {}, {}, 0.0
    for r in range(rounds):
        for name, kw in variants:
            w0, c0 = time.perf_counter(), cpu_time()
            results[name] = mbcomp.batch(model, table, t_end=t_end, **TOL, **kw)
            times.setdefault(name, []).append((time.perf_counter() - w0, cpu_time() - c0))
        w0, c0 = time.perf_counter(), cpu_time()
        mine = range(r, runs, rounds)
        for i in mine:
            res = mbcomp.simulate(model, t_end=t_end, params={k: v[i] for k, v in table.items()}, **TOL)
            if i < SAMPLE:
                first = results[variants[0][0]]
                diff = max(diff, max(float(np.max(np.abs(res[n] - first[n][i]))) for n in names))
        scale = runs / len(mine)
        times.setdefault("simulate calls", []).append(((time.perf_counter() - w0) * scale,
                                                       (cpu_time() - c0) * scale))
    base = np.array(times[variants[0][0]])
    out = {}
    for name, tc in times.items():
        tc = np.array(tc)
        out[name] = (float(np.median(tc[:, 0])), float(np.median(tc[:, 1])),
                     float(np.median(tc[:, 0] / base[:, 0])), float(np.median(tc[:, 1] / base[:, 1])))
    return out, results, diff


def angles(res):
    return np.stack([res[f"joint{k + 1}.phi"] for k in range(N)], -1)


def mujoco_rollout(phi, t_end, dt, threads, chunk=100):
    """(wall s, hinge angles on the output grid) of MuJoCo RK4 rollouts from the start angles ``phi``."""
    import mujoco
    from mujoco import rollout
    from peers import mujoco_pendulum

    model = mujoco_pendulum.build(N).model
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = dt
    nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    nstep, every = int(round(t_end / dt)), int(round(OUT_DT / dt))
    datas = [mujoco.MjData(model) for _ in range(threads)]
    state = np.empty((min(chunk, len(phi)), nstep, nstate))
    out = np.empty((len(phi), nstep // every + 1, N))
    t0 = time.perf_counter()
    for s in range(0, len(phi), chunk):
        part = phi[s: s + chunk]
        x0 = np.zeros((len(part), nstate))
        x0[:, 1: 1 + N] = part  # [time, qpos, qvel]
        st = state[: len(part)]
        rollout.rollout(model, datas, x0, nstep=nstep, state=st, persistent_pool=True)
        out[s: s + len(part), 0] = part
        out[s: s + len(part), 1:] = st[:, every - 1:: every, 1: 1 + N]
    return time.perf_counter() - t0, out


def matched_step(phi, t_end, ref, target, threads):
    """The largest MuJoCo step 0.02/k s whose error on the sample is at most ``target``; and the
    (step, error) tried."""
    tried = []
    for k in STEPS_PER_OUTPUT:
        dt = OUT_DT / k
        _, q = mujoco_rollout(phi[:SAMPLE], t_end, dt, threads)
        err = float(np.max(np.abs(q - ref)))
        tried.append((dt, err))
        if err <= target:
            return dt, tried
    return None, tried


def pendulum(args, threads):
    table, phi = pendulum_table(args.runs)
    model = PENDULUM(N=N)
    names = [f"joint{k + 1}.{c}" for k in range(N) for c in ("phi", "w")]
    times, results, diff = interleaved(model, table, args.t_end, args.repeat, names)
    res = results["batch"]
    ref = mbcomp.batch(model, {k: v[:SAMPLE] for k, v in table.items()}, t_end=args.t_end, rtol=1e-12, atol=1e-14)
    err_b = float(np.max(np.abs(angles(res)[:SAMPLE] - angles(ref))))
    rows = [("batch", times["batch"], err_b, res), ("simulate calls", times["simulate calls"], err_b, None)]
    try:
        import mujoco  # noqa: F401
    except ImportError as exc:
        print(f"(no MuJoCo row: {exc})")
    else:
        dt, tried = matched_step(phi, args.t_end, angles(ref), err_b, threads)
        print("MuJoCo RK4 error on the sample against the step: "
              + ", ".join(f"dt={d:.4g} s: {e:.2g} rad" for d, e in tried))
        if dt is not None:
            tc = []
            for _ in range(args.repeat):
                c0 = cpu_time()
                w, q = mujoco_rollout(phi, args.t_end, dt, threads)
                tc.append((w, cpu_time() - c0))
            wall, cpu = np.median(np.array(tc), axis=0)
            b = times["batch"]
            rows.append((f"mujoco rollout RK4 dt={dt:.4g} s", (wall, cpu, wall / b[0], cpu / b[1]),
                         float(np.max(np.abs(q[:SAMPLE] - angles(ref)))), None))
    report(f"5-link pendulum, {args.runs} runs of {args.t_end:g} s, rtol {TOL['rtol']:g}", rows, args.runs)
    print(f"batch vs simulate: largest state difference on the runs simulated of the first {SAMPLE}: {diff:.2g}")


def slider(args):
    table = slider_table(args.runs)
    model = SLIDER()
    names = ["crank_joint.phi", "crank_joint.w", "slider_joint.s", "slider_joint.v"]
    prog = "batch, initialization='program'"
    times, results, diff = interleaved(model, table, args.t_end, args.repeat, names,
                                       (("batch", {}), (prog, {"initialization": "program"})))
    res, res_p = results["batch"], results[prog]
    ref = mbcomp.batch(model, {k: v[:SAMPLE] for k, v in table.items()}, t_end=args.t_end, rtol=1e-12, atol=1e-14)

    def err(r):
        return max(float(np.max(np.abs(r[n][:SAMPLE] - ref[n]))) for n in ("crank_joint.phi", "pin.phi"))
    rows = [("batch", times["batch"], err(res), res), (prog, times[prog], err(res_p), res_p),
            ("simulate calls", times["simulate calls"], err(res), None)]
    report(f"slider-crank, {args.runs} runs of {args.t_end:g} s, rtol {TOL['rtol']:g}", rows, args.runs)
    print(f"batch vs simulate: largest state difference on the runs simulated of the first {SAMPLE}: {diff:.2g}; "
          f"with initialization='program' (starts equal to rounding) "
          f"{max(float(np.nanmax(np.abs(res_p[n] - res[n]))) for n in names):.2g} over all runs")


def report(title, rows, runs):
    print(f"\n### {title}\n")
    print("| method | wall (s) | per run (ms) | wall / batch | CPU (s) | CPU / batch | max angle error (rad) |")
    print("|---|---|---|---|---|---|---|")
    for name, (wall, cpu, rw, rc), err, res in rows:
        print(f"| {name} | {wall:.3g} | {1e3 * wall / runs:.3g} | {rw:.3g} | {cpu:.3g} | {rc:.3g} | "
              f"{'' if err is None else f'{err:.2g}'} |")
        if res is not None:
            st = res.stats
            where = f"{st['processes']} worker processes" if st["processes"] else "this process"
            print(f"|   of which Python: starts ({where}), parameters | {st['setup_time']:.3g} | | | | | |")
            print(f"|   of which C calls (threads={st['threads']}, overlapping; their CPU {st['c_cpu_time']:.3g} s) | "
                  f"{st['integrate_time']:.3g} | | | | | |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--only", choices=("pendulum", "slider"))
    args = ap.parse_args()
    threads = os.cpu_count() or 1
    print(f"{threads} cores; mbcomp.batch threads = {threads}")
    if args.only in (None, "pendulum"):
        pendulum(args, threads)
    if args.only in (None, "slider"):
        slider(args)


if __name__ == "__main__":
    main()
