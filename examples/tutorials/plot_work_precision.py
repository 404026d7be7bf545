"""
A work-precision chart
======================

How much CPU time does an accuracy cost, method by method? ``work_precision`` runs a model file
over a sweep of tolerances for each formulation x solver pair (a ``Combo``) and measures the
error at the end against a reference -- here an exact one: the pendulum released from rest at
:math:`\\theta_0` swings as

.. math:: \\theta(t) = 2\\arcsin\\!\\big(k\\,\\mathrm{sn}(K(k) - \\omega t,\\ k)\\big),\\qquad
   k = \\sin(\\theta_0/2),\\ \\omega = \\sqrt{g/l},

with the Jacobi elliptic function sn and the complete elliptic integral :math:`K`. (``mbcomp
bench <model file>`` prints the same table for every combo.)
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipj, ellipk

from mbcomp.analysis.workprecision import Combo, fastest, work_precision

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
MODEL = ROOT / "models" / "textbook" / "ex6_1_pendulum.py"     # l = 0.8 m, theta0 = 1.2 rad
l, g, theta0, t_end = 0.8, 9.81, 1.2, 2.0
k = np.sin(theta0 / 2)
sn = ellipj(ellipk(k * k) - np.sqrt(g / l) * t_end, k * k)[0]
exact = 2 * np.arcsin(k * sn)
print(f"theta({t_end} s) = {exact:.15f} rad (elliptic functions)")

combos = [Combo("DOP853 (C)", dict(method="DOP853")), Combo("RADAU5 (C)", dict(method="radau5")),
          Combo("RK45 (scipy)", dict(method="RK45", backend="python"))]
rows = work_precision(MODEL, combos=combos, tols=[1e-4, 1e-6, 1e-8, 1e-10], t_end=t_end,
                      reference=(t_end, {"hinge.phi": exact}, "elliptic functions"), log=lambda *a: None)

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3.5))
for combo in combos:
    mine = [r for r in rows if r["combo"] == combo.label and r["status"] == "success"]
    ax.loglog([r["nfev"] for r in mine], [r["error"] for r in mine], "o-", label=combo.label)
ax.set_xlabel("function evaluations")
ax.set_ylabel("error at t_end (rad)")
ax.legend(fontsize=8)
print("least CPU time (s) reaching 1e-6 rad:", fastest(rows, target=1e-6))

# %%
# The check: at the tightest tolerance each method lands within 1e-7 rad of the exact angle,
# and the error falls as the tolerance does.
CHECKS = {}
for combo in combos:
    errs = [r["error"] for r in rows if r["combo"] == combo.label]
    CHECKS[f"{combo.label}: error at rtol 1e-10 (rad)"] = (errs[-1], 1e-7)
    CHECKS[f"{combo.label}: error at 1e-10 / error at 1e-4"] = (errs[-1] / errs[0], 1e-2)
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
