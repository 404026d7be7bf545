"""
A door closing against its stop
===============================

A door leaf on a vertical hinge is pushed shut and hits the frame's stop at
:math:`\\varphi = 0`: a rigid stop (``Revolute(limits=...)``) with Newton's restitution. Each
impact keeps :math:`e^2` of the kinetic energy; the rebounds shrink until the door rests
against the frame. Without damping the impact times are exact -- ``reference()`` in the
model file chains them to the state at the end.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "door.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=401))
ref = mod.reference()
impacts = [ev.time for ev in res.events if ev.kind == "impact"]
print("impacts (s):", np.round(impacts, 9), " reference:", ref["impacts"])

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["hinge.phi"])
ax.plot(ref["impacts"], [0.0] * len(ref["impacts"]), "x", label="closed-form impacts")
ax.set_xlabel("t (s)")
ax.set_ylabel("door angle (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The door at the end of the run (animation: ``door.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("door.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the impact times and the state at the end against ``reference()``.
CHECKS = {"max |impact time - reference| (s)": (np.max(np.abs(np.array(impacts) - ref["impacts"])), 1e-9),
          "|phi(t_end) - reference| (rad)": (abs(res["hinge.phi"][-1] - ref["values"]["hinge.phi"]), 1e-8),
          "|w(t_end) - reference| (rad/s)": (abs(res["hinge.w"][-1] - ref["values"]["hinge.w"]), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
