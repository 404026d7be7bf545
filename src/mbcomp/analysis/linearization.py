"""Linearization about a steady state in independent coordinates, eigenvalues, classification.

:func:`linearize` builds the state matrix ``A`` of the perturbation equations
``dY/dt = A Y`` (seed eq. 7.14) in independent coordinates: position increments along the
joint speeds (quaternion joints by rotation vectors), minus the directions that moving
coordinates take (they must be cyclic) and those the holonomic constraints determine, plus
the independent speeds (:mod:`mbcomp.analysis.reduced`). A perturbed state is mapped onto the
constraint manifold and its accelerations come from the full saddle-point system, so the
multiplier terms of holonomic and nonholonomic constraints are in ``A`` exactly (no
null-space shortcut that would drop them). States that influence nothing (zero columns of
``A``: ignorable coordinates such as a bicycle's position and heading, conserved speeds) are
removed and named; each removes one zero root.

Derivatives are exact wherever a generated program evaluates the model
(``derivatives="auto"``): the tangent program of the traced evaluation
(:mod:`mbcomp.codegen.eval_tangent`, one Jacobian-vector product per direction) gives the
derivatives of the dynamic balance and of the constraint rows, the map onto the manifold is
differentiated by the implicit function theorem and the saddle-point solution by one solve
with its own matrix (:meth:`~mbcomp.analysis.reduced.Reduced.exact`; the values at the state
from the jet recursion): ``A`` is exact to the rounding of float64 (the bicycle's eigenvalues
within 1.1e-14 1/s of the benchmark recomputed in 40 digits). Without a program
(``backend="numeric"``, a law that cannot be traced) or where it does not hold at the state,
central differences with Richardson extrapolation (error ~1e-11);
:attr:`Linearization.derivatives` says which. The eigenvalues come from :func:`eigen`, which
deflates exact null directions first.

:func:`classify` follows seed Section 7.2: a real root > 0 or a complex root with positive
real part is unstable; roots on the imaginary axis (the rest stable) are marginally stable;
all real parts negative is asymptotically stable.

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

from dataclasses import dataclass, field

import numpy as np

from ..assembly.initialization import initialize
from ..errors import SimulationError
from .evaluation import system_for
from .reduced import Reduced, direction_names
from .steady import SteadyState

__all__ = ["Linearization", "linearize", "classify", "zero_tolerance", "eigen", "DERIVATIVES"]

#: how :func:`linearize` differentiates: ``"auto"`` (exact where a generated program
#: evaluates the model, else differences), ``"exact"`` (always; an error where impossible),
#: ``"differences"`` (central differences with Richardson extrapolation)
DERIVATIVES = ("auto", "exact", "differences")


def zero_tolerance(eigenvalues):
    """The classification's zero for a set of eigenvalues (1/s): ``1e-7 (1 + max |lambda|)``,
    the accuracy of the linearization; a real part within it counts as zero (:func:`classify`).

    Examples
    --------
    >>> from mbcomp.analysis.linearization import zero_tolerance
    >>> print(zero_tolerance([3j, -3j]), zero_tolerance([]))     # max |lambda| = 3
    4e-07 1e-07
    """
    return 1e-7 * (1.0 + (np.abs(eigenvalues).max() if len(eigenvalues) else 0.0))


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
    tol = zero_tolerance(eigs) if tol is None else tol
    top = eigs.real.max()
    if top > tol:
        return "unstable"
    if top >= -tol:
        return "marginally stable"
    return "asymptotically stable"


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
    derivatives : {"exact", "differences"}
        How ``A`` was differentiated: from the generated evaluation's tangent program
        (exact to rounding) or by central differences with Richardson extrapolation (error
        ~1e-11 relative).

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
    derivatives: str = "differences"

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
        """Text: the states, the classification, how ``A`` was differentiated, the moving
        and removed directions, then :meth:`modes`."""
        head = [f"linearization: {len(self.state_names)} states ({', '.join(self.state_names)})",
                f"classification: {self.classification}",
                "derivatives: " + ("exact (the evaluation's tangent program)" if self.derivatives == "exact"
                                   else "central differences with Richardson extrapolation")]
        if self.moving:
            head.append(f"moving at constant rates (cyclic, not states): {', '.join(self.moving)}")
        if self.removed:
            head.append(f"removed (influence nothing; one zero root each): {', '.join(self.removed)}")
        return "\n".join(head + ["eigenvalues (1/s), dominant states:", self.modes()])

    def to_dict(self):
        return dict(state_names=self.state_names, A=self.A.tolist(),
                    eigenvalues=[[float(e.real), float(e.imag)] for e in self.eigenvalues],
                    classification=self.classification, removed=self.removed, moving=self.moving,
                    derivatives=self.derivatives)


def linearize(model, state=None, params=None, t=None, remove_ignorable=True, backend="python", derivatives="auto"):
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
    derivatives : {"auto", "exact", "differences"}
        How ``A`` is differentiated (:data:`DERIVATIVES`): ``"auto"`` uses the exact
        derivatives of the generated evaluation (:mod:`mbcomp.codegen.eval_tangent`) whenever
        a program evaluates the model (every backend but ``"numeric"``) and holds at the
        state, else central differences; ``"exact"`` asks for them with any backend and raises
        where there are none; ``"differences"`` always differences.
        :attr:`Linearization.derivatives` says which was used.

    Returns
    -------
    Linearization

    Raises
    ------
    SimulationError
        The state is not steady (names the largest acceleration), or a moving coordinate
        is not cyclic (the motion is not an equilibrium in these coordinates), or
        ``derivatives="exact"`` and the model has no exact derivatives at the state.
    """
    if derivatives not in DERIVATIVES:
        raise ValueError(f"linearize: derivatives={derivatives!r} is unknown; use one of {', '.join(DERIVATIVES)}")
    system = system_for(model, params, backend)
    state = _steady_state(system, state, t)
    if system.row_mask is None:
        initialize(system, state.t)
    red = Reduced(system, state.t if t is None else float(t), state.q, state.u)
    dnames = direction_names(system)
    names = [dnames[i] for i in red.pind] + [system.u_names[i] for i in red.vind]
    moving = [dnames[i] for i in red.moving]
    f0 = red.rate(np.zeros(red.n))
    uscale = max(1.0, float(np.abs(state.u).max(initial=0.0)))
    _check_steady(f0, uscale, names, moving)
    scale = np.concatenate((np.ones(red.pind.size), np.full(red.vind.size, uscale)))
    exact = _exact(system, red, derivatives)
    if exact is not None:
        A, Am = exact
        how = "exact"
    else:
        A = red.jacobian(red.rate, red.n, scale)
        Am = None
        how = "differences"
    _check_cyclic(red, A, moving, Am)
    removed = _ignorable(red, A, f0, scale) if remove_ignorable and A.size else []
    keep = [j for j in range(len(names)) if j not in removed]
    A = A[np.ix_(keep, keep)]
    lam, V = eigen(A)
    return Linearization(A, [names[j] for j in keep], lam, V, classify(lam), [names[j] for j in removed], moving,
                         state, how)


def _exact(system, red, derivatives):
    """``(A, A_moving)`` from the evaluation's derivative program
    (:mod:`mbcomp.codegen.eval_tangent`), or None: asked for differences, a numeric system
    under ``"auto"``, or no exact derivative at this state (a failed guard, a non-finite
    entry, a singular block). Raises for ``derivatives="exact"`` when there is none."""
    if derivatives == "differences" or (derivatives == "auto" and system.backend == "numeric"):
        return None
    from ..codegen import CodegenError
    from ..codegen.eval_tangent import eval_tangent

    why = None
    try:
        dev = eval_tangent(system, "c" if system.backend == "c" else "python")
    except CodegenError as exc:
        dev, why = None, str(exc)
    out = red.exact(dev) if dev is not None else None
    if out is None and derivatives == "exact":
        raise SimulationError("linearize: no exact derivatives for this model at this state ("
                              + (why or "the derivative program does not hold here: a law's branch, a non-finite "
                                        "value or a singular block") + ") -> use derivatives='auto' or 'differences'")
    return out


def eigen(A):
    """Eigenvalues (sorted by decreasing real part, then imaginary part) and unit eigenvectors
    of the state matrix ``A``, its exact null directions deflated first.

    A direction ``A`` maps to zero to rounding (singular value at most ``n eps`` of the
    largest: a family of steady states, such as a rolling disk's steady turns) is a zero root
    exactly; the other roots are those of ``A`` restricted to the orthogonal complement
    ``W^T A W`` (``[V W]^T A [V W]`` is block upper triangular when ``A V = 0``). Near a
    collision with the zero root the full eigenproblem is ill-conditioned: at a spin 1e-9
    from the rolling disk's critical one, LAPACK moved the zero root of the 3 x 3 ``A`` to
    +2.9e-7 1/s (an unstable root) depending on the last bit of one entry; deflated, it stays
    0 and the colliding pair is ``+-sqrt`` of the restricted matrix's exact-to-rounding square.
    The deflation is at the eigensolver's own backward error, so it loses nothing.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.analysis.linearization import eigen
    >>> lam, V = eigen(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -2.0], [8.0, 4.0, 0.0]]))
    >>> lam.tolist()          # 0 and +-sqrt(8 - 2 * 4): a triple root at zero, two of it defective
    [0j, 0j, 0j]
    >>> lam, V = eigen(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -2.0], [9.0, 4.0, 0.0]]))
    >>> np.round(lam.real, 12).tolist(), lam[1] == 0   # +-sqrt(9 - 8), and the zero root exactly
    ([1.0, 0.0, -1.0], np.True_)
    >>> bool(np.allclose(np.array([[0, 0, 1], [0, 0, -2], [9, 4, 0]]) @ V, V * lam))
    True
    """
    n = A.shape[0]
    if not n:
        return np.zeros(0, complex), np.zeros((0, 0), complex)
    _, sv, Vt = np.linalg.svd(A)
    k = int(np.count_nonzero(sv <= n * np.finfo(float).eps * sv[0]))
    if k == 0:
        lam, X = np.linalg.eig(A)
    else:
        N, W = Vt[n - k:].T, Vt[: n - k].T  # null directions, their orthogonal complement
        mu, Y = np.linalg.eig(W.T @ A @ W) if n > k else (np.zeros(0, complex), np.zeros((0, 0), complex))
        # an eigenvector W y of the restriction is one of A with a part N z, z = N^T A W y / mu
        tiny = np.abs(mu) <= n * np.finfo(float).eps * sv[0]
        Z = (N.T @ A @ W @ Y) / np.where(tiny, 1.0, mu)
        Z[:, tiny] = 0.0
        lam = np.concatenate((np.zeros(k, complex), mu))
        X = np.hstack((N.astype(complex), W @ Y + N @ Z))
        X /= np.linalg.norm(X, axis=0)
    order = np.lexsort((-lam.imag, -lam.real))
    return lam[order], X[:, order]


def _steady_state(system, state, t):
    """``state`` as a :class:`SteadyState` (default: the system's consistent start state)."""
    if state is None:
        init = initialize(system, 0.0 if t is None else t)
        return SteadyState(init.q, init.u, 0.0 if t is None else float(t), {}, np.nan, "the model's start state")
    if not isinstance(state, SteadyState):
        q, u = state
        return SteadyState(np.asarray(q, float), np.asarray(u, float), 0.0 if t is None else float(t), {}, np.nan,
                           "given")
    return state


def _check_steady(f0, uscale, names, moving):
    """Refuse a state whose rates ``f0`` do not vanish, naming the largest and the likely cause."""
    acc_tol = 1e-7 * uscale * (1.0 + uscale)
    if not f0.size or np.abs(f0).max() <= acc_tol:
        return
    k = int(np.argmax(np.abs(f0)))
    hint = "find the steady state first (mbcomp.stability.steady_states or --steady)"
    turning = [n for n in moving if ".rot." in n]
    if turning:  # body-axis speeds of a quaternion joint turn with the body in any steady rotation
        hint = ("if the motion is steady (e.g. a steady precession), it is not steady in these coordinates: "
                f"{', '.join(turning)} turn(s) the body-axis speeds of a quaternion joint, so no steady state "
                "exists here -> model the motion with Revolute chains whose angles are cyclic (precession, "
                "nutation, spin); otherwise " + hint)
    raise SimulationError(f"not a steady state: d/dt of {names[k]} is {f0[k]:.3g} (all must vanish) -> {hint}")


def _check_cyclic(red, A, moving, Am=None):
    """The motion is an equilibrium only if the moving coordinates are cyclic: their values
    must not change any rate (``Am``: the rates' derivatives along them, differenced if None)."""
    if not red.moving.size:
        return
    if Am is None:
        Am = red.jacobian(lambda y: red.rate(np.zeros(red.n), moving=y), red.moving.size, np.ones(red.moving.size))
    bad = np.abs(Am).max(axis=0) if Am.size else np.zeros(0)
    lim = 1e-6 * (1.0 + np.abs(A).max(initial=0.0))
    if bad.size and bad.max() > lim:
        k = int(np.argmax(bad))
        raise SimulationError(
            f"not a steady motion in these coordinates: {moving[k]} moves at a constant rate but the dynamics "
            f"depend on its value (sensitivity {bad[k]:.3g}) -> model that motion with a joint whose angle is "
            "cyclic (e.g. Revolute chains for precession and spin instead of a Spherical/FreeMotion quaternion)")


def _ignorable(red, A, f0, scale):
    """Indices of the states that influence nothing, in the order they were removed: a zero
    column of ``A`` among the kept rows, confirmed by a finite perturbation."""
    lim = 1e-7 * (1.0 + np.abs(A).max())
    flim = 1e-10 * (1.0 + np.abs(A).max())
    keep = list(range(A.shape[1]))
    removed = []

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
                removed.append(j)
                changed = True
    return removed
