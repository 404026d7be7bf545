"""
A bowling ball: sliding, then rolling
=====================================

A ball thrown down a lane slides first: Coulomb friction :math:`\\mu_k m g` against the slip
decelerates the centre and spins the ball up, so the slip speed falls linearly and the slide
ends at :math:`t^* = |s_0| / (\\mu_k g (1 + 1/k))` (the contact's ``stick`` event, a switch to
rolling); from then on it rolls at :math:`v^* = 5 v_0 / 7` (a uniform sphere, no spin). The
model file throws it down an oiled lane (:math:`\\mu_k = 0.04`: 5.8 s of sliding, 8 s run);
here a dry lane, :math:`\\mu_k = 0.2`, 2 s -- the same physics in a quarter of the time.
``reference()`` in the model file is the closed form.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "bowling.py")
res = mbcomp.simulate(mod.build(mu_k=0.2), **dict(mod.SIMULATION, t_end=2.0, n_out=41))  # straight lines: few outputs
ref = mod.reference(t_end=2.0, mu_k=0.2)
sticks = [ev.time for ev in res.events if ev.kind != "impact"]
print("events:", [(ev.kind, round(ev.time, 9)) for ev in res.events], " t* =", round(ref["t_roll"], 9))

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["ball.v.x"], label="centre speed (m/s)")
ax.plot(res.time, -0.109 * res["ball.w.y"], label="r w (m/s)")
ax.axvline(ref["t_roll"], color="gray", lw=0.8, label="t* (closed form)")
ax.set_xlabel("t (s)")
ax.legend(fontsize=8)
plt.show()

# %%
# The ball at the end of the run (animation: ``bowling.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("bowling.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the slide's end and the state at 2 s against the closed form.
CHECKS = {"|stick time - t*| (s)": (abs(sticks[0] - ref["t_roll"]), 1e-8)}
for key, value in ref["values"].items():
    CHECKS[f"|{key} - closed form|"] = (abs(res[key][-1] - value), 1e-7)
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
