"""
A slider and a ball joint: five degrees of freedom (textbook Sections 4.3-4.5)
==============================================================================

Body 1 rides on a cylindrical pair (a ``Prismatic`` along world :math:`y` and a ``Revolute``
about it: the book's slider, four constraints); body 2 hangs from body 1 on a ``Spherical``
joint (three constraints). Grübler's count gives :math:`6\\cdot 2 - (4 + 3) = 5` degrees of
freedom: ``r_y``, ``phi`` and the ball joint's three rotations (a quaternion, four coordinates,
three speeds). The reactions the book names are outputs (``R_x``, ``R_z``, ``M_x``, ``M_z``).
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "textbook" / "ex4_3_slider_spherical.py")
system = mbcomp.assemble(mod.build())
print("coordinates:", system.nq, " speeds:", system.nu)
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=201))

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
axs[0].plot(res.time, res["r_y"], label="r_y (m)")
axs[0].plot(res.time, res["phi"], label="phi (rad)")
axs[0].legend(fontsize=8)
for name in ("R_x", "R_z", "M_x", "M_z"):
    axs[1].plot(res.time, res[name], label=f"{name} ({res.units[name]})")
axs[1].legend(fontsize=8, ncol=2)
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The mechanism at the end of the run (animation: ``ex4_3_slider_spherical.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("ex4_3_slider_spherical.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: five speeds; body 1 stays on the slider's axis (x = z = 0 for its origin);
# nothing dissipates, so the energy is kept.
CHECKS = {"speeds - 5": (abs(system.nu - 5), 0),
          "max |body1 off the axis| (m)": (np.max(np.hypot(res["body1.r.x"], res["body1.r.z"])), 1e-12),
          "energy drift (J)": (np.ptp(res["energy.total"]), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
