"""
A rolling disk: when does it stay upright?
==========================================

A thin disk rolls without slip on level ground (a ``DiskContact``: one holonomic, two
nonholonomic rows), modelled on one-axis joints so that steady upright rolling is an
equilibrium of its coordinates. Linearized about upright rolling at spin rate :math:`W`,
the lean obeys :math:`J\\ddot\\varphi + K\\varphi = 0` with

.. math:: J = I_d + m r^2,\\qquad K = (I_a + m r^2) I_a W^2/I_d - m g r,

so upright rolling is stable for :math:`W^2 > g/(3r)`, and a small lean push oscillates at
:math:`\\sqrt{K/J}`. The model file runs 5 s upright; here the disk gets a lean rate of
0.05 rad/s.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "rolling_disk.py")
r, m, g, W, push = 0.3, 2.0, 9.81, 6.0, 0.05
res = mbcomp.simulate(mod.build(spin=W, lean_rate0=push), **dict(mod.SIMULATION, n_out=251))
Ia, Id = m * r * r / 2, m * r * r / 4
J, K = Id + m * r * r, (Ia + m * r * r) * Ia * W ** 2 / Id - m * g * r
omega = np.sqrt(K / J)
lean_linear = push / omega * np.sin(omega * res.time)
lin = mbcomp.analysis.linearize(mod.build(spin=W), t=0.0)
print(f"sqrt(K/J) = {omega:.6f} rad/s; linearize: {np.round(lin.eigenvalues, 6)}")

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["lean.phi"], label="mbcomp")
ax.plot(res.time, lean_linear, "--", label="linear theory")
ax.set_xlabel("t (s)")
ax.set_ylabel("lean (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The disk at the end of the run (animation: ``rolling_disk.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("rolling_disk.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: ``linearize`` finds the frequency :math:`\\sqrt{K/J}`; the run follows the linear
# lean to 1 % of its amplitude (the rest is nonlinear); no slip: the energy is kept.
freq = np.max(np.abs(lin.eigenvalues.imag))
CHECKS = {"|linearized frequency - sqrt(K/J)| (rad/s)": (abs(freq - omega), 1e-6),
          "max |lean - linear| / amplitude": (np.max(np.abs(res["lean.phi"] - lean_linear)) / (push / omega), 1e-2),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
