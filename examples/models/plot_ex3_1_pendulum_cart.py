"""
Pendulum on a prescribed cart (textbook Example 3.1)
====================================================

A uniform rod hangs from a massless cart whose position is *prescribed*,
:math:`u(t) = A\\sin\\Omega t` (a ``PrescribedMotion`` drive on a ``Prismatic`` joint). In the
angle convention of the book's (3.16) the equation of motion is

.. math:: \\left(I_c + \\tfrac{mL^2}{4}\\right)\\ddot\\theta + \\tfrac{mgL}{2}\\sin\\theta
   = -\\tfrac{mL}{2}\\ddot u\\cos\\theta

(the printed (3.18) lacks the minus sign: a cart accelerating to :math:`+x` leaves the rod
behind). The hinge force along the rod is the tension (3.19),
:math:`F_r = \\tfrac{mL}{2}\\dot\\theta^2 + m g\\cos\\theta - m\\ddot u\\sin\\theta`.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex3_1_pendulum_cart.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

m, L, g, A, Om = 1.4, 0.8, 9.81, 0.2, 6.0
Ic = m * L ** 2 / 12


def udd(t):
    return -A * Om ** 2 * np.sin(Om * t)


ref = solve_ivp(lambda t, y: [y[1], (-m * g * L / 2 * np.sin(y[0]) - m * L / 2 * udd(t) * np.cos(y[0]))
                              / (Ic + m * L ** 2 / 4)],
                (0, res.time[-1]), [0.3, -0.5], t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
th, thd, t = ref.y[0], ref.y[1], res.time
Fr = m * L / 2 * thd ** 2 + m * g * np.cos(th) - m * udd(t) * np.sin(th)

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(t, res["theta"], label="mbcomp")
axs[0].plot(t, th, "--", label="(3.18), corrected sign")
axs[0].set_ylabel("theta (rad)")
axs[0].legend(fontsize=8)
axs[1].plot(t, res["F_r"], label="hinge force along the rod, mbcomp")
axs[1].plot(t, Fr, "--", label="tension (3.19)")
axs[1].set_ylabel("F_r (N)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The mechanism at the end of the run (animation: ``ex3_1_pendulum_cart.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex3_1_pendulum_cart.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the angle and the rod tension against the book's formulas.
CHECKS = {"max |theta - (3.18)| (rad)": (np.max(np.abs(res["theta"] - th)), 1e-7),
          "max |F_r - (3.19)| (N)": (np.max(np.abs(res["F_r"] - Fr)), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
