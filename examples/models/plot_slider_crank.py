"""
Slider-crank: a closed kinematic loop
=====================================

Crank, connecting rod and slider form one closed loop: mbcomp builds a spanning tree, cuts
one revolute joint (its rows become constraints with Lagrange multipliers) and drops the
three out-of-plane rows, redundant in a planar loop (``mbcomp info models/slider_crank.py``
says which). One degree of freedom; the slider's position is a closed form of the crank angle,

.. math:: x = c\\cos\\varphi + \\sqrt{L^2 - c^2\\sin^2\\varphi}.

The model file runs 10 s; 3 s here.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "slider_crank.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, t_end=3.0, n_out=301))
c, L = 0.2, 0.6
phi = res["crank_angle"]
x_closed = c * np.cos(phi) + np.sqrt(L ** 2 - (c * np.sin(phi)) ** 2)

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, res["slider_position"], label="mbcomp")
axs[0].plot(res.time, x_closed, "--", label="closed form of the crank angle")
axs[0].set_ylabel("slider x (m)")
axs[0].legend(fontsize=8)
axs[1].semilogy(res.time, np.maximum(res["residual.position"], 1e-17))
axs[1].set_ylabel("loop residual (m)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The mechanism at the end of the run (animation: ``slider_crank.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("slider_crank.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the slider where the loop puts it (to the run's tolerances, rtol = 1e-8), and the
# energy kept.
CHECKS = {"max |x - closed form| (m)": (np.max(np.abs(res["slider_position"] - x_closed)), 1e-7),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
