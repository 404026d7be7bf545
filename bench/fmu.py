"""The exported FMU against mbcomp itself: one derivative evaluation, a whole simulation, export time.

* **one call**: the FMU's ``SetContinuousStates`` + ``GetContinuousStateDerivatives`` (FMI 3.0)
  called from a tiny C harness that ``dlopen``s the FMU's binary (no Python in the loop), and
  through FMPy's ctypes wrappers from Python; against mbcomp's own ``LagrangeIndex1.fun`` on
  its compiled program (from Python, as scipy calls it) -- the N-link pendulum, N = 2, 10, 40;
* **simulation**: ``fmpy.simulate_fmu`` as Co-Simulation (the FMU's DOP853) and as Model
  Exchange (FMPy's CVODE) against ``mbcomp.simulate`` for the slider-crank, 10 s, each at
  rtol 1e-8 and 1e-10: wall time and the crank angle's largest difference to a tight
  mbcomp run (DOP853 at 1e-12);
* **export**: ``mbcomp.export_fmu`` wall time (tracing, printing, gcc) for the 10-link
  pendulum and Andrews' squeezer.

Ratios are to mbcomp's own figure in the same run. Needs FMPy (``pip install -e ".[fmu]"``) and
a C compiler. Run: python bench/fmu.py
"""
import ctypes
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.export import export_fmu
from mbcomp.formulations import LagrangeIndex1

ROOT = pathlib.Path(__file__).resolve().parent.parent

HARNESS = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdbool.h>
#include <time.h>
typedef void *(*inst_t)(const char *, const char *, const char *, bool, bool, void *, void *);
typedef int (*setx_t)(void *, const double *, size_t);
typedef int (*getdx_t)(void *, double *, size_t);
typedef int (*init_t)(void *, bool, double, double, bool, double);
typedef int (*exit_t)(void *);
typedef int (*ct_t)(void *);
int main(int argc, char **argv)
{
    void *lib = dlopen(argv[1], RTLD_NOW);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    inst_t inst = (inst_t)dlsym(lib, "fmi3InstantiateModelExchange");
    setx_t setx = (setx_t)dlsym(lib, "fmi3SetContinuousStates");
    getdx_t getdx = (getdx_t)dlsym(lib, "fmi3GetContinuousStateDerivatives");
    init_t init = (init_t)dlsym(lib, "fmi3EnterInitializationMode");
    exit_t ex = (exit_t)dlsym(lib, "fmi3ExitInitializationMode");
    ct_t ct = (ct_t)dlsym(lib, "fmi3EnterContinuousTimeMode");
    size_t n = (size_t)atoi(argv[3]);
    long reps = atol(argv[4]);
    void *c = inst("h", argv[2], "", false, false, NULL, NULL);
    if (!c || init(c, false, 0.0, 0.0, false, 0.0) || ex(c) || ct(c)) { fprintf(stderr, "setup failed\n"); return 3; }
    double *x = calloc(n, sizeof(double)), *dx = calloc(n, sizeof(double));
    for (size_t i = 0; i < n; i++) x[i] = 0.3 + 0.01 * (double)i;
    struct timespec a, b;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
    for (long r = 0; r < reps; r++) {
        x[0] += 1e-12;
        if (setx(c, x, n) || getdx(c, dx, n)) { fprintf(stderr, "call failed\n"); return 4; }
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
    printf("%.6g\n", ((double)(b.tv_sec - a.tv_sec) * 1e9 + (double)(b.tv_nsec - a.tv_nsec)) / (double)reps);
    free(x); free(dx);
    return 0;
}
"""


def per_call(f, seconds=0.2):
    n, t = 1, 0.0
    while t < seconds:
        c0 = time.process_time()
        for _ in range(n):
            f()
        t = time.process_time() - c0
        n *= 2
    return t / (n // 2)


def harness(tmp):
    src, exe = tmp / "harness.c", tmp / "harness"
    src.write_text(HARNESS)
    subprocess.run([c_compiler(), "-O2", str(src), "-o", str(exe), "-ldl"], check=True)
    return exe


def one_call(tmp, exe):
    pend = mbcomp.load_model_file(ROOT / "models" / "n_link_pendulum.py")
    print("\n### One derivative evaluation, N-link pendulum (CPU us per call; ratio to mbcomp's fun from Python)\n")
    print("| N | mbcomp fun (C program, from Python) | FMU from a C loop | ratio | FMU through FMPy (Python) | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Model

    for N in (2, 10, 40):
        model = pend.build(N=N)
        s = compile_system(mbcomp.assemble(model), "c", verify=False, lazy=True)
        initialize(s)
        fun = LagrangeIndex1(s).fun
        y = np.concatenate((0.3 + 0.01 * np.arange(N), np.zeros(N)))
        t_mb = per_call(lambda: fun(0.0, y))
        path = tmp / f"p{N}.fmu"
        info = export_fmu(model, path)
        unz = extract(str(path))
        lib = f"{unz}/binaries/x86_64-linux/{info['model_identifier']}.so"
        ns = float(subprocess.run([str(exe), lib, info["guid"], str(2 * N), "200000"], capture_output=True, text=True,
                                  check=True).stdout)
        md = read_model_description(str(path))
        fmu = FMU3Model(guid=md.guid, unzipDirectory=unz, modelIdentifier=md.modelExchange.modelIdentifier)
        fmu.instantiate()
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.enterContinuousTimeMode()
        x = (ctypes.c_double * (2 * N))(*y)
        dx = (ctypes.c_double * (2 * N))()

        def through_fmpy():
            fmu.fmi3SetContinuousStates(fmu.component, x, 2 * N)
            fmu.fmi3GetContinuousStateDerivatives(fmu.component, dx, 2 * N)
        t_py = per_call(through_fmpy)
        fmu.terminate()
        fmu.freeInstance()
        print(f"| {N} | {1e6 * t_mb:.3g} | {ns / 1e3:.3g} | {ns / 1e3 / (1e6 * t_mb):.2f} | {1e6 * t_py:.3g} | "
              f"{t_py / t_mb:.2f} |")


def simulation(tmp):
    import fmpy

    sc = mbcomp.load_model_file(ROOT / "models" / "slider_crank.py")
    model = sc.build()
    path = tmp / "crank.fmu"
    export_fmu(model, path)
    ref = mbcomp.simulate(model, t_end=10.0, n_out=501, rtol=1e-12, atol=1e-14)
    print("\n### Slider-crank, 10 s, 501 outputs (wall s; crank angle's max difference to mbcomp DOP853 at 1e-12)\n")
    print("| run | rtol | wall s | max error (rad) | ratio to mbcomp.simulate |")
    print("|---|---:|---:|---:|---:|")
    for tol in (1e-8, 1e-10):
        w0 = time.perf_counter()
        r = mbcomp.simulate(model, t_end=10.0, n_out=501, rtol=tol, atol=tol / 100)
        base = time.perf_counter() - w0
        err = float(np.max(np.abs(r["crank_joint.phi"] - ref["crank_joint.phi"])))
        print(f"| mbcomp.simulate (default dop853, C engine) | {tol:g} | {base:.3f} | {err:.1e} | 1 |")
        for kind in ("CoSimulation", "ModelExchange"):
            w0 = time.perf_counter()
            f = fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=10.0, output=["crank_joint.phi"],
                                  relative_tolerance=tol, output_interval=0.02)
            wall = time.perf_counter() - w0
            e = float(np.max(np.abs(np.interp(ref.time, f["time"], f["crank_joint.phi"]) - ref["crank_joint.phi"])))
            print(f"| FMPy {kind} | {tol:g} | {wall:.3f} | {e:.1e} | {wall / base:.2f} |")


def export_times(tmp):
    print("\n### Export (wall s: trace, print, gcc; cold)\n")
    print("| model | states | outputs | wall s | FMU bytes |")
    print("|---|---:|---:|---:|---:|")
    for label, mod, kw in (("10-link pendulum", "n_link_pendulum", dict(N=10)), ("Andrews' squeezer", "andrews", {})):
        model = mbcomp.load_model_file(ROOT / "models" / f"{mod}.py").build(**kw)
        w0 = time.perf_counter()
        info = export_fmu(model, tmp / f"{mod}.fmu")
        print(f"| {label} | {len(info['states'])} | {len(info['outputs'])} | {time.perf_counter() - w0:.2f} | {info['size']} |")


def main():
    if c_compiler() is None:
        sys.exit("bench/fmu.py needs a C compiler")
    with tempfile.TemporaryDirectory() as d:
        tmp = pathlib.Path(d)
        one_call(tmp, harness(tmp))
        simulation(tmp)
        export_times(tmp)


if __name__ == "__main__":
    main()
