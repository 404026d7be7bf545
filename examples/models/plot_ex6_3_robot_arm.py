"""
Two-link robot arm with joint motors (textbook Example 6.3)
===========================================================

Two links turn about vertical hinges (gravity does no work); a motor at each joint exerts a
PD torque toward a target, ``kp (q_ref - q) - kd dq/dt``, written as a ``Torque`` law on the
joint's flange. The book writes Lagrange's equations in the **absolute** angles
:math:`\\alpha_1, \\alpha_2` with the generalized forces :math:`Q_1 = \\tau_1 - \\tau_2`,
:math:`Q_2 = \\tau_2` (6.53)-(6.54); mbcomp's joints measure the elbow *relative* to link 1
(:math:`\\alpha_2 = \\alpha_1 + q_2`). scipy integrates the book's equations as the reference.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex6_3_robot_arm.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

m1, l1, a1, m2, l2, a2 = 2.0, 0.5, 0.25, 1.0, 0.4, 0.2
I1, I2 = m1 * l1 ** 2 / 12, m2 * l2 ** 2 / 12
q_ref, kp, kd = (1.0, 0.8), (8.0, 3.0), (1.5, 0.5)


def book(t, y):
    al1, al2, w1, w2 = y
    tau1 = kp[0] * (q_ref[0] - al1) - kd[0] * w1
    tau2 = kp[1] * (q_ref[1] - (al2 - al1)) - kd[1] * (w2 - w1)
    c, s = np.cos(al1 - al2), np.sin(al1 - al2)
    M = [[I1 + m1 * a1 ** 2 + m2 * l1 ** 2, m2 * a2 * l1 * c], [m2 * a2 * l1 * c, m2 * a2 ** 2 + I2]]
    f = [tau1 - tau2 - m2 * a2 * l1 * w2 ** 2 * s, tau2 + m2 * a2 * l1 * w1 ** 2 * s]
    return [w1, w2, *np.linalg.solve(M, f)]


ref = solve_ivp(book, (0, res.time[-1]), [0, 0, 0, 0], t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)
fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["alpha1"], label="alpha1, mbcomp")
ax.plot(res.time, ref.y[0], "--", label="alpha1, (6.53)-(6.54)")
ax.plot(res.time, res["alpha1"] + res["elbow_angle"], label="alpha2, mbcomp")
ax.plot(res.time, ref.y[1], "--", label="alpha2, (6.53)-(6.54)")
ax.set_xlabel("t (s)")
ax.set_ylabel("angle (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The arm at the end of the run (animation: ``ex6_3_robot_arm.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex6_3_robot_arm.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: both absolute angles against the book's equations.
CHECKS = {"max |alpha1 - book| (rad)": (np.max(np.abs(res["alpha1"] - ref.y[0])), 1e-7),
          "max |alpha2 - book| (rad)": (np.max(np.abs(res["alpha1"] + res["elbow_angle"] - ref.y[1])), 1e-7)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
