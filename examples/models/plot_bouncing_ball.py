"""
A bouncing ball
===============

A ball dropped from :math:`h_0` onto the ground: a unilateral ``PlaneContact`` with Newton's
restitution :math:`e`. Each impact reverses the speed times :math:`e`, so the flights shrink
geometrically and the impact times are a closed form,

.. math:: t_k = t_0 + 2 t_0 e\\frac{1 - e^k}{1 - e},\\qquad t_0 = \\sqrt{2h_0/g},

accumulating (Zeno) at :math:`t_\\infty = t_0(1 + 2e/(1 - e))`, where the run settles the ball at
rest. The model file has no ``SIMULATION``: ``simulate``'s defaults, 1 s; here 4.5 s, to
see the rest.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "bouncing_ball.py")
res = mbcomp.simulate(mod.build(), t_end=4.5, rtol=1e-10, atol=1e-12, n_out=601)
h0, e, g = 1.0, 0.8, 9.81
t0 = np.sqrt(2 * h0 / g)
impacts = [ev.time for ev in res.events if ev.kind == "impact"]
k = np.arange(len(impacts))
closed = t0 + 2 * t0 * e * (1 - e ** k) / (1 - e)
print(f"{len(impacts)} impacts, then {res.events[-1].kind} at {res.events[-1].time:.6f} s "
      f"(t_inf = {t0 * (1 + 2 * e / (1 - e)):.6f} s)")

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["ball.r.z"] - 0.1, label="height of the lowest point")
ax.plot(closed, 0 * closed, "x", label="closed-form impact times")
ax.set_xlabel("t (s)")
ax.set_ylabel("height (m)")
ax.legend(fontsize=8)
plt.show()

# %%
# The ball at the end of the run (animation: ``bouncing_ball.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("bouncing_ball.png", t=0.3)))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the impact times; the rest comes after the last impact and no later than the
# accumulation point (the run settles the ball once its bounces are too small to resolve).
rest = res.events[-1]
t_inf = t0 * (1 + 2 * e / (1 - e))
CHECKS = {"max |impact time - closed form| (s)": (np.max(np.abs(np.array(impacts) - closed)), 1e-8),
          "rest not between the last impact and t_inf": (float(not (rest.kind == "rest" and impacts[-1] <= rest.time <= t_inf)), 0.0)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
