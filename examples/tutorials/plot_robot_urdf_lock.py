"""
A robot from a URDF file, with locked joints
============================================

:func:`mbcomp.load_urdf` reads a robot description into library components named as the
file's joints and links (``res["shoulder.phi"]``); ``model.lock(joints, at=...)`` holds
joints rigidly at given angles -- their coordinates disappear, the bodies they joined move as
one. Here the four-joint arm of ``models/data/robot_arm.urdf`` (without its joint damping)
keeps only its shoulder: the straight arm (upper arm, forearm, hand) is a compound pendulum.
Hanging down it swings at :math:`\\omega^2 = g\\sum m_i d_i / \\sum(I_i + m_i d_i^2)`, from the
links' masses, centres (distance :math:`d_i` from the shoulder) and inertias in the file.
"""
import pathlib
import warnings

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
with warnings.catch_warnings():   # the loader warns of what it leaves out: here the damping, on purpose
    warnings.simplefilter("ignore")
    arm = mbcomp.load_urdf(ROOT / "models" / "data" / "robot_arm.urdf", damping=False)
print("not imported:", arm.urdf_notes)
held = arm.lock(["base_yaw", "elbow", "wrist"], at={"base_yaw": 0.0, "elbow": 0.0, "wrist": 0.0})
print("coordinates:", mbcomp.assemble(arm).q_names, "->", mbcomp.assemble(held).q_names)

# %%
# Linearized hanging down (shoulder at pi), and a swing from 0.1 rad beside it
start = {"shoulder.phi0": np.pi}
lin = mbcomp.linearize(held, params=start)
res = mbcomp.simulate(held, t_end=3.0, params={"shoulder.phi0": np.pi + 0.1}, rtol=1e-10, atol=1e-12, n_out=301)
m = np.array([1.5, 1.0, 0.5])                      # upper_arm, forearm, hand (kg)
d = np.array([0.2, 0.4 + 0.175, 0.4 + 0.35 + 0.05])  # their centres from the shoulder (m)
Iyy = np.array([0.02045, 0.010433, 0.0005])          # about their centres (kg m^2)
omega = np.sqrt(9.81 * m @ d / (Iyy + m * d ** 2).sum())
print(f"omega = {omega:.6f} rad/s; linearize: {lin.eigenvalues}")

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["shoulder.phi"] - np.pi, label="shoulder - pi, mbcomp")
ax.plot(res.time, 0.1 * np.cos(omega * res.time), "--", label="0.1 cos(omega t)")
ax.set_xlabel("t (s)")
ax.set_ylabel("angle (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The locked arm at the end of the run (animation: ``robot_urdf_lock.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("robot_urdf_lock.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: one coordinate left; the linearization's frequency is the compound pendulum's.
freq = np.max(np.abs(lin.eigenvalues.imag))
CHECKS = {"coordinates - 1": (len(mbcomp.assemble(held).q_names) - 1, 0),
          "|linearized frequency - omega| (rad/s)": (abs(freq - omega), 1e-5),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
