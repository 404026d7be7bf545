"""BDF + D'Alembert on the four-bar before and after the restart rule changed (issue 15, item 6).

Commit 4e56546 ("Multistep steppers keep their own state within 100 tolerance units of the
projection; D'Alembert restarts only when the partition changes", ``RESTART_DRIFT``) stopped
multistep steppers from restarting after every projection that moved the state by more than
one tolerance unit. This runs ``mbcomp.simulate(four_bar.build(**params), method="BDF",
formulation="dalembert", rtol=1e-8, atol=1e-10, ...)`` at

* **old**: the commit before it (a ``git worktree`` of it, ``PYTHONPATH=<worktree>/src``; its
  default backend is the numeric evaluation),
* **current, numeric**: the working tree with ``backend="numeric"`` (the old one's evaluation:
  only the stepping differs),
* **current, default**: the working tree with its default backend (the compiled program),

each in a fresh process, and prints restarts, repartitions, steps, function evaluations,
Jacobians, CPU time and the largest joint-angle error on the output grid against a Lagrange
index-1 + projection DOP853 run at rtol = atol = 1e-12 (current tree). Cases: the four-bar's
own defaults (gap 1e-3, crank at 8 rad/s, 1 s: two passes near the flat position) and the
re-partition case of ``tests/mechanisms/test_four_bar.py`` (gap 1e-4, starting with the pin
speed as the independent one, which the D'Alembert form must re-choose; 0.25 s).

Run: python bench/restarts.py [--old COMMIT] [--worktree PATH] [--cases default,repartition]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent

CASES = {
    "default": dict(params={}, t_end=1.0, n_out=101, options={}),
    "repartition": dict(params=dict(gap=1e-4), t_end=0.25, n_out=251, options=dict(independent=["pin.w"])),
}
TOL = dict(rtol=1e-8, atol=1e-10)  # four_bar.SIMULATION


def child(tree, case, backend):
    import resource
    import time
    import warnings

    import mbcomp

    c = CASES[case]
    model = mbcomp.load_model(str(pathlib.Path(tree) / "models" / "four_bar.py"), **c["params"])
    kw = dict(c["options"], **TOL)
    if backend:
        kw["backend"] = backend
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        c0, w0 = time.process_time(), time.perf_counter()
        res = mbcomp.simulate(model, t_end=c["t_end"], n_out=c["n_out"], method="BDF", formulation="dalembert", **kw)
        ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = time.process_time() - c0 + (ch1.ru_utime + ch1.ru_stime) - (ch0.ru_utime + ch0.ru_stime)
        wall = time.perf_counter() - w0
    names = [n for n in ("crank_joint.phi", "coupler_joint.phi", "rocker_joint.phi", "pin.phi")]
    cols = {}
    for n in names:
        try:
            cols[n] = [float(x) for x in res[n]]
        except Exception:  # noqa: BLE001 - a coordinate this version names otherwise
            pass
    st = res.stats
    print(json.dumps(dict(status=res.status, message=res.message, cpu_s=cpu, wall_s=wall, time=[float(t) for t in res.time],
                          cols=cols, **{k: st.get(k) for k in ("restarts", "repartitions", "steps", "nfev", "njev",
                                                              "nlu", "projections", "backend")})))


def run_child(src, tree, case, backend, timeout):
    env = dict(os.environ, PYTHONPATH=str(src))
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    cmd = [sys.executable, __file__, "--child", "--tree", str(tree), "--case", case, "--backend", backend or ""]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd="/", timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(status=f"over {timeout:g} s (wall)", message="")
    if p.returncode:
        return dict(status="error", message=p.stderr.strip().splitlines()[-1][:150] if p.stderr.strip() else "")
    return json.loads(p.stdout.strip().splitlines()[-1])


def reference(case):
    import warnings

    import mbcomp

    c = CASES[case]
    model = mbcomp.load_model(str(ROOT / "models" / "four_bar.py"), **c["params"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = mbcomp.simulate(model, t_end=c["t_end"], n_out=c["n_out"], method="DOP853", stabilization="projection",
                              rtol=1e-12, atol=1e-12)
    assert res.success, res.message
    return {n: np.asarray(res[n], float) for n in ("crank_joint.phi", "coupler_joint.phi", "rocker_joint.phi",
                                                    "pin.phi")}


def old_commit():
    """The parent of the commit that introduced RESTART_DRIFT."""
    out = subprocess.run(["git", "-C", str(ROOT), "log", "--format=%H", "--reverse", "-S", "RESTART_DRIFT", "--", "src"],
                         capture_output=True, text=True, check=True).stdout.split()
    if not out:
        raise SystemExit("no commit introduces RESTART_DRIFT; pass --old")
    return subprocess.run(["git", "-C", str(ROOT), "rev-parse", out[0] + "^"], capture_output=True, text=True,
                          check=True).stdout.strip()


def ensure_worktree(commit, path):
    path = pathlib.Path(path)
    if not (path / "src" / "mbcomp").is_dir():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(path), commit], check=True,
                       capture_output=True)
    head = subprocess.run(["git", "-C", str(path), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    if not head.startswith(commit[:7]):
        raise SystemExit(f"{path} is at {head[:10]}, not {commit[:10]}: pass another --worktree")
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default=None, help="the 'before' commit (default: the parent of the RESTART_DRIFT commit)")
    ap.add_argument("--worktree", default=None, help="where the old commit is checked out (default /tmp/mbcomp-old-<sha>)")
    ap.add_argument("--cases", default="default,repartition")
    ap.add_argument("--timeout", type=float, default=900.0, help="wall seconds allowed per run")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--tree", help=argparse.SUPPRESS)
    ap.add_argument("--case", help=argparse.SUPPRESS)
    ap.add_argument("--backend", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args.tree, args.case, args.backend or None)
    old = args.old or old_commit()
    tree = ensure_worktree(old, args.worktree or f"/tmp/mbcomp-old-{old[:7]}")
    cur = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True,
                         text=True).stdout.strip()
    print(f"old: {old[:10]} ({tree}); current: {cur} ({ROOT})", flush=True)
    versions = [("old " + old[:7], tree / "src", tree, None),
                ("current, numeric", ROOT / "src", ROOT, "numeric"),
                ("current, default backend", ROOT / "src", ROOT, "")]
    rows = []
    for case in args.cases.split(","):
        ref = reference(case)
        for label, src, t, backend in versions:
            print(f"  {case}: {label} ...", flush=True)
            r = run_child(src, t, case, backend, args.timeout)
            err = max((float(np.max(np.abs(np.asarray(v) - ref[n]))) for n, v in r.get("cols", {}).items()
                       if n in ref and len(v) == len(ref[n])), default=float("nan"))
            rows.append((case, label, r, err))
    print("\n### BDF + D'Alembert on the four-bar, rtol 1e-8, atol 1e-10: before/after the restart rule "
          "(RESTART_DRIFT = 100 tolerance units; no restart when the partition is unchanged)\n")
    print("| case | version | status | restarts | repartitions | steps | nfev | njev | CPU s | ratio to old | "
          "max angle error (rad) |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = {}
    for case, label, r, err in rows:
        if label.startswith("old") and "cpu_s" in r:
            base[case] = r["cpu_s"]
        cpu = r.get("cpu_s")
        ratio = f"{cpu / base[case]:.3f}" if cpu is not None and base.get(case) else "-"
        cells = [r.get(k, "-") for k in ("restarts", "repartitions", "steps", "nfev", "njev")]
        print(f"| {case} | {label} | {r['status']} | " + " | ".join(str(c) for c in cells)
              + f" | {cpu:.2f} | {ratio} | {err:.1e} |" if cpu is not None else
              f"| {case} | {label} | {r['status']} {r.get('message', '')} | - | - | - | - | - | - | - | - |")
    print(f"\ncase 'default': four_bar defaults (gap 1e-3, w0 8 rad/s), 1 s, 101 points; case 'repartition': gap 1e-4, "
          f"independent=['pin.w'], 0.25 s, 251 points. Error: max over the four hinge angles and the output grid "
          f"against DOP853 + projection at 1e-12 (current tree).")


if __name__ == "__main__":
    main()
