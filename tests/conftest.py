import os
import pathlib

# One BLAS thread per test process, set before numpy is first imported (this file is the first
# to import it; the xdist workers inherit the environment). The suite's matrices are small and
# `pytest -n 2` already keeps both cores busy: OpenBLAS's extra threads only spin and take the
# other worker's core (the N = 40 four-bar: 71 s of CPU with two threads, 9 s with one; an SVD
# of 200 x 121, 35 ms against 2.4 ms on a loaded 2-core machine). A test file setting this
# itself comes too late: numpy is loaded by then.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.modeling.loader import import_file  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def load_model(relpath):
    """A model file (``models/...py``, relative to the repository root) as a module:
    :func:`mbcomp.load_model_file`, so the tests load models as users and the CLI do."""
    return mbcomp.load_model_file(ROOT / relpath)


def load_module(relpath):
    """Any Python file (relative to the repository root) as a module, build() or not."""
    return import_file(ROOT / relpath)


@pytest.fixture
def models_dir():
    return ROOT / "models"


def torque_pendulum(law):
    """A 1 m, 1 kg pendulum released at 0.5 rad from rest, driven by a hinge torque
    ``law(t, phi, w)`` (component ``"motor"``): the tests' model of a misbehaving user law."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("hinge", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    motor = m.add("motor", Torque(tau=law))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m


def stop_pendulum(limits=(0.0, 3.0), e=0.7, phi0=0.8, joint=None):
    """A 1 kg point mass on a 1 m rod on a hinge (``joint``: Revolute by default) released at
    ``phi0`` (rad) from rest under g = 9.81 along -y, with stops at ``limits`` (rad; None: no
    stops) of restitution ``e``: the model of the events-in-C tests and bench/events.py."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    lim = dict(limits=limits, restitution=e) if limits else {}
    j = m.add("hinge", (joint or Revolute)(phi0=phi0, w0=0.0, **lim))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def turntable(tau):
    """A 2 kg point mass on a 1 m rod turning about a vertical hinge ``j`` (no gravity: 2 kg m^2
    about the axis), driven by a torque ``tau`` (component ``"motor"``): ``2 phi'' = tau``."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("j", Revolute(phi0=0.0, w0=0.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    motor = m.add("motor", Torque(tau=tau))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m


def compiled(model, backend="c"):
    """``model`` assembled and compiled with both programs made now (``simulate``'s own
    systems make the evaluation program lazily), for tests that use the programs directly."""
    from mbcomp.codegen import compile_system

    return compile_system(mbcomp.assemble(model), backend)


def step_through(solver):
    """Step ``solver`` (a :class:`mbcomp.solvers.Stepper`) to its end, every step succeeding:
    the times (k,) and states (k, n), the start included."""
    import numpy as np

    ts, ys = [solver.t], [solver.y.copy()]
    while solver.status == "running":
        msg = solver.step()
        assert msg is None, msg
        ts.append(solver.t)
        ys.append(solver.y.copy())
    return np.array(ts), np.array(ys)


def moving_frame(R0, r0, w, v, alpha, acc):
    """An exact motion with pose (R0, r0) and the given rates at t = 0 (world coordinates): a
    function of t giving the frame's jet (no speed columns), for checking a row's jets against
    finite differences in time."""
    from scipy.spatial.transform import Rotation

    from mbcomp.jets import FrameJet

    def at(t):
        A = Rotation.from_rotvec(w * t).as_matrix()
        B = Rotation.from_rotvec(alpha * t * t / 2).as_matrix()
        z = np.zeros((3, 0))
        Aal = A @ alpha
        return FrameJet(A @ B @ R0, r0 + v * t + acc * t * t / 2, w + Aal * t, v + acc * t, z, z,
                        Aal + t * np.cross(w, Aal), acc.copy())
    return at


def double_pendulum():
    """Two point masses (1.5 kg, 0.5 kg) on rods of 1 m and 0.7 m, hinges about z, released
    from 0.7 and -0.4 rad at 1.3 and -0.8 rad/s, gravity -9.81 y: the small model the
    derivative programs are checked against sympy on (joints ``j1``, ``j2``, rods ``r1``,
    ``r2``, masses ``b1``, ``b2``)."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, World

    m = mbcomp.Model()
    w = m.add("world", World())
    j1 = m.add("j1", Revolute(n=(0, 0, 1), phi0=0.7, w0=1.3))
    r1 = m.add("r1", FixedTranslation(r=(0, -1.0, 0)))
    b1 = m.add("b1", PointMass(m=1.5))
    j2 = m.add("j2", Revolute(n=(0, 0, 1), phi0=-0.4, w0=-0.8))
    r2 = m.add("r2", FixedTranslation(r=(0, -0.7, 0)))
    b2 = m.add("b2", PointMass(m=0.5))
    m.connect(w.frame_b, j1.frame_a)
    m.connect(j1.frame_b, r1.frame_a)
    m.connect(r1.frame_b, b1.frame_a)
    m.connect(r1.frame_b, j2.frame_a)
    m.connect(j2.frame_b, r2.frame_a)
    m.connect(r2.frame_b, b2.frame_a)
    return m

def ball_loop():
    """Two links on ball joints (quaternions: nq 8, nu 6) whose tip is held at a fixed point by a
    third ball joint (the cut): 3 DOF, every start free, the loop closed at the start."""
    from mbcomp.library import FixedTranslation, RigidBody, Spherical, World

    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, -9.81, 0)))
    j1, l1 = mdl.add("j1", Spherical()), mdl.add("l1", FixedTranslation(r=(0, -0.5, 0)))
    b1 = mdl.add("b1", RigidBody(m=1.0, r_cm=(0, -0.25, 0), I=np.diag([0.02, 0.001, 0.02])))
    j2, l2 = mdl.add("j2", Spherical()), mdl.add("l2", FixedTranslation(r=(0.5, 0, 0)))
    b2 = mdl.add("b2", RigidBody(m=1.0, r_cm=(0.25, 0, 0), I=np.diag([0.001, 0.02, 0.02])))
    anchor, cut = mdl.add("anchor", FixedTranslation(r=(0.45, -0.45, 0.1))), mdl.add("cut", Spherical())
    for a, b in [(w.frame_b, j1.frame_a), (j1.frame_b, l1.frame_a), (j1.frame_b, b1.frame_a),
                 (l1.frame_b, j2.frame_a), (j2.frame_b, l2.frame_a), (j2.frame_b, b2.frame_a),
                 (w.frame_b, anchor.frame_a), (l2.frame_b, cut.frame_a), (anchor.frame_b, cut.frame_b)]:
        mdl.connect(a, b)
    return mdl
