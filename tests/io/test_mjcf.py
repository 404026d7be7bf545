"""MJCF import checked against MuJoCo: mass matrices, bias forces and accelerations of dm-control's models.

mbcomp's equations are ``M du/dt = f``; MuJoCo's ``M qacc = qfrc_passive - qfrc_bias +
qfrc_actuator + qfrc_constraint`` with ``qfrc_bias = C(q, v) v + g(q)``. The models are
compiled by MuJoCo from the same file (mbcomp reads it without MuJoCo), then compared with
MuJoCo's fluid forces (``opt.density``, ``opt.viscosity``) set to 0 and the hinges' and
slides' armature on both sides (mbcomp's ``ReflectedInertia``/``ReflectedMass``, see
:mod:`mbcomp.io.mjcf_joints`; cheetah, walker, hopper, humanoid, quadruped, humanoid_CMU and
dog have it on their hinges, the others none); the joints' springs and dampers are in
``f``, so ``f = -qfrc_bias + qfrc_spring + qfrc_damper``. The states are the same numbers:
mbcomp's hinge and slide coordinates are MuJoCo's ``qpos`` (``ref`` included), a ball's and a
free joint's quaternion is MuJoCo's (w x y z), their speeds MuJoCo's ``qvel`` (a ball's
angular velocity in body axes; a free joint's linear velocity in world axes, angular in body
axes), matched by joint name (``model.mjcf_joints``, MuJoCo's joint order).
"""
import copy
import functools
import os
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.io.mjcf import body_frames, load_mjcf
from mujoco_matrices import full_mass_matrix

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is not installed (the reference engine of these checks)")


def _suite_dir():
    try:
        import dm_control
    except ImportError:
        return None
    return os.path.join(os.path.dirname(dm_control.__file__), "suite")


SUITE = _suite_dir()
needs_suite = pytest.mark.skipif(SUITE is None, reason="dm-control is not installed (pip install mbcomp[robots])")

MODELS = ["pendulum", "cartpole", "acrobot", "cheetah", "walker", "hopper", "reacher", "finger", "swimmer",
          "point_mass", "ball_in_cup", "fish", "humanoid", "quadruped", "manipulator", "stacker", "humanoid_CMU", "dog"]


@functools.lru_cache(maxsize=None)
def _pair(path, armature=True):
    """(mbcomp model, system, MuJoCo model) of one file, fluid off; ``armature=False``: off on
    both sides."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        model = load_mjcf(path, armature=armature)
    system = mbcomp.assemble(model)
    mj = _compiled(path)
    mj.opt.density = mj.opt.viscosity = 0.0
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT  # no bearing on M and qfrc_bias; random
    # states would interpenetrate (the dog's contacts overflow MuJoCo's arena, logged to the working directory)
    mj.tendon_stiffness[:] = mj.tendon_damping[:] = 0.0  # tendons are not imported (noted)
    if not armature:
        mj.dof_armature[:] = 0.0
    for note in model.mjcf_notes:  # joints whose stiffness and damping MuJoCo derives from M (not imported)
        if note.endswith("springdamper (stiffness and damping from a time constant) not imported"):
            k = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, note.split("'")[1])
            mj.jnt_stiffness[k] = mj.dof_damping[mj.jnt_dofadr[k]] = 0.0
    return model, system, mj


def _compiled(path):
    """MuJoCo's model of ``path``, compiled in a scratch directory (MuJoCo writes its warnings,
    e.g. settotalmass's deprecation, to MUJOCO_LOG.TXT in the working directory)."""
    import tempfile

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)
        try:
            return mujoco.MjModel.from_xml_path(os.path.abspath(os.path.join(here, path)))
        finally:
            os.chdir(here)


def _layout(model, system, mj):
    """For each MuJoCo joint: its type, qpos and dof addresses and mbcomp's q and u indices."""
    out = []
    for k, cname in enumerate(model.mjcf_joints):
        q = [i for i, n in enumerate(system.q_names) if n.split(".")[0] == cname]
        u = [i for i, n in enumerate(system.u_names) if n.split(".")[0] == cname]
        out.append((int(mj.jnt_type[k]), int(mj.jnt_qposadr[k]), int(mj.jnt_dofadr[k]), q, u))
    return out


def _random_state(layout, mj, rng):
    """Equal states: MuJoCo's (qpos, qvel) and mbcomp's (q, u), and the permutation ``u = P qvel``."""
    qpos, qvel = mj.qpos0.copy(), rng.standard_normal(mj.nv)
    nq = sum(len(q) for *_, q, _ in layout)
    q, P = np.zeros(nq), np.zeros((sum(len(u) for *_, u in layout), mj.nv))
    for typ, qa, da, qi, ui in layout:
        if typ == mujoco.mjtJoint.mjJNT_FREE:
            quat = rng.standard_normal(4)
            qpos[qa:qa + 7] = np.r_[rng.uniform(-1, 1, 3), quat / np.linalg.norm(quat)]
        elif typ == mujoco.mjtJoint.mjJNT_BALL:
            quat = rng.standard_normal(4)
            qpos[qa:qa + 4] = quat / np.linalg.norm(quat)
        else:
            qpos[qa] = qpos[qa] + rng.uniform(-1.5, 1.5)
        width = len(ui)
        q[qi] = qpos[qa:qa + len(qi)]
        P[ui, da:da + width] = np.eye(width)
    return qpos, qvel, q, P @ qvel, P


def _mujoco_terms(mj, qpos, qvel):
    d = mujoco.MjData(mj)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(mj, d)
    return full_mass_matrix(mujoco, mj, d), -d.qfrc_bias + d.qfrc_spring + d.qfrc_damper


def _differences(path, n_states=3, armature=True):
    """Largest relative differences of M and of f over random states."""
    model, system, mj = _pair(path, armature)
    layout = _layout(model, system, mj)
    rng = np.random.default_rng(34)
    dM = df = 0.0
    for _ in range(n_states):
        qpos, qvel, q, u, P = _random_state(layout, mj, rng)
        ev = system.evaluate(0.0, q, u)
        M, f = _mujoco_terms(mj, qpos, qvel)
        dM = max(dM, np.abs(P.T @ ev.M @ P - M).max() / np.abs(M).max())
        df = max(df, np.abs(P.T @ ev.f - f).max() / np.abs(f).max())
    return dM, df


def _forward_difference(path, n_states=2, armature=True):
    """Largest relative difference of mbcomp's accelerations (articulated-body solve) and
    MuJoCo's ``qacc`` with contacts and constraints (limits, friction loss, equalities) off."""
    from mbcomp.assembly.recursive import lagrange_accelerations

    model, system, mj = _pair(path, armature)
    mj = copy.copy(mj)  # the cached model keeps its constraints
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT \
        | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    layout = _layout(model, system, mj)
    rng = np.random.default_rng(35)
    worst = 0.0
    for _ in range(n_states):
        qpos, qvel, q, u, P = _random_state(layout, mj, rng)
        d = mujoco.MjData(mj)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(mj, d)
        ud = lagrange_accelerations(system, 0.0, q, u)
        worst = max(worst, np.abs(P.T @ ud - d.qacc).max() / np.abs(d.qacc).max())
    return worst


@needs_suite
@pytest.mark.parametrize("name", MODELS)
def test_suite_model_matches_mujoco(name):
    dM, df = _differences(os.path.join(SUITE, name + ".xml"))
    print(f"{name}: nv {_pair(os.path.join(SUITE, name + '.xml'))[2].nv}, M {dM:.1e}, f {df:.1e}")
    assert dM < 1e-9 and df < 1e-9, f"{name}: mass matrix {dM:.1e}, bias forces {df:.1e} relative"


@needs_suite
@pytest.mark.parametrize("name", MODELS)
def test_forward_dynamics_matches_mujoco(name):
    d = _forward_difference(os.path.join(SUITE, name + ".xml"))
    print(f"{name}: qacc {d:.1e}")
    assert d < 1e-9, f"{name}: accelerations {d:.1e} relative"


def _write(tmp_path, text, name="model.xml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _load(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_mjcf(path, **kw)


DEFAULTS = """<mujoco><default><joint damping="1" axis="0 1 0"/><geom density="500"/>
  <default class="leg"><joint stiffness="4"/><geom type="box" size=".1 .2 .3"/>
    <default class="foot"><geom density="2000"/></default></default></default>
<worldbody><body name="thigh" childclass="leg" pos="0 0 2"><joint name="hip"/><geom/>
  <body name="foot" pos="0 0 -1"><joint name="ankle" damping="3"/><geom class="foot" pos="0.1 0 0"/></body>
</body></worldbody></mujoco>"""


def test_default_classes_are_inherited_as_mujoco_reads_them(tmp_path):
    """``childclass`` gives the thigh's geom the class ``leg`` (a box of density 500 from
    ``main``: 500 * 8 * 0.1 * 0.2 * 0.3 = 24 kg); ``foot`` inherits the box and overrides the
    density (96 kg); the ankle keeps ``leg``'s stiffness 4 and overrides ``main``'s damping 1
    with 3; axes along y from ``main``."""
    path = _write(tmp_path, DEFAULTS)
    model = _load(path)
    assert model["thigh"].p.m == pytest.approx(24.0, rel=1e-14)
    assert model["foot"].p.m == pytest.approx(96.0, rel=1e-14)
    assert model["foot"].p.r_cm.tolist() == [0.1, 0.0, 0.0]
    assert (model["hip_spring"].p.c, model["hip_spring"].p.d) == (4.0, 1.0)
    assert (model["ankle_spring"].p.c, model["ankle_spring"].p.d) == (4.0, 3.0)
    assert model["ankle"].p.n.tolist() == [0.0, 1.0, 0.0]
    dM, df = _differences(path, n_states=3)
    assert dM < 1e-13 and df < 1e-13, (dM, df)


ORIENTED = """<mujoco><compiler {compiler}/><worldbody>
<body name="b" pos="0.1 0.2 0.3" {spec}><joint type="slide" axis="1 0 0"/><geom type="box" size=".1 .2 .3"/></body>
</worldbody></mujoco>"""


@pytest.mark.parametrize("compiler, spec", [
    ('angle="degree"', 'euler="10 -20 130"'), ('angle="degree" eulerseq="XYZ"', 'euler="10 -20 130"'),
    ('angle="radian" eulerseq="zyx"', 'euler="0.3 1.1 -2.0"'), ('eulerseq="ZyX"', 'euler="40 -75 12"'),
    ('', 'axisangle="1 2 -1 160"'), ('angle="radian"', 'axisangle="0 0 3 1.0"'),
    ('', 'xyaxes="1 1 0 -1 2 0.5"'), ('', 'zaxis="0.3 -1 0.2"'), ('', 'zaxis="0 0 -1"'),
    ('', 'quat="0.5 0.1 -0.7 0.2"')])
def test_orientations_are_mujocos(tmp_path, compiler, spec):
    """Every way MJCF orients a frame, with degrees (MuJoCo's default) and radians, intrinsic
    (lowercase) and extrinsic (uppercase) Euler sequences: the body's world orientation at
    qpos0 equals MuJoCo's ``xmat`` to rounding."""
    path = _write(tmp_path, ORIENTED.format(compiler=compiler, spec=spec))
    frame = body_frames(_load(path))["b"]
    mj = _compiled(path)
    d = mujoco.MjData(mj)
    mujoco.mj_kinematics(mj, d)
    np.testing.assert_allclose(frame.R0, d.xmat[1].reshape(3, 3), rtol=0, atol=1e-14)
    np.testing.assert_allclose(frame.p0, d.xpos[1], rtol=0, atol=1e-15)


CAPSULE = """<mujoco><worldbody><body name="rod"><joint name="pivot" axis="1 0 0"/>
<geom type="capsule" fromto="0 0 0 0 0 {L}" size="{r}" density="{rho}"/></body></worldbody></mujoco>"""


def test_fromto_capsule_mass_properties_closed_form(tmp_path):
    """A capsule from the origin up z: a cylinder of length L and two hemispheres of radius
    r. Each hemisphere has mass m_h, centroid 3r/8 beyond the cylinder's end and transverse
    inertia 83/320 m_h r^2 about its centroid (the textbook values, not MuJoCo's expression),
    so about the pivot at the origin the moment is I_cm + m (L/2)^2 -- M of the hinge."""
    L, r, rho = 0.7, 0.09, 800.0
    path = _write(tmp_path, CAPSULE.format(L=L, r=r, rho=rho))
    model = _load(path)
    m_c, m_h = rho * np.pi * r * r * L, rho * 2.0 * np.pi * r ** 3 / 3.0
    across = m_c * (3 * r * r + L * L) / 12 + 2 * m_h * (83 / 320 * r * r + (L / 2 + 3 * r / 8) ** 2)
    along = m_c * r * r / 2 + 2 * m_h * 2 * r * r / 5
    body = model["rod"].p
    assert body.m == pytest.approx(m_c + 2 * m_h, rel=1e-14)
    np.testing.assert_allclose(body.r_cm, (0, 0, L / 2), atol=1e-16)
    np.testing.assert_allclose(np.diag(body.I), (across, across, along), rtol=1e-13)
    ev = mbcomp.assemble(model).evaluate(0.0, np.array([0.4]), np.array([0.0]))
    assert ev.M[0, 0] == pytest.approx(across + body.m * (L / 2) ** 2, rel=1e-13)
    assert ev.f[0] == pytest.approx(9.81 * body.m * L / 2 * np.sin(0.4), rel=1e-13)  # z up, tipped over


TWO_JOINTS = """<mujoco><option gravity="0.5 -2 -9"/><worldbody><body name="base" pos="0 0 1" euler="20 0 0">
<joint name="swing" pos="0.1 0 0.2" axis="0 1 0.5" ref="30" stiffness="3" springref="10" damping="0.2"/>
<joint name="slide" type="slide" axis="1 0 1" ref="0.1" stiffness="5" springref="0.3"/>
<joint name="turn" pos="-0.2 0.1 0" axis="1 0 0"/>
<geom type="box" size=".2 .1 .05" pos="0.3 0 0" euler="0 30 10"/><geom type="sphere" size=".07" pos="-.2 .1 0"/>
<body name="ball" pos="0.4 0 -0.3"><joint name="knob" type="ball" pos="0 0.05 0"/>
<geom type="ellipsoid" size=".1 .05 .2" pos="0 0 -.1" quat="0.9 0.1 0.3 0"/>
<body name="tip" pos="0 0 -.3"><joint name="last" axis="0 0 1"/><geom type="cylinder" fromto="0 0 0 0.1 0.1 -0.2" size=".03"/>
</body></body></body></worldbody></mujoco>"""


def test_a_body_with_three_joints_and_a_ball_matches_mujoco(tmp_path):
    """A hinge off the body's origin with ``ref`` and a spring, a slide with ``ref``, another
    hinge at another anchor, all in one body (MuJoCo applies them in order at the body), then
    a ball joint off its body's origin and a hinge beyond it: mbcomp's coordinates are
    MuJoCo's qpos (refs included), and M and f agree with MuJoCo's at random states."""
    path = _write(tmp_path, TWO_JOINTS)
    model = _load(path)
    system = mbcomp.assemble(model)
    assert [n for n in system.q_names if not n.startswith("knob")] == ["swing.phi", "slide.s", "turn.phi", "last.phi"]
    assert model["swing"].p.phi0 == pytest.approx(np.pi / 6) and model["slide"].p.s0 == 0.1  # qpos0 = ref
    dM, df = _differences(path, n_states=5)
    assert dM < 1e-13 and df < 1e-13, (dM, df)


ARMATURE = """<mujoco><worldbody>
<body name="cart"><joint name="rail" type="slide" axis="1 0 0" armature="0.7"/><geom type="box" size=".2 .1 .1"/>
  <body name="pole" pos="0 0 .1"><joint name="hinge" axis="0 1 0" armature="0.3" damping="0.1"/>
  <geom type="capsule" fromto="0 0 0 0.1 0 0.6" size=".04"/>
    <body name="tip" pos="0.1 0 0.6"><joint name="wrist" axis="0 1 0.5" armature="0.02"/>
    <geom type="box" size=".05 .1 .2" pos="0 0 .2"/></body></body></body>
<body name="wheel" pos="1 0 0"><joint name="axle" axis="0.6 0 0.8" armature="0.05"/>
  <geom type="cylinder" size=".3 .02" pos="0.1 0 0"/></body></worldbody></mujoco>"""


def test_armature_of_hinges_and_slides_is_mujocos(tmp_path):
    """A slide's armature (a reflected mass), hinges on the ground, on a slider and on a
    turning pole (``wrist``: its carrier turns about a part of its axis, where a rotor turning
    with the body would add ``J (n . w_pole)`` cross terms): mbcomp's M, f and accelerations are
    MuJoCo's *with* its armature, and the elements add exactly ``diag(armature)`` to ``M``."""
    path = _write(tmp_path, ARMATURE)
    dM, df = _differences(path, n_states=4)
    assert dM < 1e-13 and df < 1e-13, (dM, df)
    assert _forward_difference(path) < 1e-13  # the reflected rotors on the articulated-body pivots
    model, system, mj = _pair(path)
    assert type(model["rail_armature"]).__name__ == "ReflectedMass"
    assert type(model["wrist_armature"]).__name__ == "ReflectedInertia"
    plain = mbcomp.assemble(_load(path, armature=False))
    assert plain.u_names == system.u_names
    q, u = np.array([0.3, -0.4, 0.8, 1.2]), np.array([0.5, 2.0, -1.5, -1.0])
    gap = system.evaluate(0.0, q, u).M - plain.evaluate(0.0, q, u).M
    J = {"rail.v": 0.7, "hinge.w": 0.3, "wrist.w": 0.02, "axle.w": 0.05}
    np.testing.assert_allclose(gap, np.diag([J[n] for n in system.u_names]), rtol=0, atol=1e-14)


@needs_suite
@pytest.mark.parametrize("name", ["cheetah", "humanoid"])
def test_dropping_the_armature_fails_the_comparison(name):
    """The suite comparisons are not blind to armature: mbcomp without it (armature=False)
    against MuJoCo with it misses exactly ``diag(dof_armature)`` in ``M``, far above the
    comparisons' 1e-9, and its accelerations differ; the import says it left it out."""
    path = os.path.join(SUITE, name + ".xml")
    model, system, mj = _pair(path)
    bare = _pair(path, False)
    layout = _layout(model, system, mj)
    qpos, qvel, q, u, P = _random_state(layout, mj, np.random.default_rng(7))
    M_mj, _ = _mujoco_terms(mj, qpos, qvel)
    M_bare = P.T @ bare[1].evaluate(0.0, q, u).M @ P
    np.testing.assert_allclose(M_mj - M_bare, np.diag(mj.dof_armature), rtol=0, atol=1e-12 * np.abs(M_mj).max())
    assert np.abs(M_mj - M_bare).max() / np.abs(M_mj).max() > 1e-4
    assert any(n.startswith("armature of ") and n.endswith("not imported (armature=False)")
               for n in bare[0].mjcf_notes)


@needs_suite
def test_the_compiled_program_carries_the_armature():
    """Humanoid (21 hinges with armature) through the generated C programs: the evaluation's
    M and the Lagrange right-hand side (the articulated-body solve traced, the armature on its
    pivots) against MuJoCo's M and qacc with constraints off, as the numeric paths are."""
    from mbcomp.codegen import compile_system

    path = os.path.join(SUITE, "humanoid.xml")
    model, system, mj = _pair(path)
    mj = copy.copy(mj)
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    fast = compile_system(system, "c")
    qpos, qvel, q, u, P = _random_state(_layout(model, system, mj), mj, np.random.default_rng(36))
    d = mujoco.MjData(mj)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(mj, d)
    M = full_mass_matrix(mujoco, mj, d)
    assert np.abs(P.T @ fast.evaluate(0.0, q, u).M @ P - M).max() < 1e-12 * np.abs(M).max()
    ud = fast.evaluator.lagrange_fun(0.0, np.concatenate((q, u)), 0.0, 0.0)[len(q):]
    assert np.abs(P.T @ ud - d.qacc).max() < 1e-9 * np.abs(d.qacc).max()


GRIPPER = """<mujoco><compiler angle="radian"/>
<option timestep="0.0005" integrator="RK4"><flag contact="disable"/></option><worldbody>
<body name="palm" pos="0 0 1"><geom type="box" size="0.2 0.05 0.02" mass="1"/>
 <body name="link_a" euler="0 2.27 0"><joint name="hinge_a" axis="0 1 0" armature="0.02"/>
  <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.015" mass="0.4"/>
  <body name="jaw" pos="0.5 0 0" euler="0 -2.27 0"><joint name="jaw_a" axis="0 1 0" armature="0.03"/>
   <geom type="box" pos="0.15 0 -0.05" size="0.15 0.03 0.05" mass="0.8"/></body></body>
 <body name="link_b" pos="0.3 0 0" euler="0 2.27 0"><joint name="hinge_b" axis="0 1 0" armature="0.04"/>
  <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.015" mass="0.4"/>
  <body name="knuckle" pos="0.5 0 0" euler="0 -2.27 0"><joint name="jaw_b" axis="0 1 0" armature="0.05"/>
   <geom type="box" pos="0 0 -0.05" size="0.03 0.03 0.05" mass="0.3"/></body></body></body>
</worldbody><equality><weld name="grip" body1="jaw" body2="knuckle"/></equality></mujoco>"""


def test_armature_on_every_joint_of_a_loop_keeps_them_in_the_tree(tmp_path):
    """A parallelogram closed by a weld (a 0-DOF closure, kept in the tree before any hinge)
    with armature on all four hinges: the reflected rotors need their joints' own speeds, so
    the topology cuts a rigid offset instead of a hinge (jaw_b then a reversed tree joint). A
    run keeps the loop closed and the energy, and follows MuJoCo's (armature on, its weld
    soft) to MuJoCo's softness (6e-4 rad over a 1.4 rad swing), where the same run without
    armature is 0.9 rad off."""
    path = _write(tmp_path, GRIPPER)
    model = _load(path)
    system = mbcomp.assemble(model)
    assert system.topology.cut == ["knuckle_offset"] and len(system.u_names) == 4
    t_end = 2.0
    res = mbcomp.simulate(model, t_end=t_end, n_out=201, rtol=1e-10, atol=1e-12, stabilization="projection")
    E = res["energy.total"]
    assert np.ptp(E) < 1e-8 * np.abs(E).max() and np.max(res["residual.position"]) < 1e-10
    mj = _compiled(path)
    d = mujoco.MjData(mj)
    theirs = []
    for k in range(int(round(t_end / mj.opt.timestep)) + 1):
        if k % 20 == 0:  # every 0.01 s
            theirs.append(d.qpos[0])
        mujoco.mj_step(mj, d)
    gap = np.abs(np.array(theirs) - res["hinge_a.phi"]).max()
    bare = mbcomp.simulate(_load(path, armature=False), t_end=t_end, n_out=201, rtol=1e-10, atol=1e-12,
                           stabilization="projection")
    assert np.ptp(theirs) > 0.5 and gap < 2e-3 and np.abs(np.array(theirs) - bare["hinge_a.phi"]).max() > 100 * gap


NOTED = """<mujoco model="noted"><include file="parts.xml"/>
<option density="1.2"/>
<worldbody><light name="sun" pos="0 0 3"/>
<body name="arm" pos="0 0 1"><joint name="shoulder" axis="0 1 0" frictionloss="0.5" armature="0.01"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.05" material="red"/><site name="tip" pos="0 0 -.5"/>
  <body name="fore" pos="0 0 -.5"><joint name="elbow" type="slide" axis="0 0 1" armature="0.2"/>
  <geom type="sphere" size=".1" rgba="0 0 1 0.5"/></body></body></worldbody>
<tendon><fixed name="t"><joint joint="shoulder" coef="1"/></fixed></tendon>
<equality><tendon name="loop" tendon1="t"/></equality>
<actuator><motor name="m1" joint="shoulder" gear="50"/><position name="p1" joint="elbow" kp="20"/></actuator>
<sensor><jointpos joint="shoulder"/><jointvel joint="shoulder"/><touch site="tip"/></sensor>
</mujoco>"""
PARTS = """<mujoco><asset><material name="red" rgba="1 0 0 1"/></asset></mujoco>"""


def test_what_is_not_imported_is_said(tmp_path):
    """Actuators one by one with their gains, sensors and tendons grouped, the equality as
    "not imported yet", the fluid forces and frictionloss (friction=False); a slide's armature
    is imported (a reflected mass);
    one UserWarning; the include's material colours the capsule."""
    _write(tmp_path, PARTS, "parts.xml")
    path = _write(tmp_path, NOTED)
    with pytest.warns(UserWarning, match="MJCF elements not imported"):
        model = load_mjcf(path)
    notes = "\n".join(model.mjcf_notes)
    for said in ("actuator <motor> 'm1' on joint 'shoulder' (gear=50)", "actuator <position> 'p1' on joint 'elbow' (kp=20)",
                 "3 sensors (1 jointpos, 1 jointvel, 1 touch): not imported", "1 tendons (1 fixed): not imported",
                 "equality <tendon> 'loop' (t): not imported", "<option density=1.2>: fluid forces",
                 "joint 'shoulder': frictionloss=0.5 not imported (friction=False)",
                 "1 light, 1 site: not imported"):
        assert said in notes, said
    assert "armature" not in notes and model["elbow_armature"].p.m == 0.2 and model["shoulder_armature"].p.J == 0.01
    shapes = model["arm"].look.shape
    assert [type(s).__name__ for s in shapes] == ["Cylinder", "Sphere", "Sphere"]
    assert shapes[0].color == "#ff0000" and shapes[0].length == pytest.approx(0.5)
    assert model["fore"].look.shape[0].opacity == 0.5
    with pytest.warns(UserWarning):
        rubbing = load_mjcf(path, friction=True)
    assert rubbing["shoulder"].p.friction.static == 0.5
    frame = body_frames(model)["fore"]
    assert frame.p0.tolist() == [0.0, 0.0, 0.5] and frame.port == model["fore"].frame_a


def test_bad_files_are_refused_with_the_fix(tmp_path):
    def refused(text, match, name="bad.xml"):
        with pytest.raises(ValueError, match=match):
            _load(_write(tmp_path, text, name))

    refused("<robot name='r'/>", "not <mujoco> -> is it an MJCF")
    refused("<mujoco><include file='gone.xml'/><worldbody/></mujoco>", r"<include file='gone.xml'>: no such file")
    body = "<mujoco><worldbody><body name='b'>{}<geom size='.1'/></body></worldbody></mujoco>"
    refused(body.format("<joint name='j' type='screw'/>"), "joint 'j' of body 'b': type 'screw' is not one of hinge")
    refused("<mujoco><worldbody><body name='b'><joint name='j'/><geom size='.1' mass='0'/></body></worldbody></mujoco>",
            "body 'b': joint 'j' moves no mass")
    refused("<mujoco><worldbody><body name='a'><geom size='.1'/><body name='b'><freejoint/><geom size='.1'/></body>"
            "</body></worldbody></mujoco>", "body 'b': a free joint must be the only joint of a child of the worldbody")
    refused(body.format("<joint/>").replace("<geom size='.1'/>", "<geom type='mesh' mesh='m'/>"),
            "a mesh geom carrying mass .* give its body an <inertial>")
    refused(body.format("<joint euler='0 0 1' quat='1 0 0 0'/>").replace("<body name='b'>", "<body name='b' euler='1 0 0' quat='1 0 0 0'>"),
            "orientation given twice")
    refused(body.format("<joint class='nope'/>"), "class 'nope' is not defined")
    refused(body.format("<joint range='1 -1'/>"), "give lower < upper")


def test_limits_become_stops_only_when_asked(tmp_path):
    """``range`` (degrees) with autolimits: the hinge's stops in rad with ``limits=True``; a
    ``ref`` outside the range starts the joint at the range's middle (noted)."""
    text = ("<mujoco><worldbody><body name='b'><joint name='j' range='-30 60' ref='{ref}'/>"
            "<geom type='box' size='.1 .1 .1' pos='0.2 0 0'/></body></worldbody></mujoco>")
    plain = _load(_write(tmp_path, text.format(ref=0)))
    assert plain["j"].p.limits is None
    stopped = _load(_write(tmp_path, text.format(ref=0)), limits=True)
    np.testing.assert_allclose(stopped["j"].p.limits, np.deg2rad([-30, 60]), rtol=1e-15)
    with pytest.warns(UserWarning, match="starts at the middle of its range"):
        outside = load_mjcf(_write(tmp_path, text.format(ref=90)), limits=True)
    assert outside["j"].p.phi0 == pytest.approx(np.deg2rad(15))


def test_top_level_name():
    assert mbcomp.load_mjcf is load_mjcf


MESHED = """<mujoco><compiler meshdir="parts"/><asset><mesh name="wedge" file="wedge.stl" {extra}/></asset>
<worldbody><body name="b" pos="0 0 1"><joint name="j" axis="1 0.3 0"/>
<geom type="mesh" mesh="wedge" pos="0.1 0.2 0" euler="10 20 30" density="700"/>
<geom type="sphere" size="0.05" pos="0 0 -0.3"/></body></worldbody></mujoco>"""


def _wedge_stl(path):
    """A binary STL of a triangular prism (legs 0.3 and 0.2, depth 0.1), its triangles outward."""
    import struct

    a = [(0, 0, 0), (0.3, 0, 0), (0, 0.2, 0)]
    b = [(x, y, 0.1) for x, y, _ in a]
    tris = [(a[0], a[2], a[1]), (b[0], b[1], b[2]), (a[0], a[1], b[1]), (a[0], b[1], b[0]),
            (a[1], a[2], b[2]), (a[1], b[2], b[1]), (a[2], a[0], b[0]), (a[2], b[0], b[2])]
    data = b"\0" * 80 + struct.pack("<I", len(tris))
    for t in tris:
        data += struct.pack("<12fH", 0, 0, 0, *[c for v in t for c in v], 0)
    path.write_bytes(data)


@pytest.mark.parametrize("extra, tol", [("", 1e-12), ('inertia="exact"', 1e-12), ('scale="1.5 0.5 2" refpos="0.1 0 0"', 1e-12),
                                        ('scale="1.5 0.5 2" refpos="0.1 0 0" refquat="0.9 0.2 0.1 0.3"', 1e-9)])
def test_mesh_geom_mass_properties_are_mujocos(tmp_path, extra, tol):
    """A prism read from a binary STL, placed and rotated in its body, MuJoCo's default
    (legacy) and exact inertia, scaled and re-referenced: the prism's volume is 0.003 m^3
    (times the scales), and M and f equal MuJoCo's. With ``refquat`` the body's two larger
    principal moments lie 0.6 % apart and MuJoCo's principal axes (its iterative eigen
    solver stops at an absolute 1e-12 off-diagonal) are off by ~1e-8 rad: its M agrees to
    5e-10 there (the issue's 1e-9), the eigenvalues to rounding."""
    (tmp_path / "parts").mkdir()
    _wedge_stl(tmp_path / "parts" / "wedge.stl")
    path = _write(tmp_path, MESHED.format(extra=extra))
    model = _load(path)
    sphere = 1000 * 4 / 3 * np.pi * 0.05 ** 3
    scale = 1.5 * 0.5 * 2 if "scale" in extra else 1.0
    assert model["b"].p.m == pytest.approx(700 * 0.5 * 0.3 * 0.2 * 0.1 * scale + sphere, rel=1e-6)  # float32 file
    dM, df = _differences(path, n_states=3)
    assert dM < tol and df < tol, (dM, df)


INERTIALS = """<mujoco><compiler inertiafromgeom="{fromgeom}" boundmass="0.3" boundinertia="0.002" settotalmass="7"/>
<worldbody><body name="a"><joint name="j1" axis="0 1 0"/><geom type="box" size=".1 .2 .05" pos="0 0 -.2"/>
<inertial pos="0.1 0 -0.3" mass="2" fullinertia="0.05 0.04 0.03 0.001 -0.002 0.003"/>
<body name="b" pos="0 0.1 -0.5"><joint name="j2" axis="1 0 0"/><geom type="sphere" size=".02"/>
<inertial pos="0 0 -0.2" quat="0.8 0.3 -0.1 0.2" mass="0.1" diaginertia="0.001 0.003 0.004"/>
<body name="c" pos="0 0 -0.4"><joint name="j3" type="slide" axis="0 0 1"/><geom type="cylinder" size=".05 .1"/>
</body></body></body></worldbody></mujoco>"""


@pytest.mark.parametrize("fromgeom", ["auto", "true"])
def test_inertial_elements_bounds_and_total_mass_are_mujocos(tmp_path, fromgeom):
    """``<inertial>`` with a full tensor and with a rotated diagonal one, or the geoms instead
    (``inertiafromgeom="true"``), ``boundmass``/``boundinertia`` raising the light bodies and
    ``settotalmass`` scaling all: MuJoCo's M and f. With ``inertiafromgeom="false"`` the
    slider's body (geoms, no ``<inertial>``) has no mass: refused, naming it."""
    path = _write(tmp_path, INERTIALS.format(fromgeom=fromgeom))
    with pytest.raises(ValueError, match="body 'c': joint 'j3' moves no mass"):
        _load(_write(tmp_path, INERTIALS.format(fromgeom="false").replace('boundmass="0.3" boundinertia="0.002"', ""),
                     "false.xml"))
    model = _load(path)
    assert sum(model[n].p.m for n in ("a", "b", "c")) == pytest.approx(7.0, rel=1e-14)
    dM, df = _differences(path, n_states=3)
    assert dM < 1e-12 and df < 1e-12, (dM, df)


def test_unnamed_and_odd_names(tmp_path):
    """Unnamed bodies and joints get generated names; a name that is no identifier is
    sanitized and said; a body sharing its joint's name is ``<name>_body``."""
    text = ("<mujoco><worldbody><body><joint/><geom size='.1' pos='0 0 -1'/>"
            "<body name='fore-arm' pos='0 0 -1'><joint name='fore-arm' type='slide'/><joint/><geom size='.1'/></body>"
            "</body></worldbody></mujoco>")
    model = _load(_write(tmp_path, text))
    system = mbcomp.assemble(model)
    assert system.q_names == ["body1_joint1.phi", "fore_arm.s", "fore_arm_joint2.phi"]
    assert model.mjcf_joints == ["body1_joint1", "fore_arm", "fore_arm_joint2"]
    assert model["fore_arm_body"].p.m == pytest.approx(1000 * 4 / 3 * np.pi * 0.001, rel=1e-14)
    assert "joint 'fore-arm': named 'fore_arm' in the model" in "\n".join(model.mjcf_notes)
    assert set(body_frames(model)) == {"body1", "fore-arm"}


def _generated(tmp_path, name):
    """dm-control's models made by code (the swimmer of 6 links, a 3-body LQR chain): their XML
    and included files written to ``tmp_path``."""
    import importlib

    module = importlib.import_module(f"dm_control.suite.{name}")
    xml, assets = module.get_model_and_assets(6) if name == "swimmer" else \
        module.get_model_and_assets(3, 2, np.random.RandomState(5))
    for rel, data in assets.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(data)
    path = tmp_path / f"{name}.xml"
    path.write_bytes(xml if isinstance(xml, bytes) else xml.encode())
    return str(path)


@needs_suite
@pytest.mark.filterwarnings("ignore::UserWarning")  # dm-control's viewer finds no display
@pytest.mark.parametrize("name", ["swimmer", "lqr"])
def test_generated_suite_models_match_mujoco(tmp_path, name):
    path = _generated(tmp_path, name)
    dM, df = _differences(path)
    assert dM < 1e-9 and df < 1e-9, f"{name}: mass matrix {dM:.1e}, bias forces {df:.1e} relative"
    assert _forward_difference(path) < 1e-9
