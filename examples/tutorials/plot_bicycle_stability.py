"""
A bicycle's stability against speed
===================================

``mbcomp.sweep`` linearizes a model at each value of a parameter and follows the eigenvalues:
here the benchmark bicycle (``models/bicycle.py``, upright, straight ahead) at 3, 5 and 7 m/s (a coarse grid: the sweep locates the crossings between grid speeds by root
finding; the test suite runs the full 0..10 m/s grid).
Where an eigenvalue's real part crosses zero the sweep locates the speed by root finding: the
**weave** speed (an oscillatory pair turns stable) and the **capsize** speed (a real root
turns unstable). Meijaard et al. (2007) publish 4.292382445956 and 6.024262015827 m/s.
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
bicycle = mbcomp.load_model_file(ROOT / "models" / "bicycle.py")
sw = mbcomp.sweep(lambda v: bicycle.build(v=v), "v", [3.0, 5.0, 7.0])
for change in sw.changes:
    print(f"{change['kind']:12s} at v = {change['value']:.9f} m/s: {change['from']} -> {change['to']}")

fig, ax = plt.subplots(layout="constrained", figsize=(6, 3.5))
for v, eig in zip(sw.values, sw.eigenvalues):
    ax.plot([v] * len(eig), np.real(eig), "k.", ms=3)
ax.axhline(0.0, color="gray", lw=0.8)
for change in sw.changes:
    ax.axvline(change["value"], ls="--", lw=0.8)
ax.set_ylim(-10, 10)
ax.set_xlabel("v (m/s)")
ax.set_ylabel("Re(eigenvalue) (1/s)")
plt.show()

# %%
# The check: both critical speeds against the paper's Table 2 (the printed weave speed carries
# its own 1e-7 rounding).
weave, capsize = (c["value"] for c in sw.changes)
CHECKS = {"|weave speed - paper| (m/s)": (abs(weave - 4.292382445956), 2e-7),
          "|capsize speed - paper| (m/s)": (abs(capsize - 6.024262015827), 1e-8)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
