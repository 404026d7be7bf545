"""
Motor-driven two-link arm (textbook Example 4.7)
================================================

A massless link turns about the vertical, driven by a motor whose torque falls with speed,
:math:`M_d = M_0 - \\Delta M\\,\\omega` -- one line in the model: a ``Torque`` law
``lambda t, phi, w: M0 - dM * w`` on the joint's flange. A uniform rod hangs from the link's
end on a horizontal hinge and swings outwards as the arm speeds up. The equations (4.20)-(4.21),
with (4.20)'s velocity-product coefficients corrected (:math:`m a l` and
:math:`\\tfrac23 m l^2`, as Lagrange gives), are integrated by scipy as the reference.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex4_7_two_link_arm.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

m, a, l, dM, M0, g = 2.0, 0.1, 0.5, 0.5, 1.0, 9.81


def book(t, y):
    al, b, w, bd = y
    s, c = np.sin(b), np.cos(b)
    wd = (M0 - dM * w - m * a * l * w * bd * c - 2 / 3 * m * l ** 2 * w * bd * s * c) \
        / (m * (a ** 2 + l ** 2 / 3 * s ** 2 + a * l * s))
    bdd = (2 / 3 * l * w ** 2 * s * c + a * w ** 2 * c - g * s) / (2 / 3 * l)
    return [w, bd, wd, bdd]


ref = solve_ivp(book, (0, res.time[-1]), [0, 0, 0, 0], t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for ax, name, row in zip(axs, ("omega", "beta"), (ref.y[2], ref.y[1])):
    ax.plot(res.time, res[name], label="mbcomp")
    ax.plot(res.time, row, "--", label="(4.20)-(4.21)")
    ax.set_ylabel(f"{name} ({res.units[name]})")
axs[0].legend(fontsize=8)
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The arm at the end of the run (animation: ``ex4_7_two_link_arm.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex4_7_two_link_arm.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the arm's rate and the rod's swing against the corrected equations.
CHECKS = {"max |omega - book| (rad/s)": (np.max(np.abs(res["omega"] - ref.y[2])), 1e-6),
          "max |beta - book| (rad)": (np.max(np.abs(res["beta"] - ref.y[1])), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
