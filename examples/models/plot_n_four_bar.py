"""
The N-four-bar: passing singular positions
==========================================

:math:`N` parallelograms in a row (the IFToMM benchmark), :math:`2N + 1` links on hinges. The
chain moves as one parallelogram with a single degree of freedom, obeying

.. math:: J\\ddot\\theta = -g\\cos\\theta\\, m L\\left(\\tfrac{N+1}{2} + N\\right),\\qquad
   J = m L^2\\left(\\tfrac{N+1}{3} + N\\right).

Whenever :math:`\\theta` is a multiple of :math:`\\pi` every link lies on the ground line: the
closure Jacobian loses rank. ``simulate(..., singular="pass")`` goes through those instants
(the default, ``"stop"``, reports the first). The model file runs 20 s; 5 s here.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "n_four_bar.py")
res = mbcomp.simulate(mod.build(N=2), **dict(mod.SIMULATION, t_end=5.0, n_out=251))
theta0 = res["theta"][0]
ref = solve_ivp(lambda t, y: [y[1], mod.exact_rate(y[0], N=2)], (0, res.time[-1]), [theta0, 1.0],
                t_eval=res.time, method="DOP853", rtol=1e-11, atol=1e-12)

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["theta"], label="mbcomp (singular='pass')")
ax.plot(res.time, ref.y[0], "--", label="one-DOF equation")
for k in range(0, 3):
    ax.axhline(k * np.pi, color="gray", lw=0.6)
ax.set_xlabel("t (s)")
ax.set_ylabel("theta (rad)")
ax.legend(fontsize=8)
plt.show()

# %%
# The chain at the end of the run (animation: ``n_four_bar.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("n_four_bar.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the crank angle follows the one-degree-of-freedom equation through every flat
# position (several are passed: theta goes beyond 2 pi).
CHECKS = {"max |theta - one-DOF equation| (rad)": (np.max(np.abs(res["theta"] - ref.y[0])), 1e-5),
          "flat positions not passed": (float(np.max(res["theta"]) < 2 * np.pi), 0.0)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
