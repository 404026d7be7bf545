"""The output program (:mod:`mbcomp.codegen.outputs`): the result columns of a whole output
grid in one call, against the numeric recursive columns and the numeric path's results."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.outputs import HIDDEN, output_values
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.codegen.outputs import OutputProgram
from mbcomp.kinematics import matrix_to_quat

from conftest import load_model, torque_pendulum

MODELS = ["n_link_pendulum", "chain_3d", "four_bar", "slider_crank", "andrews", "bicycle", "rolling_disk"]
BACKENDS = ["python"] + (["c"] if c_compiler() else [])


def reference(s, t, q, u):
    """The numeric columns of one point, with the hidden ones the program carries for the
    tolerance energy: the dense evaluation's ``f`` and ``M u`` (another route than the
    program's recursive pass)."""
    cols, rot = output_values(s, t, q, u, 10.0, 12.0, baumgarte=True)
    ev = s.evaluate_numeric(t, q, u)
    cols.update({f"{HIDDEN}f.{i}": x for i, x in enumerate(ev.f)})
    cols.update({f"{HIDDEN}p.{i}": x for i, x in enumerate(ev.M @ u)})
    return cols, rot


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", MODELS)
def test_the_grid_is_the_numeric_columns(name, backend, tmp_path):
    """Every column at 40 perturbed states equals the numeric evaluation of the same
    recursive algorithms (C: the chunked program with guards across chunks, e.g. the 3-D chain)."""
    s = mbcomp.assemble(load_model(f"models/{name}.py").build())
    initialize(s)
    prog = OutputProgram.build(s, backend, baumgarte=True, cache_dir=str(tmp_path))
    rng = np.random.default_rng(5)
    n = 40
    Q = np.array([s.normalize(s.default_q() + 0.02 * rng.standard_normal(s.nq)) for _ in range(n)])
    Y = np.hstack((Q, rng.standard_normal((n, s.nu))))
    T = np.linspace(0.0, 2.0, n)
    names, V, R, ok = prog.grid(s, T, Y, (10.0, 12.0))
    assert ok.all()
    for k in (0, 17, n - 1):
        cols, rot = reference(s, T[k], Y[k, : s.nq], Y[k, s.nq:])
        ref = np.array([cols[c] for c in names])
        np.testing.assert_allclose(V[:, k], ref, rtol=1e-10, atol=1e-10 * (1 + np.abs(ref).max()), err_msg=name)
        for path, Rk in rot.items():
            np.testing.assert_allclose(R[path][k], matrix_to_quat(Rk), atol=1e-13)


@pytest.mark.parametrize("backend", BACKENDS)
def test_rows_on_the_other_branch_of_a_law_come_from_the_numeric_route(backend):
    """A torque law with a branch (traced on one side): the grid flags the rows on the other
    side, the post-processing computes them numerically, and the whole result equals the
    numeric path's."""
    def law(t, phi, w):
        return -0.5 * w if phi > 0 else 0.3 * np.sin(t)   # a guard on phi's sign

    runs = {b: mbcomp.simulate(torque_pendulum(law), t_end=4.0, n_out=401, backend=b, method="RK45", rtol=1e-10,
                               atol=1e-12) for b in ("numeric", backend)}
    ref, res = runs["numeric"], runs[backend]
    phi = ref["hinge.phi"]
    assert (phi > 0).any() and (phi < 0).any()   # both branches are on the grid
    for col in ("hinge.w.der", "hinge.f.x", "hinge.f.y", "hinge.tau.z", "energy.total", "bob.Q.w", "bob.v.x"):
        np.testing.assert_allclose(res[col], ref[col], rtol=1e-7, atol=1e-8, err_msg=col)
    # the program was traced at phi = 0.5: exactly the rows with phi <= 0 failed its guard
    fast = compile_system(mbcomp.assemble(torque_pendulum(law)), backend)
    _, _, _, ok = fast.evaluator.output_grid(ref.time, np.column_stack((phi, ref["hinge.w"])), None)
    np.testing.assert_array_equal(ok, phi > 0)


@pytest.mark.skipif(not c_compiler(), reason="needs a C compiler")
def test_a_long_chains_constant_outputs_come_from_tables(tmp_path):
    """A 40-link planar chain has hundreds of outputs that are numbers or inputs (the zero
    and unit entries of its rotations about z, the joint angles): the C program copies them
    from static tables (so gcc -O2 stays fast); every column still equals the numeric one."""
    from mbcomp.codegen.printers import TAIL_TABLE

    s = mbcomp.assemble(load_model("models/n_link_pendulum.py").build(N=40))
    initialize(s)
    prog = OutputProgram.build(s, "c", baumgarte=True, cache_dir=str(tmp_path))
    assert "static const double value[" in prog.source and "= q[from[i]]" in prog.source
    rng = np.random.default_rng(8)
    Y = np.hstack((rng.uniform(-2, 2, (3, s.nq)), rng.standard_normal((3, s.nu))))
    T = np.array([0.0, 0.5, 1.0])
    names, V, R, ok = prog.grid(s, T, Y, (10.0, 12.0))
    assert ok.all()
    n_const = 0
    for k in range(3):
        cols, rot = reference(s, T[k], Y[k, : s.nq], Y[k, s.nq:])
        ref = np.array([cols[c] for c in names])
        np.testing.assert_allclose(V[:, k], ref, rtol=1e-10, atol=1e-10 * (1 + np.abs(ref).max()))
        for path, Rk in rot.items():
            np.testing.assert_allclose(R[path][k], matrix_to_quat(Rk), atol=1e-13)
            n_const += int(np.sum((Rk == 0.0) | (Rk == 1.0)))
    assert n_const // 3 > TAIL_TABLE


@pytest.mark.skipif(not c_compiler(), reason="needs a C compiler")
def test_the_program_made_beside_the_run_is_the_one_made_when_asked(tmp_path, monkeypatch):
    # simulate starts the output program's C build before integrating (prepare_outputs): the run's
    # columns are those of a run that made it at the post-processing, bit for bit, and a forked
    # child (which has the pending build but not its thread) makes its own instead of waiting
    import os
    import mbcomp.codegen.evaluator as evaluator
    from mbcomp.codegen.outputs import PendingOutputs

    build = load_model("models/slider_crank.py").build
    monkeypatch.setenv("MBCOMP_CACHE", str(tmp_path / "a"))
    started = []
    real = evaluator.ProgramEvaluator.prepare_outputs

    def spy(self, n, gains):
        real(self, n, gains)
        started.append((self.funs, self.outputs_key(gains), self.funs.get(self.outputs_key(gains))))
    monkeypatch.setattr(evaluator.ProgramEvaluator, "prepare_outputs", spy)
    beside = mbcomp.simulate(build(), t_end=1.0)
    [(funs, key, pending)] = started
    assert isinstance(pending, PendingOutputs) and funs[key] is pending.result()  # the one the columns took
    monkeypatch.setattr(evaluator.ProgramEvaluator, "prepare_outputs", lambda *a, **k: None)
    monkeypatch.setenv("MBCOMP_CACHE", str(tmp_path / "b"))
    asked = mbcomp.simulate(build(), t_end=1.0)
    assert beside.names == asked.names and len(beside.names) > 50
    for name in beside.names:
        np.testing.assert_array_equal(beside[name], asked[name])
    pending = PendingOutputs(lambda: "made")
    assert pending.result() == "made"
    pid = os.fork()
    if pid == 0:  # the child: False at once (nothing is made there), never a wait
        os._exit(0 if pending.result() is False else 1)
    assert os.waitpid(pid, 0)[1] == 0
