"""Cold start: a fresh Python process's first ``simulate`` of the showcase against Pinocchio's.

The README's quick start runs the showcase, ``mbcomp simulate models/slider_crank.py``: the
planar slider-crank (a closed loop: three moving bodies, three tree joints, a cut revolute, one
degree of freedom) with the file's ``SIMULATION`` settings (``t_end`` = 10 s, ``rtol`` = 1e-8,
``atol`` = 1e-10). Each measured job is a new interpreter (``subprocess``) doing the whole
user's job from nothing:

* **mbcomp showcase**: ``import mbcomp``, build the slider-crank, ``simulate`` it;
* **mbcomp pendulum**: the same for the planar 3-link pendulum of ``models/n_link_pendulum.py``
  (3 bodies on 3 hinges) with the showcase's settings: the like-for-like mechanism of the peer;
* **Pinocchio**: ``import pinocchio``, build the same 3-link pendulum
  (``bench/peers/pinocchio_pendulum.py``), integrate ``[u, aba(q, u, 0)]`` with scipy's
  ``solve_ivp`` (LSODA, the project's Pinocchio peer, same ``t_end`` and tolerances). Pinocchio
  has no closed-loop forward dynamics on this path, so the 3-link chain stands in for the
  slider-crank (same bodies' count; the chain has 3 degrees of freedom, the showcase 1).

The mbcomp jobs run with the programs' compile cache ``$MBCOMP_CACHE`` in one of four states:

* **warm**: a directory filled by a previous run of the same job;
* **new model**: a fresh copy of a cache filled by another model's run (the 2-link pendulum):
  what every model shares is built (the runtime's integrators, the thin call's extension,
  compiled once per machine and Python; the output grid's loop), the showcase's own programs
  are not -- what a user meets at the first run of a model new to the machine.
* **cold cache**: a fresh empty directory per run: the C compiler runs for the model's programs
  and everything else the cache holds; the runtime (the integrators, the thin call's
  extension) is the machine's, built once per machine in ``$MBCOMP_RUNTIME`` (a directory of
  this benchmark's, filled by the warm-up) -- a version of mbcomp keeping its runtime in the
  programs' cache compiles it here too;
* **first run**: nothing built anywhere (a fresh ``$MBCOMP_CACHE``, ``$MBCOMP_RUNTIME`` and
  ``$HOME``) but what the install built: a machine's first run after ``pip install``, whose
  build step compiled the runtime's objects into the package (``setup.py``,
  ``mbcomp/codegen/prebuilt``; an editable install made before that step has none: install
  again, ``pip install -e .``); the run copies them, and compiles the thin call's extension;
* **not installed**: the first run without the install's objects (``MBCOMP_PREBUILT=""``):
  a machine where the install could not compile them (no compiler then, a wheel built for
  another one), where the C compiler runs for the runtime as well;

Rounds alternate the jobs (round-robin), the figures are medians over ``--rounds``; wall
seconds (``time.perf_counter`` around the child) and CPU seconds (the child's and its
compilers', ``getrusage(RUSAGE_CHILDREN)``). The children write bytecode to a private
``PYTHONPYCACHEPREFIX`` filled by a first unmeasured run, as a pip install does (this machine
sets ``PYTHONDONTWRITEBYTECODE=1``, which makes every fresh process compile mbcomp's ~120
modules from source, ~0.12 s; ``--no-bytecode`` measures that way too).

Then, unless ``--no-breakdown``, where mbcomp's fresh process spends its time in each cache
mode: the stages timed inside one child each (imports, model build, then ``simulate``'s
phases: system, initialization, formulation, integration with the program's trace and C build,
post-processing with the output program's), and the packages ``python -X importtime`` charges
most.

Run: ``python bench/cold_start.py`` (``--rounds 7``; ``--jobs showcase pinocchio``).
"""
import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BENCH = os.path.join(ROOT, "bench")

#: the showcase's settings (models/slider_crank.py SIMULATION), used by every job
T_END, RTOL, ATOL = 10.0, 1e-8, 1e-10
#: links of the chain standing in for the slider-crank (its moving bodies)
N_LINKS = 3

_MBCOMP = """
import time
t0 = time.perf_counter()
import mbcomp
t1 = time.perf_counter()
model = mbcomp.load_model({path!r}{kwargs})
t2 = time.perf_counter()
res = mbcomp.simulate(model, t_end={t_end!r}, rtol={rtol!r}, atol={atol!r})
t3 = time.perf_counter()
assert res.status == "success", res.message
import json
print(json.dumps(dict(import_s=t1 - t0, build_s=t2 - t1, run_s=t3 - t2, nfev=int(res.stats.get("nfev", 0)))))
"""

_PINOCCHIO = """
import time
t0 = time.perf_counter()
import sys
sys.path.insert(0, {bench!r})
import numpy as np
import pinocchio
from scipy.integrate import solve_ivp
t1 = time.perf_counter()
from peers.pinocchio_pendulum import build
peer = build({n})
y0 = np.concatenate((np.full({n}, 0.3), np.zeros({n})))
t2 = time.perf_counter()
sol = solve_ivp(peer.rhs, (0.0, {t_end!r}), y0, method="LSODA", rtol={rtol!r}, atol={atol!r})
t3 = time.perf_counter()
assert sol.success, sol.message
import json
print(json.dumps(dict(import_s=t1 - t0, build_s=t2 - t1, run_s=t3 - t2, nfev=int(sol.nfev))))
"""


def job_code(job):
    """The Python source a child runs for ``job``."""
    settings = dict(t_end=T_END, rtol=RTOL, atol=ATOL)
    if job == "showcase":
        return _MBCOMP.format(path=os.path.join(ROOT, "models", "slider_crank.py"), kwargs="", **settings)
    if job == "pendulum":
        return _MBCOMP.format(path=os.path.join(ROOT, "models", "n_link_pendulum.py"), kwargs=f", N={N_LINKS}",
                              **settings)
    if job == "pinocchio":
        return _PINOCCHIO.format(bench=BENCH, n=N_LINKS, **settings)
    raise ValueError(f"unknown job {job!r}: give showcase, pendulum or pinocchio")


def child_cpu():
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_child(code, env, args=()):
    """Run ``code`` in a fresh interpreter: ``(wall s, CPU s, the JSON it printed last)``."""
    c0, w0 = child_cpu(), time.perf_counter()
    out = subprocess.run([sys.executable, *args, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - w0, child_cpu() - c0
    if out.returncode != 0:
        raise RuntimeError(f"the child failed ({out.returncode}):\n{out.stderr[-3000:]}")
    return wall, cpu, json.loads(out.stdout.strip().splitlines()[-1]), out.stderr


#: the job filling the cache a "new model" run starts from: another model (the 2-link
#: pendulum), run once, so that what every model shares is built (the runtime, the thin call's
#: extension, the output grid's loop) and the showcase's own programs are not
SEED = _MBCOMP.format(path=os.path.join(ROOT, "models", "n_link_pendulum.py"), kwargs=", N=2", t_end=1.0, rtol=RTOL,
                      atol=ATOL)


class Env:
    """The children's environments: bytecode, and the compile caches of each cache mode."""

    def __init__(self, bytecode, keep):
        self.tmp = tempfile.mkdtemp(prefix="mbcomp_cold_start_")
        self.keep = keep
        base = dict(os.environ)
        base.pop("MBCOMP_CACHE", None)
        if bytecode:
            base.pop("PYTHONDONTWRITEBYTECODE", None)
            base["PYTHONPYCACHEPREFIX"] = os.path.join(self.tmp, "pycache")
        base["MBCOMP_RUNTIME"] = os.path.join(self.tmp, "machine")  # this machine's runtime, built once
        self.base = base
        self.warm = os.path.join(self.tmp, "warm")
        self.seed = os.path.join(self.tmp, "seed")
        self.n = 0

    def fresh(self, seeded=False):
        """A new cache directory: empty, or a copy of the seed cache if ``seeded``."""
        self.n += 1
        d = os.path.join(self.tmp, f"cold{self.n}")
        if seeded:
            if not os.path.isdir(self.seed):  # its runtime in it too: a version keeping it there finds it
                run_child(SEED, dict(self.base, MBCOMP_CACHE=self.seed, MBCOMP_RUNTIME=self.seed))
            shutil.copytree(self.seed, d)
        else:
            os.makedirs(d)
        return d

    def of(self, mode):
        """The environment of one child in cache ``mode`` (None for a peer)."""
        env = dict(self.base)
        if mode == "warm":
            env["MBCOMP_CACHE"] = self.warm
        elif mode in ("new model", "cold cache"):
            env["MBCOMP_CACHE"] = self.fresh(seeded=mode == "new model")
        elif mode in ("first run", "not installed"):  # the caches and the home directory new
            env["MBCOMP_CACHE"], env["MBCOMP_RUNTIME"], env["HOME"] = self.fresh(), self.fresh(), self.fresh()
            if mode == "not installed":  # nor the install's objects of the runtime
                env["MBCOMP_PREBUILT"] = ""
        elif mode is not None:
            raise ValueError(f"unknown cache mode {mode!r}: give warm, 'new model', 'cold cache', 'first run' or "
                             "'not installed'")
        return env

    def close(self):
        if not self.keep:
            shutil.rmtree(self.tmp, ignore_errors=True)


def cases(jobs, modes, baseline):
    """The measured (job, mode) pairs: every mbcomp job in every cache mode (and again as
    ``job + " (baseline)"`` from the ``baseline`` source tree), each peer once."""
    out = []
    for job in jobs:
        if job == "pinocchio":
            out.append((job, None))
            continue
        out.extend((job, m) for m in modes)
        if baseline:
            out.extend((job + " (baseline)", m) for m in modes)
    return out


def measure(env, jobs, modes, rounds, baseline=None):
    """Median wall and CPU seconds (and the child's own stage times) of every case."""
    todo = cases(jobs, modes, baseline)

    def child(job, mode):
        e = env.of(mode)
        if job.endswith(" (baseline)"):
            job = job.removesuffix(" (baseline)")
            e["PYTHONPATH"] = os.pathsep.join([baseline] + ([e["PYTHONPATH"]] if e.get("PYTHONPATH") else []))
        return run_child(job_code(job), e)[:3]

    for job, mode in todo:  # unmeasured: the bytecode written, the warm cache filled
        child(job, None if mode is None else "warm")
    samples = {c: [] for c in todo}
    for r in range(rounds):
        order = todo if r % 2 == 0 else todo[::-1]
        for case in order:
            samples[case].append(child(*case))
    table = {}
    for case, s in samples.items():
        table[case] = dict(wall=statistics.median(x[0] for x in s), cpu=statistics.median(x[1] for x in s),
                           **{k: statistics.median(x[2][k] for x in s) for k in s[0][2]})
    return table


def print_table(table, rounds):
    peer = next((v for (job, _), v in table.items() if job == "pinocchio"), None)
    print(f"\nfresh process, whole job, median of {rounds} rounds (ratios: / Pinocchio's fresh process)")
    head = f"{'job':<22}{'cache':<14}{'wall s':>8}{'ratio':>8}{'CPU s':>8}{'ratio':>8}" \
           f"{'import s':>10}{'build s':>9}{'run s':>8}{'nfev':>8}"
    print(head)
    print("-" * len(head))
    for (job, mode), v in table.items():
        rw = f"{v['wall'] / peer['wall']:.2f}x" if peer else "-"
        rc = f"{v['cpu'] / peer['cpu']:.2f}x" if peer else "-"
        print(f"{job:<22}{mode or '-':<14}{v['wall']:8.3f}{rw:>8}{v['cpu']:8.3f}{rc:>8}"
              f"{v['import_s']:10.3f}{v['build_s']:9.3f}{v['run_s']:8.3f}{v['nfev']:8.0f}")


_TIMELINE = """
import functools, json, threading, time
T0 = time.perf_counter()
spent = {{}}


def timed(owner, name, label):
    f = getattr(owner, name)

    @functools.wraps(f)
    def g(*a, **k):
        s = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            key = label if threading.current_thread() is threading.main_thread() else label + " (thread)"
            spent[key] = spent.get(key, 0.0) + time.perf_counter() - s
    setattr(owner, name, g)


import mbcomp
t1 = time.perf_counter()
import mbcomp.codegen.compiler as cp, mbcomp.codegen.thin as th
for owner, name, label in [(cp, "runtime_objects", "runtime"), (th, "_build", "thin")]:
    timed(owner, name, label)
simulate = mbcomp.simulate  # as a user's script: the runtime may start compiling here
import mbcomp.simulation.driver as dr
t2 = time.perf_counter()
import mbcomp.codegen.outputs as ou
for owner, name, label in [(dr, "system_of", "system"), (dr, "initialize_in_modes", "init"), (dr, "build", "form"),
                           (dr, "integrate", "integrate"), (dr, "postprocess", "post"), (cp.Code, "_build_c", "prog_c"),
                           (ou.OutputProgram, "build", "out"), (ou.OutputProgram, "_build_c", "out_c")]:
    timed(owner, name, label)
model = mbcomp.load_model({path!r})
t3 = time.perf_counter()
res = simulate(model, t_end={t_end!r}, rtol={rtol!r}, atol={atol!r})
t4 = time.perf_counter()
print(json.dumps(dict(import_s=t1 - T0, driver_s=t2 - t1, build_s=t3 - t2, run_s=t4 - t3, total_s=t4 - T0, **spent)))
"""

#: the timeline's rows: (label, key of the child's record, keys subtracted)
PHASES = [("import mbcomp (numpy, the framework)", "import_s", ()),
          ("import the simulation (scipy.linalg, ...)", "driver_s", ()),
          ("model build (load_model)", "build_s", ()),
          ("simulate", "run_s", ()),
          ("  system: assemble, copy", "system", ()),
          ("  initialization", "init", ()),
          ("  formulation", "form", ()),
          ("  integration", "integrate", ()),
          ("    its program's C build (wait, link, load)", "prog_c", ()),
          ("    the thin call's extension (C build)", "thin", ()),
          ("    the rest (trace, print, C steps)", "integrate", ("prog_c", "thin")),
          ("  (the runtime's objects, on the main thread)", "runtime", ()),
          ("  (the runtime's objects, on a thread)", "runtime (thread)", ()),
          ("  (the thin call's extension, on a thread)", "thin (thread)", ()),
          ("  post-processing", "post", ()),
          ("    the output program: trace, print", "out", ("out_c",)),
          ("    the output program's C build", "out_c", ()),
          ("fresh process, inside (s)", "total_s", ())]


def breakdown(env, modes):
    """Where mbcomp's fresh process spends its time in each cache mode: the stages timed in the
    child (wall seconds, one run each)."""
    code = _TIMELINE.format(path=os.path.join(ROOT, "models", "slider_crank.py"), t_end=T_END, rtol=RTOL, atol=ATOL)
    cols = {mode: run_child(code, env.of(mode))[2] for mode in modes}
    print("\nwhere the showcase's fresh process spends its time (wall s, timed inside the child, one run each)")
    print(f"{'stage':<48}" + "".join(f"{m:>14}" for m in cols))
    for label, key, minus in PHASES:
        vals = [rec.get(key, 0.0) - sum(rec.get(k, 0.0) for k in minus) for rec in cols.values()]
        print(f"{label:<48}" + "".join(f"{v:14.3f}" for v in vals))


def import_costs(env, top=12):
    """The packages ``-X importtime`` charges most in a warm showcase job (self time, summed per
    package)."""
    _, _, _, err = run_child(job_code("showcase"), env.of("warm"), ("-X", "importtime"))
    per = {}
    total = 0
    for line in err.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        self_us, _, name = line[len("import time:"):].split("|")
        name = name.strip()
        parts = name.split(".")
        key = ".".join(parts[:2]) if parts[0] in ("mbcomp", "scipy") else parts[0]
        per[key] = per.get(key, 0) + int(self_us)
        total += int(self_us)
    print(f"\nimports of a warm showcase job (python -X importtime, self time summed per package; all: "
          f"{total / 1e6:.3f} s)")
    for key, us in sorted(per.items(), key=lambda kv: -kv[1])[:top]:
        print(f"  {key:<34}{us / 1e3:8.1f} ms")


def installed_runtime():
    """Whether the install built the runtime's core as the sources are now (``setup.py``): an
    editable install's objects fall behind a later change of the runtime's C."""
    sys.path.insert(0, os.path.join(ROOT, "src", "mbcomp", "codegen"))
    try:
        import runtime_build as rb  # the standard library only: as setup.py loads it
    finally:
        sys.path.pop(0)
    cc, pre = rb.find_compiler(), rb.prebuilt_directory()
    return bool(cc and pre) and all(os.path.exists(o) for _, _, o in rb.object_paths(cc, pre, "core"))


def runtime_sources():
    """A hash of the runtime's sources: a change during the run (someone editing them) makes
    the "new model" cache miss the runtime."""
    import hashlib

    h = hashlib.sha256()
    for d in (os.path.join(ROOT, "src", "mbcomp", "codegen", "runtime"),):
        for name in sorted(os.listdir(d)):
            if name.endswith((".c", ".h")):
                with open(os.path.join(d, name), "rb") as fh:
                    h.update(fh.read())
    for name in ("engine.py", "runtime_build.py"):
        with open(os.path.join(ROOT, "src", "mbcomp", "codegen", name), "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--jobs", nargs="+", default=["showcase", "pendulum", "pinocchio"],
                    choices=["showcase", "pendulum", "pinocchio"])
    ap.add_argument("--modes", nargs="+", default=["warm", "new model", "cold cache", "first run", "not installed"])
    ap.add_argument("--no-bytecode", action="store_true", help="keep this environment's PYTHONDONTWRITEBYTECODE")
    ap.add_argument("--no-breakdown", action="store_true")
    ap.add_argument("--keep", action="store_true", help="keep the temporary caches")
    ap.add_argument("--baseline", metavar="SRC",
                    help="also run the mbcomp jobs from this source tree (a directory holding the package "
                         "mbcomp, put first on PYTHONPATH): before and after in one run")
    a = ap.parse_args(argv)
    env = Env(bytecode=not a.no_bytecode, keep=a.keep)
    try:
        print(f"cold start: {os.cpu_count()} processors, Python {sys.version.split()[0]}, bytecode "
              f"{'not cached (PYTHONDONTWRITEBYTECODE)' if a.no_bytecode else 'cached'}; caches under {env.tmp}")
        if "first run" in a.modes and not installed_runtime():
            print("note: the install's runtime is missing or older than the runtime's sources (an editable "
                  "install made before them: pip install -e . again): 'first run' is 'not installed'")
        before = runtime_sources()
        table = measure(env, a.jobs, a.modes, a.rounds, a.baseline)
        print_table(table, a.rounds)
        if runtime_sources() != before:
            print("warning: the runtime's sources changed during the run: 'new model' rows may include its compile")
        if not a.no_breakdown:
            breakdown(env, a.modes)
            import_costs(env)
    finally:
        env.close()


if __name__ == "__main__":
    main()
