"""
Cart on a spring with a pendulum (textbook Example 6.2)
=======================================================

A cart (mass :math:`m_1`) slides on a spring of rate :math:`k`; a bob (mass :math:`m_2`) swings
below it on a massless rod of length :math:`L`. Two degrees of freedom, coupled through the
rod's angle. Lagrange's equations (6.36)-(6.37) of the book,

.. math::

   (m_1 + m_2)\\ddot x + m_2 L \\ddot\\theta\\cos\\theta - m_2 L\\dot\\theta^2\\sin\\theta + k x = 0,
   \\qquad m_2 L^2\\ddot\\theta + m_2 L\\ddot x\\cos\\theta + m_2 g L\\sin\\theta = 0,

are integrated here by scipy as the independent reference for mbcomp's run of the model file,
which is made of library components only (a ``Prismatic`` with a spring, a ``Revolute``, a rod
and a point mass).
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex6_2_cart_pendulum.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
print(res.status, res.stats["steps"], "steps")

# %%
# The book's equations, solved for the accelerations at each step
# ----------------------------------------------------------------
m1, m2, L, k, g = 2.0, 0.7, 0.9, 35.0, 9.81


def book(t, y):
    x, th, xd, thd = y
    M = [[m1 + m2, m2 * L * np.cos(th)], [m2 * L * np.cos(th), m2 * L ** 2]]
    f = [m2 * L * thd ** 2 * np.sin(th) - k * x, -m2 * g * L * np.sin(th)]
    return [xd, thd, *np.linalg.solve(M, f)]


ref = solve_ivp(book, (0, res.time[-1]), [0.15, 1.1, -0.3, 0.8], t_eval=res.time, method="DOP853",
                rtol=1e-11, atol=1e-12)
fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for ax, name, row in zip(axs, ("x", "theta"), ref.y):
    ax.plot(res.time, res[name], label="mbcomp")
    ax.plot(res.time, row, "--", label="book (6.36)-(6.37)")
    ax.set_ylabel(f"{name} ({res.units[name]})")
axs[0].legend()
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The mechanism at the end of the run (an animation is in ``ex6_2_cart_pendulum.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex6_2_cart_pendulum.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: both coordinates follow the book's equations; no friction, so the energy is kept.
CHECKS = {"max |x - book| (m)": (np.max(np.abs(res["x"] - ref.y[0])), 1e-7),
          "max |theta - book| (rad)": (np.max(np.abs(res["theta"] - ref.y[1])), 1e-7),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
