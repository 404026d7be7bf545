"""Importer x model x interface: mbcomp's FMUs run by FMPy and by the Reference-FMUs' fmusim.

For each standard model (and each hybrid one the export takes), FMI 3.0 and 2.0, Model Exchange
(the importer's CVODE at rtol 1e-10) and Co-Simulation (the FMU's own DOP853 at 1e-10): the
largest deviation of one coordinate from ``mbcomp.simulate`` (rtol 1e-11) over 101 points, and
the wall time of the importer's run. fmusim comes from ``$MBCOMP_FMUSIM``, ``PATH`` or is built
from ``../shared/tools/fmusim`` (tests/export/fmusim_tool.py).

Run: python bench/fmu_importers.py [--models slider_crank,four_bar,...]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "export"))

import fmpy  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.export import export_fmu  # noqa: E402

import fmusim_tool  # noqa: E402

#: model file, simulated time (s), compared coordinate
MODELS = [("n_link_pendulum", 5.0, "joint3.phi"), ("slider_crank", 10.0, "crank_joint.phi"),
          ("four_bar", 1.0, "crank_joint.phi"), ("andrews", 0.03, "hinge_A_AG.phi"),
          ("rolling_disk", 2.0, "x.s"), ("bicycle", 2.0, "free.r.x"), ("bouncing_ball", 2.0, "free.r.z"),
          ("door", 2.0, None), ("falling_bicycle", 1.0, "free.r.z")]
#: rows that build a model file with arguments: (file, build() arguments)
VARIANTS = {"falling_bicycle": ("bicycle", dict(v=5.0, unilateral=True, h0=0.05, pitch0=0.05))}


def load(name):
    """The model of a row: an object whose ``build()`` makes it."""
    file, kwargs = VARIANTS.get(name, (name, {}))
    mod = mbcomp.load_model_file(os.path.join(ROOT, "models", f"{file}.py"))
    return type("Row", (), {"build": staticmethod(lambda: mod.build(**kwargs))})


def deviation(r_time, r_var, ref, var):
    return float(np.max(np.abs(np.interp(ref.time, r_time, r_var) - ref[var])))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default=",".join(m[0] for m in MODELS))
    args = ap.parse_args(argv)
    exe, why = fmusim_tool.fmusim()
    if exe is None:
        print(f"fmusim: {why}")
    tmp = tempfile.mkdtemp(prefix="fmu_importers_")
    rows = []
    for name, t_end, var in MODELS:
        if name not in args.models.split(","):
            continue
        mod = load(name)
        if var is None:  # the first state
            var = mbcomp.assemble(mod.build()).q_names[0]
        ref = mbcomp.simulate(mod.build(), t_end=t_end, n_out=101, rtol=1e-11, atol=1e-13)
        for fmi in ("3.0", "2.0"):
            path = os.path.join(tmp, f"{name}_{fmi[0]}.fmu")
            try:
                export_fmu(mod.build(), path, fmi=fmi)
            except Exception as exc:  # noqa: BLE001 - a model the export refuses is a row saying why
                rows.append((name, fmi, "-", "-", f"not exported: {str(exc)[:90]}"))
                break
            for itype, ftype in (("me", "ModelExchange"), ("cs", "CoSimulation")):
                t0 = time.perf_counter()
                try:
                    r = fmpy.simulate_fmu(path, fmi_type=ftype, stop_time=t_end, output=[var],
                                          relative_tolerance=1e-10, output_interval=t_end / 100)
                    rows.append((name, fmi, itype.upper(), "FMPy",
                                 f"{deviation(r['time'], r[var], ref, var):.1e} ({time.perf_counter() - t0:.2f} s)"))
                except Exception as exc:  # noqa: BLE001
                    rows.append((name, fmi, itype.upper(), "FMPy", f"failed: {str(exc)[:80]}"))
                if exe is None:
                    continue
                t0 = time.perf_counter()
                try:
                    r = fmusim_tool.run(path, itype, t_end, [var])
                    rows.append((name, fmi, itype.upper(), "fmusim",
                                 f"{deviation(r['time'], r[var], ref, var):.1e} ({time.perf_counter() - t0:.2f} s)"))
                except AssertionError as exc:
                    rows.append((name, fmi, itype.upper(), "fmusim", f"failed: {str(exc)[:80]}"))
    print("| model | FMI | interface | importer | max deviation from mbcomp.simulate (wall) |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
