"""
The Whipple bicycle (Meijaard et al. 2007 benchmark)
====================================================

Four rigid bodies -- rear frame with rider, rear wheel, fork with handlebar, front wheel --
composed from library components, with knife-edge wheels rolling without slip
(``DiskContact``: one holonomic and two nonholonomic rows each). At 5 m/s the benchmark
bicycle is *self-stable* (between the weave speed 4.29 and the capsize speed 6.02 m/s): pushed
sideways (a roll rate of 0.05 rad/s; the model file's ``SIMULATE_PARAMS`` push ten times harder),
it leans, weaves and rights itself.
Once the lean is small, the motion is the linearized one: a sum of the decaying **capsize**
mode and the damped **weave** oscillation, whose roots ``mbcomp.linearize`` gives from the same
model at the upright operating point.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "bicycle.py")
res = mbcomp.simulate(mod.build(v=5.0, roll_rate0=0.05), **mod.SIMULATION)
print(res.status, "|", res.stats["steps"], "steps")

lin = mbcomp.analysis.linearize(mod.build(v=5.0), t=0.0)
capsize = max(e.real for e in lin.eigenvalues if abs(e.imag) < 1e-9 and -5 < e.real < -1e-6)
print("eigenvalues at 5 m/s:", np.round(lin.eigenvalues[np.abs(lin.eigenvalues) > 1e-6], 4))

# %%
# From t = 2 s on, fit roll(t) by the two modes' shapes (least squares in their three
# amplitudes): the residual says whether the motion is what the linear roots predict.
weave = next(e for e in lin.eigenvalues if e.imag > 1.0)
late = res.time > 2.0
t = res.time[late] - 2.0
shapes = np.c_[np.exp(capsize * t), np.exp(weave.real * t) * np.cos(weave.imag * t),
               np.exp(weave.real * t) * np.sin(weave.imag * t)]
amplitudes = np.linalg.lstsq(shapes, res["roll"][late], rcond=None)[0]
fit = shapes @ amplitudes
fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, res["roll"], label="roll")
axs[0].plot(res.time, res["steer_angle"], label="steer")
axs[0].set_ylabel("angle (rad)")
axs[0].legend(fontsize=8)
axs[1].plot(res.time[late], res["roll"][late], label="roll")
axs[1].plot(res.time[late], fit, "--", label="capsize + weave modes")
axs[1].set_ylabel("roll (rad)")
axs[1].set_xlabel("t (s)")
axs[1].legend(fontsize=8)
plt.show()

# %%
# The bicycle at the end of the run (animation: ``bicycle.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("bicycle.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the late roll is the two linear modes to 0.1 % of its size (what is left is the
# nonlinear part); no slip, no friction: the energy is kept.
E = res["energy.total"]
CHECKS = {"max |roll - modes| / max |roll| (t > 2 s)": (np.max(np.abs(res["roll"][late] - fit)) / np.max(np.abs(res["roll"][late])), 1e-3),
          "relative energy drift": (np.ptp(E) / abs(E[0]), 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
