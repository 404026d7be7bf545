"""
Three-dimensional chain on ball joints
======================================

:math:`N` solid cylinders hanging in a chain of ``Spherical`` joints (quaternion coordinates),
started with a twist and a spin about the vertical so the motion is genuinely
three-dimensional. Gravity and the pivot force exert no torque about the vertical through the
top pivot: the **vertical angular momentum** is conserved, and so is the energy.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "chain_3d.py")
res = mbcomp.simulate(mod.build(N=4), **dict(mod.SIMULATION, n_out=201))
E, Hy = res["energy.total"], res["angular_momentum.y"]

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, E - E[0], label="E - E(0) (J)")
axs[0].plot(res.time, Hy - Hy[0], label="H_y - H_y(0) (kg m^2/s)")
axs[0].legend(fontsize=8)
axs[1].plot(res.time, res["energy.kinetic"], label="kinetic energy (J)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The chain at the end of the run (animation: ``chain_3d.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("chain_3d.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: both conserved quantities, to what rtol = 1e-8 leaves open.
CHECKS = {"energy drift (J)": (np.ptp(E), 1e-6),
          "vertical angular momentum drift (kg m^2/s)": (np.ptp(Hy), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
