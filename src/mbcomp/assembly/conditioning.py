"""Is the mass matrix of the admissible motions invertible, and how well?

At the consistent start, initialization restricts the mass matrix ``M`` to the motions the
constraints allow (``Mr = N^T M N``, ``N`` a null-space basis of the constraint Jacobian) and
looks at its eigenvalues ``w_1 <= ... <= w_n`` relative to the largest, ``w_n``:

* ``w_i <= MASSLESS * w_n`` -- a massless direction: ``M`` is known only to roundoff (every
  entry is a sum of products of masses, inertias and lever arms, each rounded at ``eps``
  relative to the largest, and ``N`` carries the rounding of its own decomposition), so a
  smaller eigenvalue cannot be told from zero and the accelerations along it are
  undetermined. Every such direction is listed (a point mass floating freely has three
  massless rotations), one problem each, and initialization fails.
* ``MASSLESS * w_n < w_1 < ILL_CONDITIONED * w_n`` -- a finite but extreme ratio (a 1 mg part on
  a 10 kg body): the solve loses about ``log10(w_n / w_1)`` of the 16 digits, more than half
  of them. The run goes on, with a warning naming the lightest and heaviest bodies and the
  ratio (and a note in :attr:`InitialState.notes`).

``MASSLESS = 1e-12`` is about 4500 ``eps``: the roundoff of a mass matrix summed over a few
dozen bodies, with margin for the null-space basis. ``ILL_CONDITIONED = sqrt(eps)`` (1.5e-8)
is where fewer than half the digits remain -- the accuracy a tight integration asks for
(``rtol = 1e-8``), so beyond it the tolerance may no longer be met.

Examples
--------
>>> import numpy as np
>>> from mbcomp.assembly.conditioning import directions
>>> massless, ratio = directions(np.diag([1.0, 1e-10, 0.0]))  # one massless direction
>>> massless.shape[1], ratio
(1, None)
>>> massless, ratio = directions(np.diag([1.0, 1e-10]))  # extreme but finite: a warning
>>> massless.shape[1], ratio
(0, 1e-10)
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from ..errors import InitializationError, Problem
from .recursive import mass_matrix, speed_columns, tree_pass

__all__ = ["MASSLESS", "ILL_CONDITIONED", "directions", "check_inertia", "check_tree_inertia", "moving_scale",
           "tree_moving_scale"]

EPS = np.finfo(float).eps
MASSLESS = 1e-12
ILL_CONDITIONED = float(np.sqrt(EPS))
#: how far above ``ILL_CONDITIONED`` the eigenvalues without vectors decide alone (their
#: rounding, ``n eps`` of the largest, is far below this margin)
SCREEN = 2.0


def directions(Mr, scale=0.0):
    """Massless directions of the symmetric positive semi-definite ``Mr`` and its conditioning.

    Parameters
    ----------
    Mr : ndarray (n, n)
        The mass matrix of the admissible motions (kg, kg m, kg m^2 by coordinate).
    scale : float
        The size of the masses and inertias that move (:func:`moving_scale`): the roundoff
        of ``Mr`` is relative to it even when every eigenvalue is that roundoff (a point mass
        on a hinge's axis 1 m from the origin: ``6 kg (1e-16 m)^2``, no larger eigenvalue to
        compare with).

    Returns
    -------
    massless : ndarray (n, k)
        Orthonormal basis of the directions whose eigenvalue is at most ``MASSLESS`` times
        the largest (all of them when the largest is 0).
    ratio : float or None
        Smallest over largest eigenvalue when no direction is massless and the ratio is below
        ``ILL_CONDITIONED``; else ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.assembly.conditioning import directions
    >>> directions(np.diag([2.0, 1.0]))[0].shape, directions(np.diag([2.0, 1.0]))[1]
    ((2, 0), None)
    """
    sym = 0.5 * (Mr + Mr.T)
    # the eigenvalues alone first (a third of the work): they differ from eigh's by rounding
    # (n eps of the largest), so only a matrix far from both limits is decided by them (its
    # ratio, if ill-conditioned, theirs); any other takes eigh's values and vectors
    w = np.linalg.eigvalsh(sym)
    top = max(w[-1] if w.size else 0.0, scale, 0.0)
    if top > 0.0 and w[0] > SCREEN * ILL_CONDITIONED * top:
        return np.zeros((len(w), 0)), None
    if top > 0.0 and SCREEN * MASSLESS * top < w[0] < ILL_CONDITIONED * top / SCREEN:
        # far from both limits on the ill-conditioned side: the same decision, the ratio from these
        # values (a long chain: eigh's vectors were 0.1 s of a 1000-link start)
        return np.zeros((len(w), 0)), float(w[0] / top)
    w, V = np.linalg.eigh(sym)
    top = max(w[-1] if w.size else 0.0, scale, 0.0)
    small = w <= MASSLESS * top
    if small.any() or top == 0.0:
        return V[:, small | (top == 0.0)], None
    ratio = w[0] / top
    return V[:, :0], (float(ratio) if ratio < ILL_CONDITIONED else None)


def check_inertia(system, ev):
    """Raise on massless directions; warn (and return notes) on an extreme mass ratio.

    Parameters
    ----------
    system : MultibodySystem
    ev : Evaluation
        At the consistent start (``ev.M``, ``ev.A``).

    Returns
    -------
    list of str
        Notes for the run (an ill-conditioning warning's text), possibly empty.

    Raises
    ------
    InitializationError
        One problem per massless direction, named by the coordinate that best represents it.
    """
    if system.nu == 0:
        return []
    C = ev.A
    N = sla.null_space(C) if C.size else np.eye(system.nu)
    if N.shape[1] == 0:
        return []
    M = ev.M
    # no rows: N = I and N^T M N is M itself (a finite float M: the products add exact zeros)
    plain = not C.size and isinstance(M, np.ndarray) and M.dtype.kind == "f" and np.isfinite(M).all()
    Mr = M if plain else N.T @ M @ N
    return _decided(system, Mr, moving_scale(system, ev.jets), N)


def check_tree_inertia(system, t, q, u):
    """:func:`check_inertia` of a system without constraint rows (a tree: ``N = I``) from one
    kinematic pass of the recursive algorithms instead of the dense evaluation: the same
    mass matrix to rounding by the composite-rigid-body algorithm (one product of the links'
    motion subspaces with their composite inertias, kept where one link is the other's
    ancestor: O(N^2) numbers in numpy, not O(N^2) jet columns in Python) and the same
    :func:`moving_scale`, then the same decisions (:func:`directions`). At N = 1000 links
    0.1 s instead of 0.6 s.

    Parameters
    ----------
    system : MultibodySystem
        Without cut joints, flange constraints or nonholonomic rows.
    t : float
        Time (s).
    q, u : ndarray
        The start (coordinates, speeds).

    Returns
    -------
    list of str
        As :func:`check_inertia`.

    Raises
    ------
    InitializationError
        As :func:`check_inertia`.
    """
    if system.nu == 0:
        return []
    tp = tree_pass(system, t, q, u, forces=False)
    if speed_columns(tp, system.nu) is None:  # a speed no tree joint has: the dense way
        return check_inertia(system, system.evaluate(t, q, u))
    M = mass_matrix(tp, system.nu)
    return _decided(system, M, tree_moving_scale(system, tp))


def _decided(system, Mr, scale, N=None):
    """What :func:`check_inertia` says of the admissible motions' mass matrix ``Mr`` (speeds
    ``N`` times its coordinates; None: the speeds themselves): raises on massless directions,
    warns and returns the note on an extreme ratio, else ``[]``."""
    Z, ratio = directions(Mr, scale)
    if Z.shape[1]:
        raise _massless(system, Z if N is None else N @ Z)
    if ratio is None:
        return []
    note = _ill_conditioned(system, ratio)
    warnings.warn(f"mbcomp: {note}", RuntimeWarning, stacklevel=4)  # the caller of initialize's caller
    return [note]


def tree_moving_scale(system, tp):
    """:func:`moving_scale` from a kinematic pass (:func:`~mbcomp.assembly.recursive.tree_pass`):
    a body's Jacobian columns are its ancestor links' motion subspaces ``S = [w; v_O]`` (about
    the world origin O), so ``|J_w|^2`` sums ``|w|^2`` over them and ``|J_c|^2`` sums
    ``|v_O + w x c|^2 = |v_O|^2 + 2 c . (v_O x w) + |c|^2 |w|^2 - (c . w)^2`` (``c``: the body's
    centre, world): every body and column at once."""
    nu = system.nu
    bodies = tp.bodies  # (link, m, c, Iw) of the bodies on links, as the pass summed them
    if not bodies:
        return 0.0
    S, link = speed_columns(tp, nu)
    w, v = S[:3], S[3:]
    m = np.array([float(b[1]) for b in bodies])
    tr = np.array([float(b[3].trace()) for b in bodies])
    C = np.array([b[2] for b in bodies], float)
    blink = np.array([b[0] for b in bodies], int)
    on = tp.ancestry()[np.ix_(link, blink)].T  # (bodies, columns): the column moves the body
    w2 = (w * w).sum(axis=0)
    vxw = v[_NEXT] * w[_LAST] - v[_LAST] * w[_NEXT]  # numpy.cross(v.T, w.T).T's products and differences
    r2 = (C * C).sum(axis=1)
    jc = (v * v).sum(axis=0)[None, :] + 2.0 * C @ vxw + r2[:, None] * w2[None, :] - (C @ w) ** 2
    Jc2 = np.where(on, np.maximum(jc, 0.0), 0.0).sum(axis=1)
    Jw2 = np.where(on, w2[None, :], 0.0).sum(axis=1)
    moving = (Jc2 > 0.0) | (Jw2 > 0.0)
    return float(np.where(moving, m * (Jc2 + r2 * Jw2) + tr * Jw2, 0.0).sum())


def moving_scale(system, jets):
    """``sum m (|J_c|^2 + |r_cm|^2 |J_w|^2) + trace(I_cm) |J_w|^2`` over the bodies that move
    (``J_c``, ``J_w``: the Jacobians of the centre's velocity and of the angular velocity,
    Frobenius norms; SI units taken as numbers): the size of the entries the bodies give the
    mass matrix, which sets its roundoff. A turning body's lever arm ``r x w`` is rounded
    relative to its distance from the origin ``|r_cm|`` (a point mass on a hinge's axis 1 m
    from the origin has ``m (1e-16 m)^2`` about it: roundoff, not inertia); a body that only
    translates has no lever arm to round (a 1e10 kg slider 10 m out next to a 1 kg one is a
    stiff mass ratio, not a massless motion)."""
    moving = []  # (m, r . r, trace I, Jw, Jv, rho) of the bodies that move
    for path, comp, node in system.topology.bodies:
        J = jets[node]
        Jw, Jv = _columns(J.Jw), _columns(J.Jv)
        if not (Jv.any() or Jw.any()):
            continue
        m, rc, I = comp.mass_properties(system.P[path])
        rho = J.R.dot(np.asarray(rc, float))
        r = J.r + rho
        moving.append((float(m), float(r.dot(r)), float(np.asarray(I, float).trace()), Jw, Jv, rho))
    if not moving:
        return 0.0
    # every body at once: v_c = v + w x rho column by column (numpy.cross's products and
    # differences, rows permuted), the squares summed per body (each body's block a row: the
    # same sums as the body's own)
    Jw = np.stack([b[3] for b in moving])
    rho = np.array([b[5] for b in moving])[:, :, None]
    wxr = Jw[:, _NEXT] * rho[:, _LAST] - Jw[:, _LAST] * rho[:, _NEXT]
    Jc = np.stack([b[4] for b in moving]) + wxr
    k = len(moving)
    w2 = (Jw * Jw).reshape(k, -1).sum(axis=1).tolist()
    c2 = (Jc * Jc).reshape(k, -1).sum(axis=1).tolist()
    total = 0.0
    for (m, rr, tr, *_), w2k, c2k in zip(moving, w2, c2):
        total += m * (c2k + rr * w2k) + tr * w2k
    return total


#: the rows of a cross product's two terms: (w x r)_i = w_{i+1} r_{i+2} - w_{i+2} r_{i+1}
_NEXT, _LAST = np.array([1, 2, 0]), np.array([2, 0, 1])


def _columns(J):
    """A jet's Jacobian as a float array of three rows (numpy.atleast_2d's, without its calls where it is one)."""
    return J if type(J) is np.ndarray and J.dtype == float and J.ndim == 2 else np.atleast_2d(np.asarray(J, float))


def _massless(system, modes):
    """One problem per massless direction (columns of ``modes``, speeds coordinates)."""
    k = modes.shape[1]
    _, _, piv = sla.qr(modes.T, pivoting=True, mode="economic")
    names = system.u_names
    probs = []
    for i in range(k):
        j = piv[i]
        mode = modes[:, i]
        also = [names[m] for m in np.argsort(-np.abs(mode)) if m != j and abs(mode[m]) > 1e-6][:3]
        with_ = f" (moving with {', '.join(also)})" if also else ""
        turn = system.topology.u_units[j] == "rad/s"
        give = ("mass away from the axis or rotational inertia (a PointMass has none of its own: use a "
                "RigidBody with I)" if turn else "mass")
        probs.append(Problem(names[j], f"this {'rotation' if turn else 'motion'}{with_} carries no mass or "
                                       "inertia, so its acceleration is undetermined",
                             f"give the bodies it moves {give}, or prescribe the motion with a drive"))
    return InitializationError(probs, header="the mechanism has massless degrees of freedom")


def _ill_conditioned(system, ratio):
    """Text of the warning for a finite but extreme smallest/largest eigenvalue ratio."""
    masses = []
    for path, comp, _ in system.topology.bodies:
        m = float(comp.mass_properties(system.P[path])[0])
        if m > 0:
            masses.append((m, path))
    bodies = ""
    if len(masses) > 1:
        (m_lo, lo), (m_hi, hi) = min(masses), max(masses)
        bodies = f"; lightest body {lo} ({m_lo:.3g} kg), heaviest {hi} ({m_hi:.3g} kg), mass ratio {m_hi / m_lo:.3g}"
    digits = int(round(-np.log10(ratio)))
    return (f"the mass matrix is ill-conditioned: its smallest eigenvalue is {ratio:.3g} of its largest"
            f"{bodies}; accelerations lose about {digits} of 16 digits -> make the light part heavier or lump it "
            "into the body it rides on, or check the mass units (g vs kg)")
