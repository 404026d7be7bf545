"""
Joint friction: slip, stick
===========================

A block on a spring slides on a rough surface: a ``Prismatic`` joint with
``friction=SlidingFriction(mu_s, mu_k, normal)``, a Coulomb law with modes -- *slip* (the
kinetic force :math:`F_k = \\mu_k N` against the motion) and *stick* (the joint held, until the
force needed exceeds :math:`F_s = \\mu_s N`). Between turning points the block oscillates about
:math:`\\pm F_k/k`, so each half swing shortens the amplitude by :math:`2F_k/k`; it sticks for
good at the first turning point where the spring force :math:`k|x|` is below :math:`F_s`.
The run's events say when it switched.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import Prismatic, PointMass, SlidingFriction, TranslationalSpringDamper, World

m, k, x0, mu_s, mu_k, N = 1.0, 100.0, 0.1, 0.5, 0.4, 4.0
model = mbcomp.Model()
world = model.add("world", World(g=(0, 0, 0)))
slide = model.add("slide", Prismatic(n=(1, 0, 0), s0=x0, v0=0.0, friction=SlidingFriction(mu_s, mu_k, normal=N)))
spring = model.add("spring", TranslationalSpringDamper(c=k))
block = model.add("block", PointMass(m=m))
model.connect(world.frame_b, slide.frame_a)
model.connect(slide.frame_b, block.frame_a)
model.connect(slide.support, spring.flange_a)
model.connect(slide.axis, spring.flange_b)

res = mbcomp.simulate(model, t_end=1.5, rtol=1e-10, atol=1e-12, n_out=301)
print([(ev.kind, round(ev.time, 6)) for ev in res.events])

# %%
# The closed form: turning points every half period :math:`\\pi\\sqrt{m/k}`, each
# :math:`2F_k/k` closer to the centre, until the spring cannot break the block loose.
Fk, Fs, half = mu_k * N, mu_s * N, np.pi * np.sqrt(m / k)
turns, x = [], x0
while k * abs(x) > Fs:
    x = -np.sign(x) * (abs(x) - 2 * Fk / k)
    turns.append(x)
print("turning points (m):", np.round(turns, 6), "-> sticks at", turns[-1])
fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["slide.s"], label="mbcomp")
ax.plot(half * np.arange(1, len(turns) + 1), turns, "o", label="closed-form turning points")
ax.set_xlabel("t (s)")
ax.set_ylabel("x (m)")
ax.legend(fontsize=8)
plt.show()

# %%
# The check: the block ends where the closed form stops it, at the predicted time.
i_end = np.searchsorted(res.time, half * len(turns) + 0.05)
CHECKS = {"|final position - closed form| (m)": (abs(res["slide.s"][-1] - turns[-1]), 1e-8),
          "max |x - final| after the last turn (m)": (np.max(np.abs(res["slide.s"][i_end:] - turns[-1])), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
