"""
N-link pendulum (the scaling benchmark)
=======================================

:math:`N` uniform rods on hinges in a chain, released curled (every relative angle 0.3 rad):
a chaotic motion with nothing to compare it to pointwise -- but no friction, so the total
energy must stay what it was, and :math:`N` is a build parameter (``build(N=...)``), so one
file gives every size of the benchmark. The model file runs 3 s.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "n_link_pendulum.py")
res = mbcomp.simulate(mod.build(N=5), **dict(mod.SIMULATION, n_out=301))
E = res["energy.total"]

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for k in range(1, 6):
    axs[0].plot(res.time, res[f"phi{k}"], lw=0.8, label=f"phi{k}")
axs[0].set_ylabel("relative angle (rad)")
axs[0].legend(fontsize=7, ncol=5)
axs[1].plot(res.time, E - E[0])
axs[1].set_ylabel("E - E(0) (J)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The chain at the end of the run (animation: ``n_link_pendulum.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("n_link_pendulum.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the energy is kept to what the tolerances leave open (rtol = 1e-8).
CHECKS = {"relative energy drift": (np.ptp(E) / np.ptp(res["energy.kinetic"]), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
