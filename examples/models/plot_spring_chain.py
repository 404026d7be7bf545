"""
A pendulum chain on stiff springs
=================================

Four links on hinges whose bobs slide on stiff springs (:math:`c = 10^6` N/m, lightly damped):
the sliders ring at :math:`\\sqrt{c/m} = 1000` rad/s while the pendulum swings at a few rad/s
-- an oscillatory stiffness every method must resolve. The default method (``"auto"``)
starts explicit and hands over to an implicit one (radau5) where it finds the problem stiff.
The dampers only take energy out.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
mod = mbcomp.load_model_file(ROOT / "models" / "spring_chain.py")
res = mbcomp.simulate(mod.build(), **dict(mod.SIMULATION, n_out=401))
print(res.status, "|", res.stats["steps"], "steps, method", res.stats["method"])
E = res["energy.total"]

fig, axs = plt.subplots(2, 1, layout="constrained", figsize=(6, 4), sharex=True)
for k in range(4):
    axs[0].plot(res.time, res[f"s{k}.s"] * 1e3, lw=0.8, label=f"s{k}")
axs[0].set_ylabel("spring stretch (mm)")
axs[0].legend(fontsize=7, ncol=4)
axs[1].plot(res.time, E - E[0])
axs[1].set_ylabel("E - E(0) (J)")
axs[1].set_xlabel("t (s)")
plt.show()

# %%
# The chain at the end of the run (animation: ``spring_chain.html``)
fig, ax = plt.subplots(layout="constrained", figsize=(4, 3))
ax.imshow(plt.imread(res.snapshot("spring_chain.png")))
ax.set_axis_off()
# %%
# The motion in the HTML player (drag to turn the view, the slider scrubs time; the
# same page as ``res.animate("motion.html")`` writes):
res.animate()

# %%
# The check: the dampers never put energy in (to what rtol = 1e-6 leaves open), and they do
# take some out.
CHECKS = {"largest energy rise (J)": (max(np.max(np.diff(E)), 0.0), 1e-4),
          "no energy dissipated (1 if E(end) >= E(0))": (float(E[-1] >= E[0]), 0.0)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
