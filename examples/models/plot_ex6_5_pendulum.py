"""
The rod tension as a Lagrange multiplier (textbook Example 6.5)
===============================================================

The book frees the pendulum's bob radially (coordinates :math:`r, \\theta`) and imposes
:math:`r = l` with a multiplier :math:`\\lambda`, which is the rod tension (6.79):

.. math:: \\lambda = m l\\dot\\theta^2 + m g\\cos\\theta .

The model file builds exactly that: the bob on a radial ``Prismatic`` on the hinge, and the
constraint as a kinematic loop -- a massless rod on its own hinge pinned to the bob by a
``Spherical`` joint that mbcomp cuts. The multiplier of the cut joint's row along the rod is a
result column, ``lambda.pin.y`` :math:`= -\\lambda`.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex6_5_pendulum.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
m, l, g = 1.3, 0.8, 9.81
tension = m * l * res["theta_dot"] ** 2 + m * g * np.cos(res["theta"])

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, -res["lambda.pin.y"], label="-lambda.pin.y (mbcomp's multiplier)")
ax.plot(res.time, tension, "--", label="(6.79) from the run's theta")
ax.set_xlabel("t (s)")
ax.set_ylabel("tension (N)")
ax.legend(fontsize=8)
plt.show()

# %%
# The pendulum at the end of the run (animation: ``ex6_5_pendulum.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex6_5_pendulum.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the multiplier is the tension (6.79), and the radial coordinate stays at l.
CHECKS = {"max |-lambda - (6.79)| (N)": (np.max(np.abs(-res["lambda.pin.y"] - tension)), 1e-6),
          "max |r - l| (m)": (np.max(np.abs(res["r"] - l)), 1e-9)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
