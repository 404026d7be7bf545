"""
A parameter study on Dask
=========================

``mbcomp.study(build, grid, metrics=...)`` runs a model over a grid of parameter values and
collects metrics of each run in a table. ``executor="dask"`` (or a ``dask.distributed.Client``)
spreads the runs over a cluster -- here a ``LocalCluster`` of two worker processes; without
Dask installed the study runs serially (the same rows). The study: the period of a pendulum
against its amplitude, against the closed form
:math:`T = 4\\sqrt{l/g}\\,K(\\sin^2(\\theta_0/2))` (the complete elliptic integral).

Dask starts its workers by *spawning* fresh Python processes, which import the main module
again: run this as a script (``python plot_study_dask.py``) only with the study under an
``if __name__ == "__main__":`` guard. (In the docs build and the test suite the script is not
the main module.)
"""
import pathlib

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipk

import mbcomp

HERE = pathlib.Path(__file__).parent if "__file__" in globals() else pathlib.Path.cwd()  # sphinx-gallery: no __file__,
ROOT = HERE.resolve().parents[1]                                               # the cwd is this folder
MODEL = ROOT / "models" / "textbook" / "ex6_1_pendulum.py"   # build(m, l, g, theta0, theta_dot0)


def period(res):
    """Twice the time between the first two crossings of theta = 0 (s), located linearly."""
    th, t = res["theta"], res.time
    i = np.nonzero(np.sign(th[1:]) != np.sign(th[:-1]))[0][:2]
    tc = t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])
    return 2 * (tc[1] - tc[0])


try:
    from dask.distributed import Client, LocalCluster
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None, host="127.0.0.1")
    executor = Client(cluster)
    print("on Dask:", executor)
except ImportError:
    cluster, executor = None, None
    print("Dask is not installed: the study runs serially")

amplitudes = [0.2, 1.0, 2.0, 2.8]
try:
    study = mbcomp.study(str(MODEL), {"theta0": amplitudes}, t_end=4.0, metrics={"period": period},
                         executor=executor, rtol=1e-10, atol=1e-12, n_out=4001)
finally:
    if cluster is not None:
        executor.close()
        cluster.close()
print(len(study), "runs; periods:", study["period"])

# %%
l, g = 0.8, 9.81
closed = 4 * np.sqrt(l / g) * ellipk(np.sin(np.array(amplitudes) / 2) ** 2)
T = np.asarray(study["period"], float)
fig, ax = plt.subplots(layout="constrained", figsize=(5, 3))
ax.plot(amplitudes, T, "o", label="mbcomp study")
ax.plot(amplitudes, closed, "--", label="4 sqrt(l/g) K(sin^2(theta0/2))")
ax.set_xlabel("amplitude theta0 (rad)")
ax.set_ylabel("period (s)")
ax.legend(fontsize=8)
plt.show()

# %%
# The check: every period against the elliptic integral (the crossings are located linearly
# between outputs 1 ms apart: about 1e-7 s).
CHECKS = {"max |period - closed form| (s)": (np.max(np.abs(T - closed)), 1e-6)}
for name, (err, tol) in CHECKS.items():
    print(f"{name}: {err:.2e} (tolerance {tol:.0e})")
    assert err <= tol, name
