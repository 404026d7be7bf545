"""
Bricard's linkage: a redundant loop that moves
==============================================

Five 1 m links and the ground closed by six revolute joints with perpendicular axes.
Grübler-Kutzbach counts :math:`6\\cdot 5 - 5\\cdot 6 = 0` degrees of freedom, yet the linkage
moves with one: one of the loop's six closure equations is redundant at every position.
mbcomp cuts one joint, finds the redundant row and drops it (``mbcomp info models/bricard.py``
names both), and the linkage falls under gravity with its loop closed. The model file runs
10 s; 3 s here.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "bricard.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, t_end=3.0, n_out=301))
angles = [n for n in res.names if n.startswith("joint") and n.endswith(".phi")]

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for n in angles:
    axs[0].plot(res.time, res[n], lw=0.8, label=n)
axs[0].set_ylabel("angle (rad)")
axs[0].legend(fontsize=7, ncol=3)
axs[1].semilogy(res.time, np.maximum(res["residual.position"], 1e-17))
axs[1].set_ylabel("loop residual (m)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The linkage at the end of the run (animation: ``bricard.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("bricard.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: it moves (a joint turns by more than 0.5 rad) with its loop closed and its
# energy kept.
CHECKS = {"stays still (1 if no joint turns 0.5 rad)": (float(max(np.ptp(res[n]) for n in angles) < 0.5), 0.0),
          "max loop residual (m)": (np.max(res["residual.position"]), 1e-8),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
