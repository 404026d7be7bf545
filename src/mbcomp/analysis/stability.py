"""Stability: steady states, linearization in independent coordinates, eigenvalues, sweeps.

The seed's Chapter 7 for any composed model, holonomic and nonholonomic alike:

* :func:`steady_states` finds states where chosen coordinates are at rest and the others
  move at constant rates (an equilibrium when all rates are zero): every speed's
  acceleration vanishes. Unknown coordinates and rates are searched in ranges by
  multi-start least squares; all distinct solutions are reported with how they were found.
* :func:`linearize` builds the state matrix ``A`` of the perturbation equations
  ``dY/dt = A Y`` (seed eq. 7.14) in independent coordinates: position increments along the
  joint speeds (quaternion joints by rotation vectors), minus the directions that moving
  coordinates take (they must be cyclic) and those the holonomic constraints determine, plus
  the independent speeds. A perturbed state is mapped onto the constraint manifold (Newton on
  the dependent positions, the velocity constraints solved for the dependent speeds) and its
  accelerations come from the full saddle-point system, so the multiplier terms of holonomic
  and nonholonomic constraints are in ``A`` exactly (no null-space shortcut that would drop
  them). Derivatives are central differences with Richardson extrapolation (error ~1e-11).
  States that influence nothing (zero columns of ``A``: ignorable coordinates such as a
  bicycle's position and heading, conserved speeds) are removed and named; each removes one
  zero root.
* :func:`classify` follows seed Section 7.2: a real root > 0 or a complex root with positive
  real part is unstable; roots on the imaginary axis (the rest stable) are marginally stable;
  all real parts negative is asymptotically stable.
* :func:`sweep` repeats the analysis over a parameter and locates the values where the
  classification changes by root finding: Brent on the largest real part where it changes
  sign; where a real pair meets at zero and leaves along the imaginary axis (conservative
  systems), Brent on its signed square (``+a^2`` unstable, ``-b^2`` marginally stable); else
  bisection on the classification.

Examples
--------
The bead on a ring spinning at omega (seed Example 7.1): at the bottom the roots are
``+-sqrt(omega^2 - g/r)`` (7.34).

>>> import mbcomp
>>> from mbcomp.library import World, Revolute, PrescribedMotion, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> spin = m.add("spin", Revolute(n=(0, 1, 0))); drive = m.add("drive", PrescribedMotion(s=lambda t: 6.0 * t))
>>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
>>> rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); bead = m.add("bead", PointMass(m=0.1))
>>> m.connect(w.frame_b, spin.frame_a); m.connect(drive.flange_b, spin.axis)
>>> m.connect(spin.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a); m.connect(rod.frame_b, bead.frame_a)
>>> lin = mbcomp.linearize(m)
>>> lin.state_names, lin.classification
(['hinge.phi', 'hinge.w'], 'unstable')
>>> round(float(max(lin.eigenvalues.real)), 6)  # sqrt(36 - 9.81/0.5)
4.047221
"""
from __future__ import annotations

import itertools
import json
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq, least_squares

from ..errors import ModelError, Problem, SimulationError
from ..formulations.lagrange import LagrangeIndex1
from ..assembly.initialization import initialize
from ..assembly.system import MultibodySystem, assemble

__all__ = ["SteadyState", "Linearization", "Sweep", "steady_states", "linearize", "classify", "sweep",
           "parse_steady"]


# ------------------------------------------------------------------------------------------
# names
# ------------------------------------------------------------------------------------------
def _direction_names(system):
    """Names of the ``nu`` position-increment directions (one per speed)."""
    names = [None] * system.nu
    for e in system.topology.tree:
        if e.u.stop <= e.u.start:
            continue
        c = e.comp
        if c.nq == c.nu:
            for k, (n, _) in enumerate(c.coordinates):
                names[e.u.start + k] = f"{e.name}.{n}"
        else:
            for k, (n, _) in enumerate(c.speeds):
                if n.startswith("w."):
                    n = "rot." + n[2:]
                elif n.startswith("v."):
                    n = "r." + n[2:]
                else:
                    n = f"d{n}"
                names[e.u.start + k] = f"{e.name}.{n}"
    return names


BACKENDS = ("python", "numeric", "c", "auto")


def _system(model_or_system, params, backend="python"):
    """The assembled system, evaluated by a generated program unless ``backend="numeric"``.

    A linearization evaluates the model a few hundred times at nearby states; the generated
    Python program (:mod:`mbcomp.codegen`) does that 10-20x faster than the numeric path for
    a trace of a few tens of milliseconds, and agrees with it to rounding. A model that cannot
    be traced falls back to the numeric path with a warning naming the component.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is unknown; use one of {', '.join(BACKENDS)}")
    if isinstance(model_or_system, MultibodySystem):
        system = model_or_system.with_params(params) if params else model_or_system
    else:
        system = assemble(model_or_system, params)
    if backend == "numeric":
        return system
    from ..codegen.program import CodegenError, CompiledSystem, compile_system

    if isinstance(system, CompiledSystem):
        return system
    try:
        return compile_system(system, backend)
    except CodegenError as exc:
        warnings.warn(f"stability: the numeric path evaluates this model (slower): {exc}", stacklevel=3)
        return system


# ------------------------------------------------------------------------------------------
# the reduced dynamics around a state
# ------------------------------------------------------------------------------------------
class _Reduced:
    """Maps independent position increments and speeds onto the constraint manifold and
    returns their rates."""

    def __init__(self, system, t, q0, u0, rest_tol=1e-10):
        self.s, self.t, self.q0, self.u0 = system, float(t), np.array(q0, float), np.array(u0, float)
        self.form = LagrangeIndex1(system, stabilization="none")
        nu = system.nu
        ev = system.evaluate(self.t, self.q0, self.u0)
        scale = max(1.0, float(np.abs(self.u0).max(initial=0.0)))
        moving = np.abs(self.u0) > rest_tol * scale
        self.moving = np.where(moving)[0]
        rest = np.where(~moving)[0]
        # holonomic rows: dependent position directions among those at rest
        C = ev.C
        if C.shape[0]:
            pdep = _pivot_columns(C, rest, "position", system)
        else:
            pdep = np.zeros(0, int)
        self.pdep = pdep
        self.pind = np.array([i for i in rest if i not in set(pdep)], int)
        A = ev.A
        self.vdep = _pivot_columns(A, np.arange(nu), "speed", system) if A.shape[0] else np.zeros(0, int)
        self.vind = np.array([i for i in range(nu) if i not in set(self.vdep)], int)
        self.n = self.pind.size + self.vind.size

    # --- state -> (q, u) ---------------------------------------------------------------------
    def positions(self, dpos, moving=None):
        """Coordinates with the independent increments ``dpos`` (and optional increments of
        the moving directions), projected onto ``Phi = 0`` along the dependent directions."""
        s = self.s
        d = np.zeros(s.nu)
        d[self.pind] = dpos
        if moving is not None:
            d[self.moving] = moving
        q = s.increment(self.q0, d)
        if self.pdep.size:
            for _ in range(30):
                ev = s.evaluate(self.t, q, np.zeros(s.nu))
                if np.abs(ev.Phi).max() <= 1e-15:
                    break
                dd = np.zeros(s.nu)
                dd[self.pdep] = -np.linalg.lstsq(ev.C[:, self.pdep], ev.Phi, rcond=None)[0]
                q = s.increment(q, dd)
                if np.abs(dd).max() <= 1e-16:
                    break
            else:
                raise SimulationError("linearization: the position constraints could not be closed near the "
                                      "steady state (a singular position?)")
        return q

    def speeds(self, q, dv):
        """Speeds with the independent ones moved by ``dv``, the dependent ones solved from the
        velocity constraints (linear in ``u``: one solve is exact); returns ``(u, evaluation)``."""
        s = self.s
        u = self.u0.copy()
        u[self.vind] += dv
        ev = s.evaluate(self.t, q, u)
        if self.vdep.size:
            res = np.concatenate((ev.Phid, ev.Psi))
            u[self.vdep] -= np.linalg.solve(ev.A[:, self.vdep], res)
            ev = s.evaluate(self.t, q, u)
        return u, ev

    def rate(self, x, moving=None):
        npos = self.pind.size
        q = self.positions(x[:npos], moving)
        u, ev = self.speeds(q, x[npos:])
        ud, _ = self.form.solve(ev, stabilize=False)
        return np.concatenate((u[self.pind], ud[self.vind]))

    def jacobian(self, f, n, scale):
        """Central differences with one Richardson step: ``(4 D(h/2) - D(h)) / 3``."""
        x0 = np.zeros(n)
        cols = []
        for j in range(n):
            h = 1e-4 * scale[j]

            def D(hh, j=j):
                e = np.zeros(n)
                e[j] = hh
                return (f(x0 + e) - f(x0 - e)) / (2 * hh)

            cols.append((4 * D(h / 2) - D(h)) / 3)
        return np.column_stack(cols) if cols else np.zeros((0, 0))


def _pivot_columns(A, allowed, what, system):
    """Columns of ``A`` (restricted to ``allowed``) chosen by pivoted QR as dependent."""
    m = A.shape[0]
    allowed = np.asarray(allowed, int)
    if allowed.size < m:
        raise SimulationError(f"linearization: {m} {what} constraint rows but only {allowed.size} directions at rest "
                              "to satisfy them")
    _, R, piv = sla.qr(A[:, allowed], pivoting=True, mode="economic")
    d = np.abs(np.diag(R))
    if d.size < m or d[m - 1] <= 1e-10 * max(d[0], 1e-300):
        raise SimulationError(f"linearization: the {what} constraints are singular at this state (or need a "
                              "moving coordinate to be satisfied); choose another steady state")
    return np.sort(allowed[piv[:m]])


# ------------------------------------------------------------------------------------------
# classification
# ------------------------------------------------------------------------------------------
def _tol(eigs):
    return 1e-7 * (1.0 + (np.abs(eigs).max() if len(eigs) else 0.0))


def classify(eigenvalues, tol=None):
    """Seed Section 7.2: ``"unstable"`` if a root has a positive real part (real or complex),
    ``"marginally stable"`` if the largest real part is zero (roots on the imaginary axis),
    ``"asymptotically stable"`` if all real parts are negative. Real parts within ``tol``
    (default ``1e-7 (1 + max |lambda|)``, the accuracy of the linearization) count as zero.

    Examples
    --------
    >>> from mbcomp.stability import classify
    >>> classify([-1 + 2j, -1 - 2j]), classify([3j, -3j]), classify([0.5, -0.5])
    ('asymptotically stable', 'marginally stable', 'unstable')
    """
    eigs = np.asarray(eigenvalues, complex)
    if eigs.size == 0:
        return "marginally stable"
    tol = _tol(eigs) if tol is None else tol
    top = eigs.real.max()
    if top > tol:
        return "unstable"
    if top >= -tol:
        return "marginally stable"
    return "asymptotically stable"


# ------------------------------------------------------------------------------------------
# results
# ------------------------------------------------------------------------------------------
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


@dataclass(frozen=True)
class Linearization:
    """State matrix of the perturbation equations ``dY/dt = A Y`` about a steady state.

    Attributes
    ----------
    A : ndarray (n, n)
        In units of the states per second.
    state_names : list of str
        Position increments (``<joint>.<coordinate>``, or ``<joint>.rot.x|y|z`` for rotation
        vectors of quaternion joints, body axes) then independent speeds (``<joint>.<speed>``).
    eigenvalues : ndarray (n,), complex, 1/s
        Sorted by decreasing real part.
    eigenvectors : ndarray (n, n), complex
        Columns, normalized to unit length, in the order of ``eigenvalues``.
    classification : str
        :func:`classify` of the eigenvalues.
    removed : list of str
        States that influence nothing (zero columns; each carried one zero root), removed.
    moving : list of str
        Position directions moving at constant rates (cyclic), not states.
    state : SteadyState

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.stability import Linearization
    >>> lin = Linearization(np.array([[0.0, 1.0], [-4.0, 0.0]]), ["x", "v"], np.array([2j, -2j]),
    ...                     np.eye(2, dtype=complex), "marginally stable", [], [], None)
    >>> lin.frequencies()
    array([2., 2.])
    """

    A: np.ndarray
    state_names: list
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    classification: str
    removed: list
    moving: list
    state: SteadyState = field(repr=False)

    def frequencies(self):
        """``|Im lambda|`` (rad/s) of each eigenvalue."""
        return np.abs(self.eigenvalues.imag)

    def modes(self):
        """Text: each eigenvalue with the states that dominate its eigenvector."""
        lines = []
        for k, lam in enumerate(self.eigenvalues):
            v = self.eigenvectors[:, k]
            big = np.argsort(-np.abs(v))[:3]
            parts = ", ".join(f"{self.state_names[i]} {abs(v[i]):.2f}" for i in big if abs(v[i]) > 1e-3)
            lines.append(f"  {lam.real:+.6g} {lam.imag:+.6g}j   ({parts})")
        return "\n".join(lines)

    def report(self):
        head = [f"linearization: {len(self.state_names)} states ({', '.join(self.state_names)})",
                f"classification: {self.classification}"]
        if self.moving:
            head.append(f"moving at constant rates (cyclic, not states): {', '.join(self.moving)}")
        if self.removed:
            head.append(f"removed (influence nothing; one zero root each): {', '.join(self.removed)}")
        return "\n".join(head + ["eigenvalues (1/s), dominant states:", self.modes()])

    def to_dict(self):
        return dict(state_names=self.state_names, A=self.A.tolist(),
                    eigenvalues=[[float(e.real), float(e.imag)] for e in self.eigenvalues],
                    classification=self.classification, removed=self.removed, moving=self.moving)


# ------------------------------------------------------------------------------------------
# linearization
# ------------------------------------------------------------------------------------------
def linearize(model, state=None, params=None, t=None, remove_ignorable=True, backend="python"):
    """Linearize about a steady state in independent coordinates (seed eqs. 7.9-7.14).

    Parameters
    ----------
    model : Model or MultibodySystem
    state : SteadyState or (q, u), optional
        Default: the model's consistent start state (its start values must describe the
        steady state; coordinates with nonzero rates must be cyclic).
    params : dict, optional
        Runtime parameter values ``{"component.param": value}``.
    t : float, optional
        Time of the linearization (default the state's, or 0); matters only for
        prescribed motions.
    remove_ignorable : bool
        Remove states that influence nothing (zero columns of ``A``).
    backend : {"python", "numeric", "c", "auto"}
        What evaluates the model (see :func:`mbcomp.simulate`): the generated Python program
        by default (10-20x faster here than ``"numeric"``, equal to rounding).

    Returns
    -------
    Linearization

    Raises
    ------
    SimulationError
        The state is not steady (names the largest acceleration), or a moving coordinate
        is not cyclic (the motion is not an equilibrium in these coordinates).
    """
    system = _system(model, params, backend)
    if state is None:
        init = initialize(system, 0.0 if t is None else t)
        state = SteadyState(init.q, init.u, 0.0 if t is None else float(t), {}, np.nan, "the model's start state")
    elif not isinstance(state, SteadyState):
        q, u = state
        state = SteadyState(np.asarray(q, float), np.asarray(u, float), 0.0 if t is None else float(t), {}, np.nan,
                            "given")
    if system.row_mask is None:
        initialize(system, state.t)
    tt = state.t if t is None else float(t)
    red = _Reduced(system, tt, state.q, state.u)
    dnames = _direction_names(system)
    names = [dnames[i] for i in red.pind] + [system.u_names[i] for i in red.vind]
    f0 = red.rate(np.zeros(red.n))
    uscale = max(1.0, float(np.abs(state.u).max(initial=0.0)))
    acc_tol = 1e-7 * uscale * (1.0 + uscale)
    if f0.size and np.abs(f0).max() > acc_tol:
        k = int(np.argmax(np.abs(f0)))
        hint = "find the steady state first (mbcomp.stability.steady_states or --steady)"
        turning = [dnames[i] for i in red.moving if ".rot." in dnames[i]]
        if turning:  # body-axis speeds of a quaternion joint turn with the body in any steady rotation
            hint = ("if the motion is steady (e.g. a steady precession), it is not steady in these coordinates: "
                    f"{', '.join(turning)} turn(s) the body-axis speeds of a quaternion joint, so no steady state "
                    "exists here -> model the motion with Revolute chains whose angles are cyclic (precession, "
                    "nutation, spin); otherwise " + hint)
        raise SimulationError(f"not a steady state: d/dt of {names[k]} is {f0[k]:.3g} (all must vanish) -> {hint}")
    scale = np.concatenate((np.ones(red.pind.size), np.full(red.vind.size, uscale)))
    A = red.jacobian(red.rate, red.n, scale)
    moving = [dnames[i] for i in red.moving]
    if red.moving.size:  # the motion is an equilibrium only if the moving coordinates are cyclic
        Am = red.jacobian(lambda y: red.rate(np.zeros(red.n), moving=y), red.moving.size, np.ones(red.moving.size))
        bad = np.abs(Am).max(axis=0) if Am.size else np.zeros(0)
        lim = 1e-6 * (1.0 + np.abs(A).max(initial=0.0))
        if bad.size and bad.max() > lim:
            k = int(np.argmax(bad))
            raise SimulationError(
                f"not a steady motion in these coordinates: {moving[k]} moves at a constant rate but the dynamics "
                f"depend on its value (sensitivity {bad[k]:.3g}) -> model that motion with a joint whose angle is "
                "cyclic (e.g. Revolute chains for precession and spin instead of a Spherical/FreeMotion quaternion)")
    removed = []
    keep = list(range(len(names)))
    if remove_ignorable and A.size:
        lim = 1e-7 * (1.0 + np.abs(A).max())
        flim = 1e-10 * (1.0 + np.abs(A).max())

        def inert(j):
            """A finite perturbation (0.1 of the state's scale) changes no kept rate: the column
            is zero structurally, not merely small at linear order (near a stability boundary)."""
            e = np.zeros(red.n)
            e[j] = 0.1 * scale[j]
            try:
                d = red.rate(e) - f0
            except SimulationError:
                return False
            return np.abs(d[keep]).max() <= flim * 0.1 * scale[j]

        changed = True
        while changed:
            changed = False
            for j in list(keep):
                if np.abs(A[keep, j]).max() <= lim and inert(j):
                    keep.remove(j)
                    removed.append(names[j])
                    changed = True
    A = A[np.ix_(keep, keep)]
    names = [names[j] for j in keep]
    if A.size:
        lam, V = np.linalg.eig(A)
        order = np.lexsort((-lam.imag, -lam.real))
        lam, V = lam[order], V[:, order]
    else:
        lam, V = np.zeros(0, complex), np.zeros((0, 0), complex)
    return Linearization(A, names, lam, V, classify(lam), removed, moving, state)


# ------------------------------------------------------------------------------------------
# steady states
# ------------------------------------------------------------------------------------------
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
        What evaluates the model (as in :func:`linearize`).

    Returns
    -------
    list of SteadyState
        Distinct solutions sorted by their unknowns; each says how it was found.
    """
    system = _system(model, params, backend)
    init = initialize(system, t)
    fixed = dict(fixed or {})
    unknown = dict(unknown)
    dnames = _direction_names(system)
    q_idx = {n: i for i, n in enumerate(system.q_names)}
    u_idx = {n: i for i, n in enumerate(system.u_names)}
    probs = []
    for name in list(fixed) + list(unknown):
        if name not in q_idx and name not in u_idx:
            probs.append(Problem(name, "is neither a coordinate nor a speed of the model",
                                 f"use one of {', '.join(system.q_names + system.u_names)}"))
        elif name in q_idx and name not in dnames:
            probs.append(Problem(name, "is a quaternion component, which cannot be searched or fixed alone",
                                 "model that rotation with Revolute joints, or give the start orientation"))
    if not unknown:
        probs.append(Problem("steady", "no unknowns to solve for", "name at least one name=lo:hi"))
    if probs:
        raise ModelError(probs, header="steady-state search")
    q0, u0 = init.q.copy(), init.u.copy()
    for n, v in fixed.items():
        (q0 if n in q_idx else u0)[q_idx[n] if n in q_idx else u_idx[n]] = v
    names = list(unknown)
    named_dirs = {dnames.index(n) for n in list(fixed) + names if n in q_idx}
    named_speeds = {u_idx[n] for n in list(fixed) + names if n in u_idx}
    form = LagrangeIndex1(system, stabilization="none")

    def state_of(z):
        q, u = q0.copy(), u0.copy()
        for n, v in zip(names, z):
            if n in q_idx:
                q[q_idx[n]] = v
            else:
                u[u_idx[n]] = v
        free_dirs = np.array([i for i in range(system.nu) if i not in named_dirs], int)
        for _ in range(40):
            ev = system.evaluate(t, q, np.zeros(system.nu))
            if not ev.Phi.size or np.abs(ev.Phi).max() <= 1e-14:
                break
            d = np.zeros(system.nu)
            d[free_dirs] = -np.linalg.lstsq(ev.C[:, free_dirs], ev.Phi, rcond=None)[0]
            q = system.increment(q, d)
        free_sp = np.array([i for i in range(system.nu) if i not in named_speeds], int)
        for _ in range(2):
            ev = system.evaluate(t, q, u)
            if ev.A.shape[0]:
                u[free_sp] -= np.linalg.lstsq(ev.A[:, free_sp], np.concatenate((ev.Phid, ev.Psi)), rcond=None)[0]
        return q, u

    def residual(z):
        q, u = state_of(z)
        ev = system.evaluate(t, q, u)
        ud, _ = form.solve(ev, stabilize=False)
        return np.concatenate((ud, ev.Phi, ev.Phid, ev.Psi))

    lo = np.array([unknown[n][0] for n in names])
    hi = np.array([unknown[n][1] for n in names])
    per = max(2, min(int(starts), int(round(400 ** (1.0 / len(names))))))
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
    how = (f"least squares (scipy trf) on du/dt = 0 from {per ** len(names)} starts spread over "
           + ", ".join(f"{n} in [{a:g}, {b:g}]" for n, a, b in zip(names, lo, hi))
           + f": {n_conv} converged (|du/dt| <= {tol:g}) to {len(found)} distinct solutions")
    out = []
    for z, res in found:
        q, u = state_of(z)
        out.append(SteadyState(q, u, float(t), dict(zip(names, map(float, z))), float(res), how))
    return out


# ------------------------------------------------------------------------------------------
# sweeps
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Sweep:
    """Eigenvalues against a parameter and the values where stability changes.

    Attributes
    ----------
    parameter : str
    values : ndarray (k,)
    eigenvalues : ndarray (k, n), complex
        Per value, sorted by decreasing real part (NaN where the analysis failed).
    classifications : list of str
    changes : list of dict
        ``{"value", "from", "to", "eigenvalue", "kind", "method"}`` for each change, found by
        root finding between grid values (``kind``: ``"oscillatory"`` when a complex pair
        crosses, ``"divergence"`` when a real root does).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.stability import Sweep
    >>> s = Sweep("v", np.array([0.0, 1.0]), np.array([[1.0 + 0j], [-1.0 + 0j]]), ["unstable", "asymptotically stable"], [])
    >>> s.ranges()  # no change located between the grid values: the segments end at them
    [(0.0, 0.0, 'unstable'), (1.0, 1.0, 'asymptotically stable')]
    """

    parameter: str
    values: np.ndarray
    eigenvalues: np.ndarray
    classifications: list
    changes: list

    def ranges(self):
        """``[(lo, hi, classification), ...]``: runs of equal classification along the sweep,
        their ends at the located changes (at the grid values where a change could not be
        located, e.g. next to a failed point)."""
        vals, cls = self.values, self.classifications
        segs, lo, cur = [], float(vals[0]), cls[0]
        for k in range(len(vals) - 1):
            if cls[k + 1] == cls[k]:
                continue
            found = [c["value"] for c in self.changes if vals[k] <= c["value"] <= vals[k + 1]
                     and c["from"] == cls[k] and c["to"] == cls[k + 1]]
            hi, nxt = (found[0], found[0]) if found else (float(vals[k]), float(vals[k + 1]))
            segs.append((lo, hi, cur))
            lo, cur = nxt, cls[k + 1]
        segs.append((lo, float(vals[-1]), cur))
        return segs

    def stable_ranges(self, include_marginal=False):
        """``[(lo, hi), ...]`` where the state is asymptotically stable (and, with
        ``include_marginal``, marginally stable)."""
        ok = ("asymptotically stable", "marginally stable") if include_marginal else ("asymptotically stable",)
        return [(a, b) for a, b, kind in self.ranges() if kind in ok]

    def to_dict(self):
        return dict(parameter=self.parameter, values=self.values.tolist(),
                    eigenvalues_real=self.eigenvalues.real.tolist(), eigenvalues_imag=self.eigenvalues.imag.tolist(),
                    classifications=self.classifications, changes=self.changes)

    def plot(self, path=None, title=None):
        """Real and imaginary parts against the parameter (like Meijaard et al. Fig. 3)."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4.5))
        v = self.values
        for k in range(self.eigenvalues.shape[1]):
            ax.plot(v, self.eigenvalues[:, k].real, "k.", ms=3, label="Re" if k == 0 else None)
            ax.plot(v, np.abs(self.eigenvalues[:, k].imag), ".", color="tab:blue", ms=2,
                    label="|Im|" if k == 0 else None)
        for c in self.changes:
            ax.axvline(c["value"], color="tab:red", lw=0.8)
            ax.annotate(f"{c['value']:.6g}", (c["value"], 0), rotation=90, fontsize=7, color="tab:red")
        ax.axhline(0, color="0.5", lw=0.5)
        ax.set_xlabel(self.parameter)
        ax.set_ylabel("eigenvalue (1/s)")
        ax.set_title(title or f"eigenvalues against {self.parameter}")
        lim = np.nanmax(np.abs(self.eigenvalues.real)) if np.isfinite(self.eigenvalues.real).any() else 1.0
        ax.set_ylim(-min(lim, 10.0) * 1.1, min(lim, 10.0) * 1.1)
        ax.legend(fontsize=8)
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=110)
            plt.close(fig)
        return fig


def sweep(build, parameter, values, analyze=None, backend="python"):
    """Linearize at each value of ``parameter`` and locate the stability changes.

    Parameters
    ----------
    build : callable
        ``build(value) -> Model`` (or ``MultibodySystem``) describing the steady state at
        that parameter value through its start values.
    parameter : str
        Name for reports and plots.
    values : array_like
        Grid (sorted); changes are bracketed by neighbours and refined by root finding.
    analyze : callable, optional
        ``analyze(model) -> Linearization`` (default :func:`linearize` of the start state),
        e.g. to solve for a steady state first.
    backend : {"python", "numeric", "c", "auto"}
        What evaluates the model in the default ``analyze`` (as in :func:`linearize`).

    Returns
    -------
    Sweep
    """
    analyze = analyze or (lambda mdl: linearize(mdl, backend=backend))
    values = np.asarray(values, float)

    def at(v):
        return analyze(build(float(v)))

    lins = []
    for v in values:
        try:
            lins.append(at(v))
        except (SimulationError, ModelError):
            lins.append(None)
    n = max((len(li.eigenvalues) for li in lins if li is not None), default=0)
    E = np.full((len(values), n), np.nan + 0j)
    cls = []
    for k, li in enumerate(lins):
        if li is None:
            cls.append("failed")
            continue
        E[k, : len(li.eigenvalues)] = li.eigenvalues
        cls.append(li.classification)

    def unstable_count(li):
        tol = _tol(li.eigenvalues)
        return int(np.sum(li.eigenvalues.real > tol))

    def top_root(li):
        return li.eigenvalues[int(np.argmax(li.eigenvalues.real))]

    changes = []
    for k in range(len(values) - 1):
        la, lb = lins[k], lins[k + 1]
        if la is None or lb is None or (cls[k] == cls[k + 1] and unstable_count(la) == unstable_count(lb)):
            continue
        a, b = values[k], values[k + 1]
        try:
            x, method = _locate(at, la, lb, a, b, cls[k], unstable_count, top_root)
        except (SimulationError, ModelError) as exc:
            changes.append(dict(value=float("nan"), **{"from": cls[k], "to": cls[k + 1]}, eigenvalue=[np.nan, np.nan],
                                kind="not located", method=f"analysis failed inside [{a:g}, {b:g}]: {exc}"))
            continue
        try:
            root = top_root(at(x))
        except (SimulationError, ModelError):
            root = complex(np.nan, np.nan)
        # the kind from the root that is unstable on one side (at the crossing itself a
        # collision at zero leaves a ~1e-6 imaginary part of either sign)
        un = lins[k + 1] if unstable_count(lins[k + 1]) > unstable_count(lins[k]) else lins[k]
        ru = top_root(un)
        changes.append(dict(value=float(x), **{"from": cls[k], "to": cls[k + 1]},
                            eigenvalue=[float(root.real), float(root.imag)],
                            kind="oscillatory" if abs(ru.imag) > _tol(un.eigenvalues) else "divergence",
                            method=method))
    return Sweep(parameter, values, E, cls, changes)


class _Other(Exception):
    """A classification other than the two of a bracket's ends turned up inside it."""


def _locate(at, la, lb, a, b, cls_a, unstable_count, top_root):
    """The parameter in ``[a, b]`` where the classification changes: Brent on the largest
    real part if it changes sign clearly, Brent on the colliding pair's signed square between
    unstable and marginally stable, else bisection on the classification."""
    fa, fb = top_root(la).real, top_root(lb).real
    if fa * fb < 0 and abs(fa) > _tol(la.eigenvalues) and abs(fb) > _tol(lb.eigenvalues):
        x = brentq(lambda v: top_root(at(v)).real, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps)
        return x, "Brent's method on the largest real part"
    if {la.classification, lb.classification} == {"unstable", "marginally stable"}:
        # a conservative boundary: a real pair +-a collides at zero and leaves as +-ib. Signed
        # squares (+a^2 unstable, -b^2 stable, b the smallest nonzero frequency) are smooth
        # across it, so Brent converges in a few steps where bisection takes ~41; the sign is
        # the classification, so the root is the classification's change whatever the sizes.
        def signed(v):
            li = at(v)
            tol = _tol(li.eigenvalues)
            if li.classification == "unstable":
                return float(top_root(li).real) ** 2
            if li.classification != "marginally stable":
                raise _Other()
            freq = np.abs(li.eigenvalues.imag)
            freq = freq[freq > tol]
            return -(float(freq.min()) ** 2 if freq.size else tol ** 2)

        try:
            x = brentq(signed, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps)
            return x, "Brent's method on the signed square of the colliding roots"
        except _Other:
            pass  # a third classification inside the bracket: bisection sorts it out
    ca = (cls_a, unstable_count(la))
    for _ in range(60):
        mid = 0.5 * (a + b)
        lm = at(mid)
        if (lm.classification, unstable_count(lm)) == ca:
            a = mid
        else:
            b = mid
        if b - a <= 1e-13 * max(1.0, abs(a)):
            break
    return 0.5 * (a + b), "bisection on the classification"


def to_json(obj, path):
    """Write a :class:`Linearization`, :class:`Sweep` or list of :class:`SteadyState` as JSON."""
    if isinstance(obj, (Linearization, Sweep)):
        data = obj.to_dict()
    elif isinstance(obj, (list, tuple)) and all(isinstance(x, SteadyState) for x in obj):
        data = [dict(q=x.q.tolist(), u=x.u.tolist(), t=x.t, values=x.values, residual=x.residual, how=x.how)
                for x in obj]
    else:
        data = obj
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1)
