"""System-wide result columns made from the others: momenta and the energy balance.

The per-body momenta and the energy balance are computed from the columns of a whole run at
once (numpy over the output grid), not in the per-point programs:

* ``momentum.x|y|z`` (kg m/s) and ``angular_momentum.x|y|z`` (kg m^2/s, about the world
  origin), world frame: summed over the bodies from their pose and twist columns and mass
  properties -- the totals are the output programs' own columns
  (:meth:`mbcomp.assembly.system.MultibodySystem.momenta`, in C over the grid), computed here
  only for a series without them; per body (``<body>.momentum.*``,
  ``<body>.angular_momentum.*``) on request;
* ``energy.work`` (J): the work done on the mechanism since the start by the elements that
  feed or take energy other than by dissipating it (actuators, external loads, drives);
  ``energy.dissipated`` (J, >= 0 for dampers): the energy the dissipative elements
  (:attr:`mbcomp.roles.ForceElement.dissipative`) took out; ``energy.balance`` (J):
  ``energy.total(t) - energy.total(0) - work + dissipated``, zero for an exact solution.

An element's non-conservative work is the integral of the power it delivers beyond its own
potential's rate (``<element>.power_nc``; ``<element>.power`` for an element without a
potential): for a spring-damper only the damper's part. The integral is taken over the
output grid (cumulative Simpson), so the balance also measures how well the grid resolves
that power: a balance error far above the tolerances on a coarse grid asks for more output
points, not a tighter ``rtol``.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass, RotationalDamper
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0)); rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0)); d = m.add("d", RotationalDamper(d=0.5))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> m.connect(j.support, d.flange_a); m.connect(j.axis, d.flange_b)
>>> r = mbcomp.simulate(m, t_end=3.0, n_out=1501)
>>> bool(r["energy.dissipated"][-1] > 1.0), bool(abs(r["energy.balance"]).max() < 1e-8)
(True, True)
"""
from __future__ import annotations

import numpy as np

from ..assembly.conservation import nonconservative

__all__ = ["momentum_columns", "energy_balance_columns", "energy_balance"]

_XYZ = ("x", "y", "z")


def _quat_matrices(Q):
    """Rotation matrices ``(n, 3, 3)`` of the unit quaternions ``Q`` (n, 4) = (w, x, y, z)."""
    w, x, y, z = Q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _vec(series, prefix):
    return np.stack([series[f"{prefix}.{ax}"] for ax in _XYZ], -1)


def momentum_columns(system, series, per_body=False):
    """``{column: ndarray (n,)}``: the whole mechanism's linear momentum (kg m/s) and
    angular momentum about the world origin (kg m^2/s), world frame, from the bodies' columns
    ``<body>.r|v|w.*`` and ``<body>.Q.*`` (see the module notes); each body's as well when
    ``per_body``. Empty when a body's columns are missing, or without ``per_body`` when the
    series has the totals (the output programs'). Every body at once (arrays
    ``(bodies, n, 3)``), summed over the bodies in their order."""
    bodies = system.topology.bodies
    if not bodies or (not per_body and "momentum.x" in series):  # the output programs' own sums
        return {}
    try:
        cols = [[series[f"{path}.{v}.{ax}"] for v in ("r", "v", "w") for ax in _XYZ]
                + [series[f"{path}.Q.{ax}"] for ax in "wxyz"] for path, _, _ in bodies]
    except KeyError:
        return {}
    X = np.asarray(cols, float).transpose(0, 2, 1)  # (bodies, n, 13)
    r, v, w, Q = X[..., 0:3], X[..., 3:6], X[..., 6:9], X[..., 9:13]
    props = [comp.mass_properties(system.P[path]) for path, comp, _ in bodies]
    m = np.array([mp[0] for mp in props], float)[:, None, None]
    rc = np.array([np.asarray(mp[1], float) for mp in props])[:, None, :, None]  # (bodies, 1, 3, 1)
    I = np.array([np.asarray(mp[2], float) for mp in props])[:, None]  # (bodies, 1, 3, 3)
    R = _quat_matrices(Q.reshape(-1, 4)).reshape(Q.shape[:-1] + (3, 3))
    rho = (R @ rc)[..., 0]
    p = m * (v + np.cross(w, rho))
    Iw = R @ I @ np.swapaxes(R, -1, -2)
    h = np.cross(r + rho, p) + np.einsum("bnij,bnj->bni", Iw, w)
    out = {}
    if per_body:
        for k, (path, _, _) in enumerate(bodies):
            for j, ax in enumerate(_XYZ):
                out[f"{path}.momentum.{ax}"], out[f"{path}.angular_momentum.{ax}"] = p[k, :, j], h[k, :, j]
    P, L = p[0], h[0]
    for k in range(1, len(bodies)):  # in the bodies' order, as the sum of the columns reads
        P, L = P + p[k], L + h[k]
    for j, ax in enumerate(_XYZ):
        out[f"momentum.{ax}"], out[f"angular_momentum.{ax}"] = P[:, j], L[:, j]
    return out


def _cumulative(t, y):
    """The integral of ``y`` from ``t[0]`` to every ``t[k]``: cumulative Simpson (scipy) on
    three points or more, the trapezoid on two."""
    if len(t) < 3:
        return np.concatenate(([0.0], np.cumsum(0.5 * np.diff(t) * (y[1:] + y[:-1]))))
    from scipy.integrate import cumulative_simpson

    return cumulative_simpson(y, x=t, initial=0.0)


def energy_balance_columns(system, t, series):
    """``{"energy.work", "energy.dissipated", "energy.balance": ndarray (n,)}`` (J) for a
    mechanism with non-conservative elements or drives (see the module notes); empty for a
    conservative one (its ``energy.total`` is the balance) or when a needed column is
    missing (a run that stopped at its start)."""
    return energy_balance(system, t, series)[0]


def energy_balance(system, t, series):
    """``(columns, quadrature)``: the columns of :func:`energy_balance_columns` and an
    estimate (J) of how much of the balance the output grid's quadrature may account for:
    the largest difference between the work integrated by Simpson's rule and by the
    trapezoid rule (the trapezoid's error, a bound on Simpson's on a grid that resolves the
    power) or by Simpson's rule on every other point (a power ringing faster than the grid
    aliases differently on the two grids)."""
    comps = system.topology.flat.components
    names = nonconservative(system)
    if not names or len(t) < 2 or "energy.total" not in series:
        return {}, 0.0
    work = np.zeros(len(t))
    dissipated = np.zeros(len(t))
    quadrature = 0.0
    for name in names:
        power = series.get(f"{name}.power_nc", series.get(f"{name}.power"))
        if power is None:  # a component that does work but reports no power: no balance
            return {}, 0.0
        if f"{name}.power_nc" not in series and f"{name}.potential" in series:
            return {}, 0.0  # a potential and no split of its power: the balance cannot be told
        w = _cumulative(t, power)
        trapezoid = np.concatenate(([0.0], np.cumsum(0.5 * np.diff(t) * (power[1:] + power[:-1]))))
        if len(t) < 5:  # too few points to tell what the quadrature missed
            quadrature = np.inf
        else:
            half = _cumulative(t[::2], power[::2])
            quadrature += max(float(np.max(np.abs(w - trapezoid))), float(np.max(np.abs(w[::2] - half))))
        if getattr(comps[name], "dissipative", False):
            dissipated -= w
        else:
            work += w
    E = series["energy.total"]
    return {"energy.work": work, "energy.dissipated": dissipated,
            "energy.balance": E - E[0] - work + dissipated}, quadrature
