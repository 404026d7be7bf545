"""Sensors (library/sensors.py): named measurements against analytic motion.

Each test compares a sensor's columns with physics computed independently of it: uniform
circular motion, free fall and Euler's equations of a free rigid body, finite differences of
the sensor's own lower-order columns (which derivative v_rel and a_rel are), rotation matrices
built from joint angles, Newton's law for the bob below a cut-force sensor; and that a
sensor changes nothing in the motion. The compiled output programs ("python", "c") must give
the numeric route's columns.
"""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.outputs import output_values
from mbcomp.codegen.outputs import OutputProgram
from mbcomp.kinematics import quat_to_matrix, rot_axis
from mbcomp.library import (AbsoluteAngles, AbsoluteSensor, CutForceAndTorque, FixedTranslation, PointMass,
                            RelativeSensor, Revolute, RigidBody, World)
from mbcomp.library.sensors import angles_from_matrix, matrix_from_angles

BACKENDS = ["numeric", "python", "c"]
G = np.array([0.0, -9.81, 0.0])


def vec(res, prefix):
    """Columns ``prefix.x|y|z`` as an (n, 3) array."""
    return np.stack([res[f"{prefix}.{a}"] for a in "xyz"], axis=1)


def rotations(res, body):
    """The body's rotation matrices (n, 3, 3) from its quaternion columns."""
    Q = np.stack([res[f"{body}.Q.{c}"] for c in "wxyz"], axis=1)
    return np.array([quat_to_matrix(q) for q in Q])


# ------------------------------------------------------------------------------------------
# RelativeSensor
# ------------------------------------------------------------------------------------------
W, L = 2.0, 1.5  # rad/s, m


def turning(resolve_in, sensor=True):
    """A bob on a 1.5 m rod turning at constant 2 rad/s about z (no gravity); the sensor from
    the world (frame_a) to the bob (frame_b)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.3, w0=W))
    rod = m.add("rod", FixedTranslation(r=(L, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    if sensor:
        s = m.add("s", RelativeSensor(resolve_in=resolve_in))
        m.connect(w.frame_b, s.frame_a)
        m.connect(bob.frame_a, s.frame_b)
    return m


@pytest.mark.parametrize("backend", BACKENDS)
def test_relative_sensor_uniform_circle_resolved_in_the_world_frame_a(backend):
    res = mbcomp.simulate(turning("frame_a"), 2.0, backend=backend, n_out=41)
    r, v, a = vec(res, "s.r_rel"), vec(res, "s.v_rel"), vec(res, "s.a_rel")
    phi = 0.3 + W * res.time
    np.testing.assert_allclose(r, np.stack([L * np.cos(phi), L * np.sin(phi), 0 * phi], axis=1), rtol=0, atol=1e-7)
    np.testing.assert_allclose(r, vec(res, "bob.r"), rtol=0, atol=1e-12)
    w = np.array([0.0, 0.0, W])
    np.testing.assert_allclose(v, np.cross(w, r), rtol=0, atol=1e-9)          # v = w x r
    np.testing.assert_allclose(a, -W ** 2 * r, rtol=0, atol=1e-9)             # centripetal
    np.testing.assert_allclose(vec(res, "s.w_rel"), np.tile(w, (len(r), 1)), rtol=0, atol=1e-9)
    wrapped = np.abs((phi + np.pi) % (2 * np.pi) - np.pi)              # rotation angle in [0, pi]
    np.testing.assert_allclose(res["s.angle"], wrapped, rtol=0, atol=1e-7)


@pytest.mark.parametrize("backend", BACKENDS)
def test_relative_sensor_resolved_in_the_rotating_frame_b_is_constant(backend):
    """Derivatives taken in frame_a (the world), resolved in the bob's turning frame: constant."""
    res = mbcomp.simulate(turning("frame_b"), 2.0, backend=backend, n_out=41)
    n = len(res.time)
    np.testing.assert_allclose(vec(res, "s.r_rel"), np.tile([L, 0, 0], (n, 1)), rtol=0, atol=1e-9)
    np.testing.assert_allclose(vec(res, "s.v_rel"), np.tile([0, W * L, 0], (n, 1)), rtol=0, atol=1e-9)
    np.testing.assert_allclose(vec(res, "s.a_rel"), np.tile([-W ** 2 * L, 0, 0], (n, 1)), rtol=0, atol=1e-9)


def double_pendulum(sensor=True):
    """Two links swinging in gravity; the sensor from the first link's end (frame_a, moving
    and turning) to the second bob."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j1 = m.add("j1", Revolute(n=(0, 0, 1), phi0=1.0))
    rod1 = m.add("rod1", FixedTranslation(r=(0, -1.0, 0)))
    b1 = m.add("b1", PointMass(m=1.0))
    j2 = m.add("j2", Revolute(n=(0, 0, 1), phi0=-0.5, w0=2.0))
    rod2 = m.add("rod2", FixedTranslation(r=(0.3, -0.8, 0)))
    b2 = m.add("b2", PointMass(m=0.5))
    m.connect(w.frame_b, j1.frame_a)
    m.connect(j1.frame_b, rod1.frame_a)
    m.connect(rod1.frame_b, b1.frame_a)
    m.connect(b1.frame_a, j2.frame_a)
    m.connect(j2.frame_b, rod2.frame_a)
    m.connect(rod2.frame_b, b2.frame_a)
    if sensor:
        for res in ("frame_a", "world"):
            s = m.add(f"s_{res}", RelativeSensor(resolve_in=res))
            m.connect(b1.frame_a, s.frame_a)
            m.connect(b2.frame_a, s.frame_b)
    return m


def test_relative_velocity_and_acceleration_are_derivatives_in_frame_a():
    """With frame_a moving and turning, v_rel and a_rel (frame_a components) are the time
    derivatives of r_rel and v_rel (frame_a components), by central differences of a dense
    output; resolved in the world they are the same vectors rotated by R_a."""
    # five-point differences (error O(h^4): 1e-8 and 3e-7 at h = 1 ms) on 1001 points: the
    # three-point ones needed 4001 (6e-6 and 1.1e-4 against the same bounds), each output
    # point evaluated numerically
    res = mbcomp.simulate(double_pendulum(), 1.0, backend="numeric", n_out=1001, rtol=1e-12, atol=1e-12)
    t = res.time
    r, v, a = vec(res, "s_frame_a.r_rel"), vec(res, "s_frame_a.v_rel"), vec(res, "s_frame_a.a_rel")
    h = t[1] - t[0]

    def derivative(f):
        return (f[:-4] - 8 * f[1:-3] + 8 * f[3:-1] - f[4:]) / (12 * h)

    assert np.abs(v).max() > 1.0 and np.abs(a).max() > 5.0  # nothing trivial
    np.testing.assert_allclose(v[2:-2], derivative(r), rtol=0, atol=2e-5)
    np.testing.assert_allclose(a[2:-2], derivative(v), rtol=0, atol=2e-4)
    # the naive world-frame difference of the positions is another vector (the Coriolis terms matter)
    assert np.abs(vec(res, "b2.v") - vec(res, "b1.v") - v).max() > 0.1
    Ra = np.array([rot_axis([0, 0, 1], p) for p in res["j1.phi"]])
    for name in ("r_rel", "v_rel", "a_rel", "w_rel"):
        np.testing.assert_allclose(vec(res, f"s_world.{name}"),
                                   np.einsum("kij,kj->ki", Ra, vec(res, f"s_frame_a.{name}")), rtol=0, atol=1e-12)
    np.testing.assert_allclose(res["s_frame_a.w_rel.z"], res["j2.w"], rtol=0, atol=1e-12)


# ------------------------------------------------------------------------------------------
# AbsoluteSensor
# ------------------------------------------------------------------------------------------
INERTIA = np.diag([1.0, 2.0, 3.0])


def tumbling(sensor=True):
    """A free rigid body falling and tumbling (principal inertias 1, 2, 3 kg m^2)."""
    m = mbcomp.Model()
    m.add("world", World())
    ball = m.add("ball", RigidBody(m=1.5, I=INERTIA), free=True)
    if sensor:
        s = m.add("s", AbsoluteSensor())
        m.connect(ball.frame_a, s.frame_a)
        s = m.add("sb", AbsoluteSensor(resolve_in="frame_a"))
        m.connect(ball.frame_a, s.frame_a)
    return m


PARAMS = {"ball.free.w0": (1.0, 2.0, 0.5), "ball.free.v0": (0.3, 1.0, 0.0)}


@pytest.mark.parametrize("backend", BACKENDS)
def test_absolute_sensor_free_fall_and_euler_equations(backend):
    res = mbcomp.simulate(tumbling(), 1.5, params=PARAMS, backend=backend, n_out=31)
    n = len(res.time)
    np.testing.assert_allclose(vec(res, "s.a"), np.tile(G, (n, 1)), rtol=0, atol=1e-9)       # free fall
    for name in ("r", "v", "w"):
        np.testing.assert_allclose(vec(res, f"s.{name}"), vec(res, f"ball.{name}"), rtol=0, atol=1e-13)
    # torque-free Euler equations, world frame: I_w alpha = -w x (I_w w)
    R, w, alpha = rotations(res, "ball"), vec(res, "ball.w"), vec(res, "s.alpha")
    Iw = R @ INERTIA @ R.transpose(0, 2, 1)
    expected = np.linalg.solve(Iw, -np.cross(w, np.einsum("kij,kj->ki", Iw, w))[..., None])[..., 0]
    assert np.abs(expected).max() > 0.5
    np.testing.assert_allclose(alpha, expected, rtol=0, atol=1e-9)
    # resolved in the body: R^T times the world vectors
    for name in ("r", "v", "a", "w", "alpha"):
        np.testing.assert_allclose(vec(res, f"sb.{name}"), np.einsum("kji,kj->ki", R, vec(res, f"s.{name}")),
                                   rtol=0, atol=1e-12)


@pytest.mark.parametrize("backend", ["python", "c"])
@pytest.mark.parametrize("build", [tumbling, lambda: double_pendulum(), lambda: pendulum(cut=True)],
                         ids=["tumbling", "double_pendulum", "cut_pendulum"])
def test_compiled_output_programs_give_the_numeric_sensor_columns(build, backend):
    """The traced output program (codegen/outputs.py) against output_values on the same states."""
    system = mbcomp.assemble(build())
    res = mbcomp.simulate(system, 1.0, params=PARAMS if build is tumbling else None, backend="numeric", n_out=11)
    system = res.system
    Y = np.stack([res[n] for n in system.q_names + system.u_names], axis=1)
    prog = OutputProgram.build(system, backend, baumgarte=False)
    names, V, _, ok = prog.grid(system, res.time, Y, None)
    assert ok.all()
    sensors = [k for k, name in enumerate(names) if name.split(".")[0] in ("s", "sb", "s_frame_a", "s_world", "cut")]
    assert len(sensors) >= 12
    for i, t in enumerate(res.time):
        cols, _ = output_values(system, t, Y[i, :system.nq], Y[i, system.nq:])
        for k in sensors:
            assert abs(V[k, i] - cols[names[k]]) <= 1e-9 * (1 + abs(cols[names[k]])), names[k]


# ------------------------------------------------------------------------------------------
# AbsoluteAngles
# ------------------------------------------------------------------------------------------
SEQUENCES = ["xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz"]


@pytest.mark.parametrize("sequence", SEQUENCES)
def test_angles_from_matrix_inverts_matrix_from_angles(sequence):
    rng = np.random.default_rng(len(sequence) + SEQUENCES.index(sequence))
    cardan = sequence[0] != sequence[2]
    for _ in range(50):
        phi = np.array([rng.uniform(-np.pi, np.pi),
                        rng.uniform(-np.pi / 2, np.pi / 2) if cardan else rng.uniform(0, np.pi),
                        rng.uniform(-np.pi, np.pi)])
        R = matrix_from_angles(phi, sequence)
        np.testing.assert_allclose(R @ R.T, np.eye(3), rtol=0, atol=1e-14)
        back = angles_from_matrix(R, sequence)
        np.testing.assert_allclose(back, phi, rtol=0, atol=1e-9)
        # any rotation: the angles rebuild it (also outside the principal ranges)
        R2 = matrix_from_angles(rng.uniform(-4, 4, 3), sequence)
        np.testing.assert_allclose(matrix_from_angles(angles_from_matrix(R2, sequence), sequence), R2, rtol=0, atol=1e-12)


def test_angles_convention_is_intrinsic_rotations_in_order():
    """"xyz": rotate about x by phi1, then about the new y by phi2, then the newest z by phi3."""
    phi = (0.4, -0.7, 1.1)
    Rx, Ry, Rz = (rot_axis(e, p) for e, p in zip(np.eye(3), phi))
    np.testing.assert_allclose(matrix_from_angles(phi, "xyz"), Rx @ Ry @ Rz, rtol=0, atol=1e-15)
    # the second rotation's axis is the once-rotated y axis, in world coordinates R_x e_y
    np.testing.assert_allclose(rot_axis(Rx @ [0, 1, 0], phi[1]) @ Rx, Rx @ Ry, rtol=0, atol=1e-15)


def gimbal(sensor=True):
    """A body on three revolute joints about x, y, z in a row (a gimbal), swinging in gravity."""
    m = mbcomp.Model()
    w = m.add("world", World())
    prev = w.frame_b
    for k, (n, phi0, w0) in enumerate(zip(np.eye(3), (0.3, -0.4, 0.9), (0.5, -0.3, 1.0))):
        j = m.add(f"j{k + 1}", Revolute(n=n, phi0=phi0, w0=w0))
        m.connect(prev, j.frame_a)
        prev = j.frame_b
    body = m.add("body", RigidBody(m=1.0, r_cm=(0.2, 0.1, -0.3), I=np.diag([0.1, 0.2, 0.25])))
    m.connect(prev, body.frame_a)
    for seq in ("xyz", "zxz") if sensor else ():
        s = m.add(f"ang_{seq}", AbsoluteAngles(sequence=seq))
        m.connect(body.frame_a, s.frame_a)
    return m


@pytest.mark.parametrize("backend", ["numeric", "c"])
def test_absolute_angles_of_a_gimbal_are_its_joint_angles(backend):
    res = mbcomp.simulate(gimbal(), 1.0, backend=backend, n_out=51)
    q = np.stack([res[f"j{k}.phi"] for k in (1, 2, 3)], axis=1)
    assert np.ptp(q, axis=0).min() > 0.1 and np.abs(q[:, 1]).max() < np.pi / 2  # moving, in range
    ang = np.stack([res[f"ang_xyz.angles.{k}"] for k in (1, 2, 3)], axis=1)
    wrap = lambda x: (x + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(wrap(ang - q), 0.0, rtol=0, atol=1e-9)
    # another sequence of the same orientation: its angles rebuild the body's rotation matrix
    R = rotations(res, "body")
    zxz = np.stack([res[f"ang_zxz.angles.{k}"] for k in (1, 2, 3)], axis=1)
    np.testing.assert_allclose(np.array([matrix_from_angles(p, "zxz") for p in zxz]), R, rtol=0, atol=1e-9)


def test_bad_sequence_and_frame_names_are_model_problems():
    m = mbcomp.Model()
    w = m.add("world", World())
    s = m.add("ang", AbsoluteAngles(sequence="xxy"))
    r = m.add("rel", RelativeSensor(resolve_in="body"))
    m.connect(w.frame_b, s.frame_a)
    m.connect(w.frame_b, r.frame_a)
    m.connect(w.frame_b, r.frame_b)
    with pytest.raises(mbcomp.ModelError) as err:
        mbcomp.assemble(m)
    text = str(err.value)
    assert "ang.sequence" in text and "'xxy'" in text and "rel.resolve_in" in text and "'frame_b'" in text


# ------------------------------------------------------------------------------------------
# CutForceAndTorque
# ------------------------------------------------------------------------------------------
M_BOB, I_BOB = 2.0, np.diag([0.01, 0.02, 0.03])


def pendulum(cut=False, sensor=True, resolve_in="frame_a"):
    """A rod (0.5 kg at its end) on a hinge about z carrying a rigid bob below a cut-force
    sensor: the sensor a tree edge, or (``cut``) a cut joint closing the loop to a bob that
    floats free."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.7, w0=-0.4))
    rod = m.add("rod", FixedTranslation(r=(0, -1.2, 0)))
    bob = m.add("bob", RigidBody(m=M_BOB, I=I_BOB), free=cut)
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, m.add("end", PointMass(m=0.5)).frame_a)
    if sensor:
        s = m.add("cut", CutForceAndTorque(cut=cut, resolve_in=resolve_in))
        m.connect(rod.frame_b, s.frame_a)
        m.connect(s.frame_b, bob.frame_a)
        acc = m.add("acc", AbsoluteSensor())
        m.connect(bob.frame_a, acc.frame_a)
    else:
        m.connect(rod.frame_b, bob.frame_a)
    return m


def _newton(res):
    """The force and torque (world) the bob needs, from the hinge's motion alone: a bob at
    R_z(phi) (0, -1.2, 0) has a = alpha x r - w^2 r; force m (a - g), torque I_zz alpha."""
    phi, w, al = res["j.phi"], res["j.w"], res["j.w.der"]
    r = np.stack([1.2 * np.sin(phi), -1.2 * np.cos(phi), 0 * phi], axis=1)
    alpha = np.stack([0 * phi, 0 * phi, al], axis=1)
    a = np.cross(alpha, r) - (w ** 2)[:, None] * r
    return M_BOB * (a - G), I_BOB[2, 2] * alpha


@pytest.mark.parametrize("cut", [False, True], ids=["tree_edge", "cut_joint"])
@pytest.mark.parametrize("backend", ["numeric", "python", "c"])
def test_cut_force_is_what_the_bob_needs_and_the_reaction(cut, backend):
    res = mbcomp.simulate(pendulum(cut, resolve_in="world"), 2.0, backend=backend, n_out=41)
    assert res.system.topology.cut == (["cut"] if cut else [])
    F, T = vec(res, "cut.force"), vec(res, "cut.torque")
    assert np.abs(F[:, 0]).max() > 1.0 and np.abs(T[:, 2]).max() > 1e-3
    # Newton and Euler for the bob (the only load on it besides gravity), its own accelerations
    np.testing.assert_allclose(F, M_BOB * (vec(res, "acc.a") - G), rtol=0, atol=1e-11)
    np.testing.assert_allclose(T, vec(res, "acc.alpha") @ I_BOB, rtol=0, atol=1e-11)  # planar: w x I w = 0
    # the same from the hinge's motion (a cut loop is closed up to the Baumgarte-stabilized drift)
    F_expected, T_expected = _newton(res)
    np.testing.assert_allclose(F, F_expected, rtol=0, atol=1e-6 if cut else 1e-11)
    np.testing.assert_allclose(T, T_expected, rtol=0, atol=1e-8 if cut else 1e-11)
    # the joint's reaction columns (exerted on frame_b, frame_b = bob coordinates): the same wrench
    Rb = rotations(res, "bob")
    np.testing.assert_allclose(F, np.einsum("kij,kj->ki", Rb, vec(res, "cut.f")), rtol=0, atol=1e-12)
    np.testing.assert_allclose(T, np.einsum("kij,kj->ki", Rb, vec(res, "cut.tau")), rtol=0, atol=1e-12)


def test_cut_force_resolved_in_frame_a_turns_with_the_rod():
    res = mbcomp.simulate(pendulum(resolve_in="frame_a"), 2.0, backend="numeric", n_out=41)
    F_expected, _ = _newton(res)
    Ra = np.array([rot_axis([0, 0, 1], p) for p in res["j.phi"]])
    np.testing.assert_allclose(vec(res, "cut.force"), np.einsum("kji,kj->ki", Ra, F_expected), rtol=0, atol=1e-8)
    # at the rod's end the rod pulls the bob along the rod: no force across it without alpha
    np.testing.assert_allclose(res["cut.force.x"], M_BOB * (1.2 * res["j.w.der"] + 9.81 * np.sin(res["j.phi"])),
                               rtol=0, atol=1e-8)


# ------------------------------------------------------------------------------------------
# sensors change nothing
# ------------------------------------------------------------------------------------------
CASES = {
    "relative": (lambda s: turning("frame_b", s), "bob", {}),
    "double_pendulum": (double_pendulum, "b2", {}),
    "absolute": (tumbling, "ball", {"params": PARAMS}),
    "angles": (gimbal, "body", {}),
    "cut_force": (lambda s: pendulum(sensor=s), "bob", {}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_sensors_change_nothing_in_the_motion(case):
    build, body, kw = CASES[case]
    runs = [mbcomp.simulate(build(s), 1.0, backend="c", n_out=21, **kw) for s in (True, False)]
    for name in ("r", "v", "w"):
        np.testing.assert_allclose(vec(runs[0], f"{body}.{name}"), vec(runs[1], f"{body}.{name}"),
                                   rtol=0, atol=1e-12, err_msg=name)
    np.testing.assert_array_equal(runs[0].time, runs[1].time)
