"""
Impacts: a bouncing ball and its restitution
============================================

A unilateral contact (``PlaneContact(unilateral=True)``) opens and closes: the run locates
each touch on the integrator's dense output (an **event**), applies an impulse with Newton's
restitution :math:`e` (an **impact**: the normal speed after is :math:`-e` times the speed
before) and carries on. ``res.events`` lists what happened; ``energy.impacts`` accumulates the
energy the impacts took. Each bounce rises to :math:`e^2` times the previous height, and each
impact takes :math:`1 - e^2` of the kinetic energy it meets.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import PlaneContact, PointMass, World
from mbcomp.modeling.free_joint import FreeTranslation

m, r, h0, g = 0.2, 0.05, 0.5, 9.81
fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
CHECKS = {}
for e in (0.5, 0.8):
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, 0, -g)))
    free = model.add("free", FreeTranslation(r0=(0.0, 0.0, h0 + r)))
    ball = model.add("ball", PointMass(m=m))
    ground = model.add("ground", PlaneContact(r=r, unilateral=True, restitution=e, open0=True))
    model.connect(world.frame_b, free.frame_a)
    model.connect(free.frame_b, ball.frame_a)
    model.connect(world.frame_b, ground.frame_a)
    model.connect(ground.frame_b, ball.frame_a)
    res = mbcomp.simulate(model, t_end=1.5, rtol=1e-10, atol=1e-12, n_out=1501)
    height = res["ball.r.z"] - r
    ax.plot(res.time, height, label=f"e = {e}")
    impacts = [ev.time for ev in res.events if ev.kind == "impact"]
    print(f"e = {e}: {len(impacts)} impacts, the first at {impacts[0]:.9f} s; last event: {res.events[-1].kind}")
    # apex heights between the first impacts, against h0 e^(2k)
    apex = [height[(res.time > a) & (res.time < b)].max() for a, b in zip(impacts[:3], impacts[1:4])]
    closed = h0 * e ** (2 * np.arange(1, len(apex) + 1))
    ax.plot(0.5 * (np.array(impacts[:len(apex)]) + impacts[1:len(apex) + 1]), closed, "kx")
    # energy taken by the first impact: (1 - e^2) of m g h0
    lost = res["energy.impacts"][np.searchsorted(res.time, impacts[0]) + 1]
    CHECKS[f"e = {e}: max |apex - h0 e^2k| (m)"] = (np.max(np.abs(np.array(apex) - closed)), 2e-5)
    CHECKS[f"e = {e}: |first impact's loss - (1 - e^2) m g h0| (J)"] = (abs(abs(lost) - (1 - e * e) * m * g * h0), 1e-8)
ax.set_xlabel("t (s)")
ax.set_ylabel("height (m)")
ax.legend(fontsize=8)
plt.show()

# %%
# The check: the apex heights (read off outputs 1 ms apart, so to a few 1e-6 m) and the energy
# each first impact takes.
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
