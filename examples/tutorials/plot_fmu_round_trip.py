"""
An FMU round trip
=================

``mbcomp.export_fmu(model, "x.fmu")`` writes the model as a Functional Mock-up Unit (FMI 3.0
by default; ``fmi="2.0"`` too): its equations compiled to C, with the runtime's integrator for
Co-Simulation. Any FMI importer runs it; here FMPy, the FMI reference importer for Python,
runs the Co-Simulation FMU of the slider-crank and we compare with ``mbcomp.simulate``. The
states (here the slider's ``slider_joint.s``) are FMU variables; ``outputs`` picks other result
columns to export (the energy).
``derivatives=False`` leaves out the exact directional derivatives: a smaller FMU built faster.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
crank = mbcomp.load_model_file(ROOT / "models" / "slider_crank.py")
info = mbcomp.export_fmu(crank.build(), "slider_crank.fmu", kind="cs", outputs=["energy.total"],
                         stop_time=2.0, derivatives=False)
print(f"{info['size'] / 1e3:.0f} kB, {len(info['states'])} states, outputs {info['outputs']}")

# %%
# Run it in FMPy (skipped, and said, when FMPy is not installed)
try:
    import fmpy
except ImportError:
    fmpy = None
    print("FMPy is not installed (pip install fmpy): the round trip is skipped")
res = mbcomp.simulate(crank.build(), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=201)
if fmpy is not None:
    out = fmpy.simulate_fmu("slider_crank.fmu", stop_time=2.0, output_interval=0.01, relative_tolerance=1e-10,
                            output=["slider_joint.s", "energy.total"])
    fmu_x = np.interp(res.time, out["time"], out["slider_joint.s"])
    fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
    ax.plot(res.time, res["slider_position"], label="mbcomp.simulate")
    ax.plot(out["time"], out["slider_joint.s"], "--", label="the FMU in FMPy")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("slider x (m)")
    ax.legend(fontsize=8)

# %%
# The check: the FMU's slider follows the simulation (both at rtol 1e-10).
CHECKS = {"max |FMU - simulate| (m)": (np.max(np.abs(fmu_x - res["slider_position"])) if fmpy else 0.0, 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
