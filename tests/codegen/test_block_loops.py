"""Repeated blocks of a straight-line program computed by loops (codegen/block_loops.py).

The loops perform the straight-line program's operations in its order on the same operands,
so every program printed with them must give the straight-line program's values (checked to
1e-12 relative; they are equal bit for bit), and the dynamics must still agree with the
numeric path and with Pinocchio's dense solve on the 3-D chains of issue 32 item 3.
"""
import pathlib
import warnings

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import block_loops
from mbcomp.codegen.compiler import Bound, Code
from mbcomp.codegen.graph import Fallback, Graph
from mbcomp.codegen.loaded import LoadedProgram
from mbcomp.codegen.printers import Program
from mbcomp.codegen.tracer import trace
from mbcomp.formulations import LagrangeIndex1
from mbcomp.initialization import initialize

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
CHAIN = mbcomp.load_model_file(MODELS / "chain_3d.py")
PENDULUM = mbcomp.load_model_file(MODELS / "n_link_pendulum.py")
L, M, A, G = 0.5, 1.0, 0.02, 9.81


def tree(limbs=3, n=4):
    """A free-flying box (FreeMotion) with ``limbs`` limbs of ``n`` ball-jointed cylinders."""
    from mbcomp.library import FixedTranslation, FreeMotion, RigidBody, Spherical, World

    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0.0, -G, 0.0)))
    free = mdl.add("free", FreeMotion())
    base = mdl.add("base", RigidBody(m=5.0, r_cm=(0.0, 0.0, 0.0), I=np.diag([0.05, 0.1, 0.08])))
    mdl.connect(world.frame_b, free.frame_a)
    mdl.connect(free.frame_b, base.frame_a)
    for li in range(limbs):
        at = mdl.add(f"at{li}", FixedTranslation(r=(0.2 * np.cos(2.1 * li), -0.1, 0.15 * np.sin(2.1 * li))))
        mdl.connect(free.frame_b, at.frame_a)
        prev = at.frame_b
        for k in range(n):
            joint = mdl.add(f"j{li}_{k}", Spherical())
            link = mdl.add(f"b{li}_{k}", RigidBody(m=M * (1 + 0.1 * k), r_cm=(0.0, -L / 2, 0.0),
                                                   I=CHAIN.cylinder_inertia(M, L, A)))
            mdl.connect(prev, joint.frame_a)
            mdl.connect(joint.frame_b, link.frame_a)
            if k < n - 1:
                tip = mdl.add(f"t{li}_{k}", FixedTranslation(r=(0.0, -L, 0.0)))
                mdl.connect(joint.frame_b, tip.frame_a)
                prev = tip.frame_b
    return mdl


def system_of(mdl):
    system = mbcomp.assemble(mdl)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a hanging chain's start is ill-conditioned; not used
        initialize(system, 0.0)
    return system


def states(system, n=3, seed=5):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = system.normalize(system.default_q() + 0.3 * rng.standard_normal(system.nq))
        yield np.concatenate([q, rng.standard_normal(system.nu)])


def code_with(monkeypatch, system, **policy):
    """The system's Code (eval, qrate and fun) printed under ``policy`` (block_loops' constants)."""
    with monkeypatch.context() as mp:
        for name, value in policy.items():
            mp.setattr(block_loops, name, value)
        return Code(trace(system, 3_000_000, program="fun"), "c")


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    return np.max(np.abs(a - b), initial=0.0) / max(np.max(np.abs(b), initial=0.0), 1e-300)


CASES = {
    "ball chain": (lambda: CHAIN.build(N=12, L=L, m=M, a=A, g=G), {}),
    "floating tree": (lambda: tree(3, 4), {}),
    # the planar pendulum's blocks are short (14-42 statements): rolled only when asked
    "planar pendulum": (lambda: PENDULUM.build(N=30), {"MIN_PERIOD": 8}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_loops_give_the_straight_line_values(monkeypatch, case):
    build, policy = CASES[case]
    system = system_of(build())
    straight = code_with(monkeypatch, system, BLOCK_MIN=0)
    rolled = code_with(monkeypatch, system, BLOCK_MIN=1, **policy)
    assert block_loops.MARK not in straight.c_source
    n_loops = rolled.c_source.count(block_loops.MARK)
    assert n_loops >= 3, f"{case}: no repeated block was computed by a loop"
    assert len(rolled.c_source) < 0.7 * len(straight.c_source), (len(rolled.c_source), len(straight.c_source))
    b0, b1 = Bound(straight, system), Bound(rolled, system)
    nq = system.nq
    for y in states(system):
        q, u = y[:nq], y[nq:]
        f0, f1 = b0.run_fun(0.3, y, 0.0, 0.0), b1.run_fun(0.3, y, 0.0, 0.0)
        assert rel(f1, f0) <= 1e-12
        assert rel(b1.run(0.3, q, u), b0.run(0.3, q, u)) <= 1e-12
        assert rel(b1.run_qrate(q, u), b0.run_qrate(q, u)) <= 1e-12
        # and the dynamics: the numeric path's du/dt (its own jets and dense solve)
        ref = LagrangeIndex1(system).fun(0.3, y)
        assert rel(f1[nq:], ref[nq:]) <= 1e-9, case


def test_program_text_stops_growing_with_the_chain():
    """The ball chain's ``fun`` at N = 20 and 40: the straight-line text doubles, the rolled
    text stays (the loops' bodies are one link's statements; only tables of places grow)."""
    sizes = {}
    for N in (20, 40):
        system = system_of(CHAIN.build(N=N, L=L, m=M, a=A, g=G))
        tr = trace(system, 3_000_000, program="fun")
        prog = Program(tr.graph, tr.groups, guard_groups=tr.guard_groups)
        rolled, _ = prog.c_function("fun", "f", 400, blocks=1)
        straight, _ = prog.c_function("fun", "f", 400, blocks=0)
        sizes[N] = (rolled.count("\n"), straight.count("\n"))
        nodes = prog.op_nodes("fun").tolist()
        where_out, _ = prog.output_places("fun", nodes)
        blocks = block_loops.find_blocks(prog, nodes, prog.guards_by_node("fun"), where_out)
        assert sum(b.L * b.R for b in blocks) >= 0.9 * len(nodes)
    assert sizes[40][1] > 1.8 * sizes[20][1]
    assert sizes[40][0] < 1.25 * sizes[20][0], sizes


def test_a_guard_failing_inside_a_loop_fails_the_call(monkeypatch, tmp_path):
    """A recursion x_k = x_(k-1) u_k + 1 with the guard x_k > 0 taken at every body: the
    loop's values are the Python program's, and a state making one body's x negative makes
    the C call return 1 (the fallback), as the straight-line program does."""
    n = 40
    with Graph() as g:
        x = g.input("q", 0, 0.5)
        outs = []
        for k in range(n):
            x = x * g.input("u", k, 1.0 + 0.01 * k) + 1.0
            assert x > 0.0
            outs.append(x * x)
    for name, value in {"BLOCK_MIN": 1, "MIN_PERIOD": 1, "MIN_COVER": 8}.items():
        monkeypatch.setattr(block_loops, name, value)
    prog = Program(g, {"out": outs})
    src, _ = prog.c_function("out", "f", 400)
    assert src.count(block_loops.MARK) == 1 and "return 1;" in src
    lp = LoadedProgram(prog, "out", "mbcomp_test_block_guard", "c", str(tmp_path), "test program")
    py = LoadedProgram(prog, "out", "f", "python", None, "test program")
    h = np.array(lp.pre.run([]) + [0.0])
    w = np.zeros(max(lp.n_work, 1))
    out = np.zeros(n)
    d = np.zeros(1)
    for u in (np.linspace(0.5, 1.5, n), np.linspace(1.5, 0.5, n)):
        q = np.array([0.7])
        rc = lp.cfun(q.ctypes.data, u.ctypes.data, 0.0, d.ctypes.data, h.ctypes.data, d.ctypes.data,
                     w.ctypes.data, out.ctypes.data)
        assert rc == 0
        assert np.array_equal(out, py.fun(q.tolist(), u.tolist(), 0.0, [], list(h[:-1])))
    u = np.ones(n)
    u[23] = -50.0  # x_23 < 0
    rc = lp.cfun(q.ctypes.data, u.ctypes.data, 0.0, d.ctypes.data, h.ctypes.data, d.ctypes.data,
                 w.ctypes.data, out.ctypes.data)
    assert rc == 1
    with pytest.raises(Fallback):
        py.fun(q.tolist(), u.tolist(), 0.0, [], list(h[:-1]))


def test_ball_chain_against_pinocchio():
    """The rolled ball chain's du/dt (N = 40: its fun is printed with loops by default)
    against Pinocchio's crba and nonLinearEffects solved densely, to max(1e-10, 10 eps
    cond(M)) of the largest acceleration."""
    pin = pytest.importorskip("pinocchio")
    N = 40
    system = system_of(CHAIN.build(N=N, L=L, m=M, a=A, g=G))
    code = Code(trace(system, 3_000_000, program="fun"), "c")
    assert block_loops.MARK in code.c_source
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, -G, 0.0]), np.zeros(3))
    link = pin.Inertia(M, np.array([0.0, -L / 2, 0.0]), CHAIN.cylinder_inertia(M, L, A))
    parent = 0
    for k in range(1, N + 1):
        down = np.array([0.0, -L, 0.0]) if k > 1 else np.zeros(3)
        parent = model.addJoint(parent, pin.JointModelSpherical(), pin.SE3(np.eye(3), down), f"joint{k}")
        model.appendBodyToJoint(parent, link, pin.SE3.Identity())
    rng = np.random.default_rng(3)
    np.random.seed(3)
    qp = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v = 0.8 * rng.standard_normal(model.nv)
    y = np.zeros(system.nq + system.nu)
    for k in range(1, N + 1):
        qi, ui = system.q_names.index(f"joint{k}.Q.w"), system.u_names.index(f"joint{k}.w.x")
        y[qi:qi + 4] = np.roll(qp[4 * (k - 1):4 * k], 1)  # Pinocchio (x, y, z, w) -> (w, x, y, z)
        y[system.nq + ui:system.nq + ui + 3] = v[3 * (k - 1):3 * k]
    Mp = pin.crba(model, model.createData(), qp)
    Mp = np.triu(Mp) + np.triu(Mp, 1).T
    a = np.linalg.solve(Mp, -pin.nonLinearEffects(model, model.createData(), qp, v))
    ref = np.zeros(system.nu)
    for k in range(1, N + 1):
        ui = system.u_names.index(f"joint{k}.w.x")
        ref[ui:ui + 3] = a[3 * (k - 1):3 * k]
    got = Bound(code, system).run_fun(0.0, y, 0.0, 0.0)[system.nq:]
    tol = max(1e-10, 10 * np.finfo(float).eps * np.linalg.cond(Mp))
    assert rel(got, ref) <= tol
