"""
Linearization and stability of an equilibrium
=============================================

``mbcomp.linearize(model)`` returns the linear model :math:`\\dot x = A x` about the state the
model starts in, and its eigenvalues. A pendulum hanging down has
:math:`\\lambda = \\pm i\\sqrt{g/l}` (a stable oscillation); standing up,
:math:`\\lambda = \\pm\\sqrt{g/l}` (one root in the right half-plane: unstable). The same model
serves both: the start angle is a build parameter.
"""
import matplotlib.pyplot as plt
import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World


def pendulum(theta0, l=0.5, g=9.81):
    model = mbcomp.Model()
    world = model.add("world", World(g=(0, -g, 0)))
    hinge = model.add("hinge", Revolute(n=(0, 0, 1), phi0=theta0))
    rod = model.add("rod", FixedTranslation(r=(0, -l, 0)))
    bob = model.add("bob", PointMass(m=1.0))
    model.connect(world.frame_b, hinge.frame_a)
    model.connect(hinge.frame_b, rod.frame_a)
    model.connect(rod.frame_b, bob.frame_a)
    return model


down = mbcomp.linearize(pendulum(0.0))
up = mbcomp.linearize(pendulum(np.pi))
print("hanging:", down.eigenvalues, " standing:", up.eigenvalues)
print("A (hanging) =\n", down.A)

fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.plot(down.eigenvalues.real, down.eigenvalues.imag, "o", label="hanging")
ax.plot(up.eigenvalues.real, up.eigenvalues.imag, "s", label="standing")
ax.axvline(0.0, color="gray", lw=0.8)
ax.set_xlabel("Re (1/s)")
ax.set_ylabel("Im (1/s)")
ax.legend(fontsize=8)
plt.show()

# %%
# The check: both pairs are :math:`\\sqrt{g/l}` in size, on the axis the closed form says.
w = np.sqrt(9.81 / 0.5)
CHECKS = {"|hanging - (+-i sqrt(g/l))| (1/s)": (np.max(np.abs(np.sort_complex(down.eigenvalues) - [-1j * w, 1j * w])), 1e-8),
          "|standing - (+-sqrt(g/l))| (1/s)": (np.max(np.abs(np.sort_complex(up.eigenvalues) - [-w, w])), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
