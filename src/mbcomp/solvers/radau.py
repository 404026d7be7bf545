"""Radau IIA of order 5 (3 stages) for semi-explicit DAEs ``E dy/dt = fun(t, y)`` of index <= 3.

The method and its implementation follow Hairer & Wanner, *Solving Ordinary Differential
Equations II*, sec. IV.8 and VI/VII (the code RADAU5); every coefficient below is derived
at import time from the method's definition (collocation at the Radau points
``c = ((4 - sqrt 6)/10, (4 + sqrt 6)/10, 1)``) rather than typed in.

Stage equations
    With ``Z_i = Y_i - y0`` the collocation conditions read
    ``(A^{-1} (x) E) Z = h F(Z)``, ``F_i = fun(t0 + c_i h, y0 + Z_i)``. They are solved by
    simplified Newton iterations with the matrix ``A^{-1} (x) E - h I (x) J``; the
    transformation ``T^{-1} A^{-1} T = diag(gamma, [[alpha, -beta], [beta, alpha]])``
    decouples it into one real system ``(gamma/h) E - J`` and one complex system
    ``((alpha + i beta)/h) E - J`` of size ``n``.
Error estimate
    ``err = ((gamma/h) E - J)^{-1} (fun(t0, y0) + E (d_1 Z_1 + d_2 Z_2 + d_3 Z_3)/h)``: the
    difference to an embedded order-3 formula that uses ``fun(t0, y0)``, filtered through the
    real iteration matrix (the filter keeps the estimate bounded for stiff components and
    for the algebraic ones). After a rejection or on the first step the estimate is
    re-filtered once with ``fun(t0, y0 + err)`` (RADAU5's improvement for very stiff
    problems). Index-2 components are weighted by ``h`` and index-3 components by ``h**2``
    before the scaled RMS norm is taken (Hairer, Lubich & Roche), because their local errors
    are one and two powers of ``h`` larger than the differential ones.
Step size
    ``h_new = h * clip(fac * err**(-1/4), 1/5, 8)`` with a safety factor that shrinks with the
    number of Newton iterations used, combined with Gustafsson's predictive controller after
    accepted steps.
Jacobian and LU reuse (RADAU5's rule, Hairer & Wanner IV.8)
    After an accepted step the Jacobian is kept when Newton contracted faster than
    ``THETA_JAC`` (rate ``theta``; one iteration counts as converged at once), else a new one
    is formed at the new point. With the Jacobian kept and ``h_new / h`` in ``QUOT_KEEP``
    (``[1, 1.2]``) ``h`` is kept too, and so are the LU factors of both iteration matrices;
    otherwise they are factored again at ``h_new``. After a failed attempt (error test,
    Newton divergence or slow convergence, singular matrix) ``h`` shrinks and the matrices
    are factored again -- with a new Jacobian first when the current one is stale (formed at
    an earlier point), with the same one when it is up to date. The factors:
    :mod:`mbcomp.solvers.radau_linalg`; what a step costs and why almost every attempt
    factors on the stiff spring chain's DAE: ``docs/design/equations.md``, *radau5's cost*.
Dense output
    The collocation polynomial (degree 3) through ``y0`` and the three stage values.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from mbcomp.solvers.radau import Radau5
>>> Radau5.capabilities()
{'implicit': True, 'adaptive': True, 'one_step': True, 'max_index': 3, 'problem': 'dae'}
"""
from __future__ import annotations

import math

import numpy as np

from .base import StepFailure, Stepper
from .compiled_radau import CompiledRadau5
from .radau_linalg import IterationMatrices, SingularMatrix

__all__ = ["Radau5", "RadauDenseOutput"]

EPS = np.finfo(float).eps


# ==========================================================================================
# method coefficients, derived from the collocation definition
# ==========================================================================================
def _radau_iia_coefficients():
    """Coefficients of the 3-stage Radau IIA method and of its RADAU5 implementation.

    Returns
    -------
    dict
        ``c`` (3,) nodes; ``A`` (3, 3) Butcher matrix; ``T``, ``TI`` (3, 3) with
        ``TI @ inv(A) @ T = LAM``; ``LAM`` (3, 3) block form; ``gamma`` real eigenvalue of
        ``inv(A)``; ``mu`` complex eigenvalue ``alpha + i beta`` used in the complex system;
        ``d`` (3,) error-estimate weights; ``P`` (3, 3) collocation-polynomial coefficients:
        ``y(t0 + s h) = y0 + sum_i Z_i sum_k P[i, k] s**(k+1)``.
    """
    s6 = np.sqrt(6.0)
    c = np.array([(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0])
    # Lagrange basis l_j on the nodes; A_ij = int_0^{c_i} l_j(s) ds
    A = np.empty((3, 3))
    for j in range(3):
        others = np.delete(c, j)
        poly = np.poly1d(others, r=True) / np.prod(c[j] - others)
        integ = np.polyint(poly)
        A[:, j] = integ(c) - integ(0.0)
    b = A[2].copy()  # stiffly accurate: b = last row of A
    Ainv = np.linalg.inv(A)
    lam, vec = np.linalg.eig(Ainv)
    ireal = int(np.argmin(np.abs(lam.imag)))
    icplx = int(np.argmin(lam.imag))  # eigenvalue alpha - i beta (beta > 0)
    gamma = float(lam[ireal].real)
    v1 = vec[:, ireal].real
    v2 = vec[:, icplx]
    T = np.column_stack([v1 / np.max(np.abs(v1)), v2.real, v2.imag])
    TI = np.linalg.inv(T)
    LAM = TI @ Ainv @ T
    LAM[np.abs(LAM) < 1e-13] = 0.0
    # complex block [[a, b], [-b, a]] -> system ((a - i b)/h) E - J  (see _newton)
    mu = complex(LAM[1, 1], -LAM[1, 2])
    # embedded order-3 formula with nodes (0, c1, c2, c3) and bhat_0 = gamma0 = 1/gamma
    gamma0 = 1.0 / gamma
    V = np.vstack([np.ones(3), c, c ** 2])
    bhat = np.linalg.solve(V, np.array([1.0 - gamma0, 0.5, 1.0 / 3.0]))
    e = (bhat - b) @ Ainv  # yhat - y = gamma0 h f0 + sum_j e_j Z_j
    d = gamma * e  # scaled to the form (gamma/h E - J)^{-1} (f0 + E sum d_j Z_j / h)
    # collocation polynomial: L_i(s) = sum_k P[i, k] s**(k+1), L_i(c_j) = delta_ij
    Vc = np.column_stack([c, c ** 2, c ** 3])  # Vc[j, k] = c_j**(k+1)
    P = np.linalg.inv(Vc.T)
    return dict(c=c, A=A, b=b, T=T, TI=TI, LAM=LAM, gamma=gamma, mu=mu, d=d, P=P)


_COEF = _radau_iia_coefficients()
C = _COEF["c"]
T = _COEF["T"]
TI = _COEF["TI"]
LAM = _COEF["LAM"]
GAMMA = _COEF["gamma"]
MU = _COEF["mu"]
D_ERR = _COEF["d"]
P_DENSE = _COEF["P"]
C1, C2, C3 = (float(c) for c in C)  # the nodes as Python floats: the stage times in float arithmetic
_P_DENSE_T = np.ascontiguousarray(P_DENSE.T)

NEWTON_MAXITER = 7  # RADAU5's NIT
#: Reuse the Jacobian when Newton contracts faster than this (RADAU5's THET: 1e-3 for cheap
#: Jacobians, 0.1 for costly ones). A differenced Jacobian costs nq + nu evaluations, a Newton
#: iteration 3. bench/radau_reuse.py, rtol 1e-8, evaluations at 1e-3 / 0.01 / 0.03 / 0.1: 4-link
#: chain (index 1) 30.3k / 22.7k / 23.9k / 29.4k (1634 / 391 / 148 / 54 Jacobians); four-bar near
#: flat (index 3) 12.4k / 12.0k / 10.8k / 11.2k; slider-crank (3 s) index 3 25.0k / 23.3k / 21.9k
#: / 23.8k, index 1 40.5k / 37.4k / 35.2k / 41.9k; at 0.1 rejections double or triple. Exact
#: Jacobians (codegen/dae_jacobian.py, ~3 evaluations each; bench/stiff_jacobians.py) at 1e-3-0.01:
#: 1-8 % fewer evaluations at index 3, up to 6x the Jacobians, 60 % more time at index 1: it stays.
THETA_JAC = 0.03
SAFETY = 0.9
FAC_MAX = 8.0  # largest step increase
FAC_MIN = 0.2  # largest step decrease after an error-test rejection
QUOT_KEEP = (1.0, 1.2)  # keep h (and the LU factors) when h_new/h lies in here
MAX_SINGULAR = 5  # consecutive singular iteration matrices before giving up
MAX_FAILURES = 60  # consecutive failed attempts within one step before giving up
#: shortest default first step (s), RADAU5's default ``H``: see ``_initial_step``
H_START = 1e-6


def _all_finite(x, zeros):
    """Whether every entry of the 1-d array ``x`` is finite (``zeros``: >= ``x.size`` zeros): ``x . 0``
    is 0 then, NaN if one is infinite or NaN (a third of ``np.isfinite(x).all()``'s cost)."""
    return not math.isnan(x.dot(zeros[: x.size]))


class RadauDenseOutput:
    """The collocation polynomial of one Radau IIA step, ``y(t)`` for ``t`` in ``[t_old, t]``.

    Parameters
    ----------
    t_old, h : float
        Start (s) and length (s) of the step.
    y_old : ndarray (n,)
        State at ``t_old``.
    Z : ndarray (3, n)
        Stage increments ``Y_i - y_old`` at ``t_old + c_i h``.

    Notes
    -----
    Calling with a scalar ``t`` returns shape ``(n,)``; with an array of ``m`` times, shape
    ``(n, m)`` (as scipy's ``DenseOutput``). Evaluation outside the step extrapolates the
    polynomial (used internally to predict the next step's stages).
    """

    def __init__(self, t_old, h, y_old, Z):
        self.t_old, self.h = float(t_old), float(h)
        self.t_min, self.t_max = self.t_old, self.t_old + self.h
        self.y_old = np.array(y_old, dtype=float)
        self.Q = _P_DENSE_T.dot(Z)  # (3, n): y = y_old + sum_k Q[k] s**(k+1)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        s = (t - self.t_old) / self.h
        if t.ndim == 0:
            return self.y_old + self.Q.T @ np.array([s, s * s, s ** 3])
        powers = np.vstack([s, s * s, s ** 3])  # (3, m)
        return self.y_old[:, None] + self.Q.T @ powers

    def increments(self, t, h, y, out):
        """``y(t + c_i h) - y`` (3, n) at the three nodes of a step ``[t, t + h]``, written into
        ``out``: the next step's predicted stage increments (the numbers of
        ``(self(t + c h) - y[:, None]).T``, in fewer array calls)."""
        t0, h0 = self.t_old, self.h
        s1, s2, s3 = (((t + c * h) - t0) / h0 for c in (C1, C2, C3))
        p1, p2, p3 = np.power((s1, s2, s3), 3).tolist()  # numpy's power: the numbers of s ** 3
        powers = np.array(((s1, s1 * s1, p1), (s2, s2 * s2, p2), (s3, s3 * s3, p3)))
        np.add(self.y_old, powers.dot(self.Q), out)
        out -= y
        return out


class Radau5(Stepper):
    """Radau IIA of order 5 (RADAU5) for ``E dy/dt = fun(t, y)``, ``E = diag(mass)``, index <= 3.

    Implicit, L-stable, stiffly accurate collocation method with adaptive step size,
    simplified Newton iterations on the stage equations (real + complex decoupled systems),
    Jacobian reuse, and index-aware error control (index-2 errors weighted by ``h``, index-3
    errors by ``h**2``). See the module docstring for the algorithm.

    Parameters
    ----------
    problem : SemiExplicitDAE
        ``n``; ``mass`` (n,) diagonal of ``E`` (1 differential row, 0 algebraic row);
        ``index`` (n,) DAE index of each variable (1, 2 or 3); ``fun(t, y)`` -> (n,); and
        optionally ``jac(t, y)`` -> (n, n) ``d fun / d y`` (``None`` or absent: forward
        finite differences). Missing ``mass``/``index`` default to ones (an ODE).
    t0 : float
        Start time (s).
    y0 : array_like (n,)
        Consistent initial state (algebraic equations satisfied, for index 2 and 3 also the
        hidden constraints).
    t_bound : float
        End time (s); integration runs forward only (``t_bound > t0``).
    rtol, atol : float or array_like (n,)
        Relative and absolute tolerance; a component's weight is
        ``atol + rtol * max(|y_old|, |y_new|)`` (divided by ``h**(index-1)``).
    first_step : float, optional
        Initial step (s). Default: :meth:`_initial_step` (at least 1e-6 s).
    max_step : float, optional
        Largest step (s); default unbounded.

    Attributes
    ----------
    t, y, t_old, status
        As for :class:`~mbcomp.solvers.base.Stepper`.
    h : float
        Step size (s) the next step will try.
    stats : dict
        ``nsteps`` accepted steps, ``nreject`` rejected attempts (error test, Newton failure
        or singular matrix), ``nfev`` calls of ``fun`` (finite-difference Jacobians
        included), ``njev`` Jacobians, ``nlu`` LU factorizations (real and complex each
        count), ``nnewton`` Newton iterations, ``nfail_newton`` Newton failures,
        ``nfail_singular`` singular iteration matrices.

    Raises
    ------
    ValueError
        From the constructor on inconsistent shapes or an index outside 1..3.

    Notes
    -----
    :meth:`step` returns ``None`` or, on failure, the message of the :class:`StepFailure`
    (status ``"failed"``): a collapsed step size (with the reason of the last failed
    attempt), a singular iteration matrix (the DAE is of index > 3 or structurally
    singular), or non-finite values of ``fun``/``jac``.

    Examples
    --------
    Index-1 DAE ``y' = z``, ``0 = z + y`` (so ``y = exp(-t)``, ``z = -y``):

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from mbcomp.solvers.radau import Radau5
    >>> dae = SimpleNamespace(n=2, mass=np.array([1.0, 0.0]), index=np.array([1, 1]),
    ...                       fun=lambda t, y: np.array([y[1], y[1] + y[0]]),
    ...                       jac=lambda t, y: None)
    >>> s = Radau5(dae, 0.0, [1.0, -1.0], 2.0, rtol=1e-8, atol=1e-10)
    >>> while s.status == "running":
    ...     msg = s.step()
    >>> s.status, s.t, round(float(s.y[0]), 8), round(float(np.exp(-2.0)), 8)
    ('finished', 2.0, 0.13533528, 0.13533528)
    >>> bool(abs(s.y[1] + s.y[0]) < 1e-12)  # the algebraic equation holds at the step ends
    True
    >>> tm = 0.5 * (s.t_old + s.t)  # dense output inside the last step
    >>> bool(abs(s.dense_output()(tm)[0] - np.exp(-tm)) < 1e-8)
    True
    """

    implicit = True
    adaptive = True
    one_step = True
    max_index = 3
    problem = "dae"
    #: with the Lagrange formulation and no index asked for, the run steps the index-1 *ODE*
    #: (:meth:`on_ode`; ``E = I``, ``[q, u]``) rather than the index-1 DAE ``[q, u, a, lam]``:
    #: measured on the damped stiff spring chain (N = 10) the DAE takes 931 steps with 210
    #: Newton failures at rtol 1e-5 where the ODE takes 256 (0.74-0.82x scipy's Radau, against
    #: 1.53-1.87x); 0.70-0.76x on the 4-link chain (0.90-1.03x), 0.82-0.89x on the slider-crank
    #: (0.65-0.72x): ``bench/radau_vs_scipy.py``. ``index=1`` asks for the DAE.
    ode_by_default = True

    @classmethod
    def on_ode(cls):
        """This method stepping an ODE ``dy/dt = f(t, y)`` (``problem = "ode"``: every
        variable differential, index 1), as the Lagrange index-1 ODE asks for."""
        return _RADAU5_ODE

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf):
        super().__init__(problem, t0, y0, t_bound, rtol=rtol, atol=atol, first_step=first_step, max_step=max_step)
        n = self.y.size
        if self.y.ndim != 1 or n != int(getattr(problem, "n", n)):
            raise ValueError(f"Radau5: y0 has shape {self.y.shape}, the problem has n={getattr(problem, 'n', '?')}")
        self.n = n
        self.mass = np.array(getattr(problem, "mass", np.ones(n)), dtype=float).reshape(-1)
        self.index = np.array(getattr(problem, "index", np.ones(n, dtype=int)), dtype=int).reshape(-1)
        if self.mass.shape != (n,) or self.index.shape != (n,):
            raise ValueError("Radau5: problem.mass and problem.index must have shape (n,)")
        if np.any((self.index < 1) | (self.index > 3)):
            raise ValueError(f"Radau5: variable indices must be 1, 2 or 3, got {self.index.tolist()}")
        self.rtol = np.broadcast_to(np.asarray(rtol, dtype=float), (n,)).copy()
        self.atol = np.broadcast_to(np.asarray(atol, dtype=float), (n,)).copy()
        if np.any(self.rtol < 0) or np.any(self.atol < 0) or not np.all(self.rtol + self.atol > 0):
            raise ValueError("Radau5: tolerances must be >= 0 and not both zero")
        rmin = float(np.min(self.rtol)) if np.any(self.rtol > 0) else 1e-3
        self.newton_tol = max(10.0 * EPS / rmin, min(0.03, rmin ** 0.5))
        self.max_step = float(max_step)
        if not self.max_step > 0:
            raise ValueError("Radau5: max_step must be positive")
        self.stats.update(nnewton=0, nfail_newton=0, nfail_singular=0)
        self.h = None if first_step is None else float(first_step)
        if self.h is not None and not self.h > 0:
            raise ValueError("Radau5: first_step must be positive")
        self.f = None  # fun(t, y)
        self.J = None
        self.J_current = False  # J was evaluated at the current (t, y)
        self.lu = None  # IterationMatrices at the current J and self.lu.h
        self.faccon = 1.0  # Newton contraction factor carried between steps (RADAU5)
        self.theta = THETA_JAC
        self.first = True  # no step accepted yet
        self.h_acc = self.err_acc = None  # Gustafsson's controller memory
        self._dense = None  # collocation polynomial of the last accepted step
        self._hasjac = callable(getattr(problem, "jac", None))
        self._index_m1 = self.index - 1
        self._scaled = bool(np.any(self.index > 1))  # error weights depend on h
        self._ode = bool(np.all(self.mass == 1.0))  # E = I: the products with E are skipped
        # work arrays of a step (the stage increments Z, their transform W, the Newton
        # right-hand side and increment, the scaled increment): no allocation per iteration
        self._Z, self._W, self._R, self._dW, self._v, self._F = (np.empty((3, n)) for _ in range(6))
        self._zeros = np.zeros(3 * n)  # for _all_finite

    # ------------------------------------------------------------------ evaluations
    def _fun(self, t, y):
        self.stats["nfev"] += 1
        return np.asarray(self.prob.fun(t, y), dtype=float).reshape(self.n)

    def _fun_checked(self, t, y, what):
        f = self._fun(t, y)
        if not _all_finite(f, self._zeros):
            bad = np.flatnonzero(~np.isfinite(f)).tolist()
            raise StepFailure(f"Radau5: fun returned non-finite values at t={t:.17g} ({what}; components {bad})")
        return f

    def _jacobian(self):
        """``d fun / d y`` (n, n) at the current point: ``problem.jac`` or forward differences."""
        t, y = self.t, self.y
        self.stats["njev"] += 1
        J = self.prob.jac(t, y) if self._hasjac else None
        if J is not None:
            if hasattr(J, "toarray"):
                J = J.toarray()
            J = np.array(J, dtype=float)
            if J.shape != (self.n, self.n):
                raise ValueError(f"Radau5: problem.jac returned shape {J.shape}, expected {(self.n, self.n)}")
            if not np.all(np.isfinite(J)):
                raise StepFailure(f"Radau5: problem.jac returned non-finite values at t={t:.17g}")
        else:
            J = np.empty((self.n, self.n))
            f0 = self.f
            for j in range(self.n):
                delta = np.sqrt(EPS * max(1e-5, abs(y[j])))
                yp = y.copy()
                yp[j] += delta
                delta = yp[j] - y[j]  # exactly representable increment
                J[:, j] = (self._fun_checked(t, yp, "finite-difference Jacobian") - f0) / delta
        self.J, self.J_current = J, True
        self.lu = None  # factors of the old J are void

    def _factorize(self, h):
        self.lu = None
        self.lu = IterationMatrices(self.J, self.mass, GAMMA, MU, h, self._ode)
        self.stats["nlu"] += 2  # the real and the complex matrix

    def reset_state(self, y):
        """Continue from a modified state ``y`` at the current time (after a projection):
        refresh ``fun(t, y)``; the last collocation polynomial still serves as predictor."""
        self.y = np.array(y, dtype=float)
        self.f = self._fun_checked(self.t, self.y, "projected state")

    # ------------------------------------------------------------------ norms
    def _scale(self, h, abs_y, y_b=None):
        """Error weights (n,): ``atol + rtol*|y|``, divided by ``h**(index-1)``; ``|y|`` is
        ``abs_y`` (the step's start, computed once a step) or ``max(abs_y, |y_b|)``."""
        ya = abs_y if y_b is None else np.maximum(abs_y, np.abs(y_b))
        sc = self.atol + self.rtol * ya
        return sc / h ** self._index_m1 if self._scaled else sc

    @staticmethod
    def _norm(x, scale):
        """Scaled RMS norm ``sqrt(mean((x/scale)**2))`` (one dot product: np.mean's overhead
        was a tenth of the stepper's time)."""
        v = (x / scale).ravel()
        return math.sqrt(float(v.dot(v)) / v.size)

    # ------------------------------------------------------------------ initial step
    def _initial_step(self):
        """The first step (s): ``0.01 ||y|| / ||dy/dt||`` on the index-1 differential rows
        (weighted), at least :data:`H_START`, at most the span and ``max_step``. Speed rows
        (index 2 in the index-3 form) stay out: sized by a resting mechanism's accelerations
        the step (1e-9 s for Andrews) leaves the index-3 matrix singular (condition ~h^-3).
        A restart at a located root (a stop at ``phi = 0``) has round-off for ``||y||``: the
        ratio gave 1e-17 s and the door failed at its impact; a too long first step costs a
        rejection only."""
        span = self.t_bound - self.t
        diff = (self.mass != 0) & (self.index == 1)
        h0 = H_START
        if np.any(diff):
            sc = self.atol + self.rtol * np.abs(self.y)
            d0 = self._norm(self.y[diff], sc[diff])
            d1 = self._norm(self.f[diff] / self.mass[diff], sc[diff])
            if d0 > 1e-5 and d1 > 1e-5:
                h0 = max(H_START, 0.01 * d0 / d1)
        return min(h0, span, self.max_step)

    # ------------------------------------------------------------------ Newton
    def _newton(self, t, y, h, Z0, scale):
        """Simplified Newton iteration for the stage increments, from ``Z0`` (updated in place).

        Returns
        -------
        tuple
            ``(ok, Z (3, n), n_iter, info)``; on failure ``info`` is ``(reason, factor)`` with
            the suggested step-size factor, on success the contraction rate ``theta``.
        """
        Z, W, R, dW, v, F = Z0, self._W, self._R, self._dW, self._v, self._F  # Z0: _predict's work array
        TI.dot(Z, W)
        Mh = 1.0 / h if self._ode else self.mass / h  # E / h (E = I: the scalar, the same numbers)
        t1, t2, t3 = t + C1 * h, t + C2 * h, t + C3 * h
        fun, lu, stats = self.prob.fun, self.lu, self.stats
        vr = v.reshape(-1)  # a view
        faccon = max(self.faccon, EPS) ** 0.8
        theta = THETA_JAC
        dnorm_old = thq_old = None
        for k in range(NEWTON_MAXITER):
            stats["nnewton"] += 1
            stats["nfev"] += 3
            Y = y + Z  # a new array each iteration: fun may keep its argument
            F[0] = fun(t1, Y[0])
            F[1] = fun(t2, Y[1])
            F[2] = fun(t3, Y[2])
            TI.dot(F, R)  # ndarray.dot: the numbers of @, a third of its call cost
            LAM.dot(W, v)
            v *= Mh
            R -= v
            lu.solve_stages(R, dW)
            np.divide(dW, scale, v)
            dnorm = math.sqrt(float(vr.dot(vr)) / vr.size)  # the scaled RMS norm (_norm)
            if not math.isfinite(dnorm):  # a non-finite F gives a non-finite increment
                if not np.isfinite(F).all():
                    return False, Z, k + 1, ("fun returned non-finite values at a Newton iterate", 0.5)
                return False, Z, k + 1, ("the Newton increment is not finite", 0.5)
            if k >= 1:
                thq = dnorm / dnorm_old if dnorm_old > 0 else 0.0
                theta = thq if k == 1 else math.sqrt(thq * thq_old)
                thq_old = thq
                if theta < 0.99:
                    faccon = theta / (1.0 - theta)
                    # predicted error after the remaining iterations
                    dyth = faccon * dnorm * theta ** (NEWTON_MAXITER - 1 - k) / self.newton_tol
                    if dyth >= 1.0:
                        qnewt = max(1e-4, min(20.0, dyth))
                        fac = 0.8 * qnewt ** (-1.0 / (4 + NEWTON_MAXITER - 1 - k))
                        return False, Z, k + 1, (f"Newton converges too slowly (rate {theta:.3g})", fac)
                else:
                    return False, Z, k + 1, (f"Newton diverges (rate {theta:.3g})", 0.5)
            dnorm_old = dnorm
            W += dW
            T.dot(W, Z)
            if faccon * dnorm <= self.newton_tol:
                self.faccon = faccon
                return True, Z, k + 1, theta
        return False, Z, NEWTON_MAXITER, (f"no convergence in {NEWTON_MAXITER} Newton iterations", 0.5)

    # ------------------------------------------------------------------ one step
    def _fail(self, h, kind, reason, n_fail):
        """Raise the :class:`StepFailure` of a collapsed step size, naming the last cause."""
        t = self.t
        if kind == "newton":
            msg = (f"Radau5: Newton iteration failed to converge at t={t:.17g} with h={h:.3g} "
                   f"(step size collapsed): {reason} ({n_fail} consecutive failed attempts)")
        elif kind == "error":
            msg = (f"Radau5: step size collapsed at t={t:.17g} with h={h:.3g}: the local error test "
                   f"keeps failing (last {reason}; {n_fail} consecutive failed attempts)")
        elif kind == "singular":
            msg = (f"Radau5: the iteration matrix is singular at t={t:.17g} with h={h:.3g} (step size "
                   f"collapsed; the DAE is not of index <= 3 or a constraint lost rank): {reason}")
        else:
            msg = (f"Radau5: step size collapsed at t={t:.17g}: h={h:.3g} is below 1e-14*|t| without a "
                   f"failed attempt in this step (the solution blows up or is not smooth there)")
        raise StepFailure(msg)

    def _step(self):
        t, y = self.t, self.y
        if self.f is None:
            self.f = self._fun_checked(t, y, "initial state")
        if self.h is None:
            self.h = self._initial_step()
        h = min(self.h, self.max_step)
        kind, reason, history = "none", "", ""
        n_fail = n_singular = 0
        abs_y, scale = np.abs(y), None
        while True:
            hmin = 1e-14 * abs(t)
            if h <= hmin or n_fail >= MAX_FAILURES:
                self._fail(h, kind, reason, n_fail)
            last = t + 1.0001 * h >= self.t_bound
            if last:
                h = self.t_bound - t
            elif t + 2.0 * h > self.t_bound:
                # no sliver of a last step: an index-3 multiplier's error grows as the step shrinks
                h = 0.5 * (self.t_bound - t)
            if self.J is None:
                self._jacobian()
            if self.lu is None or h != self.lu.h:
                try:
                    self._factorize(h)
                except SingularMatrix as exc:
                    self.stats["nfail_singular"] += 1
                    self.stats["nreject"] += 1
                    n_singular += 1
                    if n_singular == 1 and kind in ("newton", "error"):
                        what = "local error test, " if kind == "error" else ""
                        history = (f"; before that the step size had been cut by {n_fail} failed attempts "
                                   f"(last: {what}{reason}) -- check the declared variable indices")
                    if exc.structural or n_singular >= MAX_SINGULAR:
                        raise StepFailure(
                            f"Radau5: the iteration matrix is singular at t={t:.17g} with h={h:.3g} "
                            f"(the DAE is not of index <= 3 or a constraint lost rank): {exc}{history}") from None
                    kind, reason = "singular", str(exc)
                    n_fail += 1
                    h = self._retry(h, 0.5)
                    continue
            if scale is None or self._scaled:  # the weights of an index-1 problem do not depend on h
                scale = self._scale(h, abs_y)
            ok, Z, n_iter, info = self._newton(t, y, h, self._predict(t, y, h), scale)
            if not ok:
                reason, fac = info
                kind = "newton"
                self.stats["nfail_newton"] += 1
                self.stats["nreject"] += 1
                n_fail += 1
                h = self._retry(h, fac)
                continue
            theta = info
            y_new = y + Z[2]
            err = self._error(t, y, h, Z, y_new, n_fail, abs_y)
            fac = min(SAFETY, SAFETY * (2 * NEWTON_MAXITER + 1) / (n_iter + 2 * NEWTON_MAXITER))
            quot = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, err ** 0.25 / fac))
            h_new = h / quot
            if err >= 1.0:
                self.stats["nreject"] += 1
                kind, reason = "error", f"scaled error {err:.3g}"
                n_fail += 1
                h = self._retry(h, 0.1 if self.first else h_new / h)
                continue
            break
        self._accept(t, y, h, Z, y_new, err, quot, h_new, n_fail, theta, last)

    def _retry(self, h, fac):
        """The step size ``h * fac`` of the next attempt after a failed one (error test,
        Newton iteration or singular matrix). A stale Jacobian (from an earlier point) is
        recomputed first, as the failure may be its fault; a current one is kept, and only the
        iteration matrices are factored again at the new step size (RADAU5's ``CALJAC``)."""
        if not self.J_current:
            self._jacobian()
        return h * fac

    def _predict(self, t, y, h):
        """Starting values of the stage increments (3, n): the last step's collocation
        polynomial extrapolated (zero at the first step or if it is not finite)."""
        Z = self._Z
        if self._dense is not None:
            self._dense.increments(t, h, y, Z)
            if _all_finite(Z.reshape(-1), self._zeros):
                return Z
        Z.fill(0.0)
        return Z

    def _error(self, t, y, h, Z, y_new, n_fail, abs_y):
        """Scaled local error of the step (>= 1e-10; ``inf`` if not finite), with the
        improved estimate after a rejection or at the first step (Hairer-Wanner IV.8)."""
        MZE = D_ERR.dot(Z)
        MZE /= h
        if not self._ode:
            MZE *= self.mass
        err_vec = self.lu.solve_real(self.f + MZE)
        scale = self._scale(h, abs_y, y_new)
        err = self._norm(err_vec, scale)
        if err >= 1.0 and (self.first or n_fail > 0) and math.isfinite(err):
            f1 = self._fun(t, y + err_vec)
            if np.isfinite(f1).all():
                err_vec = self.lu.solve_real(f1 + MZE)
                err = self._norm(err_vec, scale)
        if not math.isfinite(err):
            err = math.inf
        return max(err, 1e-10)

    def _accept(self, t, y, h, Z, y_new, err, quot, h_new, n_fail, theta, last):
        """Take the accepted step; choose the next step size (Gustafsson's predictive
        controller) and whether the Jacobian and LU factors are kept."""
        if not self.first and self.h_acc is not None:
            facgus = (self.h_acc / h) * (err ** 2 / self.err_acc) ** 0.25 / SAFETY
            facgus = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, facgus))
            quot = max(quot, facgus)
            h_new = h / quot
        self.h_acc, self.err_acc = h, max(1e-2, err)
        if n_fail > 0:
            h_new = min(h_new, h)
        self.first = False
        self.theta = theta
        self._dense = RadauDenseOutput(t, h, y, Z)
        self.t_old = t
        self.t = self.t_bound if last else t + h
        self.y = y_new
        self.f = self._fun_checked(self.t, self.y, "accepted step")
        self.stats["nsteps"] += 1
        # Jacobian and LU reuse for the next step
        if theta > THETA_JAC:
            self.J = None  # recompute at the new point (lazily, in the next step)
        self.J_current = False
        qt = h_new / h
        if theta <= THETA_JAC and QUOT_KEEP[0] <= qt <= QUOT_KEEP[1] and not last:
            self.h = h  # keep h and the LU factors
        else:
            self.h = min(h_new, self.max_step)

    def dense_output(self):
        """The collocation polynomial of the last step.

        Returns
        -------
        RadauDenseOutput
            Callable ``y(t)``: (n,) for scalar ``t``, (n, m) for ``m`` times, valid on
            ``[t_old, t]``.
        """
        if self._dense is None:
            raise RuntimeError("Radau5.dense_output(): no step has been taken yet")
        return self._dense


_RADAU5_ODE = type("radau5", (CompiledRadau5, Radau5), dict(
    problem="ode", ode_by_default=False, __module__=__name__,
    __doc__="radau5 over the Lagrange index-1 ODE: what ``simulate(method='radau5')`` steps when no index is "
            "asked for (:class:`Radau5`; in C over a compiled program: :mod:`mbcomp.solvers.compiled_radau`)."))
