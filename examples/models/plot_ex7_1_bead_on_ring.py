"""
Bead on a spinning ring (textbook Example 7.1)
==============================================

A bead slides on a smooth ring of radius :math:`r` that turns at the constant rate
:math:`\\omega` about its vertical diameter. The equation of motion (7.23),

.. math:: r\\ddot\\alpha - \\omega^2 r\\sin\\alpha\\cos\\alpha + g\\sin\\alpha = 0,

has the steady states :math:`\\alpha = 0` and, above :math:`\\omega^2 = g/r`,
:math:`\\cos\\alpha^* = g/(r\\omega^2)` -- the bead rides up the ring and oscillates about
:math:`\\alpha^*` with the angular frequency :math:`\\sqrt{-\\lambda^2}` of the linearization
(7.33), :math:`\\lambda^2 = \\omega^2\\cos 2\\alpha^* - (g/r)\\cos\\alpha^*`.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex7_1_bead_on_ring.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

r, g, omega, alpha0 = 0.5, 9.81, 6.0, 0.5
ref = solve_ivp(lambda t, y: [y[1], omega ** 2 * np.sin(y[0]) * np.cos(y[0]) - g / r * np.sin(y[0])],
                (0, res.time[-1]), [alpha0, 0.0], t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
alpha_star = np.arccos(g / (r * omega ** 2))
lam2 = omega ** 2 * np.cos(2 * alpha_star) - g / r * np.cos(alpha_star)
print(f"alpha* = {alpha_star:.4f} rad, small oscillation period {2 * np.pi / np.sqrt(-lam2):.4f} s")

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["alpha"], label="mbcomp")
ax.plot(res.time, ref.y[0], "--", label="book (7.23)")
ax.axhline(alpha_star, color="gray", lw=0.8, label="steady state alpha*")
ax.set_xlabel("t (s)")
ax.set_ylabel("alpha (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The mechanism at the end of the run (animation: ``ex7_1_bead_on_ring.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex7_1_bead_on_ring.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the run follows (7.23), and ``mbcomp.linearize`` at the steady state gives the
# book's :math:`\\lambda^2` (7.33).
lin = mbcomp.analysis.linearize(mod.build(alpha0=alpha_star), t=0.0)
freq = np.max(np.abs(np.imag(lin.eigenvalues)))
CHECKS = {"max |alpha - book| (rad)": (np.max(np.abs(res["alpha"] - ref.y[0])), 1e-7),
          "|linearized frequency - sqrt(-lambda^2)| (rad/s)": (abs(freq - np.sqrt(-lam2)), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
