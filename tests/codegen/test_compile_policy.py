"""How generated C is compiled (mbcomp.codegen.toolchain, printers, rolling): every program at
-O2, output expressions of one shape (the mass matrix's N^2 entries) computed by table-driven
loops, the straight-line rest in short functions split into translation units compiled in
parallel, and each unit's object file cached by the hash of its source and flags.

* Rolled loops give bit for bit the values of the straight-line program (same operations in
  the same order) and the numeric evaluation's to rounding, on a planar and a 3-D chain; the
  C text of the pendulum's evaluation grows linearly with the number of links.
* Programs split into many units (and into tiny functions, where a guard's operands come from
  different functions) give the same values.
* Object cache: a library rebuilt with one unit changed compiles that unit only (the others'
  object files are untouched and reused); the Lagrange program's build reuses the evaluation
  build's equal units; the libraries' results are the numeric path's.
"""
import ctypes
import os

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.codegen import printers, toolchain
from mbcomp.codegen.printers import Program
from mbcomp.codegen.tracer import FIELDS, param_vector, trace, trace_point
from mbcomp.formulations import LagrangeIndex1
from mbcomp.initialization import initialize

from conftest import load_model

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="no C compiler")


def pendulum(N):
    return mbcomp.assemble(load_model("models/n_link_pendulum.py").build(N=N))


def chain_3d(N):
    s = mbcomp.assemble(load_model("models/chain_3d.py").build(N=N))
    initialize(s)
    return s


def states(s, k=4, seed=3):
    rng = np.random.default_rng(seed)
    for _ in range(k):
        yield rng.uniform(0, 2), s.normalize(rng.normal(size=s.nq)), rng.normal(size=s.nu)


def flat(c, t, q, u):
    ev = c.evaluate(t, q, u, masked=False)
    return np.concatenate([np.ravel(getattr(ev, name)) for name in FIELDS])


@pytest.mark.parametrize("make, in_loops", [(lambda: pendulum(30), 0.5), (lambda: chain_3d(6), 0.3)],
                         ids=["pendulum_30", "chain_3d_6"])
def test_rolled_loops_equal_the_straight_line_program_bit_for_bit(make, in_loops, tmp_path, monkeypatch):
    s = make()
    rolled = compile_system(s, "c", cache_dir=str(tmp_path))
    code = rolled.evaluator.bound.code
    assert "_tab[" in code.source and code.n_statements["eval"] < (1 - in_loops) * code.n_ops  # M: in loops
    assert set(code.opt.values()) == {"-O2"}
    monkeypatch.setattr(printers, "ROLL_MIN", 0)  # the same program, all straight-line
    straight = compile_system(s, "c", cache_dir=str(tmp_path))
    assert "_tab[" not in straight.evaluator.bound.code.source
    for t, q, u in states(s):
        np.testing.assert_array_equal(flat(rolled, t, q, u), flat(straight, t, q, u))
        num = s.evaluate_numeric(t, q, u, masked=False)
        ref = np.concatenate([np.ravel(getattr(num, name)) for name in FIELDS])
        np.testing.assert_allclose(flat(rolled, t, q, u), ref, rtol=0, atol=1e-12 * (1 + np.abs(ref).max()))
    assert rolled.stats["fallbacks"] == 0


def test_the_evaluation_text_grows_linearly_with_the_links():
    """M has N^2 entries but its C text (straight-line statements, loop tables) grows like N."""
    sizes = {}
    for N in (20, 40, 80):
        tr = trace(pendulum(N), 3_000_000)
        prog = Program(tr.graph, tr.groups, guard_groups=tr.guard_groups)
        src, _ = prog.c_function("eval", "mbcomp_eval", toolchain.CHUNK)
        sizes[N] = (prog.n_ops("eval"), len(src))
    assert sizes[80][0] > 3 * sizes[40][0] and sizes[40][0] > 2.7 * sizes[20][0]  # operations: ~N^2
    assert sizes[80][1] < 2.2 * sizes[40][1] and sizes[40][1] < 2.2 * sizes[20][1]  # text: ~N


def test_many_units_and_tiny_functions_give_the_same_values(tmp_path, monkeypatch):
    """A 3-D chain (quaternions, guarded pivots in the Lagrange program) printed as one unit
    per program, then as units of ~150 statements in functions of 7 (guards whose operands
    come from different functions read them from the work array)."""
    s = chain_3d(4)
    one = compile_system(s, "c", cache_dir=str(tmp_path))
    monkeypatch.setattr(toolchain, "PART", 150)
    monkeypatch.setattr(toolchain, "CHUNK", 7)
    monkeypatch.setattr(toolchain, "SMALL_CHUNK", 7)
    monkeypatch.setattr(toolchain, "LOOP_CHUNK", 7)
    many = compile_system(s, "c", cache_dir=str(tmp_path))
    form_one, form_many = LagrangeIndex1(one, alpha=5.0, beta=5.0), LagrangeIndex1(many, alpha=5.0, beta=5.0)
    num = LagrangeIndex1(s, alpha=5.0, beta=5.0)
    assert "lagrange_fun" in many.evaluator.capabilities
    code, fun = many.evaluator.bound.code, many.evaluator._fun_bound().code
    assert code.n_units > 3 and fun.n_units > 6 and fun.state_guards["fun"] > 0
    for t, q, u in states(s):
        np.testing.assert_array_equal(flat(one, t, q, u), flat(many, t, q, u))
        y = np.concatenate((q, u))
        np.testing.assert_array_equal(form_one.fun(t, y), form_many.fun(t, y))
        ref = num.fun(t, y)
        np.testing.assert_allclose(form_many.fun(t, y), ref, rtol=0, atol=1e-10 * (1 + np.abs(ref).max()))
    assert many.stats["fallbacks"] == 0


def _units(prog, groups, n_parts=1):
    units = []
    for group in groups:
        parts, _ = prog.c_parts(group, f"mbcomp_{group}", toolchain.CHUNK, n_parts)
        units += [(f"{group}{k}", toolchain.HEADER + src, list(toolchain.FLAGS)) for k, src in enumerate(parts)]
    return units


def _call(lib, name, system, tr, prog, n_out):
    """``name`` of a library built from ``prog`` at the trace point: its outputs."""
    fn = getattr(ctypes.CDLL(lib), name)
    P = ctypes.c_void_p
    fn.argtypes = [P, P, ctypes.c_double, P, P, P, P, P]
    fn.restype = ctypes.c_int
    t, q, u = trace_point(system)
    q, u = np.ascontiguousarray(q, float), np.ascontiguousarray(u, float)
    d = np.array([10.0, 10.0])  # Baumgarte gains
    h = np.array([nd.v for nd in (tr.graph.nodes[i] for i in prog.hoisted)] + [0.0])
    p = np.array(param_vector(system, tr.layout) + [0.0])
    w, out = np.zeros(100_000), np.zeros(n_out)
    assert fn(q.ctypes.data, u.ctypes.data, t, d.ctypes.data, h.ctypes.data, p.ctypes.data, w.ctypes.data,
              out.ctypes.data) == 0
    return out


def test_a_rebuilt_library_compiles_only_the_changed_unit(tmp_path, monkeypatch):
    """The evaluation program of a 12-link pendulum in three units with the Lagrange program
    of a 12-link one, then of a 13-link one: the second library compiles the new Lagrange
    unit only (one compiler run), the evaluation's object files keep their bytes and times,
    and both libraries compute what the numeric path does."""
    cc, d = c_compiler(), str(tmp_path)
    a, b = pendulum(12), pendulum(13)
    tr_a, tr_b = trace(a, 3_000_000, program="fun"), trace(b, 3_000_000, program="fun")
    tr_e = trace(a, 3_000_000)
    prog_a, prog_b = (Program(tr.graph, tr.groups, guard_groups=tr.guard_groups) for tr in (tr_a, tr_b))
    prog_e = Program(tr_e.graph, tr_e.groups, guard_groups=tr_e.guard_groups)
    # each library: the evaluation of a, the Lagrange program of a or b (each program is
    # called with the values of its own trace)
    eval_units = _units(prog_e, ["eval"], n_parts=3)
    lib1, lib2 = os.path.join(d, "one.so"), os.path.join(d, "two.so")
    runs = []
    real_popen = toolchain.subprocess.Popen

    def popen(args, *x, **k):
        if "-c" in args:  # a compilation (not the link)
            runs.append(args[-1])
        return real_popen(args, *x, **k)

    monkeypatch.setattr(toolchain.subprocess, "Popen", popen)
    first = toolchain.compile_units(cc, eval_units + _units(prog_a, ["fun"]), lib1, d)
    assert sorted(first["compiled"]) == ["eval0", "eval1", "eval2", "fun0"] and len(runs) == 4
    objs = sorted(tmp_path.glob("mbcomp_*.o"))
    before = {o: (o.stat().st_mtime_ns, o.read_bytes()) for o in objs}
    runs.clear()
    second = toolchain.compile_units(cc, eval_units + _units(prog_b, ["fun"]), lib2, d)
    assert second == {"compiled": ["fun0"], "reused": ["eval0", "eval1", "eval2"]} and len(runs) == 1
    assert all((o.stat().st_mtime_ns, o.read_bytes()) == before[o] for o in objs)
    # results: the evaluation (same object in both) and each Lagrange program against numerics
    n_eval = len(tr_e.groups["eval"])
    ev1 = _call(lib1, "mbcomp_eval", a, tr_e, prog_e, n_eval)
    np.testing.assert_array_equal(ev1, _call(lib2, "mbcomp_eval", a, tr_e, prog_e, n_eval))
    t, q, u = trace_point(a)
    num = a.evaluate_numeric(t, q, u, masked=False)
    np.testing.assert_allclose(ev1[: a.nu ** 2].reshape(a.nu, a.nu), num.M, rtol=1e-12, atol=1e-12)
    for lib, s, tr, prog in ((lib1, a, tr_a, prog_a), (lib2, b, tr_b, prog_b)):
        t, q, u = trace_point(s)
        dy = _call(lib, "mbcomp_fun", s, tr, prog, len(tr.groups["fun"]))
        ref = LagrangeIndex1(s, alpha=10.0, beta=10.0).fun(t, np.concatenate((q, u)))
        np.testing.assert_allclose(dy, ref, rtol=0, atol=1e-9 * (1 + np.abs(ref).max()))


def test_the_lagrange_build_reuses_the_evaluation_builds_equal_units(tmp_path):
    """compile_system builds the evaluation library; the Lagrange program, made at its first
    use, is a second library: its equal units (the coordinate rates here) are not compiled
    again, and its right-hand side is the numeric one."""
    s = pendulum(8)
    c = compile_system(s, "c", cache_dir=str(tmp_path))
    ev = c.evaluator.bound.code
    assert ev.cache == "miss" and ev.objects["compiled"] == ["eval", "qrate"]
    fun = c.evaluator._fun_bound().code
    assert fun.objects == {"compiled": ["eval", "fun"], "reused": ["qrate"]}
    t, q, u = trace_point(s)
    y = np.concatenate((q, u))
    np.testing.assert_allclose(LagrangeIndex1(c, alpha=1.0, beta=1.0).fun(t, y),
                               LagrangeIndex1(s, alpha=1.0, beta=1.0).fun(t, y), rtol=1e-9, atol=1e-9)
    again = compile_system(s, "c", cache_dir=str(tmp_path))
    assert again.evaluator.bound.code.cache == "hit" and again.evaluator._fun_bound().code.cache == "hit"


_HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>

static double *load(FILE *f, int n)
{
    double *a = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    for (int i = 0; i < n; i++)
        if (fscanf(f, "%lf", &a[i]) != 1)
            exit(3);
    return a;
}

int main(int argc, char **argv)
{
    FILE *f = fopen(argv[1], "r");
    int n[7];  /* q, u, d, h, p, w, out: the exact sizes */
    double t;
    for (int i = 0; i < 7; i++)
        if (fscanf(f, "%d", &n[i]) != 1)
            return 3;
    if (fscanf(f, "%lf", &t) != 1)
        return 3;
    double *q = load(f, n[0]), *u = load(f, n[1]), *d = load(f, n[2]), *h = load(f, n[3]), *p = load(f, n[4]);
    double *w = load(f, 0), *out = load(f, 0);
    free(w);
    free(out);
    w = malloc(sizeof(double) * (size_t)(n[5] > 0 ? n[5] : 1));
    out = malloc(sizeof(double) * (size_t)n[6]);
    fclose(f);
    int rc = FN(q, u, t, d, h, p, w, out);
    printf("%d\n", rc);
    for (int i = 0; i < n[6]; i++)
        printf("%.17g\n", out[i]);
    free(q); free(u); free(d); free(h); free(p); free(w); free(out);
    return 0;
}
"""
SAN_FLAGS = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-O1"]


def test_generated_programs_under_asan_ubsan(tmp_path):
    """The evaluation (rolled loops) of a 20-link pendulum and the Lagrange program (guards)
    of a 3-D chain, each in its own process with heap buffers of exactly the sizes the
    program declares (work array included), under AddressSanitizer + UBSan: no error, and
    the values of the library."""
    import subprocess

    cc = c_compiler()
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    res = subprocess.run([cc, *SAN_FLAGS, str(probe), "-o", str(tmp_path / "probe")], capture_output=True)
    if res.returncode != 0 or subprocess.run([str(tmp_path / "probe")], capture_output=True).returncode != 0:
        pytest.skip("AddressSanitizer/UBSan not usable here")
    cases = []
    for s in (pendulum(20), chain_3d(3)):
        ev = compile_system(s, "c", cache_dir=str(tmp_path)).evaluator
        cases.append((s, ev.bound, "mbcomp_eval", ev.bound.code.n_out))
        cases.append((s, ev._fun_bound(), "mbcomp_fun", s.nq + s.nu))
    assert "_tab[" in cases[0][1].code.source and cases[3][1].code.state_guards["fun"] > 0
    for k, (s, bound, fn, n_out) in enumerate(cases):
        code = bound.code
        src = tmp_path / f"prog{k}.c"
        src.write_text(code.c_source + _HARNESS)
        exe = tmp_path / f"prog{k}"
        res = subprocess.run([cc, *SAN_FLAGS, f"-DFN={fn}", str(src), "-o", str(exe), "-lm"], capture_output=True,
                             text=True)
        assert res.returncode == 0, res.stderr[-3000:]
        t, q, u = next(states(s, 1, seed=k))
        d = [10.0, 10.0] if fn == "mbcomp_fun" else []
        h, p = list(bound.hbuf[:-1]), list(bound.pbuf[:-1])
        data = tmp_path / f"in{k}.txt"
        sizes = [s.nq, s.nu, len(d), len(h), len(p), code.n_work, n_out]
        data.write_text(" ".join(map(str, sizes)) + "\n" + " ".join(repr(float(x)) for x in [t, *q, *u, *d, *h, *p]) + "\n")
        run = subprocess.run([str(exe), str(data)], capture_output=True, text=True, timeout=120,
                             env={"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
        assert run.returncode == 0 and "runtime error" not in run.stderr, run.stderr[-3000:]
        lines = run.stdout.split()
        assert lines[0] == "0"
        got = np.array([float(x) for x in lines[1:]])
        want = bound.run(t, q, u) if fn == "mbcomp_eval" else bound.run_fun(t, np.concatenate((q, u)), 10.0, 10.0)
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
