"""Nonholonomic constraints B(q) u = b through the whole pipeline: the Chaplygin sleigh.

A user-written joint (public API only): a knife edge on a plane, i.e. a planar joint with
one velocity-level constraint (no lateral slip of the blade). With the centre of mass a
distance ``a`` ahead of the blade, the sleigh obeys (Neimark & Fufaev)::

    m v' = m a w^2,    (I_c + m a^2) w' = -m a v w,

v the blade's forward speed, w the yaw rate; the lateral blade force is m (v w + a w').
"""
import numpy as np
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp import Guess, Joint, Param
from mbcomp.jets import local_point, local_vector, position_constraints, velocity_along
from mbcomp.kinematics import rot_axis
from mbcomp.library import RigidBody, World
from mbcomp.roles import split_start

EX, EY, EZ = np.eye(3)


class KnifeEdge(Joint):
    """Planar motion of frame_b on frame_a's x-y plane with no slip across frame_b's y axis."""

    coordinates = (("x", "m"), ("y", "m"), ("theta", "rad"))
    speeds = (("vx", "m/s"), ("vy", "m/s"), ("w", "rad/s"))
    q0 = Param(None, unit="m, m, rad", shape=(3,), kind="start", doc="start x, y, theta")
    u0 = Param(None, unit="m/s, m/s, rad/s", shape=(3,), kind="any", doc="start rates (list of numbers/Guess)")

    def start(self, p):
        q, qf = split_start(p.q0, 3)
        u = np.zeros(3)
        uf = np.zeros(3, bool)
        for i, v in enumerate(p.u0 or []):
            val, fixed = split_start(v, 1)
            u[i], uf[i] = val[0], fixed
        return q, np.full(3, qf), u, uf

    def relative(self, q, p):
        return rot_axis(EZ, q[2]), np.array([q[0], q[1], 0.0])

    def motion(self, q, p):
        return np.outer(EZ, [0, 0, 1.0]), np.column_stack((EX, EY, np.zeros(3)))

    def constraints(self, a, b, p):
        raise NotImplementedError("not needed: the sleigh's knife edge is a tree joint here")

    def velocity_constraints(self, a, b, p):
        return [("no_slip", velocity_along(local_point(b, 1), local_vector(b, EY, 1)))]


def sleigh(m=2.0, Ic=0.05, a=0.3, theta0=0.5, w0=2.0):
    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0, 0, -9.81)))
    edge = mdl.add("edge", KnifeEdge(q0=(0.0, 0.0, theta0), u0=[Guess(1.0), Guess(0.0), w0]))
    body = mdl.add("body", RigidBody(m=m, r_cm=(a, 0, 0), I=np.diag([Ic, Ic, Ic])))
    mdl.connect(world.frame_b, edge.frame_a)
    mdl.connect(edge.frame_b, body.frame_a)
    return mdl


def test_chaplygin_sleigh_matches_its_reduced_equations():
    m, Ic, a = 2.0, 0.05, 0.3
    res = mbcomp.simulate(sleigh(m, Ic, a), t_end=4.0, rtol=1e-10, atol=1e-12, n_out=201)
    assert res.success, res.message
    th = res["edge.theta"]
    v = res["edge.vx"] * np.cos(th) + res["edge.vy"] * np.sin(th)  # forward speed of the blade
    w = res["edge.w"]
    lateral = -res["edge.vx"] * np.sin(th) + res["edge.vy"] * np.cos(th)
    assert np.abs(lateral).max() < 1e-9  # no slip, including the initialized start
    assert abs(w[0] - 2.0) < 1e-14  # the fixed start rate was honoured

    def rhs(_, y):
        vv, ww = y
        return [a * ww ** 2, -m * a * vv * ww / (Ic + m * a ** 2)]

    ref = solve_ivp(rhs, (0, 4.0), [v[0], w[0]], t_eval=res.time, rtol=1e-12, atol=1e-12, method="DOP853")
    np.testing.assert_allclose(v, ref.y[0], atol=1e-7)
    np.testing.assert_allclose(w, ref.y[1], atol=1e-7)
    E = res["energy.kinetic"]
    assert np.abs(E - E[0]).max() < 1e-8 * E[0]  # the no-slip force does no work
    # lateral blade force (reaction on frame_b along its y axis) = m (v w + a w')
    wdot = np.array(rhs(0, [v, w])[1])
    np.testing.assert_allclose(res["edge.f.y"], m * (v * w + a * wdot), atol=1e-6)
    assert res["residual.nonholonomic"].max() < 1e-9


def test_summary_counts_nonholonomic_constraints_separately():
    text = mbcomp.assemble(sleigh()).summary()
    assert "degrees of freedom: 3 " in text
    assert "nonholonomic constraints (velocity level): 1; motion DOF 2" in text


def test_baumgarte_and_projection_agree_on_the_sleigh():
    kw = dict(t_end=2.0, rtol=1e-10, atol=1e-12, n_out=21)
    r1 = mbcomp.simulate(sleigh(), stabilization="baumgarte", **kw)
    r2 = mbcomp.simulate(sleigh(), stabilization="projection", **kw)
    np.testing.assert_allclose(r1["edge.x"], r2["edge.x"], atol=1e-8)
    np.testing.assert_allclose(r1["edge.y"], r2["edge.y"], atol=1e-8)
