"""Reflected rotors (``ReflectedInertia``, ``ReflectedMass``: MuJoCo's armature) against closed forms.

The carrier test is a double pendulum in the vertical x-y plane (gravity -y, hinges about z):
link 1 (point mass ``m1`` at ``L1``) turns about the world hinge ``j1``; the hinge ``j2`` rides
on it, carrying a point mass ``m2`` at ``l2`` and a reflected rotor ``J`` -- a hinge on a
carrier that turns about the hinge's own axis, where a rotor turning with a body would add
``J`` to every entry. With ``th1`` absolute, ``th2`` relative (from hanging down),
``c = cos th2``, ``s = sin th2``, Lagrange's equations give ``M qdd = f`` with::

    M = [[m1 L1^2 + m2 (L1^2 + l2^2 + 2 L1 l2 c),  m2 (l2^2 + L1 l2 c)],
         [m2 (l2^2 + L1 l2 c),                     m2 l2^2 + J       ]]
    f = [m2 L1 l2 s (2 w1 w2 + w2^2) - (m1 + m2) g L1 sin th1 - m2 g l2 sin(th1 + th2),
         -m2 L1 l2 s w1^2 - m2 g l2 sin(th1 + th2)]

(the rotor's energy ``J w2^2 / 2`` is constant in ``q``: ``J`` on the diagonal, nothing in ``f``).
The rotor's torque ``-J dw2/dt`` acts inside the joint, so the reaction torque ``j2`` puts on
its frame_b about the axis is ``-J dw2/dt`` (a free hinge without the rotor carries none).
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.assembly.recursive import generalized_momenta, lagrange_accelerations, tree_evaluation, tree_pass
from mbcomp import Flange
from mbcomp.errors import ModelError
from mbcomp.library import (Cylindrical, FixedTranslation, IdealGear, Inertia, PointMass, PrescribedMotion, Prismatic,
                            ReflectedInertia, ReflectedMass, Revolute, RigidBody, World)

M1, M2, L1, L2, J, G = 1.5, 0.8, 0.7, 0.5, 0.3, 9.81
Q0, U0 = (0.4, -0.9), (1.3, -2.1)


def pendulum(rotor="reflected", N=None, q0=Q0, u0=U0, J=J):
    """The double pendulum; ``rotor``: "reflected" (ReflectedInertia on j2), "absolute"
    (Inertia on j2), "geared" (``Inertia(J / N^2)`` on a shaft on link 1 geared to j2 by
    ``IdealGear(ratio=N)``) or None."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    j1 = m.add("j1", Revolute(phi0=q0[0], w0=u0[0]))
    r1, b1 = m.add("r1", FixedTranslation(r=(0, -L1, 0))), m.add("b1", PointMass(m=M1))
    j2 = m.add("j2", Revolute(phi0=q0[1], w0=u0[1]))
    r2, b2 = m.add("r2", FixedTranslation(r=(0, -L2, 0))), m.add("b2", PointMass(m=M2))
    m.connect(w.frame_b, j1.frame_a); m.connect(j1.frame_b, r1.frame_a); m.connect(r1.frame_b, b1.frame_a)
    m.connect(r1.frame_b, j2.frame_a); m.connect(j2.frame_b, r2.frame_a); m.connect(r2.frame_b, b2.frame_a)
    if rotor in ("reflected", "absolute"):
        rot = m.add("motor", ReflectedInertia(J=J) if rotor == "reflected" else Inertia(J=J))
        m.connect(rot.flange, j2.axis)
    elif rotor == "geared":  # the motor's housing on link 1, its shaft geared to j2
        shaft = m.add("shaft", Revolute(w0=N * u0[1]))
        rot, gear = m.add("rotor", Inertia(J=J / N ** 2)), m.add("gear", IdealGear(ratio=N))
        m.connect(r1.frame_b, shaft.frame_a); m.connect(rot.flange, shaft.axis)
        m.connect(gear.flange_a, shaft.axis); m.connect(gear.flange_b, j2.axis)
    return m


def closed_form(q, u, J=J):
    (th1, th2), (w1, w2) = q, u
    c, s = np.cos(th2), np.sin(th2)
    M = np.array([[M1 * L1 ** 2 + M2 * (L1 ** 2 + L2 ** 2 + 2 * L1 * L2 * c), M2 * (L2 ** 2 + L1 * L2 * c)],
                  [M2 * (L2 ** 2 + L1 * L2 * c), M2 * L2 ** 2 + J]])
    f = np.array([M2 * L1 * L2 * s * (2 * w1 * w2 + w2 ** 2) - (M1 + M2) * G * L1 * np.sin(th1)
                  - M2 * G * L2 * np.sin(th1 + th2),
                  -M2 * L1 * L2 * s * w1 ** 2 - M2 * G * L2 * np.sin(th1 + th2)])
    return M, f


def closed_energy(q, u):
    M, _ = closed_form(q, u)
    (th1, th2) = q
    V = -(M1 + M2) * G * L1 * np.cos(th1) - M2 * G * L2 * np.cos(th1 + th2)
    return 0.5 * u @ M @ u + V


STATES = [(np.array([0.4, -0.9]), np.array([1.3, -2.1])), (np.array([2.5, 1.1]), np.array([-0.7, 3.0])),
          (np.array([-1.2, 3.0]), np.array([0.2, 0.4]))]


@pytest.mark.parametrize("k", range(len(STATES)))
def test_every_path_gives_the_closed_form(k):
    """Dense jets (M, f), the composite-rigid-body M, the articulated-body accelerations, the
    generalized momenta and the energy, and the generated C programs (the evaluation and the
    Lagrange right-hand side) against the closed form: ``J`` on j2's diagonal only."""
    from mbcomp.codegen import compile_system

    q, u = STATES[k]
    M, f = closed_form(q, u)
    tol = 1e-13 * np.abs(M).max()
    s = mbcomp.assemble(pendulum())
    ev = s.evaluate(0.0, q, u)
    np.testing.assert_allclose(ev.M, M, rtol=0, atol=tol)
    np.testing.assert_allclose(ev.f, f, rtol=0, atol=1e-13 * np.abs(f).max())
    np.testing.assert_allclose(tree_evaluation(s, 0.0, q, u).M, M, rtol=0, atol=tol)
    acc = np.linalg.solve(M, f)
    np.testing.assert_allclose(lagrange_accelerations(s, 0.0, q, u), acc, rtol=1e-12)
    np.testing.assert_allclose(generalized_momenta(tree_pass(s, 0.0, q, u), u, 2), M @ u, rtol=1e-13)
    T, V = s.energies(ev)
    assert abs(T + V - closed_energy(q, u)) < 1e-13 * abs(T) + 1e-13 * abs(V)
    c = compile_system(s, "c")
    cev = c.evaluate(0.0, q, u)
    np.testing.assert_allclose(cev.M, M, rtol=0, atol=tol)
    np.testing.assert_allclose(cev.f, f, rtol=0, atol=1e-13 * np.abs(f).max())
    dy = c.evaluator.lagrange_fun(0.0, np.concatenate((q, u)), 0.0, 0.0)
    np.testing.assert_allclose(dy, np.concatenate((u, acc)), rtol=1e-12)
    # the rotor turning with the body instead adds J to every entry (w_b = w1 + w2): not this
    assert abs(mbcomp.assemble(pendulum("absolute")).evaluate(0.0, q, u).M[0, 0] - M[0, 0] - J) < tol


def _reference(t_end):
    """The closed form integrated by scipy (DOP853, tolerances far below the runs')."""
    def rhs(t, y):
        M, f = closed_form(y[:2], y[2:])
        return np.concatenate((y[2:], np.linalg.solve(M, f)))
    return solve_ivp(rhs, (0.0, t_end), np.r_[Q0, U0], method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)


@pytest.mark.parametrize("formulation,backend", [("lagrange", "c"), ("dalembert", "c"), ("lagrange", "numeric")])
def test_a_run_follows_the_closed_form_conserves_energy_and_the_joint_carries_the_rotor(formulation, backend):
    """A compiled (and a numeric) run against the closed form's trajectory, the energy conserved
    to the run's tolerance, and j2's reaction torque about its axis ``-J dw2/dt`` (the
    rotor's torque acts inside the joint), every output time."""
    kw = {} if backend == "c" else {"backend": "numeric"}
    res = mbcomp.simulate(pendulum(), t_end=3.0, rtol=1e-10, atol=1e-10, formulation=formulation, **kw)
    assert (res.stats["backend"], res.stats["formulation"]) == (backend, formulation)
    assert res.status == "success"  # the energy alarm counts the rotor's energy
    ref = _reference(3.0).sol(res.time)
    assert np.abs(res["j1.phi"] - ref[0]).max() < 1e-7 and np.abs(res["j2.phi"] - ref[1]).max() < 1e-7
    E = res["energy.total"]
    assert abs(E[0] - closed_energy(np.array(Q0), np.array(U0))) < 1e-12
    assert np.ptp(E) < 1e-7 * np.abs(E).max()
    tau = res["j2.tau.z"]  # the reaction on frame_b, frame_b axes (the hinge axis is z)
    assert np.abs(tau).max() > 1.0  # the rotor is really accelerated
    np.testing.assert_allclose(tau, -J * res["j2.w.der"], rtol=0, atol=1e-9 * np.abs(tau).max())


def test_the_dense_reactions_carry_the_rotor_and_a_rotor_on_the_body_would_not():
    """The dense route's reactions (:meth:`MultibodySystem.reactions` with the Jacobians) at a
    state: ``-J dw2/dt`` about the axis; a rotor turning with frame_b (``Inertia``) is part of
    the body, so the free hinge carries nothing about its axis."""
    q, u = STATES[1]
    for rotor, expect in (("reflected", lambda ud: -J * ud[1]), ("absolute", lambda ud: 0.0)):
        s = mbcomp.assemble(pendulum(rotor))
        ev = s.evaluate(0.0, q, u)
        ud = np.linalg.solve(ev.M, ev.f)
        tau = s.reactions(ev, ud, np.zeros(0))["j2"][1][2]
        assert abs(tau - expect(ud)) < 1e-12 * (1 + abs(J * ud[1])), rotor


def test_a_rotor_through_a_gear_of_large_ratio_converges_to_the_reflected_one_as_1_over_n():
    """``Inertia(J / N^2)`` on a shaft carried by link 1 and geared to j2 by ``IdealGear(ratio=N)``
    turns at ``w1 + N w2``: energy ``J w2^2 / 2 + J w1 w2 / N + J w1^2 / (2 N^2)``. Its
    accelerations tend to the reflected rotor's, the difference falling as ``1 / N``."""
    q, u = np.array(Q0), np.array(U0)
    M, f = closed_form(q, u)
    exact = np.linalg.solve(M, f)
    errs = []
    for N in (10, 100, 1000):
        s = mbcomp.assemble(pendulum("geared", N))
        assert s.u_names == ["j1.w", "j2.w", "shaft.w"]
        ud = lagrange_accelerations(s, 0.0, np.r_[q, 0.0], np.r_[u, N * u[1]])
        errs.append(np.abs(ud[:2] - exact).max())
    for a, b in zip(errs, errs[1:]):
        assert 9.0 < a / b < 11.0, errs  # 1 / N
    assert errs[-1] < 1e-2 * np.abs(exact).max()


def turntable(m_r=0.6, drive=False):
    """A bead (mass 2) on a radial slider of a free turntable (inertia 0.5 about z): the slide's
    reflected mass ``m_r``."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    table = m.add("table", Revolute(n=(0, 0, 1), w0=1.5))
    disk = m.add("disk", RigidBody(m=1.0, I=np.diag([0.3, 0.3, 0.5])))
    slide = m.add("slide", Prismatic(n=(1, 0, 0), s0=0.3, v0=0.2))
    bead = m.add("bead", PointMass(m=2.0))
    screw = m.add("screw", ReflectedMass(m=m_r))
    m.connect(w.frame_b, table.frame_a); m.connect(table.frame_b, disk.frame_a)
    m.connect(table.frame_b, slide.frame_a); m.connect(slide.frame_b, bead.frame_a)
    m.connect(screw.flange, slide.axis)
    if drive:
        d = m.add("drive", PrescribedMotion(s=lambda t: 0.3 + t))
        m.connect(d.flange_b, slide.axis)
    return m


def test_a_reflected_mass_on_a_slider_on_a_turntable():
    """``T = (0.5 + 2 s^2) psi_dot^2 / 2 + (2 + m_r) s_dot^2 / 2``: ``M = diag(0.5 + 2 s^2,
    2 + m_r)``, ``f = (-4 s s_dot psi_dot, 2 s psi_dot^2)``, on every path."""
    s = mbcomp.assemble(turntable())
    assert s.u_names == ["table.w", "slide.v"]
    q, u = np.array([0.7, 0.4]), np.array([1.5, -0.8])
    M = np.diag([0.5 + 2 * 0.4 ** 2, 2.6])
    f = np.array([-4 * 0.4 * -0.8 * 1.5, 2 * 0.4 * 1.5 ** 2])
    ev = s.evaluate(0.0, q, u)
    np.testing.assert_allclose(ev.M, M, rtol=0, atol=1e-15)
    np.testing.assert_allclose(ev.f, f, rtol=0, atol=1e-14)
    np.testing.assert_allclose(tree_evaluation(s, 0.0, q, u).M, M, rtol=0, atol=1e-15)
    np.testing.assert_allclose(lagrange_accelerations(s, 0.0, q, u), f / M.diagonal(), rtol=1e-14)


def _problems(model):
    with pytest.raises(ModelError) as err:
        mbcomp.assemble(model)
    return str(err.value)


def test_a_reflected_rotor_without_a_joint_speed_of_its_own_is_refused_with_the_fix():
    m = pendulum(None)
    rot = m.add("motor", ReflectedInertia(J=J))
    m.connect(rot.flange, m["j2"].support)
    said = _problems(m)
    assert "motor" in said and "j2's support flange" in said and "connect it to j2.axis" in said
    said = _problems(turntable(drive=True))
    assert "screw" in said and "slide, whose motion drive prescribes" in said and "use Inertia" in said
    m = mbcomp.Model()  # two coaxial hinges on one wheel, each with a reflected rotor: one closes a loop
    w = m.add("world", World())
    wheel = m.add("wheel", RigidBody(m=1.0, I=np.eye(3)))
    for name in ("a", "b"):
        j = m.add(name, Revolute())
        rot = m.add(f"{name}_motor", ReflectedInertia(J=0.1))
        m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, wheel.frame_a); m.connect(rot.flange, j.axis)
    said = _problems(m)
    assert "closes a kinematic loop" in said and "keep" in said and "in the spanning tree" in said
    m = pendulum(None)
    rot = m.add("motor", ReflectedMass(m=1.0))
    m.connect(rot.flange, m["j2"].axis)
    assert "ReflectedMass" in _problems(m)  # a reflected mass on a hinge: the wrong kind of axis

    class Geared(Cylindrical):
        """A cylindrical joint with a turning axis flange: two speeds."""

        axis = Flange("the turning axis", optional=True)
        axis_kind = "rotational"

    m = mbcomp.Model()
    w, j, b = m.add("world", World()), m.add("j", Geared()), m.add("b", RigidBody())
    rot = m.add("motor", ReflectedInertia(J=0.1))
    m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a); m.connect(rot.flange, j.axis)
    said = _problems(m)
    assert "on j (Geared), a joint of 2 speeds" in said and "put it on a 1-DOF joint's axis" in said


def test_locking_the_joint_drops_its_reflected_rotor_and_says_so():
    """A reflected rotor turns at its joint's own rate, which the lock makes zero: the locked
    model's M is that of the model without the rotor, and a note says it was dropped."""
    with pytest.warns(UserWarning, match="turns at the joint's own rate"):
        held = pendulum().lock(["j2"], at={"j2": 0.6})
    assert any("'motor' on locked j2: dropped" in n for n in held.lock_notes)
    bare = pendulum(None).lock(["j2"], at={"j2": 0.6})
    q, u = np.array([0.3]), np.array([1.0])
    assert mbcomp.assemble(held).evaluate(0.0, q, u).M == pytest.approx(mbcomp.assemble(bare).evaluate(0.0, q, u).M,
                                                                      rel=1e-15)


def test_the_symbolic_equations_have_the_rotor_on_the_diagonal():
    """``mbcomp.equations`` (sympy): M and the kinetic energy are the closed form's, with the
    rotor's ``J w2^2 / 2`` alone (numbers as exact rationals)."""
    import sympy

    eq = mbcomp.equations(pendulum())
    at = {eq.q[0]: sympy.Rational(2, 5), eq.q[1]: sympy.Rational(-9, 10), eq.u[0]: sympy.Rational(13, 10),
          eq.u[1]: sympy.Rational(-21, 10)}
    M, _ = closed_form(np.array(Q0), np.array(U0))
    np.testing.assert_allclose(np.array(eq.M.subs(at), dtype=float), M, rtol=1e-15)
    T = 0.5 * np.array(U0) @ M @ np.array(U0)
    assert abs(float(eq.T.subs(at)) - T) < 1e-14 * T


def test_the_sensitivity_to_the_rotors_inertia_is_the_finite_difference():
    """The forward sensitivity ``d th2(1 s) / d J`` (exact derivative programs of the traced
    rotor) against a central difference of two runs."""
    res = mbcomp.simulate(pendulum(), t_end=1.0, rtol=1e-11, atol=1e-11, sensitivities=["motor.J"])
    h = 1e-5
    ends = [mbcomp.simulate(pendulum(J=J + d), t_end=1.0, rtol=1e-12, atol=1e-12)["j2.phi"][-1] for d in (h, -h)]
    fd = (ends[0] - ends[1]) / (2 * h)
    assert abs(fd) > 1.0 and abs(res.sensitivity("j2.phi", "motor.J")[-1] - fd) < 1e-6 * abs(fd)


def test_two_reflected_rotors_on_one_joint_add():
    """Two rotors ``J / 3`` and ``2 J / 3`` on j2 are one of ``J``: dense M, CRBA and the
    articulated-body pivot alike."""
    m = pendulum(None)
    for name, Jk in (("motor_a", J / 3), ("motor_b", 2 * J / 3)):
        m.connect(m.add(name, ReflectedInertia(J=Jk)).flange, m["j2"].axis)
    s = mbcomp.assemble(m)
    q, u = STATES[2]
    M, f = closed_form(q, u)
    np.testing.assert_allclose(s.evaluate(0.0, q, u).M, M, rtol=1e-14)
    np.testing.assert_allclose(tree_evaluation(s, 0.0, q, u).M, M, rtol=1e-14)
    np.testing.assert_allclose(lagrange_accelerations(s, 0.0, q, u), np.linalg.solve(M, f), rtol=1e-12)
