"""sympy.physics.mechanics peer for the planar N-link pendulum: KanesMethod + lambdify + scipy.

The model is the one of ``models/n_link_pendulum.py`` (N uniform rods of mass ``m`` and length
``L`` on hinges, relative angles, gravity along -y), written the way a sympy user writes it:
frames rotated by relative angles, points located along the links, ``KanesMethod`` with
``q' = u``, then ``lambdify(cse=True)`` of the mass matrix and forcing; each right-hand side
solves ``M(q) u' = F(q, u)``.

API: ``derive(N, L, m, g) -> Derived`` (``t_derive``, ``t_lambdify`` in s) and
``simulate(derived, q0, u0, t_end, rtol, atol, method) -> dict(q, cpu_s, nfev, status)`` with
``cpu_s`` the process time of the integration only.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402


@dataclass
class Derived:
    N: int
    mass: object
    forcing: object
    t_derive: float
    t_lambdify: float


def kane(N, L=0.5, m=1.0, g=9.81):
    """``(KanesMethod, q, u)`` of the N-link pendulum after ``kanes_equations`` (``L``, ``m``,
    ``g`` numbers or sympy symbols); the pydy peer uses the same derivation."""
    import sympy.physics.mechanics as me

    q = me.dynamicsymbols(f"q:{N}")
    u = me.dynamicsymbols(f"u:{N}")
    frame_n = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame_n, 0)
    bodies, loads, kd = [], [], []
    prev_f, prev_p = frame_n, origin
    for i in range(N):
        F = prev_f.orientnew(f"F{i}", "Axis", [q[i], prev_f.z])
        F.set_ang_vel(prev_f, u[i] * prev_f.z)
        cm = prev_p.locatenew(f"G{i}", -L / 2 * F.y)
        cm.v2pt_theory(prev_p, frame_n, F)
        tip = prev_p.locatenew(f"P{i}", -L * F.y)
        tip.v2pt_theory(prev_p, frame_n, F)
        It = m * L ** 2 / 12
        bodies.append(me.RigidBody(f"B{i}", cm, F, m, (me.inertia(F, It, 0, It), cm)))
        loads.append((cm, -m * g * frame_n.y))
        kd.append(q[i].diff() - u[i])
        prev_f, prev_p = F, tip
    km = me.KanesMethod(frame_n, q_ind=q, u_ind=u, kd_eqs=kd)
    km.kanes_equations(bodies, loads)
    return km, q, u


def derive(N, L=0.5, m=1.0, g=9.81):
    import sympy as sp

    t0 = time.perf_counter()
    km, q, u = kane(N, L, m, g)
    t_derive = time.perf_counter() - t0
    t0 = time.perf_counter()
    Mf = sp.lambdify([q, u], km.mass_matrix, cse=True)
    Ff = sp.lambdify([q, u], km.forcing, cse=True)
    return Derived(N, Mf, Ff, t_derive, time.perf_counter() - t0)


def simulate(d, q0, u0, t_end, rtol, atol, method="DOP853"):
    N = d.N
    count = [0]

    def rhs(t, y):
        count[0] += 1
        q, u = y[:N], y[N:]
        return np.concatenate((u, np.linalg.solve(d.mass(q, u), np.asarray(d.forcing(q, u), float).ravel())))

    y0 = np.concatenate((np.broadcast_to(q0, N), np.broadcast_to(u0, N))).astype(float)
    rhs(0.0, y0)  # warm-up
    count[0] = 0
    c0 = time.process_time()
    sol = solve_ivp(rhs, (0.0, t_end), y0, method=method, rtol=rtol, atol=atol)
    cpu = time.process_time() - c0
    return dict(q=sol.y[:N, -1], cpu_s=cpu, nfev=count[0], status="success" if sol.success else "failed",
                message=sol.message)
