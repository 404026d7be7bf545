"""
Spatial slider-crank: spherical and universal joints
====================================================

After Modelica's ``SpatialSliderCrank``: the crank turns about the world :math:`x` axis, the
rod joins it by a ``Spherical`` joint and the slider by a ``Universal`` joint (which keeps the
rod from spinning about its own axis), and the slider runs on a line off the crank's plane.
The loop closes by the rod's length, so the slider's position is a closed form of the crank
angle (``slider_position`` in the model file):

.. math:: s = c + \\sqrt{L^2 - (a\\cos\\varphi - h_y)^2 - (a\\sin\\varphi - h_z)^2}.

The run uses the model file's settings (2 s, projection onto the constraints).
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "spatial_slider_crank.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))
s_closed = np.array([mod.slider_position(p) for p in res["crank_angle"]])

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3))
ax.plot(res.time, res["slider_position"], label="mbcomp")
ax.plot(res.time, s_closed, "--", label="slider_position(crank angle)")
ax.set_xlabel("t (s)")
ax.set_ylabel("slider s (m)")
ax.legend(fontsize=8)
plt.show()

# %%
# The mechanism at the end of the run (animation: ``spatial_slider_crank.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("spatial_slider_crank.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the slider where the loop puts it; the energy kept.
CHECKS = {"max |s - closed form| (m)": (np.max(np.abs(res["slider_position"] - s_closed)), 1e-9),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
