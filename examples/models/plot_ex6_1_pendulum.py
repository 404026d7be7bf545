"""
Simple pendulum (textbook Example 6.1)
======================================

A particle on a massless rod swings about a horizontal hinge from 1.2 rad -- far beyond the
small-angle regime. The model file ``models/textbook/ex6_1_pendulum.py`` builds it from library
components (a ``Revolute``, a ``FixedTranslation`` rod and a ``PointMass``); the book's
equation of motion is Lagrange's

.. math:: m l^2 \\ddot\\theta + m g l \\sin\\theta = 0 .

We integrate the book's equation independently (scipy) and compare the angle.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex6_1_pendulum.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
print(res.status, res.stats["steps"], "steps")

# %%
# The book's equation (6.20), integrated by scipy from the same start
# ---------------------------------------------------------------------
m, l, g, theta0 = 1.0, 0.8, 9.81, 1.2
book = solve_ivp(lambda t, y: [y[1], -g / l * np.sin(y[0])], (0, res.time[-1]), [theta0, 0.0],
                 t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["theta"], label="mbcomp")
ax.plot(res.time, book.y[0], "--", label="book (6.20), scipy")
ax.set_xlabel("t (s)")
ax.set_ylabel("theta (rad)")
ax.legend()
plt.show()

# %%
# The mechanism at the end of the run, and an animation
# -----------------------------------------------------
# ``res.snapshot`` draws one frame with matplotlib; ``res.animate()`` shows the self-contained
# three.js player below (with a path it writes the page to a file).
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex6_1_pendulum.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check
# ---------
# The angle agrees with the book's equation, and the energy (its datum at the hinge, 6.18) is
# conserved.
E = res["energy.total"]
CHECKS = {"max |theta - book| (rad)": (np.max(np.abs(res["theta"] - book.y[0])), 1e-7),
          "energy drift (J)": (np.ptp(E), 1e-7),
          "E(0) + m g l cos(theta0) (J)": (abs(E[0] + m * g * l * np.cos(theta0)), 1e-12)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
