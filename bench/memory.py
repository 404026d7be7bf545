"""Memory and time of a long run: 1,000 s of the 20-link pendulum with 100,000 output points,
the default call (``mbcomp.simulate(model, t_end=1000, n_out=100_000)``: default method,
backend and tolerances).

Reports the peak resident set size (``resource.getrusage(...).ru_maxrss``) of a fresh Python
process that imports mbcomp, loads the model and runs it, the same process's peak just before
``simulate`` (imports + model: the baseline), wall and CPU time of ``simulate``, what the
result holds (columns x rows, bytes of its arrays) and the run's statistics. The run happens in
a child process (``--child``), so the parent's own imports do not count and every size gets a
fresh process; the compiled library is built first in the same cache (a warm-up run of 1 s in
another child), so the timed run measures the run, not the compiler.

Run: python bench/memory.py [--N 20] [--t-end 1000] [--n-out 100000] [--cold]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent


def child(N, t_end, n_out):
    import resource

    import numpy as np

    import mbcomp

    model = mbcomp.load_model(str(ROOT / "models" / "n_link_pendulum.py"), N=N)
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    def cpu_now():  # this process and its finished children (a compiler)
        ch = resource.getrusage(resource.RUSAGE_CHILDREN)
        return time.process_time() + ch.ru_utime + ch.ru_stime

    w0, c0 = time.perf_counter(), cpu_now()
    res = mbcomp.simulate(model, t_end=t_end, n_out=n_out)
    wall, cpu = time.perf_counter() - w0, cpu_now() - c0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    cols = list(res.names) if hasattr(res, "names") else list(getattr(res, "columns", []))
    nbytes = 0
    for n in cols:
        try:
            nbytes += np.asarray(res[n]).nbytes
        except Exception:  # noqa: BLE001 - a column that is not an array
            pass
    stats = {k: v for k, v in res.stats.items() if isinstance(v, (int, float, str))}
    print(json.dumps(dict(status=res.status, message=res.message, rows=len(res.time), columns=len(cols),
                          result_bytes=nbytes, baseline_kb=base, peak_kb=peak, wall_s=wall, cpu_s=cpu, stats=stats)))


def describe():
    out = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True, text=True)
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    return out.stdout.strip(), sha.stdout.strip()


def run_child(N, t_end, n_out, env):
    p = subprocess.run([sys.executable, __file__, "--child", "--N", str(N), "--t-end", repr(t_end), "--n-out",
                        str(n_out)], capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit(f"the run failed (exit {p.returncode}):\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--N", type=int, default=20)
    ap.add_argument("--t-end", type=float, default=1000.0)
    ap.add_argument("--n-out", type=int, default=100_000)
    ap.add_argument("--cold", action="store_true", help="no warm-up: the timed run compiles (fresh cache)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args.N, args.t_end, args.n_out)
    import tempfile

    desc, sha = describe()
    print(f"mbcomp {desc} ({sha}): {args.N}-link pendulum, t_end = {args.t_end:g} s, {args.n_out} output points, "
          f"default call", flush=True)
    env = dict(os.environ, MBCOMP_CACHE=tempfile.mkdtemp(prefix="mbcomp-memory-"))
    if not args.cold:
        w0 = time.perf_counter()
        run_child(args.N, 1.0, 201, env)  # >= 100 points: the output program is compiled too
        print(f"warm-up (compile into a fresh cache, 1 s run): {time.perf_counter() - w0:.1f} s wall", flush=True)
    w0 = time.perf_counter()
    r = run_child(args.N, args.t_end, args.n_out, env)
    total = time.perf_counter() - w0
    st = r["stats"]
    print(f"\n| quantity | value |\n|---|---:|")
    for k, v in (("status", r["status"]), ("peak RSS (MB)", f"{r['peak_kb'] / 1024:.0f}"),
                 ("RSS before simulate: imports + model (MB)", f"{r['baseline_kb'] / 1024:.0f}"),
                 ("peak - before (MB)", f"{(r['peak_kb'] - r['baseline_kb']) / 1024:.0f}"),
                 ("result arrays (MB)", f"{r['result_bytes'] / 2**20:.0f}"),
                 ("result rows x columns", f"{r['rows']} x {r['columns']}"),
                 ("simulate wall (s)", f"{r['wall_s']:.1f}"), ("simulate CPU incl. compiler (s)", f"{r['cpu_s']:.1f}"),
                 ("of which integration (stats['cpu_time'], wall s)", f"{st.get('cpu_time', float('nan')):.1f}"),
                 ("child process wall incl. start-up (s)", f"{total:.1f}"),
                 ("steps", st.get("steps", "-")), ("nfev", st.get("nfev", "-")), ("method", st.get("method", "-")),
                 ("backend", st.get("backend", "-"))):
        print(f"| {k} | {v} |")
    if r["status"] != "success":
        print(f"\nmessage: {r['message']}")


if __name__ == "__main__":
    main()
