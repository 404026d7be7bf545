"""
A gear train driven by a motor
==============================

A motor with a falling torque-speed line, :math:`\\tau = \\tau_0 (1 - \\omega_1/\\omega_0)`,
drives a load through an ideal gear of ratio :math:`n` (``IdealGear``: a constraint between
the two shafts' flanges, :math:`\\varphi_1 = n \\varphi_2`). The load's inertia appears at the
motor divided by :math:`n^2`, so the motor shaft obeys
:math:`(J_1 + J_2/n^2)\\dot\\omega_1 = \\tau_0(1 - \\omega_1/\\omega_0)`:

.. math:: \\omega_1(t) = \\omega_0\\left(1 - e^{-t/T}\\right),\\qquad T = \\frac{(J_1 + J_2/n^2)\\,\\omega_0}{\\tau_0}.

A ``Torque`` law is any function ``tau(t, phi, w)`` of its flange's angle and rate.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import Fixed, IdealGear, Revolute, RigidBody, Torque

J1, J2, n, tau0, w0 = 0.01, 0.5, 5.0, 2.0, 30.0
model = mbcomp.Model()
base = model.add("base", Fixed())
motor_shaft = model.add("motor_shaft", Revolute(n=(0, 0, 1)))
load_shaft = model.add("load_shaft", Revolute(n=(0, 0, 1)))
rotor = model.add("rotor", RigidBody(m=1.0, I=np.diag([J1, J1, J1])))
load = model.add("load", RigidBody(m=1.0, I=np.diag([J2, J2, J2])))
gear = model.add("gear", IdealGear(ratio=n))
motor = model.add("motor", Torque(tau=lambda t, phi, w: tau0 * (1 - w / w0)))
model.connect(base.frame_b, motor_shaft.frame_a)
model.connect(motor_shaft.frame_b, rotor.frame_a)
model.connect(base.frame_b, load_shaft.frame_a)
model.connect(load_shaft.frame_b, load.frame_a)
model.connect(gear.flange_a, motor_shaft.axis)
model.connect(gear.flange_b, load_shaft.axis)
model.connect(motor.flange_b, motor_shaft.axis)

res = mbcomp.simulate(model, t_end=2.0, rtol=1e-10, atol=1e-12, n_out=201)
T = (J1 + J2 / n ** 2) * w0 / tau0
w1 = w0 * (1 - np.exp(-res.time / T))
fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["motor_shaft.w"], label="motor shaft, mbcomp")
ax.plot(res.time, w1, "--", label="closed form")
ax.plot(res.time, res["load_shaft.w"], label="load shaft, mbcomp")
ax.set_xlabel("t (s)")
ax.set_ylabel("rate (rad/s)")
ax.legend(fontsize=8)
plt.show()

# %%
# The check: the motor's rate follows the closed form; the load turns :math:`n` times slower.
CHECKS = {"max |w1 - closed form| (rad/s)": (np.max(np.abs(res["motor_shaft.w"] - w1)), 1e-7),
          "max |w1 - n w2| (rad/s)": (np.max(np.abs(res["motor_shaft.w"] - n * res["load_shaft.w"])), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
