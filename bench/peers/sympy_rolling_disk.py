"""sympy.physics.mechanics peer for the rolling disk: KanesMethod with no-slip constraints + linearize.

The model is the one of ``models/rolling_disk.py`` (thin uniform disk, radius ``r``, mass ``m``,
inertia about the centre ``diag(m r^2/4, m r^2/2, m r^2/4)`` with the axle the body y axis,
rolling without slip on the ground ``z = 0``, gravity ``-g z``), written the way a sympy/PyDy user
writes it: frames heading ``psi`` (about ``N.z``) -> lean ``phi`` (about the heading frame's x, the
rolling direction) -> spin ``theta`` (about the lean frame's y, the axle); the contact point at
``(x, y, 0)``, the centre at ``r`` along the lean frame's z from it. Coordinates
``(psi, phi, theta, x, y)``, speeds their rates (``q' = u``), of which ``xd, yd`` are dependent:
the no-slip constraints (the disk's material point at the contact has zero velocity in ``N``, its
``N.x`` and ``N.y`` components) go to ``KanesMethod`` as ``velocity_constraints``. Then
``kanes_equations`` and ``KanesMethod.linearize(op_point, A_and_B=True, simplify=False)`` about
upright straight rolling: ``psi = phi = theta = x = y = 0``, ``psid = phid = 0``, ``thetad = W``,
``xd = r W`` (the dependent speed from the constraint), all accelerations zero.

``r``, ``m``, ``g`` and ``W`` stay symbolic through the derivation and the linearization (the
general result is what a sympy user wants from the symbolic route, and it can be read against
the textbook one: ``phid' = 4 g/(5 r) phi + 6 W/5 psid``, ``psid' = -2 W phid``; ``m`` drops out);
the numbers for ``r``, ``m``, ``g`` are substituted just before ``lambdify``, which leaves
``A(W)``. The states, in ``A``'s order, are ``psi, phi, theta, x, y, psid, phid, thetad``; the
characteristic polynomial is ``lambda^6 (lambda^2 + K/J)`` (six zero roots: ``psi``, ``theta``,
``x``, ``y``, ``thetad`` and the neighbouring steady turn).

API: ``derive(r, m, g) -> Derived`` (``states``, ``A``, ``t_derive``, ``t_linearize``,
``t_lambdify`` in s wall); ``largest_real_part(derived, W)``; ``critical_spin(derived, lo, hi)``,
the stability boundary by Brent's method on ``e2(W)``, the second coefficient of the
characteristic polynomial (the sum of the products of pairs of eigenvalues,
``(tr(A)^2 - tr(A^2)) / 2``). With all other roots zero ``e2`` is the product of the nonzero
pair ``= K/J``: a polynomial in ``W``, negative below the boundary (real pair ``+-sqrt(-K/J)``),
positive above (imaginary pair); no eigenvalue solve, so no rounding-level noise near the root,
unlike the largest real part (``~0`` on the whole stable side).
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402


@dataclass
class Derived:
    states: list
    A: object
    t_derive: float
    t_linearize: float
    t_lambdify: float


def derive(r=0.3, m=2.0, g=9.81):
    import sympy as sp
    import sympy.physics.mechanics as me

    t0 = time.perf_counter()
    rs, ms, gs, W = sp.symbols("r m g W", positive=True)
    q = psi, phi, theta, x, y = me.dynamicsymbols("psi phi theta x y")
    u = psid, phid, thetad, xd, yd = me.dynamicsymbols("psid phid thetad xd yd")
    N = me.ReferenceFrame("N")
    H = N.orientnew("H", "Axis", [psi, N.z])  # heading
    L = H.orientnew("L", "Axis", [phi, H.x])  # lean, about the rolling direction
    D = L.orientnew("D", "Axis", [theta, L.y])  # disk, spinning about the axle
    H.set_ang_vel(N, psid * N.z)
    L.set_ang_vel(H, phid * H.x)
    D.set_ang_vel(L, thetad * L.y)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)  # contact point (geometric, moves along the ground)
    C.set_vel(N, xd * N.x + yd * N.y)
    G = C.locatenew("G", rs * L.z)  # centre
    G.v2pt_theory(C, N, L)
    P = G.locatenew("P", -rs * L.z)  # disk material point at the contact
    P.v2pt_theory(G, N, D)
    no_slip = [P.vel(N).dot(N.x), P.vel(N).dot(N.y)]
    kd = [qi.diff() - ui for qi, ui in zip(q, u)]
    I = me.inertia(L, ms * rs ** 2 / 4, ms * rs ** 2 / 2, ms * rs ** 2 / 4)  # axisymmetric: L = D
    disk = me.RigidBody("disk", G, D, ms, (I, G))
    km = me.KanesMethod(N, q_ind=q, u_ind=[psid, phid, thetad], u_dependent=[xd, yd], kd_eqs=kd,
                        velocity_constraints=no_slip)
    km.kanes_equations([disk], [(G, -ms * gs * N.z)])
    t_derive = time.perf_counter() - t0

    t0 = time.perf_counter()
    op = {psi: 0, phi: 0, theta: 0, x: 0, y: 0, psid: 0, phid: 0, thetad: W, xd: rs * W, yd: 0}
    op.update({ui.diff(): 0 for ui in u})
    A, _, _ = km.linearize(op_point=op, A_and_B=True, simplify=False)
    t_linearize = time.perf_counter() - t0

    t0 = time.perf_counter()
    f = sp.lambdify(W, A.subs({rs: r, ms: m, gs: g}), "numpy")
    t_lambdify = time.perf_counter() - t0
    states = [str(s.func) for s in list(q) + [psid, phid, thetad]]  # linearize orders x = [q, u_ind]
    return Derived(states, lambda w: np.asarray(f(w), dtype=float), t_derive, t_linearize, t_lambdify)


def largest_real_part(derived, W):
    return float(np.linalg.eigvals(derived.A(W)).real.max())


def e2(derived, W):
    """Sum of the products of pairs of eigenvalues of A(W); = K/J here, > 0 iff stable."""
    A = derived.A(W)
    return 0.5 * (np.trace(A) ** 2 - np.trace(A @ A))


def critical_spin(derived, lo=1.0, hi=5.0):
    return brentq(lambda w: e2(derived, w), lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)


if __name__ == "__main__":
    r, m, g = 0.3, 2.0, 9.81
    d = derive(r, m, g)
    n = 2000
    t0 = time.perf_counter()
    for _ in range(n):
        d.A(2.0)
    t_eval = (time.perf_counter() - t0) / n
    print(f"derive {d.t_derive:.3f} s  linearize {d.t_linearize:.3f} s  lambdify {d.t_lambdify:.4f} s  "
          f"A(W) {t_eval * 1e6:.1f} us")
    print("states", d.states)
    t0 = time.perf_counter()
    Wc = critical_spin(d)
    t_root = time.perf_counter() - t0
    exact = np.sqrt(g / (3 * r))
    print(f"critical spin {Wc:.15f}  exact {exact:.15f}  rel. error {abs(Wc - exact) / exact:.2e}  "
          f"({t_root * 1e3:.2f} ms)")
    Ia, Id = m * r ** 2 / 2, m * r ** 2 / 4
    J = Id + m * r ** 2
    for W in (2.0, 6.0):
        K = (Ia + m * r ** 2) * Ia * W ** 2 / Id - m * g * r
        ev = np.linalg.eigvals(d.A(W))
        nz = np.sort_complex(ev[np.abs(ev) > 1e-9])
        ref = np.sort_complex(np.array([1, -1]) * np.sqrt(complex(-K / J)))
        print(f"W={W}: nonzero eig {nz}  analytic {ref}  max |diff| {np.abs(nz - ref).max():.1e}  "
              f"zeros {np.sum(np.abs(ev) <= 1e-9)}  max Re {largest_real_part(d, W):+.3e}")
