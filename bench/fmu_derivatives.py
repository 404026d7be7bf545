"""The FMU's exact derivatives: what one call costs against one evaluation of the state
derivatives, in C (no Python in the loop), and what carrying them costs at export.

* **one call** (FMI 3.0, Model Exchange, at the start): ``GetDirectionalDerivative`` and
  ``GetAdjointDerivative`` of all state derivatives with respect to all states (one seed), against
  ``SetContinuousStates`` + ``GetContinuousStateDerivatives``; a harness compiled with the FMU's
  own sources (``-O2``), median of 5 rounds of 20000 calls; the pendulum (open tree), the
  slider-crank and Andrews' squeezer (D'Alembert's states: the right-hand side there is
  ``mbrt_dalembert_rhs``, with its condition estimate);
* **export**: ``export_fmu`` wall time and FMU size with ``derivatives=True`` (default) and
  ``False``, median of 3.

Ratios are to the evaluation (call) and to ``derivatives=False`` (export) in the same run.
Needs a C compiler. Run: python bench/fmu_derivatives.py
"""
import pathlib
import subprocess
import sys
import tempfile
import time
import zipfile

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.export import export_fmu
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

ROOT = pathlib.Path(__file__).resolve().parent.parent

HARNESS = r"""
#include MODEL_C
#include <time.h>
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
int main(void)
{
    fmi3Instance c = fmi3InstantiateModelExchange("b", GUID, "", 0, 0, NULL, NULL);
    unsigned unk[NXS], kn[NXS];
    double x[NXS], dx[NXS], seed[NXS], sens[NXS], t0, sink = 0;
    int i, k, N = 20000;
    if (!c || fmi3EnterInitializationMode(c, 0, 0, 0.0, 0, 0) || fmi3ExitInitializationMode(c)) return 1;
    for (i = 0; i < NXS; i++) { unk[i] = VR_DX + i; kn[i] = VR_X + i; seed[i] = 0.1 * (i + 1); }
    fmi3GetContinuousStates(c, x, NXS);
    for (k = 0; k < 5; k++) {
        t0 = now();
        for (i = 0; i < N; i++) {
            if (fmi3SetContinuousStates(c, x, NXS) || fmi3GetContinuousStateDerivatives(c, dx, NXS)) return 2;
            sink += dx[0];
        }
        printf("%.6g ", (now() - t0) / N);
        t0 = now();
        for (i = 0; i < N; i++) {
            if (fmi3GetDirectionalDerivative(c, unk, NXS, kn, NXS, seed, NXS, sens, NXS)) return 3;
            sink += sens[0];
        }
        printf("%.6g ", (now() - t0) / N);
        t0 = now();
        for (i = 0; i < N; i++) {
            if (fmi3GetAdjointDerivative(c, unk, NXS, kn, NXS, seed, NXS, sens, NXS)) return 4;
            sink += sens[0];
        }
        printf("%.6g\n", (now() - t0) / N);
    }
    fmi3FreeInstance(c);
    return sink == 12345.0;
}
"""


def pendulum():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def models():
    return {"pendulum": pendulum,
            "slider-crank": lambda: mbcomp.load_model_file(ROOT / "models" / "slider_crank.py").build(),
            "Andrews": lambda: mbcomp.load_model_file(ROOT / "models" / "andrews.py").build()}


def one_call(make, tmp):
    """Median seconds per call: (derivatives, directional, adjoint)."""
    path = tmp / "m.fmu"
    export_fmu(make(), path)
    with zipfile.ZipFile(path) as z:
        z.extractall(tmp / "fmu")
    src = tmp / "fmu" / "sources"
    ident = next((tmp / "fmu" / "binaries" / "x86_64-linux").glob("*.so")).stem
    (tmp / "bench.c").write_text(HARNESS)
    subprocess.run([c_compiler(), "-O2", "-fno-math-errno", f'-DMODEL_C="{ident}.c"', f"-I{src}", str(tmp / "bench.c"),
                    *map(str, sorted(src.glob("mbrt_*.c"))), "-o", str(tmp / "bench"), "-lm"], check=True)
    rows = [list(map(float, line.split())) for line in
            subprocess.run([str(tmp / "bench")], capture_output=True, text=True, check=True).stdout.splitlines()]
    return [sorted(col)[len(col) // 2] for col in zip(*rows)]


def export_cost(make, derivatives, tmp):
    times = []
    for _ in range(3):
        t = time.perf_counter()
        info = export_fmu(make(), tmp / f"e{derivatives}.fmu", derivatives=derivatives)
        times.append(time.perf_counter() - t)
    return sorted(times)[1], info["size"]


def main():
    if c_compiler() is None:
        sys.exit("needs a C compiler")
    print(f"{'model':<13} {'rhs us':>8} {'dir us':>8} {'x rhs':>6} {'adj us':>8} {'x rhs':>6} "
          f"{'export s':>9} {'x plain':>7} {'size kB':>8} {'x plain':>7}")
    for name, make in models().items():
        with tempfile.TemporaryDirectory() as d:
            tmp = pathlib.Path(d)
            rhs, fwd, adj = one_call(make, tmp)
            (te, se), (tp, sp) = export_cost(make, True, tmp), export_cost(make, False, tmp)
        print(f"{name:<13} {1e6 * rhs:8.3f} {1e6 * fwd:8.3f} {fwd / rhs:6.2f} {1e6 * adj:8.3f} {adj / rhs:6.2f} "
              f"{te:9.2f} {te / tp:7.2f} {se / 1e3:8.0f} {se / sp:7.2f}")


if __name__ == "__main__":
    main()
