"""Steady states: coordinates at rest or moving at constant rates, every acceleration zero.

:func:`steady_states` searches chosen coordinates and speeds in ranges by multi-start least
squares on ``du/dt = 0`` (scipy's trust-region reflective method, bounded); every start is
first put on the constraint manifold (positions closed along the directions not named, free
speeds solved from the velocity rows). All distinct solutions are reported with how they were
found. :func:`parse_steady` reads the command line's ``name=value, name=lo:hi``.

Examples
--------
The bead on a ring spinning at omega (seed Example 7.1) rests at ``alpha = 0``, ``+-pi`` and
``+-acos(g / (r omega^2))`` (7.28).

>>> import mbcomp, numpy as np
>>> from mbcomp.library import World, Revolute, PrescribedMotion, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> spin = m.add("spin", Revolute(n=(0, 1, 0))); drive = m.add("drive", PrescribedMotion(s=lambda t: 6.0 * t))
>>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
>>> rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); bead = m.add("bead", PointMass(m=0.1))
>>> m.connect(w.frame_b, spin.frame_a); m.connect(drive.flange_b, spin.axis)
>>> m.connect(spin.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a); m.connect(rod.frame_b, bead.frame_a)
>>> [round(s.values["hinge.phi"], 6) for s in mbcomp.steady_states(m, {"hinge.phi": (-1.5, 1.5)})]
[-0.994407, 0.0, 0.994407]
>>> round(float(np.arccos(9.81 / (0.5 * 36))), 6)
0.994407
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..assembly.initialization import initialize
from ..assembly.manifold import close_positions, solve_speeds
from ..errors import ModelError, Problem, SimulationError
from ..assembly.kkt import accelerations
from .evaluation import system_for
from .reduced import direction_names

__all__ = ["SteadyState", "steady_states", "parse_steady", "SEARCH_CLOSE_TOL"]

#: Position closure of each trial state of the search, ``||Phi||``. Tighter than
#: ``manifold.POSITION_TOL`` (1e-12) because the least-squares residual holds ``Phi`` and the
#: found state is the closed one: with 1e-12 the hanging four-bar's steady state moves by
#: 1.6e-13 (measured); 1e-14 keeps it, and the bead angles of (7.28), to rounding.
SEARCH_CLOSE_TOL = 1e-14


@dataclass(frozen=True)
class SteadyState:
    """A steady state: coordinates ``q`` and speeds ``u`` (the model's own, at time ``t``)
    where every speed's acceleration vanishes.

    Attributes
    ----------
    q, u : ndarray
    t : float
    values : dict
        The searched unknowns at the solution, by name.
    residual : float
        Largest ``|du/dt|`` left (in the speeds' units per second).
    how : str
        How it was found.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.stability import SteadyState
    >>> SteadyState(np.zeros(1), np.zeros(1), 0.0, {"hinge.phi": 0.0}, 0.0, "given").values
    {'hinge.phi': 0.0}
    """

    q: np.ndarray
    u: np.ndarray
    t: float
    values: dict
    residual: float
    how: str


def parse_steady(spec):
    """``"a=1.0, b=0:3.2"`` -> ``({"a": 1.0}, {"b": (0.0, 3.2)})``: fixed values and unknowns
    with their search ranges.

    Examples
    --------
    >>> from mbcomp.stability import parse_steady
    >>> parse_steady("hinge.w=0, hinge.phi=-3:3")
    ({'hinge.w': 0.0}, {'hinge.phi': (-3.0, 3.0)})
    """
    fixed, unknown = {}, {}
    for item in filter(None, (x.strip() for x in str(spec).split(","))):
        if "=" not in item:
            raise ValueError(f"steady spec item {item!r}: write name=value (fixed) or name=lo:hi (unknown)")
        name, val = (x.strip() for x in item.split("=", 1))
        try:
            if ":" in val:
                lo, hi = (float(x) for x in val.split(":"))
                if not lo < hi:
                    raise ValueError
                unknown[name] = (lo, hi)
            else:
                fixed[name] = float(val)
        except ValueError:
            raise ValueError(f"steady spec item {item!r}: the value must be a number or a range lo:hi "
                             "with lo < hi") from None
    return fixed, unknown


def _check_names(system, fixed, unknown, dnames):
    """A :class:`ModelError` listing every name that is no coordinate or speed, or a quaternion part."""
    probs = []
    for name in list(fixed) + list(unknown):
        if name not in system.q_names and name not in system.u_names:
            probs.append(Problem(name, "is neither a coordinate nor a speed of the model",
                                 f"use one of {', '.join(system.q_names + system.u_names)}"))
        elif name in system.q_names and name not in dnames:
            probs.append(Problem(name, "is a quaternion component, which cannot be searched or fixed alone",
                                 "model that rotation with Revolute joints, or give the start orientation"))
    if not unknown:
        probs.append(Problem("steady", "no unknowns to solve for", "name at least one name=lo:hi"))
    if probs:
        raise ModelError(probs, header="steady-state search")


class _Trial:
    """The state of a trial ``z`` of the unknowns, on the constraint manifold, and its residual."""

    def __init__(self, system, t, q0, u0, names, named):
        self.s, self.t, self.q0, self.u0, self.names = system, t, q0, u0, names
        self.q_idx = {n: i for i, n in enumerate(system.q_names)}
        self.u_idx = {n: i for i, n in enumerate(system.u_names)}
        dnames = direction_names(system)
        named_dirs = {dnames.index(n) for n in named if n in self.q_idx}
        named_speeds = {self.u_idx[n] for n in named if n in self.u_idx}
        self.free_dirs = np.array([i for i in range(system.nu) if i not in named_dirs], int)
        self.free_speeds = np.array([i for i in range(system.nu) if i not in named_speeds], int)

    def state(self, z):
        """``(q, u)``: the unknowns set to ``z``, positions closed along the directions not
        named, the speeds not named solved from the velocity rows."""
        s, t = self.s, self.t
        q, u = self.q0.copy(), self.u0.copy()
        for n, v in zip(self.names, z):
            if n in self.q_idx:
                q[self.q_idx[n]] = v
            else:
                u[self.u_idx[n]] = v
        zero = np.zeros(s.nu)

        def residual(qq):
            ev = s.evaluate(t, qq, zero)
            return ev.Phi, ev.C, None

        q = close_positions(residual, s.increment, q, columns=self.free_dirs, tol=SEARCH_CLOSE_TOL, max_iter=40).q
        for _ in range(2):  # the second pass removes the rounding of the first
            ev = s.evaluate(t, q, u)
            if ev.A.shape[0]:
                u = solve_speeds(ev.A, np.concatenate((ev.Phid, ev.Psi)), u, self.free_speeds)
        return q, u

    def residual(self, z):
        """``[du/dt, Phi, dPhi/dt, Psi]`` at the trial state."""
        q, u = self.state(z)
        ev = self.s.evaluate(self.t, q, u)
        ud, _ = accelerations(ev)
        return np.concatenate((ud, ev.Phi, ev.Phid, ev.Psi))


def steady_states(model, unknown, fixed=None, params=None, t=0.0, starts=9, tol=1e-9, backend="python"):
    """Steady states with the ``unknown`` coordinates/speeds searched in ranges.

    Every speed not named is taken from the model's consistent start state (zero: at rest)
    or solved from the velocity constraints; coordinates not named keep their start values
    except those the position constraints determine. The conditions are ``du/dt = 0`` for
    every speed: coordinates at rest stay at rest, moving ones keep constant rates.

    Parameters
    ----------
    model : Model or MultibodySystem
    unknown : dict
        ``{name: (lo, hi)}``: coordinate names (``hinge.phi``) or speed names (``hinge.w``).
    fixed : dict, optional
        ``{name: value}`` values to impose (coordinates or speeds).
    params : dict, optional
        Runtime parameter values.
    starts : int
        Starting points per unknown (evenly spread over its range; at most 400 in all).
    tol : float
        Largest ``|du/dt|`` accepted as steady.
    backend : {"python", "numeric", "c", "auto"}
        What evaluates the model (as in :func:`mbcomp.linearize`).

    Returns
    -------
    list of SteadyState
        Distinct solutions sorted by their unknowns; each says how it was found.
    """
    system = system_for(model, params, backend)
    init = initialize(system, t)
    fixed, unknown = dict(fixed or {}), dict(unknown)
    _check_names(system, fixed, unknown, direction_names(system))
    q0, u0 = init.q.copy(), init.u.copy()
    for n, v in fixed.items():
        if n in system.q_names:
            q0[system.q_names.index(n)] = v
        else:
            u0[system.u_names.index(n)] = v
    names = list(unknown)
    trial = _Trial(system, t, q0, u0, names, list(fixed) + names)
    lo = np.array([unknown[n][0] for n in names])
    hi = np.array([unknown[n][1] for n in names])
    per = max(2, min(int(starts), int(round(400 ** (1.0 / len(names))))))
    found, n_conv = _search(trial.residual, lo, hi, per, tol)
    how = (f"least squares (scipy trf) on du/dt = 0 from {per ** len(names)} starts spread over "
           + ", ".join(f"{n} in [{a:g}, {b:g}]" for n, a, b in zip(names, lo, hi))
           + f": {n_conv} converged (|du/dt| <= {tol:g}) to {len(found)} distinct solutions")
    out = []
    for z, res in found:
        q, u = trial.state(z)
        out.append(SteadyState(q, u, float(t), dict(zip(names, map(float, z))), float(res), how))
    return out


def _search(residual, lo, hi, per, tol):
    """Least squares from ``per`` starts per unknown over ``[lo, hi]``: the distinct solutions
    ``[(z, largest |residual|), ...]`` sorted by ``z``, and how many starts converged."""
    from scipy.optimize import least_squares  # here: scipy.optimize costs ~0.5 s to import

    grids = [np.linspace(a, b, per) for a, b in zip(lo, hi)]
    found, n_conv = [], 0
    for z0 in itertools.product(*grids):
        z0 = np.clip(np.array(z0), lo, hi)
        try:
            sol = least_squares(residual, z0, bounds=(lo, hi), xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200)
        except (SimulationError, np.linalg.LinAlgError, ValueError):
            continue
        res = np.abs(residual(sol.x)).max()
        if res > tol:
            continue
        n_conv += 1
        if all(np.abs(sol.x - z).max() > 1e-6 * max(1.0, np.abs(hi - lo).max()) for z, _ in found):
            found.append((sol.x, res))
    found.sort(key=lambda zr: tuple(zr[0]))
    return found, n_conv
