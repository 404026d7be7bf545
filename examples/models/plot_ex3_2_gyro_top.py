"""
Steady precession of a gyro top (textbook Example 3.2)
======================================================

A symmetric top spins on its tip (a ``Spherical`` joint: quaternion coordinates) under gravity.
It precesses steadily -- the nutation angle :math:`\\theta` and the rates :math:`\\dot\\psi`,
:math:`\\dot\\phi` constant -- when (3.33) holds,

.. math:: m g l = I_3\\dot\\psi\\dot\\phi + (I_3 - I_1)\\dot\\psi^2\\cos\\theta,
   \\qquad I_1 = I_{1c} + m l^2 ,

a quadratic in :math:`\\dot\\psi` with a slow and a fast root. The model file starts the top on
the slow root; if (3.33) is right the symmetry axis keeps its angle to the vertical and turns
about it at exactly :math:`\\dot\\psi`.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex3_2_gyro_top.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
slow, fast = mod.steady_precession_rates(0.5, 0.04, 5e-4, 1e-3, 9.81, 1.0, 40.0)
print(f"(3.33): slow precession {slow:.5f} rad/s, fast {fast:.3f} rad/s")

# %%
# The symmetry axis :math:`e_3` is the third column of the top's rotation matrix, from its
# quaternion ``top.Q``: its tilt from the vertical is the nutation angle, its azimuth turns at
# the precession rate.
w, x, y, z = (res[f"top.Q.{c}"] for c in "wxyz")
e3 = np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
theta = np.arccos(e3[2])
azimuth = np.unwrap(np.arctan2(e3[1], e3[0]))
rate = np.polyfit(res.time, azimuth, 1)[0]
fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, theta)
axs[0].set_ylabel("nutation (rad)")
axs[1].plot(res.time, azimuth - azimuth[0], label="mbcomp")
axs[1].plot(res.time, slow * res.time, "--", label="slow root of (3.33)")
axs[1].set_ylabel("precession (rad)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The top at the end of the run (animation: ``ex3_2_gyro_top.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex3_2_gyro_top.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the nutation angle stays at 1 rad and the axis precesses at the slow root.
CHECKS = {"max |theta - 1| (rad)": (np.max(np.abs(theta - 1.0)), 1e-7),
          "|precession rate - (3.33)| (rad/s)": (abs(rate - slow), 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
