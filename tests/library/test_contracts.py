"""Contract tests over every component of the standard library.

The components are enumerated from ``mbcomp.library.__all__``, so a new component is
checked automatically: its documentation (Examples section, documented parameters with
units), the doctests of every module, and the role contract it implements
(:mod:`mbcomp.roles`):

* joints (rigid offsets included): constraints vanish along the joint's own motion, the
  constraint jets (``val``, ``jac``, ``dot``, ``bias``) agree with finite differences in
  time along an exactly known trajectory, ``motion`` agrees with ``relative``/``q_rate``,
  ``increment`` is the flow of ``q_rate``, ``back_through`` inverts ``through``, and the
  jets built by ``through`` carry the true velocities and accelerations;
* force elements: action equals reaction along the line of the points, forces are minus
  the gradient of the potential, passive elements never deliver energy;
* flange elements: the same on 1-D flanges;
* drives: ``v`` and ``a`` are the derivatives of ``s``.
"""
import doctest
import importlib
import inspect
import pathlib
import zlib

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import mbcomp
import mbcomp.library as lib
from mbcomp import Body, Drive, FlangeElement, ForceElement, Ground, Joint
from mbcomp.jets import FrameJet
from mbcomp.roles import FrameState

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLASSES = [getattr(lib, name) for name in lib.__all__]
ROLES = (Ground, Body, Joint, ForceElement, FlangeElement, Drive, mbcomp.Model, mbcomp.FlangeConstraint,
         mbcomp.FlangeInertia)
JOINTS = [c for c in CLASSES if issubclass(c, Joint) and c.tree_edge]  # tree-capable joints
CONTACTS = [c for c in CLASSES if issubclass(c, Joint) and not c.tree_edge]  # constraint-only joints
VELOCITY_JOINTS = [c for c in CLASSES if issubclass(c, Joint) and c.velocity_constraints is not Joint.velocity_constraints]
FORCES = [c for c in CLASSES if issubclass(c, ForceElement)]
FLANGE_ELEMENTS = [c for c in CLASSES if issubclass(c, FlangeElement)]
DRIVES = [c for c in CLASSES if issubclass(c, Drive)]
SEEDS = [0, 1, 2]


def _ids(classes):
    return [c.__name__ for c in classes]


def _rng(cls, seed):
    return np.random.default_rng(zlib.crc32(cls.__name__.encode()) + 1000 * seed)


def random_rotation(rng):
    return Rotation.from_quat(rng.normal(size=4)).as_matrix()


def random_inertia(rng):
    a, b = rng.uniform(0.5, 2.0, 2)
    c = rng.uniform(abs(a - b), a + b)  # triangle inequality
    R = random_rotation(rng)
    return R @ np.diag([a, b, c]) @ R.T


# --- parameters tied by a cross-parameter rule (check_params), which independent random values
# break: the rule's random valid values, by class name
def _perpendicular(first, second):
    """Random ``first`` and a random ``second`` perpendicular to it (3-vectors)."""
    def make(rng):
        a = rng.normal(size=3)
        return {first: a, second: np.cross(a, rng.normal(size=3))}
    return make


TIED_PARAMS = {"Universal": _perpendicular("n_a", "n_b"), "Planar": _perpendicular("n", "n_x")}
#: ElasticStop's lo <= hi (issue 22): a free range around 0, so random flange angles hit both stops
TIED_PARAMS["ElasticStop"] = lambda rng: {"lo": -rng.uniform(0.1, 0.5), "hi": rng.uniform(0.1, 0.5)}


def random_component(cls, rng):
    """An instance of ``cls`` with random valid values for its number-like parameters (start
    values and ``kind="any"`` parameters keep their defaults)."""
    values = TIED_PARAMS[cls.__name__](rng) if cls.__name__ in TIED_PARAMS else {}
    for name, par in cls.params().items():
        if par.kind in ("start", "any") or par.default is None or name in values:
            continue
        if par.shape == ():
            candidates = [rng.uniform(0.5, 2.0)]
        elif par.shape == (3,):
            candidates = [rng.normal(size=3)]
        elif par.shape == (3, 3):
            candidates = [random_rotation(rng), random_inertia(rng)]
        else:
            candidates = []
        for cand in candidates:
            if par.coerce(cand)[1] is None:
                values[name] = cand
                break
    comp = cls(**values)
    assert comp.problems() == [], f"test generated invalid parameters for {cls.__name__}: {comp.problems()}"
    return comp


# ==========================================================================================
# documentation
# ==========================================================================================
def test_library_lists_components_of_known_roles():
    assert len(CLASSES) >= 20
    for cls in CLASSES:
        assert inspect.isclass(cls) and issubclass(cls, mbcomp.Component), cls
        assert sum(issubclass(cls, r) for r in ROLES) == 1, f"{cls.__name__} must play exactly one role"
        assert cls.role in {"ground", "body", "joint", "force", "flange_force", "drive", "model",
                            "flange_constraint", "flange_inertia"}


@pytest.mark.parametrize("cls", CLASSES, ids=_ids(CLASSES))
def test_component_docstring_has_examples(cls):
    doc = cls.__dict__.get("__doc__")  # the class's own docstring, not an inherited one
    assert doc and doc.strip(), f"{cls.__name__} has no docstring"
    doc = inspect.cleandoc(doc)
    assert "Examples\n--------" in doc, f"{cls.__name__} docstring has no Examples section"
    examples = doc.split("Examples\n--------", 1)[1]
    assert ">>>" in examples, f"{cls.__name__}: the Examples section contains no doctest"
    assert cls.__name__ in examples, f"{cls.__name__}: the Examples do not use {cls.__name__}"
    assert doctest.DocTestFinder().find(cls, cls.__name__, globs={})[0].examples


@pytest.mark.parametrize("cls", CLASSES, ids=_ids(CLASSES))
def test_every_param_and_port_is_documented(cls):
    for name, par in cls.params().items():
        assert isinstance(par.doc, str) and par.doc.strip(), f"{cls.__name__}.{name} has no doc"
        assert isinstance(par.unit, str) and par.unit.strip(), f"{cls.__name__}.{name} has no unit"
    for name, port in cls.ports().items():
        assert isinstance(port.doc, str) and port.doc.strip(), f"{cls.__name__}.{name} (port) has no doc"


SRC = ROOT / "src" / "mbcomp"
MODULES = (sorted(".".join(("mbcomp",) + p.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
                  for p in SRC.rglob("*.py"))
           + ["mbcomp.library"] + [f"mbcomp.library.{p.stem}" for p in sorted((ROOT / "library").glob("*.py"))
                                   if p.stem != "__init__"])


@pytest.mark.parametrize("modname", MODULES)
def test_module_doctests_pass(modname):
    mod = importlib.import_module(modname)
    out = []
    runner = doctest.DocTestRunner(verbose=False)
    for test in doctest.DocTestFinder().find(mod, modname):
        runner.run(test, out=out.append)
    res = runner.summarize(verbose=False)
    defines_components = any(getattr(c, "__module__", None) == modname for c in CLASSES)
    assert res.attempted > 0 or not defines_components, f"{modname} defines components but has no doctests"
    assert res.failed == 0, f"{res.failed} of {res.attempted} doctest examples failed:\n" + "".join(out)


# ==========================================================================================
# joints
# ==========================================================================================
def random_q(joint, p, rng):
    """Random valid coordinates: the start coordinates moved by a random ``increment``
    (unit quaternions stay unit), checked against explicit normalization."""
    q0 = joint.start(p)[0]
    assert q0.shape == (joint.nq,)
    q = joint.increment(q0, rng.uniform(-1.2, 1.2, joint.nu), p)
    for i, (name, _) in enumerate(joint.coordinates):
        if name == "Q.w":
            assert abs(np.linalg.norm(q[i:i + 4]) - 1.0) < 1e-12
    return q


def frame_a_jet(nj, rng):
    """Random jet for frame_a with ``nj + 6`` speed columns: the joint's speeds first, then
    frame_a's own velocity (3) and angular velocity (3); random bias accelerations."""
    nu = nj + 6
    Jv, Jw = np.zeros((3, nu)), np.zeros((3, nu))
    Jv[:, nj:nj + 3] = np.eye(3)
    Jw[:, nj + 3:] = np.eye(3)
    u = rng.normal(size=nu)
    a = FrameJet(random_rotation(rng), rng.normal(size=3), Jw @ u, Jv @ u, Jw, Jv,
                 rng.normal(size=3), rng.normal(size=3))
    return a, u


def motion_bias(joint, q, uj, p):
    """``(bw, bv)``: the rates of ``Hw u``, ``Hv u`` at constant speeds (frame_a axes), zero
    unless the joint declares them with ``motion_bias`` (a universal joint: no two speeds make
    its relative angular velocity constant)."""
    if not joint.has_motion_bias:
        return np.zeros(3), np.zeros(3)
    bw, bv = joint.motion_bias(q, uj, p)
    assert np.shape(bw) == (3,) and np.shape(bv) == (3,)
    return np.asarray(bw, float), np.asarray(bv, float)


def edge_args(joint, q, uj, p, bw=None, bv=None):
    R, r = joint.relative(q, p)
    Hw, Hv = joint.motion(q, p)
    if joint.has_motion_bias:  # the velocity-product term goes into frame_b's bias acceleration
        cw, cv = motion_bias(joint, q, uj, p)
        bw, bv = cw + (0.0 if bw is None else bw), cv + (0.0 if bv is None else bv)
    return (R, r, Hw, Hv, slice(0, joint.nu), Hw @ uj, Hv @ uj, bw, bv)


def joint_setup(cls, seed):
    rng = _rng(cls, seed)
    joint = random_component(cls, rng)
    p = joint.p
    q = random_q(joint, p, rng)
    a, u = frame_a_jet(joint.nu, rng)
    return joint, p, q, u, a, rng


def twist(a, b):
    return np.concatenate((a.v, a.w, b.v, b.w))


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_joint_shapes(cls, seed):
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    assert joint.nq >= joint.nu and len(joint.coordinates) == joint.nq and len(joint.speeds) == joint.nu
    R, r = joint.relative(q, p)
    assert R.shape == (3, 3) and r.shape == (3,)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) > 0
    Hw, Hv = joint.motion(q, p)
    assert Hw.shape == (3, joint.nu) and Hv.shape == (3, joint.nu)
    assert np.shape(joint.q_rate(q, u[:joint.nu], p)) == (joint.nq,)
    q0, qf, u0, uf = joint.start(p)
    assert q0.shape == (joint.nq,) and len(qf) == joint.nu and u0.shape == (joint.nu,) and len(uf) == joint.nu
    # the joint's speeds are independent: [Hw; Hv] has full column rank
    if joint.nu:
        assert np.linalg.matrix_rank(np.vstack((Hw, Hv))) == joint.nu


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_joint_constraints_vanish_along_the_joint_motion(cls, seed):
    """With frame_b built from frame_a by the joint's own motion the constraints, their
    Jacobian with respect to every speed, their rate and their bias all vanish -- also with
    prescribed relative accelerations along the joint's motion (a drive)."""
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    nj = joint.nu
    Hw, Hv = joint.motion(q, p)
    x = rng.normal(size=nj)
    b = a.through(*edge_args(joint, q, u[:nj], p, bw=Hw @ x, bv=Hv @ x))
    cons = joint.constraints(a, b, p)
    assert len(cons) == 6 - nj, f"a cut {cls.__name__} must add 6 - {nj} constraints"
    assert len({name for name, _ in cons}) == len(cons), "constraint names must be unique"
    Jab = np.vstack((a.Jv, a.Jw, b.Jv, b.Jw))
    tw = twist(a, b)
    for name, c in cons:
        scale = 1.0 + np.abs(c.jac).max()
        assert abs(c.val) < 1e-12 * scale, name
        np.testing.assert_allclose(c.jac @ Jab, 0.0, atol=1e-12 * scale, err_msg=name)
        assert abs(c.jac @ tw - c.dot) < 1e-12 * scale * (1 + np.abs(tw).max()), name
        assert abs(c.dot) < 1e-11 * scale * (1 + np.abs(tw).max()), name
        assert abs(c.bias) < 1e-10 * scale * (1 + np.abs(tw).max()) ** 2, name
    if cons:  # independent rows: the constraints remove exactly 6 - nu relative motions
        jac = np.array([c.jac for _, c in cons])
        assert np.linalg.matrix_rank(jac, tol=1e-9) == len(cons)


def moving_frame(R0, r0, w, v, alpha, acc):
    """Exact trajectory ``t -> FrameJet`` with pose (R0, r0), angular velocity w, velocity v,
    angular acceleration alpha and acceleration acc at t = 0 (world coordinates):
    ``R(t) = exp(S(w t)) exp(S(alpha t^2/2)) R0`` has angular velocity ``w + exp(S(w t)) alpha t``."""
    def at(t):
        A = Rotation.from_rotvec(w * t).as_matrix()
        B = Rotation.from_rotvec(alpha * t * t / 2).as_matrix()
        Aal = A @ alpha
        z = np.zeros((3, 0))
        return FrameJet(A @ B @ R0, r0 + v * t + acc * t * t / 2, w + Aal * t, v + acc * t, z, z,
                        Aal + t * np.cross(w, Aal), acc.copy())
    return at


def random_motion(rng, pose=None):
    R0, r0 = pose if pose is not None else (random_rotation(rng), rng.normal(size=3))
    return moving_frame(R0, r0, rng.normal(size=3), rng.normal(size=3), rng.normal(size=3), rng.normal(size=3))


def test_moving_frame_is_exact():
    rng = np.random.default_rng(5)
    traj = random_motion(rng)
    h = 1e-6
    J0, Jp, Jm = traj(0.3), traj(0.3 + h), traj(0.3 - h)
    Rdot = (Jp.R - Jm.R) / (2 * h)
    W = Rdot @ J0.R.T
    np.testing.assert_allclose(W, -W.T, atol=1e-8)
    np.testing.assert_allclose([W[2, 1], W[0, 2], W[1, 0]], J0.w, atol=1e-8)
    np.testing.assert_allclose((Jp.w - Jm.w) / (2 * h), J0.alpha, atol=1e-7)
    np.testing.assert_allclose((Jp.r - Jm.r) / (2 * h), J0.v, atol=1e-8)


def _two_poses(joint, p, rng):
    """Poses of frame_a and frame_b: for a tree-capable joint near a consistent pose
    (residuals of order 0.1, so all terms matter), for a contact independent random poses."""
    Ra, ra = random_rotation(rng), rng.normal(size=3)
    if not joint.tree_edge:
        return Ra, ra, random_rotation(rng), rng.normal(size=3)
    R_rel, r_rel = joint.relative(random_q(joint, p, rng), p)
    Rb = Rotation.from_rotvec(0.2 * rng.normal(size=3)).as_matrix() @ Ra @ R_rel
    rb = ra + Ra @ r_rel + 0.2 * rng.normal(size=3)
    return Ra, ra, Rb, rb


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS + CONTACTS, ids=_ids(JOINTS + CONTACTS))
def test_joint_constraint_jets_match_finite_differences(cls, seed):
    """For two independently moving frames (constraints violated), ``dot`` and ``bias`` are
    the first and second time derivatives of ``val`` along the exact trajectory, ``jac``
    column k is the derivative of ``val`` for a unit local twist k, and ``dot = jac . twist``."""
    rng = _rng(cls, seed)
    joint = random_component(cls, rng)
    p = joint.p
    Ra, ra, Rb, rb = _two_poses(joint, p, rng)
    ta, tb = random_motion(rng, (Ra, ra)), random_motion(rng, (Rb, rb))

    def cons(t, ta=ta, tb=tb):
        return joint.constraints(ta(t), tb(t), p)

    c0 = cons(0.0)
    if joint.tree_edge:
        assert len(c0) == 6 - joint.nu
    if not c0:
        return
    names = [n for n, _ in c0]
    val = lambda t, **kw: np.array([c.val for _, c in cons(t, **kw)])
    dot = lambda t: np.array([c.dot for _, c in cons(t)])
    v0 = val(0.0)
    assert np.abs(v0).max() > 1e-3, "the test should violate the constraints"
    d0 = np.array([c.dot for _, c in c0])
    b0 = np.array([c.bias for _, c in c0])
    jac = np.array([c.jac for _, c in c0])
    assert jac.shape == (len(c0), 12)
    np.testing.assert_allclose(jac @ twist(ta(0.0), tb(0.0)), d0, atol=1e-12 * (1 + np.abs(d0).max()))
    h = 1e-5
    np.testing.assert_allclose((val(h) - val(-h)) / (2 * h), d0, atol=1e-7, err_msg=f"dot of {names}")
    np.testing.assert_allclose((dot(h) - dot(-h)) / (2 * h), b0, atol=1e-6, err_msg=f"bias of {names}")
    h2 = 2e-4
    np.testing.assert_allclose((val(h2) - 2 * v0 + val(-h2)) / h2 ** 2, b0, atol=1e-4, err_msg=f"bias of {names}")
    # Jacobian column by column: unit local twists (v_a, w_a, v_b, w_b), no acceleration
    z = np.zeros(3)
    for k in range(12):
        e = np.zeros(12)
        e[k] = 1.0
        sa = moving_frame(Ra, ra, e[3:6], e[0:3], z, z)
        sb = moving_frame(Rb, rb, e[9:12], e[6:9], z, z)
        fd = (val(h, ta=sa, tb=sb) - val(-h, ta=sa, tb=sb)) / (2 * h)
        np.testing.assert_allclose(jac[:, k], fd, atol=1e-7, err_msg=f"jac column {k} of {names}")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", VELOCITY_JOINTS, ids=_ids(VELOCITY_JOINTS))
def test_velocity_constraint_jets_match_finite_differences(cls, seed):
    """Nonholonomic rows ``g = jac . twist`` of two independently moving, accelerating frames:
    ``val`` is linear in the local twists with gradient ``jac``, and ``bias`` is the time
    derivative of ``val`` along the exact trajectory (the frames carry no speeds, so every
    acceleration is bias)."""
    rng = _rng(cls, seed)
    joint = random_component(cls, rng)
    p = joint.p
    Ra, ra, Rb, rb = _two_poses(joint, p, rng)
    ta, tb = random_motion(rng, (Ra, ra)), random_motion(rng, (Rb, rb))

    def vcons(t, ta=ta, tb=tb):
        return joint.velocity_constraints(ta(t), tb(t), p)

    c0 = vcons(0.0)
    assert c0 and len({n for n, _ in c0}) == len(c0), "velocity rows must exist and have unique names"
    names = [n for n, _ in c0]
    val = lambda t, **kw: np.array([c.val for _, c in vcons(t, **kw)])
    v0 = val(0.0)
    jac = np.array([c.jac for _, c in c0])
    bias = np.array([c.bias for _, c in c0])
    assert jac.shape == (len(c0), 12)
    assert np.abs(v0).max() > 1e-3, "the test should violate the constraints"
    np.testing.assert_allclose(jac @ twist(ta(0.0), tb(0.0)), v0, atol=1e-12 * (1 + np.abs(v0).max()))
    h = 1e-5
    np.testing.assert_allclose((val(h) - val(-h)) / (2 * h), bias, atol=1e-6, err_msg=f"bias of {names}")
    z = np.zeros(3)
    for k in range(12):
        e = np.zeros(12)
        e[k] = 1.0
        sa = moving_frame(Ra, ra, e[3:6], e[0:3], z, z)
        sb = moving_frame(Rb, rb, e[9:12], e[6:9], z, z)
        np.testing.assert_allclose(val(0.0, ta=sa, tb=sb), jac[:, k], atol=1e-12, err_msg=f"jac column {k} of {names}")


def _vee(W):
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_joint_motion_matches_relative_and_q_rate(cls, seed):
    """d/dt of ``relative(q(t))`` with ``dq/dt = q_rate(q, u)`` is ``(S(Hw u) R, Hv u)``, and
    ``Hw u``, ``Hv u`` are constant at constant ``u`` (the roles contract) or change at the
    rates the joint's ``motion_bias`` declares."""
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    uj = rng.normal(size=joint.nu)
    qd = joint.q_rate(q, uj, p)
    h = 1e-6
    (Rp, rp), (Rm, rm) = joint.relative(q + h * qd, p), joint.relative(q - h * qd, p)
    R, r = joint.relative(q, p)
    Hw, Hv = joint.motion(q, p)
    W = (Rp - Rm) / (2 * h) @ R.T
    np.testing.assert_allclose(W, -W.T, atol=1e-7)
    np.testing.assert_allclose(_vee(W), Hw @ uj, atol=1e-7)
    np.testing.assert_allclose((rp - rm) / (2 * h), Hv @ uj, atol=1e-7)
    (Hwp, Hvp), (Hwm, Hvm) = joint.motion(q + h * qd, p), joint.motion(q - h * qd, p)
    bw, bv = motion_bias(joint, q, uj, p)
    np.testing.assert_allclose((Hwp - Hwm) @ uj / (2 * h), bw, atol=1e-6)
    np.testing.assert_allclose((Hvp - Hvm) @ uj / (2 * h), bv, atol=1e-6)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_joint_increment_follows_q_rate(cls, seed):
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    uj = rng.normal(size=joint.nu)
    np.testing.assert_allclose(joint.increment(q, np.zeros(joint.nu), p), q, atol=1e-14)
    for dt in (1e-4, 1e-6):
        step = joint.increment(q, uj * dt, p)
        assert step.shape == (joint.nq,)
        np.testing.assert_allclose(step, q + joint.q_rate(q, uj, p) * dt, atol=10 * dt ** 2 * (1 + np.abs(uj).max(initial=0.0)) ** 2)
    if joint.nq == 0:
        return
    # a finite increment is the flow of q_rate at constant speeds for unit time
    du = rng.uniform(-1.0, 1.0, joint.nu)
    sol = solve_ivp(lambda t, y: joint.q_rate(y, du, p), (0.0, 1.0), q, rtol=1e-11, atol=1e-12, method="DOP853")
    qe = sol.y[:, -1]
    qi = joint.increment(q, du, p)
    Re, re = joint.relative(qe, p)
    Ri, ri = joint.relative(qi, p)
    np.testing.assert_allclose(Ri, Re, atol=1e-8)
    np.testing.assert_allclose(ri, re, atol=1e-8)


def _assert_jets_equal(x, y, atol=1e-12):
    for f in FrameJet.__slots__:
        np.testing.assert_allclose(getattr(x, f), getattr(y, f), atol=atol, err_msg=f)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_back_through_inverts_through(cls, seed):
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    bw, bv = rng.normal(size=3), rng.normal(size=3)
    args = edge_args(joint, q, u[:joint.nu], p, bw, bv)
    b = a.through(*args)
    _assert_jets_equal(b.back_through(*args), a, atol=1e-11)
    # and the other way round
    b2 = a.back_through(*args)
    _assert_jets_equal(b2.through(*args), a, atol=1e-11)
    if joint.nu == 0:
        # rigid offsets: the system uses offset() (and its inverse) instead of through()
        R, r = joint.relative(None, p)
        _assert_jets_equal(a.offset(R, r), a.through(*edge_args(joint, q, u[:0], p)), atol=1e-12)
        _assert_jets_equal(a.offset(R, r).offset(R.T, -(R.T @ r)), a, atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", JOINTS, ids=_ids(JOINTS))
def test_through_gives_true_velocities_and_accelerations(cls, seed):
    """frame_b's jet from ``through`` against the actual motion: frame_a on an exact
    trajectory, the joint coordinates integrated with constant speeds."""
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    nj = joint.nu
    uj = u[:nj]
    traj_a = moving_frame(a.R, a.r, a.w, a.v, a.alpha, a.a)

    def q_at(t):
        if t == 0 or joint.nq == 0:
            return q
        return solve_ivp(lambda s, y: joint.q_rate(y, uj, p), (0.0, t), q, rtol=1e-12, atol=1e-14,
                         method="DOP853").y[:, -1]

    def b_at(t):
        at = traj_a(t)
        qt = q_at(t)
        R, r = joint.relative(qt, p)
        Hw, Hv = joint.motion(qt, p)
        Jz = np.zeros((3, nj))  # Jacobians irrelevant here
        aj = FrameJet(at.R, at.r, at.w, at.v, Jz, Jz, at.alpha, at.a)
        return aj.through(R, r, Hw, Hv, slice(0, nj), Hw @ uj, Hv @ uj)

    b = a.through(*edge_args(joint, q, uj, p))
    # velocities are linear in the speeds: v = Jv u, w = Jw u
    np.testing.assert_allclose(b.Jv @ u, b.v, atol=1e-12)
    np.testing.assert_allclose(b.Jw @ u, b.w, atol=1e-12)
    h = 1e-5
    bp, bm = b_at(h), b_at(-h)
    np.testing.assert_allclose((bp.r - bm.r) / (2 * h), b.v, atol=1e-7)
    W = (bp.R - bm.R) / (2 * h) @ b.R.T
    np.testing.assert_allclose(_vee(W), b.w, atol=1e-7)
    np.testing.assert_allclose((bp.v - bm.v) / (2 * h), b.a, atol=1e-6)
    np.testing.assert_allclose((bp.w - bm.w) / (2 * h), b.alpha, atol=1e-6)


ONE_DOF = [c for c in JOINTS if c.axis_kind is not None]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", ONE_DOF, ids=_ids(ONE_DOF))
def test_one_dof_joint_measure_and_axis(cls, seed):
    joint, p, q, u, a, rng = joint_setup(cls, seed)
    assert joint.nu == 1 and cls.axis_kind in ("rotational", "translational")
    assert {"axis", "support"} <= set(cls.ports())
    b = a.through(*edge_args(joint, q, u[:1], p))
    s, v = joint.measure(a, b, p)
    np.testing.assert_allclose([s, v], [q[0], u[0]], atol=1e-12)
    n = joint.axis_world(a.R, p)
    Hw, Hv = joint.motion(q, p)
    np.testing.assert_allclose(n, a.R @ (Hw if cls.axis_kind == "rotational" else Hv)[:, 0], atol=1e-12)
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12


# ==========================================================================================
# force elements
# ==========================================================================================
def random_state(rng, still=False):
    z = np.zeros(3)
    return FrameState(rng.normal(size=3), random_rotation(rng), z if still else rng.normal(size=3),
                      z if still else rng.normal(size=3))


def frame_ports(cls):
    return [n for n, port in cls.ports().items() if port.kind == "frame"]


def conservative(cls, base):
    return type.__getattribute__(cls, "potential") is not base.potential


# --- modes: declared by one capability object (Joint.modes(p) -> Modes | None) --------------
#: the parameters that give a library joint modes, by class name; every joint class with such a
#: parameter must be listed (a new one is then checked here too)
MODE_PARAMS = ("limits", "unilateral", "friction")
MODE_CASES = {
    "Revolute": [dict(limits=(-0.5, 1.0), restitution=0.5), dict(friction=lib.CoulombBearing(2.0, 1.5), w0=0.0)],
    "Prismatic": [dict(limits=(-0.1, 0.2), restitution=0.0), dict(friction=lib.SlidingFriction(0.5, 0.4, 10.0), v0=-1.0)],
    "PlaneContact": [dict(unilateral=True, restitution=0.8), dict(unilateral=True, open0=True)],
    "SphereContact": [dict(r=0.1, unilateral=True), dict(r=0.1, unilateral=True, friction=lib.ContactFriction(0.4, 0.3))],
    "DiskContact": [dict(unilateral=True), dict(unilateral=True, friction=lib.ContactFriction(0.6, 0.5))],
}
ALL_JOINTS = [c for c in CLASSES if issubclass(c, Joint)]
#: the 11 optional methods a mode used to need on Joint: none may come back
RETIRED = ("start_mode", "events", "on_event", "mode_rows", "rest_mode", "holds_rows", "mode_force",
           "slip_friction", "has_events", "has_mode_force", "has_slip_friction")


def _reachable(joint, declared):
    """``{mode: [(event, action)]}`` of every mode reached from the start through the actions
    at the events a mode watches: its own event functions, ``"release"`` of a held row that
    may let go, ``"break+"``/``"break-"`` of a stuck row, ``"slide"`` of a friction cone."""
    from mbcomp.modeling.events import ContactRow, Impact, StickRow, Switch

    todo, seen = [declared.start], {}
    while todo:
        mode = todo.pop()
        if mode in seen:
            continue
        names = [name for name, _, _ in declared.events(np.zeros(joint.nq), np.zeros(joint.nu), mode)]
        for row in declared.rows(mode):
            names += (["break+", "break-"] if isinstance(row, StickRow) else
                      ["release"] + (["slide"] if isinstance(row, ContactRow) and row.mu_s is not None else []))
        seen[mode] = [(name, declared.action(name, mode)) for name in names]
        for name, action in seen[mode]:
            todo += [action.mode] if isinstance(action, Switch) else [action.engage] if isinstance(action, Impact) else []
            todo += [m for m in [declared.rest(name, mode)] if m is not None]
    return seen


@pytest.mark.parametrize("cls", ALL_JOINTS, ids=_ids(ALL_JOINTS))
def test_a_joint_without_mode_parameters_declares_no_modes(cls):
    """``Joint.modes`` is the one place modes are declared: a library joint with its default
    parameters has none (``None``: the run watches nothing of it), every joint class whose
    parameters can give it modes has its cases below, and none of the retired optional
    methods is back on the joint."""
    assert cls().modes(cls().p) is None
    if set(cls.params()) & set(MODE_PARAMS):
        assert cls.__name__ in MODE_CASES, f"{cls.__name__} takes {MODE_PARAMS}: add its cases to MODE_CASES"
    assert not [n for n in RETIRED if hasattr(cls, n)], f"{cls.__name__} declares modes outside Joint.modes"


MODE_JOINTS = [getattr(lib, n)(**case) for n, cases in MODE_CASES.items() for case in cases]


@pytest.mark.parametrize("joint", MODE_JOINTS, ids=[f"{type(j).__name__}-{i % 2}" for i, j in enumerate(MODE_JOINTS)])
def test_declared_modes_match_what_the_joint_does(joint):
    """A joint's :class:`~mbcomp.modeling.modes.Modes` says what it does: it watches events or
    holds rows; its declared ``has_force`` and ``slips`` are true exactly when some reachable
    mode applies a force or slides; an impact engages a mode that holds rows; the rows are
    the joint's kind (a tree joint's on its axis, a contact's its own); only a contact's
    rows leave the system (``holds_rows``), and every action is one of the three."""
    from mbcomp.modeling.events import ACTIONS, AxisRow, ContactRow, Impact
    from mbcomp.modeling.modes import Modes

    name = type(joint).__name__
    declared = joint.modes(joint.p)
    assert isinstance(declared, Modes) and isinstance(declared.start, str)
    seen = _reachable(joint, declared)
    assert any(declared.events(np.zeros(joint.nq), np.zeros(joint.nu), m) or declared.rows(m) for m in seen)
    assert declared.has_force == any(declared.force(m) != 0.0 for m in seen)
    assert declared.slips == any(declared.slip_friction(m) is not None for m in seen)
    for mode, acts in seen.items():
        for ev, action in acts:
            assert isinstance(action, ACTIONS), f"{name} in {mode!r} at {ev!r}: {action!r} is no action"
            if isinstance(action, Impact):
                assert declared.rows(action.engage) and 0.0 <= action.restitution <= 1.0
        for _, _, direction in declared.events(np.zeros(joint.nq), np.zeros(joint.nu), mode):
            assert direction in (-1, 0, 1)
        kind = AxisRow if joint.tree_edge else ContactRow
        assert all(isinstance(r, kind) for r in declared.rows(mode)), declared.rows(mode)
        assert declared.holds_rows(mode) or not joint.tree_edge
        if declared.linear_events:  # the C loop watches the rows: events() must be exactly their values
            rng = np.random.default_rng(len(seen))
            for _ in range(5):
                q, u = rng.normal(size=joint.nq), rng.normal(size=joint.nu)
                rows = declared.event_rows(mode)
                assert [(r.name, r.value(q, u), r.direction) for r in rows] == declared.events(q, u, mode)
                assert all(0 <= r.index < (joint.nq if r.of == "q" else joint.nu) for r in rows)


def test_modes_that_are_no_modes_object_are_refused_naming_the_joint():
    """A joint whose ``modes(p)`` gives something else than a ``Modes`` (a bare start mode)
    is a model problem naming the joint and the fix, before anything runs."""
    class Odd(lib.Revolute):
        """A hinge declaring its start mode where its modes belong."""

        def modes(self, p):
            return "free"

    m = mbcomp.Model()
    w = m.add("world", lib.World(g=(0, 0, 0)))
    j = m.add("hinge", Odd(n=(0, 0, 1), phi0=0.0, w0=1.0))
    b = m.add("disk", lib.RigidBody(m=1.0, I=np.eye(3)))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    with pytest.raises(mbcomp.ModelError, match=r"hinge: modes\(p\) of Odd gave 'free', not a Modes .*fix: return"):
        mbcomp.simulate(m, t_end=0.1)


def advanced(states, t):
    """Frame states moved for time t with their velocities (first order is enough for a
    central difference of a smooth function)."""
    out = {}
    for k, s in states.items():
        out[k] = FrameState(s.r + s.v * t, Rotation.from_rotvec(s.w * t).as_matrix() @ s.R, s.v, s.w)
    return out


@pytest.mark.parametrize("cls", FORCES, ids=_ids(FORCES))
def test_force_element_returns_wrenches_on_its_frames(cls):
    rng = _rng(cls, 0)
    comp = random_component(cls, rng)
    ports = frame_ports(cls)
    assert ports
    states = {n: random_state(rng) for n in ports}
    out = comp.wrenches(0.3, states, comp.p)
    assert set(out) <= set(ports) and out
    for f, tau in out.values():
        assert np.shape(f) == (3,) and np.shape(tau) == (3,)
        assert np.all(np.isfinite(f)) and np.all(np.isfinite(tau))
    assert np.isfinite(comp.potential(states, comp.p))


# sensors (issue 21, library/sensors.py) apply nothing: checked by test_sensors_apply_nothing, not here
TWO_FRAME = [c for c in FORCES if set(frame_ports(c)) == {"frame_a", "frame_b"} and not c.sensor]
SENSORS = [c for c in FORCES if c.sensor]


@pytest.mark.parametrize("cls", SENSORS, ids=_ids(SENSORS))
def test_sensors_apply_nothing(cls):
    """A sensor's wrenches are zero on every frame, it stores no energy and declares so."""
    rng = _rng(cls, 0)
    comp = random_component(cls, rng)
    states = {n: random_state(rng) for n in frame_ports(cls)}
    out = comp.wrenches(0.0, states, comp.p)
    assert set(out) == set(states) and all(not np.any(f) and not np.any(tau) for f, tau in out.values())
    assert comp.potential(states, comp.p) == 0.0 and comp.conserves_energy(comp.p)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", TWO_FRAME, ids=_ids(TWO_FRAME))
def test_two_frame_force_is_action_reaction_along_the_line(cls, seed):
    rng = _rng(cls, seed)
    comp = random_component(cls, rng)
    states = {"frame_a": random_state(rng), "frame_b": random_state(rng)}
    out = comp.wrenches(0.0, states, comp.p)
    (fa, ta), (fb, tb) = out["frame_a"], out["frame_b"]
    assert np.linalg.norm(fa) > 1e-6, "random parameters should give a nonzero force"
    np.testing.assert_allclose(fa + fb, 0.0, atol=1e-12)
    d = states["frame_b"].r - states["frame_a"].r
    np.testing.assert_allclose(np.cross(fa, d), 0.0, atol=1e-12 * (1 + np.linalg.norm(fa)))
    net_moment = np.cross(states["frame_a"].r, fa) + np.cross(states["frame_b"].r, fb) + ta + tb
    np.testing.assert_allclose(net_moment, 0.0, atol=1e-12 * (1 + np.linalg.norm(fa)))


CONSERVATIVE_FORCES = [c for c in FORCES if conservative(c, ForceElement)]


def test_spring_elements_are_conservative():
    assert {lib.Spring, lib.SpringDamper} <= set(CONSERVATIVE_FORCES)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", CONSERVATIVE_FORCES, ids=_ids(CONSERVATIVE_FORCES))
def test_force_is_minus_gradient_of_potential(cls, seed):
    """At rest, the force on each frame is -dV/dr and the torque -dV/dtheta (finite differences)."""
    rng = _rng(cls, seed)
    comp = random_component(cls, rng)
    states = {n: random_state(rng, still=True) for n in frame_ports(cls)}
    out = comp.wrenches(0.0, states, comp.p)
    h = 1e-6
    for name, s in states.items():
        f, tau = out.get(name, (np.zeros(3), np.zeros(3)))
        grad_r, grad_th = np.zeros(3), np.zeros(3)
        for k in range(3):
            e = np.eye(3)[k] * h
            V = []
            for sign in (1, -1):
                moved = dict(states)
                moved[name] = FrameState(s.r + sign * e, s.R, s.v, s.w)
                V.append(comp.potential(moved, comp.p))
            grad_r[k] = (V[0] - V[1]) / (2 * h)
            V = []
            for sign in (1, -1):
                moved = dict(states)
                moved[name] = FrameState(s.r, Rotation.from_rotvec(sign * e).as_matrix() @ s.R, s.v, s.w)
                V.append(comp.potential(moved, comp.p))
            grad_th[k] = (V[0] - V[1]) / (2 * h)
        assert np.linalg.norm(grad_r) > 1e-6 or name not in out
        np.testing.assert_allclose(f, -grad_r, atol=1e-6, err_msg=f"{cls.__name__}.{name} force")
        np.testing.assert_allclose(tau, -grad_th, atol=1e-6, err_msg=f"{cls.__name__}.{name} torque")


def _power(out, states):
    return sum(f @ states[n].v + tau @ states[n].w for n, (f, tau) in out.items())


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", TWO_FRAME, ids=_ids(TWO_FRAME))
def test_line_force_elements_are_passive(cls, seed):
    """Power delivered to the frames plus the rate of stored energy is never positive."""
    rng = _rng(cls, seed)
    comp = random_component(cls, rng)
    states = {n: random_state(rng) for n in frame_ports(cls)}
    P = _power(comp.wrenches(0.0, states, comp.p), states)
    h = 1e-6
    Vdot = (comp.potential(advanced(states, h), comp.p) - comp.potential(advanced(states, -h), comp.p)) / (2 * h)
    assert P + Vdot <= 1e-7


@pytest.mark.parametrize("seed", SEEDS)
def test_spring_conserves_energy_and_damper_dissipates_exactly(seed):
    rng = np.random.default_rng(40 + seed)
    states = {"frame_a": random_state(rng), "frame_b": random_state(rng)}
    spring = lib.Spring(c=rng.uniform(1, 5), s_unstretched=rng.uniform(0.1, 1))
    P = _power(spring.wrenches(0.0, states, spring.p), states)
    h = 1e-6
    Vdot = (spring.potential(advanced(states, h), spring.p) - spring.potential(advanced(states, -h), spring.p)) / (2 * h)
    assert abs(P) > 1e-3
    assert abs(P + Vdot) < 1e-7
    d = rng.uniform(1, 5)
    damper = lib.Damper(d=d)
    a, b = states["frame_a"], states["frame_b"]
    e = (b.r - a.r) / np.linalg.norm(b.r - a.r)
    Ldot = e @ (b.v - a.v)
    np.testing.assert_allclose(_power(damper.wrenches(0.0, states, damper.p), states), -d * Ldot ** 2, rtol=1e-12)


def test_world_loads_apply_constants_and_laws():
    rng = np.random.default_rng(7)
    s = random_state(rng)
    f = rng.normal(size=3)
    out = lib.WorldForce(f=f).wrenches(0.0, {"frame_b": s}, lib.WorldForce(f=f).p)
    np.testing.assert_allclose(out["frame_b"][0], f)
    np.testing.assert_allclose(out["frame_b"][1], 0.0)
    comp = lib.WorldTorque(tau=lambda t, fr: t * fr.w)
    out = comp.wrenches(2.0, {"frame_b": s}, comp.p)
    np.testing.assert_allclose(out["frame_b"][1], 2.0 * s.w)
    np.testing.assert_allclose(out["frame_b"][0], 0.0)


# ==========================================================================================
# flange elements
# ==========================================================================================
def flange_ports(cls):
    return [n for n, port in cls.ports().items() if port.kind == "flange"]


TWO_FLANGE = [c for c in FLANGE_ELEMENTS if len(flange_ports(c)) == 2]
ONE_FLANGE = [c for c in FLANGE_ELEMENTS if len(flange_ports(c)) == 1]
CONSERVATIVE_FLANGE = [c for c in FLANGE_ELEMENTS if conservative(c, FlangeElement)]


# --- what the generic flange checks must be told (issue 21, drivetrain) -------------------------
#: a gear stage's flows balance along its rigid motion ``s_a = ratio s_b``, not along equal rates
RIGID_RATES = {lib.ElastoGear: lambda p: {"flange_a": p.ratio, "flange_b": 1.0}}
#: one-flange actuators with a fixed law and no law parameter (their laws: tests/library/test_drivetrain.py)
FIXED_LAW_ACTUATORS = [lib.MotorTorque]


def rigid_rates(comp, ports):
    """Flange rates of the element's rigid motion, along which its flows do no work."""
    rule = RIGID_RATES.get(type(comp))
    return rule(comp.p) if rule else {n: 1.0 for n in ports}


def acting_states(comp, draw, acts):
    """``draw()`` again (at most 50 times) while the element does not act there by ``acts``
    (a backlash's dead zone applies nothing and stores nothing); the first draw otherwise."""
    for _ in range(50):
        states = draw()
        if acts(states):
            return states
    return states


def test_flange_element_groups_are_not_empty():
    assert lib.RotationalSpring in CONSERVATIVE_FLANGE and lib.TranslationalSpringDamper in CONSERVATIVE_FLANGE
    assert lib.RotationalDamper in TWO_FLANGE and lib.Torque in ONE_FLANGE and lib.Force in ONE_FLANGE
    assert set(TWO_FLANGE) | set(ONE_FLANGE) == set(FLANGE_ELEMENTS)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", TWO_FLANGE, ids=_ids(TWO_FLANGE))
def test_two_flange_element_action_reaction_and_passivity(cls, seed):
    rng = _rng(cls, seed)
    comp = random_component(cls, rng)
    ports = flange_ports(cls)
    states = acting_states(comp, lambda: {n: tuple(rng.normal(size=2)) for n in ports},
                           lambda st: abs(comp.flange_forces(0.0, st, comp.p)[ports[0]]) > 1e-6)
    out = comp.flange_forces(0.0, states, comp.p)
    assert set(out) == set(ports)
    assert abs(out[ports[0]]) > 1e-6
    rates = rigid_rates(comp, ports)
    assert abs(sum(out[n] * rates[n] for n in ports)) < 1e-12
    P = sum(out[n] * states[n][1] for n in ports)
    h = 1e-6
    Vp = comp.potential({n: (s + h * v, v) for n, (s, v) in states.items()}, comp.p)
    Vm = comp.potential({n: (s - h * v, v) for n, (s, v) in states.items()}, comp.p)
    assert P + (Vp - Vm) / (2 * h) <= 1e-7


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", CONSERVATIVE_FLANGE, ids=_ids(CONSERVATIVE_FLANGE))
def test_flange_force_is_minus_gradient_of_potential(cls, seed):
    rng = _rng(cls, seed)
    comp = random_component(cls, rng)
    ports = flange_ports(cls)
    states = acting_states(comp, lambda: {n: (rng.normal(), 0.0) for n in ports},
                           lambda st: comp.potential(st, comp.p) > 1e-6)
    out = comp.flange_forces(0.0, states, comp.p)
    h = 1e-6
    for n in ports:
        up, dn = dict(states), dict(states)
        up[n] = (states[n][0] + h, 0.0)
        dn[n] = (states[n][0] - h, 0.0)
        dV = (comp.potential(up, comp.p) - comp.potential(dn, comp.p)) / (2 * h)
        assert abs(dV) > 1e-6
        np.testing.assert_allclose(out.get(n, 0.0), -dV, atol=1e-7, err_msg=f"{cls.__name__}.{n}")


def test_rotational_spring_torque_is_minus_dV_dphi():
    c, phi0 = 3.0, 0.2
    spring = lib.RotationalSpring(c=c, phi_rel0=phi0)
    st = {"flange_a": (0.1, 0.0), "flange_b": (0.9, 0.0)}
    tau_b = spring.flange_forces(0.0, st, spring.p)["flange_b"]
    h = 1e-6
    dV = (spring.potential({"flange_a": (0.1, 0.0), "flange_b": (0.9 + h, 0.0)}, spring.p)
          - spring.potential({"flange_a": (0.1, 0.0), "flange_b": (0.9 - h, 0.0)}, spring.p)) / (2 * h)
    np.testing.assert_allclose(tau_b, -dV, rtol=1e-8)
    np.testing.assert_allclose(tau_b, -c * (0.9 - 0.1 - phi0), rtol=1e-12)


LAW_ACTUATORS = [c for c in ONE_FLANGE if c not in FIXED_LAW_ACTUATORS]


@pytest.mark.parametrize("cls", LAW_ACTUATORS, ids=_ids(LAW_ACTUATORS))
def test_actuator_applies_its_constant_or_law(cls):
    ports = flange_ports(cls)
    law = [n for n, par in cls.params().items() if par.kind == "law"]
    assert len(law) == 1, f"{cls.__name__}: expected one law parameter"
    comp = cls(**{law[0]: 2.5})
    assert comp.flange_forces(0.0, {ports[0]: (0.3, -0.4)}, comp.p) == {ports[0]: 2.5}
    comp = cls(**{law[0]: lambda t, s, v: t + 10 * s + 100 * v})
    out = comp.flange_forces(2.0, {ports[0]: (0.3, -0.4)}, comp.p)
    np.testing.assert_allclose(out[ports[0]], 2.0 + 3.0 - 40.0, rtol=1e-12)


# ==========================================================================================
# drives
# ==========================================================================================
LAWS = {
    "string": dict(s="0.3*sin(2*t) + 0.1*t**3 - exp(-t)"),
    "sympy_lambda": dict(s=lambda t: 0.3 * sp.sin(2 * t) + 0.1 * t ** 3 - sp.exp(-t)),
    "operator_lambda": dict(s=lambda t: 0.2 * t ** 4 - t / (1 + t ** 2)),
    "string_cos": dict(s="cos(3*t)**2"),
}


def test_drive_classes_are_found():
    assert lib.PrescribedMotion in DRIVES


@pytest.mark.parametrize("law", list(LAWS))
@pytest.mark.parametrize("cls", DRIVES, ids=_ids(DRIVES))
def test_prescribed_motion_v_a_are_derivatives_of_s(cls, law):
    d = cls(**LAWS[law])
    assert d.problems() == []
    h = 1e-5
    for t in (0.0, 0.37, 1.3, 2.9):
        s, v, a = d.motion(t, d.p)
        sp_, vp, _ = d.motion(t + h, d.p)
        sm, vm, _ = d.motion(t - h, d.p)
        assert all(isinstance(x, float) for x in (s, v, a))
        np.testing.assert_allclose((sp_ - sm) / (2 * h), v, atol=1e-8, err_msg=f"v at t={t}")
        np.testing.assert_allclose((vp - vm) / (2 * h), a, atol=1e-7, err_msg=f"a at t={t}")
    assert abs(d.motion(0.37, d.p)[2]) > 1e-3  # the law is not trivially linear


def test_prescribed_motion_values_match_the_law():
    d = lib.PrescribedMotion(s="0.3*sin(2*t)")
    t = 0.8
    np.testing.assert_allclose(d.motion(t, d.p), [0.3 * np.sin(2 * t), 0.6 * np.cos(2 * t), -1.2 * np.sin(2 * t)])
    d = lib.PrescribedMotion(s=0.7)
    assert d.motion(1.0, d.p) == (0.7, 0.0, 0.0)
    d = lib.PrescribedMotion(s=np.sin, v=np.cos, a=lambda t: -np.sin(t))
    np.testing.assert_allclose(d.motion(0.4, d.p), [np.sin(0.4), np.cos(0.4), -np.sin(0.4)])


def _driven_hinge(**law):
    m = mbcomp.Model()
    w = m.add("world", lib.World())
    j = m.add("hinge", lib.Revolute(n=(0, 0, 1)))
    rod = m.add("rod", lib.FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", lib.PointMass(m=1.0))
    d = m.add("drive", lib.PrescribedMotion(**law))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(d.flange_b, j.axis)
    return m


def test_prescribed_motion_honours_runtime_law():
    """Parameters are runtime values (roles/component contract): a law given through
    ``with_params`` must be the one the system uses."""
    base = mbcomp.assemble(_driven_hinge(s="0.5*t**2"))
    new = base.with_params({"drive.s": "3*t"})
    drive = new.topology.flat.components["drive"]
    assert drive.motion(1.0, new.P["drive"]) == (3.0, 3.0, 0.0)


# ==========================================================================================
# flange constraints and rotors (gears: library/gears.py, assembly/flange_rows.py)
# ==========================================================================================
FLANGE_CONSTRAINTS = [c for c in CLASSES if issubclass(c, mbcomp.FlangeConstraint)]
FLANGE_INERTIAS = [c for c in CLASSES if issubclass(c, mbcomp.FlangeInertia)]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("cls", FLANGE_CONSTRAINTS, ids=_ids(FLANGE_CONSTRAINTS))
def test_flange_constraint_rows_are_linear_forms_over_its_flanges(cls, seed):
    """Rows name only the class's flanges, each row moves at least two of them, and the
    coefficients scale with the forms handed in (a linear form, not a function of values)."""
    from mbcomp.roles import FlangeSum

    comp = random_component(cls, _rng(cls, seed))
    ports = flange_ports(cls)
    assert set(cls.flange_kinds) <= set(ports)
    rows = comp.rows({n: FlangeSum({n: 1.0}) for n in ports}, comp.p)
    doubled = comp.rows({n: FlangeSum({n: 2.0}) for n in ports}, comp.p)
    assert rows and len({name for name, _ in rows}) == len(rows)
    for (name, form), (_, form2) in zip(rows, doubled):
        assert set(form.terms) <= set(ports), f"{cls.__name__}.{name}"
        assert sum(1 for c in form.terms.values() if c != 0) >= 2
        for n, c in form.terms.items():
            assert np.isfinite(c) and abs(form2.terms[n] - 2 * c) <= 1e-12 * abs(c)
    assert set(cls.output_units) >= set(comp.outputs(0.0, {n: (0.0, 0.0) for n in ports}, comp.p,
                                                     {n: 1.0 for n in ports}))


@pytest.mark.parametrize("cls", FLANGE_INERTIAS, ids=_ids(FLANGE_INERTIAS))
def test_flange_inertia_gives_a_positive_rotor(cls):
    comp = random_component(cls, _rng(cls, 0))
    J, gyro = comp.rotor(comp.p)
    assert J > 0 and isinstance(gyro, bool) and len(flange_ports(cls)) == 1


def test_a_start_mode_that_is_no_name_is_refused_with_the_fix():
    from mbcomp.modeling.modes import Modes

    with pytest.raises(TypeError, match=r"Modes\(start=3\): a start mode is the mode's name, a string -> fix"):
        Modes(3)
    assert Modes("free").start == "free"
