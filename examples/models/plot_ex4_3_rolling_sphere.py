"""
A sphere rolling without slip (textbook Section 4.3)
====================================================

A ball on the plane :math:`z = 0` with the book's three constraints: the centre at height
:math:`a` (holonomic) and no slip along :math:`x` and :math:`y` (two **nonholonomic** rows). The
library's ``RollingSphere`` composes them: a free ball and a ``SphereContact``, whose reactions
are outputs (``N``, ``F_1``, ``F_2``). A horizontal force ``push`` on the centre makes the
friction work: for a uniform ball Newton and Euler give the centre's acceleration
:math:`\\tfrac57 F/m` and a friction force :math:`-\\tfrac27 F`. The model file runs 2 s
without the push; here the push is 1 N.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex4_3_rolling_sphere.py")
m, F, g = 1.0, 1.0, 9.81
res = mbcomp.simulate(mod.build(push=F), **dict(mod.SIMULATION, n_out=101))
t = res.time
x_closed = 0.5 * t + 0.5 * (5 / 7) * F / m * t ** 2       # from vx0 = 0.5 m/s

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(t, res["r_cx"], label="mbcomp")
axs[0].plot(t, x_closed, "--", label="x0 + vx0 t + (5/7) F t^2 / (2 m)")
axs[0].set_ylabel("centre x (m)")
axs[0].legend(fontsize=8)
for name in ("ball.contact.N", "ball.contact.F_1", "ball.contact.F_2"):
    axs[1].plot(t, res[name], label=name)
axs[1].set_ylabel("reaction (N)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The ball at the end of the run (animation: ``ex4_3_rolling_sphere.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex4_3_rolling_sphere.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the centre moves as (5/7) F/m, the contact holds the weight and pulls back with
# (2/7) F.
CHECKS = {"max |x - closed form| (m)": (np.max(np.abs(res["r_cx"] - res["r_cx"][0] - x_closed)), 1e-8),
          "max |N - m g| (N)": (np.max(np.abs(res["ball.contact.N"] - m * g)), 1e-8),
          "max ||F_1| - 2 F / 7| (N)": (np.max(np.abs(np.abs(res["ball.contact.F_1"]) - 2 * F / 7)), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
