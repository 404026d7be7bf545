"""
Four-bar linkage near its change point
======================================

A Grashof crank-rocker whose lengths almost satisfy the change-point condition
:math:`l_1 + l_2 = l_3 + l_4`: the ground link is shorter by ``gap`` = 1 mm, so once a turn,
at crank angle :math:`\\pi`, the four links come within 1 mm of lying flat -- where the
loop-closure Jacobian would lose rank. The rocker reverses there abruptly and the loop force
peaks (about :math:`4.6/\\text{gap}` N). The rocker's angle is a closed form of the crank's
(``assembly(phi)`` in the model file: the intersection of two circles).
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "four_bar.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=401))
rocker_closed = np.array([mod.assembly(p)[1] for p in res["crank_angle"]])

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, res["rocker_angle"], label="mbcomp")
axs[0].plot(res.time, rocker_closed, "--", label="assembly(crank angle)")
axs[0].set_ylabel("rocker (rad)")
axs[0].legend(fontsize=8)
axs[1].plot(res.time, np.cos(res["crank_angle"]))
axs[1].set_ylabel("cos(crank)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The linkage at the end of the run (animation: ``four_bar.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("four_bar.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the rocker where the loop puts it, through the near-flat passages; the energy kept.
err = np.max(np.abs(np.angle(np.exp(1j * (res["rocker_angle"] - rocker_closed)))))
CHECKS = {"max |rocker - closed form| (rad)": (err, 1e-6),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-5)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
