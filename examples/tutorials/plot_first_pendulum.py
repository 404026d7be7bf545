"""
A first pendulum
================

A 1 kg point mass on a massless 1 m rod swings on a hinge under gravity. Released from
0.1 rad it follows the small-angle closed form ``phi(t) = phi0 cos(sqrt(g/L) t)`` to a
fraction of a percent of the amplitude; the simulated motion and the closed form are
plotted together, and their difference below.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

g, L, phi0 = 9.81, 1.0, 0.1

m = mbcomp.Model()
world = m.add("world", World(g=(0, -g, 0)))
hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=phi0))
rod = m.add("rod", FixedTranslation(r=(0, -L, 0)))
bob = m.add("bob", PointMass(m=1.0))
m.connect(world.frame_b, hinge.frame_a)
m.connect(hinge.frame_b, rod.frame_a)
m.connect(rod.frame_b, bob.frame_a)

res = mbcomp.simulate(m, t_end=4.0, n_out=401)

# %%
# The closed form of the linearized pendulum: the full one swings slightly slower
# (its period grows with the amplitude by about ``phi0**2 / 16``).
closed = phi0 * np.cos(np.sqrt(g / L) * res.time)
error = res["hinge.phi"] - closed
print(f"largest difference: {np.abs(error).max():.2e} rad ({np.abs(error).max() / phi0:.2%} of the amplitude)")
assert np.abs(error).max() < 0.01 * phi0

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.8))
top.plot(res.time, res["hinge.phi"], label="mbcomp")
top.plot(res.time, closed, "--", label="small-angle closed form")
top.set_ylabel("phi (rad)")
top.legend()
bottom.plot(res.time, error)
bottom.set_xlabel("time (s)")
bottom.set_ylabel("difference (rad)")
fig.tight_layout()
