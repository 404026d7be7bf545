"""
Andrews' squeezing mechanism
============================

The seven-body planar mechanism of Hairer & Wanner (*Solving ODEs II*, VII.7) and of the IVP
test set: seven bodies, revolute joints, three closed loops meeting at one point, one degree
of freedom. A constant torque drives the crank; a stiff spring pulls a triangle body. It runs
0.03 s -- the crank turns about 2.5 times -- and the published solution at the end (PSIDE at
:math:`10^{-14}`, ``REFERENCE`` in the model file) is the reference.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "andrews.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=301))

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
for name, joint in mod.COORDINATES.items():
    ax.plot(res.time * 1e3, np.mod(res[f"{joint}.phi"] + np.pi, 2 * np.pi) - np.pi, label=name)
ax.set_xlabel("t (ms)")
ax.set_ylabel("angle, wrapped (rad)")
ax.legend(fontsize=7, ncol=4)
plt.show()

# %%
# The mechanism at the end of the run (animation: ``andrews.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("andrews.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: every published coordinate at t = 0.03 s, relative to its size (the reference is
# good to about 1e-10).
print(mod.REFERENCE["source"])
CHECKS = {}
for name, joint in mod.COORDINATES.items():
    ref = mod.REFERENCE["values"][name]
    CHECKS[f"{name}: relative error"] = (abs(res[f"{joint}.phi"][-1] - ref) / max(abs(ref), 1.0), 1e-8)
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
