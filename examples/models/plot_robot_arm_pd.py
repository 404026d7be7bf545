"""
A robot arm from a URDF file, driven by PD laws
===============================================

The arm of ``models/data/robot_arm.urdf`` (a column turning about the vertical, then three
hinges) read by :func:`mbcomp.load_urdf` into library components named as the file's joints
and links. A PD law on each joint, ``kp (q* - q) - kd dq/dt``, is a
``RotationalSpringDamper`` between the joint's flanges. With **gravity compensation** (an
upward force :math:`-m g` at each link's centre of mass: exactly the torques
:math:`g(q)` a controller adds) the arm settles at the target :math:`q^*` itself; without, it
sags until the PD torque holds its weight. The model file samples 20001 outputs (to judge
the PD laws' energy balance); 501 are enough to see the motion.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "robot_arm_pd.py")
target = (0.5, 0.8, -0.6, 0.4)
res = mbcomp.simulate(mod.build(target=target, gravity_compensation=True), **dict(mod.SIMULATION, n_out=501))

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
for joint, q in zip(mod.JOINTS, target):
    line, = ax.plot(res.time, res[f"{joint}.phi"], label=joint)
    ax.axhline(q, color=line.get_color(), ls="--", lw=0.8)
ax.set_xlabel("t (s)")
ax.set_ylabel("joint angle (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The arm at the end of the run (animation: ``robot_arm_pd.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("robot_arm_pd.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: with gravity compensated, every joint ends at its target (the PD laws' decay
# leave far less than 1e-9 rad after 5 s).
CHECKS = {f"|{joint} - target| at 5 s (rad)": (abs(res[f"{joint}.phi"][-1] - q), 1e-9)
          for joint, q in zip(mod.JOINTS, target)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
