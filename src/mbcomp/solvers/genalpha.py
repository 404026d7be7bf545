"""The generalized-alpha method for index-3 constrained mechanical systems.

The scheme of Chung & Hulbert (1993) as analysed for constrained systems by Arnold & Brüls
(2007, *Convergence of the generalized-alpha scheme for constrained mechanical systems*,
Multibody Syst. Dyn. 18) and written in the Lie-group-friendly form of Arnold, Cardona &
Brüls (2016): coordinates are only ever moved by ``problem.increment`` (a vector in speed
space), so quaternion or rotation-matrix coordinates stay on their manifold.

One step of length ``h`` from ``(q_n, u_n, udot_n, a_n, lam_n)`` solves, for
``(udot_{n+1}, lam_{n+1})``,

.. math::

    (1-\\alpha_m) a_{n+1} + \\alpha_m a_n &= (1-\\alpha_f) \\dot u_{n+1} + \\alpha_f \\dot u_n \\\\
    \\Delta q_n &= u_n + (1/2-\\beta) h a_n + \\beta h a_{n+1} \\\\
    q_{n+1} &= \\mathrm{increment}(q_n, h \\Delta q_n) \\\\
    u_{n+1} &= u_n + (1-\\gamma) h a_n + \\gamma h a_{n+1} \\\\
    M(q_{n+1}) \\dot u_{n+1} + C(q_{n+1})^T \\lambda_{n+1} &= f(t_{n+1}, q_{n+1}, u_{n+1}) \\\\
    \\Phi(t_{n+1}, q_{n+1}) &= 0

(``a`` is the pseudo-acceleration, ``udot`` the acceleration). The constraint equation is
scaled by ``beta' = (1-alpha_m)/((1-alpha_f) beta h^2)`` (~ ``1/(beta h^2)``), which makes the
Newton matrix ``O(1)`` as ``h -> 0``; in the unknowns ``(udot, lam)`` it reads

.. math::

    S = \\begin{bmatrix} M + \\gamma' / \\beta' \\, C_t + K_t / \\beta' & C^T \\\\ C & 0 \\end{bmatrix}

which is the classical matrix ``[[M beta' + C_t gamma' + K_t, C^T], [C, 0]]`` in the position
increment, with its first column block divided and its last row block multiplied by
``beta'`` (``gamma' = gamma/(beta h)``). ``K_t = d(M udot + C^T lam - f)/dq`` (through
``increment``) and ``C_t = -df/du`` come from ``problem.tangents(t, q, u, udot, lam)`` when
the problem has it and it returns them (exact, from a generated program), else from forward
differences of ``problem.dynamics``.

Parameters follow from the spectral radius at infinity ``rho_inf`` (Chung & Hulbert):
``alpha_m = (2 rho_inf - 1)/(rho_inf + 1)``, ``alpha_f = rho_inf/(rho_inf + 1)``,
``gamma = 1/2 + alpha_f - alpha_m``, ``beta = (gamma + 1/2)^2 / 4``. ``rho_inf = 1`` adds no
numerical dissipation (the trapezoidal/average-acceleration rule); ``rho_inf = 0``
annihilates the unresolved high frequencies within a few steps. Second order in ``q`` and
``u`` for ``rho_inf`` in ``[0, 1)``.

Examples
--------
>>> from mbcomp.solvers.genalpha import GeneralizedAlpha
>>> GeneralizedAlpha.capabilities()
{'implicit': True, 'adaptive': False, 'one_step': True, 'max_index': 3, 'problem': 'mechanical'}
"""
from __future__ import annotations

import warnings

import numpy as np
from scipy.linalg import LinAlgWarning, get_lapack_funcs, lu_factor

from .base import StepFailure, Stepper

__all__ = ["GeneralizedAlpha", "GeneralizedAlphaDenseOutput", "genalpha_parameters"]

_EPS = np.finfo(float).eps
_SQRT_EPS = np.sqrt(_EPS)
#: The price of an iteration matrix from exact tangents (``problem.tangents``), in Newton
#: iterations, for the cost balance that refreshes an aging matrix (differenced: 2 nu + 1
#: evaluations). 3 against 2 nu + 1 (bench/stiff_jacobians.py's models, rtol 1e-6): 8-9 % less
#: CPU time and 25 % fewer evaluations on the 10-link spring chain, 5-9 % less time on the
#: flyball governor, Andrews unchanged (1 and 8: within 5 % of 3).
EXACT_MATRIX_COST = 3
#: Reciprocal condition number (1-norm, of the equilibrated iteration matrix) below which the
#: matrix is treated as singular.
RCOND_MIN = 1e-13


def genalpha_parameters(rho_inf):
    """Chung-Hulbert parameters for spectral radius at infinity ``rho_inf``.

    Parameters
    ----------
    rho_inf : float
        Spectral radius of the amplification matrix as ``omega h -> infinity``, in ``[0, 1]``.

    Returns
    -------
    alpha_m, alpha_f, gamma, beta : float
        Dimensionless method coefficients.

    Examples
    --------
    >>> [round(c, 4) for c in genalpha_parameters(1.0)]
    [0.5, 0.5, 0.5, 0.25]
    """
    rho = float(rho_inf)
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"rho_inf must lie in [0, 1], got {rho_inf!r}")
    alpha_m = (2.0 * rho - 1.0) / (rho + 1.0)
    alpha_f = rho / (rho + 1.0)
    gamma = 0.5 + alpha_f - alpha_m
    beta = 0.25 * (gamma + 0.5) ** 2
    return alpha_m, alpha_f, gamma, beta


class GeneralizedAlphaDenseOutput:
    """Interpolant of one generalized-alpha step on ``[t_old, t]``.

    ``q`` is the cubic Hermite interpolant of its end values and end rates
    (``problem.q_rate(q, u)``), ``u`` the cubic Hermite interpolant with ``udot`` as its end
    derivatives, and ``udot``, ``a``, ``lam`` are interpolated linearly.

    Parameters
    ----------
    t_old, t : float
        Step ends (s).
    y_old, y : ndarray (nq + 3 nu + m,)
        States ``[q, u, udot, a, lam]`` at the step ends.
    qd_old, qd : ndarray (nq,)
        ``dq/dt`` at the step ends.
    nq, nu : int
        Sizes of ``q`` and ``u``.

    Calling it with a scalar ``t`` returns an array (n,); with an array of k times, (n, k),
    as for scipy's ``DenseOutput``.
    """

    def __init__(self, t_old, t, y_old, y, qd_old, qd, nq, nu):
        self.t_old, self.t = float(t_old), float(t)
        self.t_min, self.t_max = min(self.t_old, self.t), max(self.t_old, self.t)
        self._y0, self._y1 = np.array(y_old, float), np.array(y, float)
        self._qd0, self._qd1 = np.array(qd_old, float), np.array(qd, float)
        self._nq, self._nu = nq, nu

    def __call__(self, t):
        t = np.asarray(t, float)
        scalar = t.ndim == 0
        tt = np.atleast_1d(t)
        h = self.t - self.t_old
        s = (tt - self.t_old) / h if h != 0.0 else np.ones_like(tt)
        # cubic Hermite basis (value at 0, slope at 0 times h, value at 1, slope at 1 times h)
        h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
        h10 = s * (1.0 - s) ** 2
        h01 = s * s * (3.0 - 2.0 * s)
        h11 = s * s * (s - 1.0)
        nq, nu = self._nq, self._nu
        y0, y1 = self._y0[:, None], self._y1[:, None]
        out = (1.0 - s) * y0 + s * y1  # linear for udot, a, lam
        out[:nq] = h00 * y0[:nq] + h10 * h * self._qd0[:, None] + h01 * y1[:nq] + h11 * h * self._qd1[:, None]
        iu, iud = slice(nq, nq + nu), slice(nq + nu, nq + 2 * nu)
        out[iu] = h00 * y0[iu] + h10 * h * y0[iud] + h01 * y1[iu] + h11 * h * y1[iud]
        return out[:, 0] if scalar else out


class GeneralizedAlpha(Stepper):
    """Generalized-alpha (Arnold & Brüls 2007, Lie-group form) for index-3 mechanical DAEs.

    Fixed step size; each step solves the nonlinear equations of the scheme (see the module
    docstring) for ``(udot_{n+1}, lam_{n+1})`` by a simplified Newton iteration whose LU
    factorization is kept across steps while the iteration contracts fast enough.

    Parameters
    ----------
    problem : MechanicalDAE
        ``nq``, ``nu``, ``m``; ``dynamics(t, q, u) -> (M (nu, nu), f (nu,), Phi (m,),
        C (m, nu))``; ``increment(q, dq)``; ``q_rate(q, u)``.
    t0 : float
        Start time (s).
    y0 : array_like (nq + 3 nu + m,)
        Consistent start state ``[q, u, udot, a, lam]``: ``Phi(t0, q) = 0``, ``C u`` matches
        the constraint velocity, ``udot`` and ``lam`` solve the index-1 equations; normally
        ``a = udot``.
    t_bound : float
        End time (s).
    rtol, atol : float
        Newton tolerance. The iterate ``(udot, lam)`` is accepted when the RMS norm of its
        estimated error, scaled per block by ``atol + rtol * max|udot|`` (m/s^2, rad/s^2) and
        ``atol + rtol * max|lam|`` (N, N m) of the last step (plus the round-off floor that the
        ``1/(beta h^2)`` constraint scaling imposes), is below 1. Positions then satisfy
        ``Phi = 0`` to about ``rtol * max|udot| * beta h^2``.
    first_step : float
        The step size ``h`` (s); required.
    max_step : float, optional
        If smaller than ``first_step``, it is used as ``h``.
    rho_inf : float, optional
        Spectral radius at infinity, in ``[0, 1]`` (default 0.9).
    max_newton : int, optional
        Newton iterations allowed with one iteration matrix (default 10).

    Attributes
    ----------
    h : float
        Nominal step size (s). Steps actually taken have length
        ``(t_bound - t) / ceil((t_bound - t) / h)`` (equal to ``h`` when the span is a
        multiple of it), so the last step is never a sliver.
    rho_inf, alpha_m, alpha_f, gamma, beta : float
        Method parameters.
    stats : dict
        ``nsteps``, ``nreject`` (always 0), ``nfev`` (calls of ``dynamics``), ``njev``
        (iteration-matrix evaluations), ``nlu`` (LU factorizations), ``nnewton`` (Newton
        iterations).

    Raises
    ------
    ValueError
        If ``first_step`` is missing or not positive, ``rho_inf`` is outside ``[0, 1]`` or
        ``y0`` has the wrong length.

    Notes
    -----
    Newton starts from ``(udot_n, lam_n)``. The factorized matrix is reused across steps
    while the iteration contracts (rate < 0.5) and until the extra iterations it costs exceed
    the price of a new one; within a step it is refreshed at most ``MAX_REFRESH`` times, a
    growing correction is taken back (and halved if the matrix is already current).

    Failures (reported by :meth:`step` as a message, status ``"failed"``): Newton does not
    converge within ``max_newton`` iterations even with fresh iteration matrices, the
    iteration matrix is singular (reciprocal condition number of the equilibrated matrix
    below ``RCOND_MIN``: a constraint lost rank), or values become non-finite. The step is
    fixed, so there is no retry with a smaller step; a smaller ``first_step`` may help.

    With constraints, ``rho_inf = 1`` is only weakly stable: the constraint-direction
    (algebraic) modes of the scheme then have a defective eigenvalue -1, so perturbations
    of ``udot``, ``lam`` grow linearly with the number of steps and, through the nonlinear
    coupling, eventually spoil the solution (on a pendulum after a few seconds). Values
    close to 1 (e.g. 0.99) need small steps for the same reason; ``rho_inf <= 0.9`` is the
    safe range for index-3 problems (Arnold & Brüls require ``rho_inf < 1``). Without
    constraints ``rho_inf = 1`` is the energy-conserving trapezoidal rule.

    ``dense_output`` interpolates ``q`` coordinate-wise (cubic Hermite with
    ``q_rate`` slopes); for quaternion coordinates the interpolant is not exactly unit.

    Examples
    --------
    A particle kept on the unit circle by a constraint, no forces, unit speed: after 1 s it
    is at angle 1 rad.

    >>> import numpy as np
    >>> from mbcomp.solvers.genalpha import GeneralizedAlpha
    >>> class Ring:
    ...     nq = nu = 2
    ...     m = 1
    ...     def dynamics(self, t, q, u):
    ...         return np.eye(2), np.zeros(2), np.array([(q @ q - 1.0) / 2]), q[None, :]
    ...     def increment(self, q, dq):
    ...         return q + dq
    ...     def q_rate(self, q, u):
    ...         return u
    >>> y0 = [1.0, 0.0, 0.0, 1.0, -1.0, 0.0, -1.0, 0.0, 1.0]   # q, u, udot, a, lam
    >>> s = GeneralizedAlpha(Ring(), 0.0, y0, 1.0, first_step=1e-2, rtol=1e-10, atol=1e-12)
    >>> while s.status == "running":
    ...     _ = s.step()
    >>> s.stats["nsteps"], bool(np.allclose(s.y[:2], [np.cos(1.0), np.sin(1.0)], atol=2e-5))
    (100, True)
    >>> round(float(s.y[-1]), 4)   # lam = centripetal force (N)
    1.0
    """

    implicit = True
    adaptive = False
    one_step = True
    max_index = 3
    problem = "mechanical"
    #: fresh iteration matrices allowed per step
    MAX_REFRESH = 4

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf,
                 rho_inf=0.9, max_newton=10):
        super().__init__(problem, t0, y0, t_bound, rtol, atol, first_step, max_step)
        if first_step is None:
            raise ValueError("GeneralizedAlpha is a fixed-step method: give the step size as first_step=h (s)")
        h = float(first_step)
        if not (np.isfinite(h) and h > 0.0):
            raise ValueError(f"first_step must be a positive finite step size, got {first_step!r}")
        if max_step is not None and np.isfinite(max_step) and 0.0 < max_step < h:
            h = float(max_step)
        self.h = h
        self.rho_inf = float(rho_inf)
        self.alpha_m, self.alpha_f, self.gamma, self.beta = genalpha_parameters(rho_inf)
        self.max_newton = int(max_newton)
        self.nq, self.nu, self.m = int(problem.nq), int(problem.nu), int(problem.m)
        n = self.nq + 3 * self.nu + self.m
        if self.y.shape != (n,):
            raise ValueError(f"y0 must be [q (nq={self.nq}), u, udot, a (nu={self.nu} each), lam (m={self.m})] "
                             f"of length {n}; got shape {self.y.shape}")
        if not np.isfinite(self.y).all():
            raise ValueError("y0 contains non-finite values")
        self.stats["nnewton"] = 0
        self._lu = None  # (lu, piv, row_scale, col_scale, h)
        self._y_old = None
        self._extra_iters = 0
        self._floor = np.zeros(self.nu + self.m)
        self._qd = None
        self._exact = False  # whether the last iteration matrix had exact tangents

    # ------------------------------------------------------------------ pieces of the scheme
    def _split(self, y):
        nq, nu = self.nq, self.nu
        return (y[:nq], y[nq:nq + nu], y[nq + nu:nq + 2 * nu], y[nq + 2 * nu:nq + 3 * nu], y[nq + 3 * nu:])

    def _set_step(self, h, q0, u0, ud0, a0):
        """Precompute the affine maps ``udot_{n+1} -> (a, u, h Dq)_{n+1}`` of one step."""
        am, af, g, b = self.alpha_m, self.alpha_f, self.gamma, self.beta
        k1 = (1.0 - af) / (1.0 - am)
        a_c = (af * ud0 - am * a0) / (1.0 - am)
        self._stg = (q0, k1, a_c, h * g * k1, u0 + h * ((1.0 - g) * a0 + g * a_c), h * h * b * k1,
                     h * (u0 + h * ((0.5 - b) * a0 + b * a_c)))

    def _stage(self, udot1):
        """``q_{n+1}, u_{n+1}, a_{n+1}`` as functions of ``udot_{n+1}`` (None if non-finite)."""
        q0, k1, a_c, ku, u_c, kq, dq_c = self._stg
        u1 = u_c + ku * udot1
        dq = dq_c + kq * udot1
        if not np.isfinite(np.dot(dq, dq) + np.dot(u1, u1)):
            return None, None, None
        q1 = np.asarray(self.prob.increment(q0, dq), float)
        return q1, u1, k1 * udot1 + a_c

    def _dyn(self, t, q, u):
        self.stats["nfev"] += 1
        M, f, Phi, C = self.prob.dynamics(t, q, u)
        nu, m = self.nu, self.m
        return (np.asarray(M, float).reshape(nu, nu), np.asarray(f, float).reshape(nu),
                np.asarray(Phi, float).reshape(m), np.asarray(C, float).reshape(m, nu))

    def _coeffs(self, h):
        """``beta'`` (1/s^2) and ``gamma'/beta'`` (s)."""
        c = (1.0 - self.alpha_f) / (1.0 - self.alpha_m)
        return 1.0 / (self.beta * h * h * c), self.gamma * h * c

    def _residual(self, t, q, u, udot, lam):
        """``[M udot + C^T lam - f, beta' Phi]`` (N, N) at the step's ``h``."""
        M, f, Phi, C = self._dyn(t, q, u)
        return np.concatenate((M @ udot + C.T @ lam - f, Phi / self._stg[5]))

    @staticmethod
    def _newton_norm(dx, weight):
        """RMS norm of a correction ``dx`` of ``(udot, lam)`` times ``weight`` (1/scale)."""
        if dx.size == 0:
            return 0.0
        v = dx * weight
        return float(np.sqrt(np.dot(v, v) / v.size))

    def _position_norm(self, dudot, q, u, h):
        """RMS norm of the corrections of ``q`` and ``u`` caused by ``dudot``, scaled by
        ``atol + rtol |value|`` (used to accept a Newton iteration stalled at round-off)."""
        bp, gb = self._coeffs(h)
        qmag = float(np.max(np.abs(q), initial=0.0))
        sq = self.atol + self.rtol * (np.abs(q) if self.nq == self.nu else qmag)
        su = self.atol + self.rtol * np.abs(u)
        return float(np.sqrt(0.5 * (np.mean((dudot / bp / sq) ** 2) + np.mean((gb * dudot / su) ** 2))))

    def _where(self, t, h):
        return f"at t={t:.10g} (h={h:.6g})"

    def _difference_tangents(self, t, q, u, udot, lam, M, f, C):
        """``(K, Ct)`` by forward differences of ``dynamics``: the problem has no exact
        ``tangents(t, q, u, udot, lam)`` or it returned None here."""
        nu = self.nu
        r0 = M @ udot + C.T @ lam - f
        K = np.empty((nu, nu))
        Ct = np.empty((nu, nu))
        dq_step = _SQRT_EPS * max(1.0, float(np.max(np.abs(q), initial=0.0)))
        for j in range(nu):
            e = np.zeros(nu)
            e[j] = dq_step
            qj = np.asarray(self.prob.increment(q, e), float)
            Mj, fj, _, Cj = self._dyn(t, qj, u)
            K[:, j] = (Mj @ udot + Cj.T @ lam - fj - r0) / dq_step
            du = _SQRT_EPS * max(1.0, abs(u[j]))
            uj = u.copy()
            uj[j] += du
            _, fj, _, _ = self._dyn(t, q, uj)
            Ct[:, j] = -(fj - f) / du
        return K, Ct

    def _factor(self, t, h, q, u, udot, lam):
        """Evaluate, equilibrate and LU-factorize the scaled iteration matrix at ``(q, u)``."""
        nu, m = self.nu, self.m
        self.stats["njev"] += 1
        M, f, Phi, C = self._dyn(t, q, u)
        exact = getattr(self.prob, "tangents", None)
        KC = exact(t, q, u, udot, lam) if exact is not None else None
        self._exact = KC is not None
        if KC is not None:
            K, Ct = (np.asarray(x, float).reshape(nu, nu) for x in KC)
        else:
            K, Ct = self._difference_tangents(t, q, u, udot, lam, M, f, C)
        bp, gb = self._coeffs(h)
        A = np.zeros((nu + m, nu + m))
        A[:nu, :nu] = M + gb * Ct + K / bp
        A[:nu, nu:] = C.T
        A[nu:, :nu] = C
        if not np.isfinite(A).all():
            raise StepFailure(f"generalized-alpha: non-finite values in the iteration matrix {self._where(t, h)} "
                              "(the solution diverged?); a smaller step size (h, first_step) may help")
        # Ruiz equilibration: the rank test must not depend on the units of masses/forces
        rs, cs = np.ones(nu + m), np.ones(nu + m)
        B = A.copy()
        for _ in range(6):
            rmax = np.max(np.abs(B), axis=1)
            cmax = np.max(np.abs(B), axis=0)
            if np.any(rmax == 0.0) or np.any(cmax == 0.0):
                break
            dr, dc = 1.0 / np.sqrt(rmax), 1.0 / np.sqrt(cmax)
            rs *= dr
            cs *= dc
            B = dr[:, None] * B * dc[None, :]
        self.stats["nlu"] += 1
        rcond = 0.0
        if np.all(np.any(B != 0.0, axis=1)):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", LinAlgWarning)
                lu, piv = lu_factor(B, check_finite=False)
            gecon, self._getrs = get_lapack_funcs(("gecon", "getrs"), (lu,))
            rcond, info = gecon(lu, np.linalg.norm(B, 1), norm="1")
            if info != 0 or not np.isfinite(rcond):
                rcond = 0.0
        if rcond < RCOND_MIN:
            self._lu = None
            raise StepFailure(f"generalized-alpha: the iteration matrix is singular {self._where(t, h)}: "
                              f"reciprocal condition number {rcond:.2e} (a constraint lost rank: singular position "
                              "or redundant constraints?)")
        self._lu = (lu, piv, rs, cs, h)
        # round-off floor for the Newton test: Phi carries errors ~ eps |q|, which the scaled
        # constraint rows amplify by beta' in udot, and by |M|/|C| beyond that in lam
        qmag = float(np.max(np.abs(q), initial=0.0))
        fl_ud = 100.0 * _EPS * bp * qmag
        mnorm = float(np.max(np.abs(M), initial=0.0))
        cnorm = float(np.max(np.linalg.norm(C, axis=1), initial=0.0)) if m else 0.0
        self._floor = np.concatenate((np.full(nu, fl_ud), np.full(m, fl_ud * mnorm / cnorm if cnorm > 0 else 0.0)))

    def _solve(self, r):
        lu, piv, rs, cs, _ = self._lu
        sol, info = self._getrs(lu, piv, rs * r)
        return -cs * sol

    def _newton_scale(self, x_n, x_pred):
        """One norm for the whole step (iterates may wander far from the solution), scaled per
        block (udot, lam) by its magnitude so that near-zero components do not dominate."""
        scale = np.empty_like(x_pred)
        for blk in (slice(0, self.nu), slice(self.nu, None)):
            mag = max(float(np.max(np.abs(x_n[blk]), initial=0.0)), float(np.max(np.abs(x_pred[blk]), initial=0.0)))
            scale[blk] = self.atol + self.rtol * mag
        return scale

    def _correction(self, t1, x):
        """``(dx, q1, u1)``: the Newton correction at the iterate ``x`` and its stage values;
        ``dx`` is ``None`` where something is not finite."""
        nu = self.nu
        q1, u1, _ = self._stage(x[:nu])
        if q1 is None or not np.isfinite(q1).all():
            return None, q1, u1
        r = self._residual(t1, q1, u1, x[:nu], x[nu:])
        if not np.isfinite(r).all():
            return None, q1, u1
        dx = self._solve(r)
        return (dx if np.isfinite(dx).all() else None), q1, u1

    def _newton(self, t1, h, x_pred, x_n):
        """Solve the step equations for ``x = (udot_{n+1}, lam_{n+1})`` from ``x_pred``.

        Simplified Newton with safeguards: the factorized matrix is kept while the
        corrections contract with rate < 0.5; a slower iteration gets a matrix evaluated at
        the current iterate; when a correction grows, the last update is taken back and the
        matrix re-evaluated where it started, or, if the matrix is already from there, that
        update is halved (damped Newton). At most ``MAX_REFRESH`` matrices per step.

        Returns
        -------
        x : ndarray (nu + m,)
        fresh : bool
            Whether a new matrix was computed during this step.
        """
        nu = self.nu
        state = dict(nref=0, mat_j=None)

        def refresh(x, j):
            if state["nref"] >= self.MAX_REFRESH:
                return False
            q1, u1, _ = self._stage(x[:nu])
            if q1 is None or not np.isfinite(q1).all():
                return False
            self._factor(t1, h, q1, u1, x[:nu], x[nu:])
            state["nref"] += 1
            state["mat_j"] = j
            return True

        def fail(how, err, rate):
            rate_s = f"{rate:.3g}" if rate is not None else "n/a"
            raise StepFailure(f"generalized-alpha: Newton failed to converge {self._where(t1, h)}: {how} "
                              f"({total} iterations, {state['nref']} fresh iteration matrices; last scaled "
                              f"correction {err:.3g}, rate {rate_s}); a smaller step size (h, first_step) may help")

        x = x_pred.copy()
        scale = self._newton_scale(x_n, x_pred)
        j = 0  # index of the current iterate
        if self._lu is None or abs(self._lu[4] - h) > 1e-3 * h:
            if not refresh(x, j):
                raise StepFailure(f"generalized-alpha: non-finite values {self._where(t1, h)}; "
                                  "a smaller step size (h, first_step) may help")
        prev = None  # (x, dx, err, j) of the previous iterate
        it, total, damp = 0, 0, 1.0
        err, rate = np.inf, None
        while True:
            dx, q1, u1 = self._correction(t1, x)
            ok = dx is not None
            total += 1
            it += 1
            self.stats["nnewton"] += 1
            if ok:
                err = self._newton_norm(dx, 1.0 / (scale + self._floor))
                rate = err / prev[2] if prev is not None and prev[2] > 0 else None
            elif prev is None:
                raise StepFailure(f"generalized-alpha: non-finite values at the Newton predictor "
                                  f"{self._where(t1, h)}; a smaller step size (h, first_step) may help")
            else:
                err, rate = np.inf, np.inf
            if rate is not None and rate >= 1.0:
                # the last update made things worse: take it back
                xp, dxp, _, jp = prev
                if state["mat_j"] == jp:
                    damp *= 0.5  # the matrix is exact there: damp the update instead
                    if damp < 1.0 / 64:
                        fail("the damped iteration diverged", err, rate)
                    x = xp + damp * dxp
                    j += 1
                    continue
                if not refresh(xp, jp):
                    fail("it diverged even with a fresh iteration matrix", err, rate)
                x, j, prev, it, damp = xp, jp, None, 0, 1.0
                continue
            est = err if rate is None else min(err, rate / (1.0 - rate) * err)
            if est <= 1.0:
                x = x + dx
                break
            if (state["nref"] and rate is not None and rate >= 0.9
                    and self._position_norm(dx[:nu], q1, u1, h) <= 1e-3):
                x = x + dx
                break  # stalled at round-off level, far below the position/speed tolerance
            if ((rate is not None and rate >= 0.5) or it >= self.max_newton) and state["mat_j"] != j:
                if refresh(x, j):
                    prev, it = None, 0
                    continue
            if it >= self.max_newton or total >= self.max_newton * (self.MAX_REFRESH + 1):
                fail("it converged too slowly" if rate is not None and rate < 1.0 else "it did not converge",
                     err, rate)
            prev = (x, dx, err, j)
            x = x + dx
            j += 1
            damp = 1.0
        self._iters = total
        return x, state["nref"] > 0

    # ------------------------------------------------------------------ one step
    def _step(self):
        t0 = self.t
        remaining = self.t_bound - t0
        if np.isfinite(remaining):
            nleft = max(1, int(np.ceil(remaining / self.h - 1e-7)))
            h = remaining / nleft
        else:
            h = self.h
        t1 = t0 + h if np.isfinite(remaining) and h < remaining else self.t_bound
        nu = self.nu
        q0, u0, ud0, a0, lam0 = self._split(self.y)
        # predictor: udot and lam of the last step (an extrapolation from two steps is more
        # accurate for smooth motion but amplifies unresolved oscillations)
        x_n = np.concatenate((ud0, lam0))
        self._set_step(h, q0, u0, ud0, a0)
        x, fresh = self._newton(t1, h, x_n.copy(), x_n)

        # cost balance: once the iterations spent beyond two per step with this (aging) matrix
        # outweigh the cost of a new one (2 nu + 1 evaluations; exact tangents: EXACT_MATRIX_COST),
        # refresh it at the next step
        self._extra_iters = 0 if fresh else self._extra_iters + max(0, self._iters - 2)
        if self._extra_iters > (EXACT_MATRIX_COST if self._exact else 2 * nu + 1):
            self._lu = None
        q1, u1, a1 = self._stage(x[:nu])
        y1 = np.concatenate((q1, u1, x[:nu], a1, x[nu:]))
        if not np.isfinite(y1).all():
            raise StepFailure(f"generalized-alpha: non-finite state {self._where(t1, h)}")
        qd0 = self._qd if self._qd is not None else np.asarray(self.prob.q_rate(q0, u0), float)
        self._qd_old, self._qd = qd0, np.asarray(self.prob.q_rate(q1, u1), float)
        self._y_old, self.y = self.y, y1
        self.t_old, self.t = t0, t1
        self.stats["nsteps"] += 1

    def dense_output(self):
        """Interpolant on ``[t_old, t]`` (see :class:`GeneralizedAlphaDenseOutput`).

        Returns
        -------
        GeneralizedAlphaDenseOutput
            ``sol(t)`` -> state (n,) for scalar ``t`` or (n, k) for k times.
        """
        if self.t_old is None:
            raise RuntimeError("dense output is available after a successful step")
        return GeneralizedAlphaDenseOutput(self.t_old, self.t, self._y_old, self.y, self._qd_old, self._qd,
                                           self.nq, self.nu)
