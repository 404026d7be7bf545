"""
Gradients by the adjoint method
===============================

``mbcomp.gradient(model, objective, params)`` differentiates a scalar objective of a run --
a value at the end (``"terminal"``) plus an integral (``"integral"``), written over the result
columns -- with respect to parameters and start values, by one forward and one backward
(adjoint) run, however many parameters. Here: the angle of a pendulum after 1 s with respect
to its start angle and its rod length. For small swings,
:math:`\\theta(T) = \\theta_0\\cos\\omega T` with :math:`\\omega = \\sqrt{g/l}`, so

.. math:: \\frac{\\partial\\theta(T)}{\\partial\\theta_0} = \\cos\\omega T,\\qquad
   \\frac{\\partial\\theta(T)}{\\partial l} = \\theta_0\\,\\frac{\\omega T}{2l}\\sin\\omega T .

The rod is ``FixedTranslation(r=(0, -l, 0))``, so the parameter is ``rod.r[1]`` :math:`= -l`.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

l, g, theta0, T = 0.8, 9.81, 0.01, 1.0


def pendulum(theta0=theta0, l=l):
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, -g, 0)))
    hinge = model.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0))
    rod = model.add("rod", FixedTranslation(r=(0, -l, 0)))
    bob = model.add("bob", PointMass(m=1.0))
    model.connect(world.frame_b, hinge.frame_a)
    model.connect(hinge.frame_b, rod.frame_a)
    model.connect(rod.frame_b, bob.frame_a)
    return model


gr = mbcomp.gradient(pendulum(), {"terminal": "hinge.phi"}, ["hinge.phi0", "rod.r[1]"], t_end=T)
w = np.sqrt(g / l)
closed = np.array([np.cos(w * T), -theta0 * w * T / (2 * l) * np.sin(w * T)])
print("theta(T) =", gr.value, " adjoint gradient:", gr.gradient, " small-angle closed form:", closed)

# %%
# A second path: central finite differences of two runs each (the adjoint needs one pair of
# runs for any number of parameters; differences need two runs per parameter).
def theta_T(**kw):
    return mbcomp.simulate(pendulum(**kw), t_end=T, rtol=1e-12, atol=1e-14, n_out=2)["hinge.phi"][-1]


h = 1e-5
fd = np.array([(theta_T(theta0=theta0 + h) - theta_T(theta0=theta0 - h)) / (2 * h),
               -(theta_T(l=l + h) - theta_T(l=l - h)) / (2 * h)])
fig, ax = plt.subplots(layout="constrained", figsize=(5, 3))
x = np.arange(2)
ax.bar(x - 0.25, gr.gradient, 0.25, label="adjoint")
ax.bar(x, fd, 0.25, label="finite differences")
ax.bar(x + 0.25, closed, 0.25, label="small-angle closed form")
ax.set_xticks(x, ["d theta(T) / d theta0", "d theta(T) / d r[1]"])
ax.legend(fontsize=8)
plt.show()

# %%
# The check: the adjoint agrees with the differences to their truncation error, and with the
# small-angle closed form to its own neglect (:math:`\\theta_0^2 \\approx 10^{-4}`).
CHECKS = {"max |adjoint - finite differences|": (np.max(np.abs(gr.gradient - fd)), 1e-7),
          "max |adjoint - closed form| / |closed form|": (np.max(np.abs(gr.gradient - closed) / np.abs(closed)), 1e-3)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
