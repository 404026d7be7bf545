"""
Sliders in a rotating slotted disk (textbook Example 5.5)
=========================================================

A massless disk turns freely; two sliders on springs move along a slot through its centre.
D'Alembert's principle gives the radial equations (5.35), (5.37) and the conservation of the
angular momentum about the axis (5.40):

.. math::

   m_i(\\ddot\\rho_i - \\dot\\theta^2\\rho_i) + k(\\rho_i - a) = 0,\\qquad
   (m_1\\rho_1^2 + m_2\\rho_2^2)\\,\\dot\\theta = H = \\text{const}.

With :math:`\\dot\\theta = H/(m_1\\rho_1^2 + m_2\\rho_2^2)` the two radial equations close; scipy
integrates them as the reference.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex5_5_slotted_disk.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

m1, m2, k, a = 1.0, 1.5, 40.0, 0.2
H = (m1 * 0.3 ** 2 + m2 * 0.15 ** 2) * 4.0


def book(t, y):
    r1, r2, v1, v2 = y
    w = H / (m1 * r1 ** 2 + m2 * r2 ** 2)
    return [v1, v2, w * w * r1 - k / m1 * (r1 - a), w * w * r2 - k / m2 * (r2 - a)]


ref = solve_ivp(book, (0, res.time[-1]), [0.3, 0.15, 0.0, 0.2], t_eval=res.time, method="DOP853",
                rtol=1e-11, atol=1e-12)
fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for i, name in enumerate(("rho1", "rho2")):
    axs[0].plot(res.time, res[name], label=f"{name}, mbcomp")
    axs[0].plot(res.time, ref.y[i], "--", label=f"{name}, (5.35)-(5.40)")
axs[0].set_ylabel("radius (m)")
axs[0].legend(fontsize=7, ncol=2)
Hrun = (m1 * res["rho1"] ** 2 + m2 * res["rho2"] ** 2) * res["theta_dot"]
axs[1].plot(res.time, Hrun - H)
axs[1].set_ylabel("H - H(0) (kg m^2/s)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The disk at the end of the run (animation: ``ex5_5_slotted_disk.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex5_5_slotted_disk.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: both radii follow the book, and the angular momentum (5.40) is kept.
CHECKS = {"max |rho1 - book| (m)": (np.max(np.abs(res["rho1"] - ref.y[0])), 1e-7),
          "max |rho2 - book| (m)": (np.max(np.abs(res["rho2"] - ref.y[1])), 1e-7),
          "max |H - H(0)| (kg m^2/s)": (np.max(np.abs(Hrun - H)), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
