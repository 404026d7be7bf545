"""
The heavy top in Euler angles (textbook Example 3.2)
====================================================

The top of ``ex3_2_gyro_top.py`` on three hinges -- precession :math:`\\psi`, nutation
:math:`\\theta`, spin :math:`\\phi`, the book's 3-1-3 Euler angles -- instead of a ball joint.
Here :math:`\\psi` and :math:`\\phi` are cyclic, so a steady precession is an *equilibrium* of the
remaining states and ``mbcomp.linearize`` can judge its stability (the quaternion model
cannot: its coordinates keep turning). The price: at :math:`\\theta = 0` the hinge axes span a
plane only (the gimbal singularity).

The run starts on the slow root of (3.33): the three angles must move at constant rates.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex3_2_top_euler.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
slow, _ = mod.steady_precession_rates(0.5, 0.04, 5e-4, 1e-3, 9.81, 1.0, 40.0)

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
for name in ("psi_dot", "theta_dot", "phi_dot"):
    ax.plot(res.time, res[name], label=name)
ax.axhline(slow, color="gray", ls="--", lw=0.8, label="(3.33) slow root")
ax.set_xlabel("t (s)")
ax.set_ylabel("rate (rad/s)")
ax.legend(fontsize=8)
plt.show()

# %%
# Linearized about the steady precession: eigenvalues on the imaginary axis (a stable,
# undamped nutation) -- plus zeros for the cyclic angles.
lin = mbcomp.analysis.linearize(mod.build(), t=0.0)
print("eigenvalues:", np.round(lin.eigenvalues, 4))

# %%
# The top at the end of the run (animation: ``ex3_2_top_euler.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex3_2_top_euler.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the rates stay constant at their (3.33) values; the linearization is neutrally
# stable (no eigenvalue with a positive real part).
CHECKS = {"max |psi_dot - (3.33)| (rad/s)": (np.max(np.abs(res["psi_dot"] - slow)), 1e-7),
          "max |theta - 1| (rad)": (np.max(np.abs(res["theta"] - 1.0)), 1e-8),
          "largest real part of an eigenvalue (1/s)": (max(np.max(np.real(lin.eigenvalues)), 0.0), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
