"""
Bar on a spinning link (textbook Example 6.4)
=============================================

A thin bar (mass :math:`m`, length :math:`l`) hangs from a hinge on a link that spins about the
vertical at the constant, *prescribed* rate :math:`\\Omega` (a ``PrescribedMotion`` drive: the
spin is no degree of freedom). Lagrange gives, with :math:`I = m l^2/3`,

.. math:: I\\ddot\\beta - I\\Omega^2\\sin\\beta\\cos\\beta + m g \\tfrac{l}{2}\\sin\\beta = 0 .

For :math:`\\Omega^2 > 3g/(2l)` the hanging bar is unstable and swings about the tilted
equilibrium :math:`\\cos\\beta^* = 3g/(2l\\Omega^2)`. The drive must supply the torque that
changes the angular momentum about the spin axis, :math:`2 I\\Omega\\sin\\beta\\cos\\beta\\,\\dot\\beta`.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex6_4_spinning_pendulum.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

m, l, Omega, g, beta0 = 1.0, 0.6, 6.0, 9.81, 0.2
I = m * l ** 2 / 3
ref = solve_ivp(lambda t, y: [y[1], Omega ** 2 * np.sin(y[0]) * np.cos(y[0]) - m * g * l / 2 * np.sin(y[0]) / I],
                (0, res.time[-1]), [beta0, 0.0], t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
beta_star = np.arccos(3 * g / (2 * l * Omega ** 2))

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, res["beta"], label="mbcomp")
axs[0].plot(res.time, ref.y[0], "--", label="book (6.63)")
axs[0].axhline(beta_star, color="gray", lw=0.8, label="tilted equilibrium")
axs[0].set_ylabel("beta (rad)")
axs[0].legend(fontsize=8)
torque = 2 * I * Omega * np.sin(ref.y[0]) * np.cos(ref.y[0]) * ref.y[1]
axs[1].plot(res.time, res["drive_torque"], label="drive torque, mbcomp")
axs[1].plot(res.time, torque, "--", label="2 I Omega sin cos beta'")
axs[1].set_ylabel("torque (N m)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The mechanism at the end of the run (animation: ``ex6_4_spinning_pendulum.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex6_4_spinning_pendulum.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the angle follows (6.63) and the drive torque is the angular momentum's rate.
CHECKS = {"max |beta - book| (rad)": (np.max(np.abs(res["beta"] - ref.y[0])), 1e-6),
          "max |drive torque - closed form| (N m)": (np.max(np.abs(res["drive_torque"] - torque)), 1e-5)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
