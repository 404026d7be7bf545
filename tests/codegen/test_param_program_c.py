"""The parameter program printed in C (:meth:`mbcomp.codegen.printers.Program.c_params`): the
hoisted values of any parameter set computed without Python -- what an exported FMU needs
for its tunable parameters. Checked against :class:`~mbcomp.codegen.printers.ParamProgram`
(the interpreter every program uses today) bit for bit, guards included."""
import ctypes
import subprocess

import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import c_compiler
from mbcomp.codegen.graph import Retrace
from mbcomp.codegen.printers import ParamProgram, Program
from mbcomp.codegen.tracer import param_layout, param_vector, trace

from conftest import load_model

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")


def build(prog, tmp_path):
    src = tmp_path / "params.c"
    src.write_text("#include <math.h>\n" + prog.c_params("params"))
    lib = tmp_path / "params.so"
    subprocess.run([c_compiler(), "-O2", "-fno-math-errno", "-fPIC", "-shared", str(src), "-o", str(lib), "-lm"],
                   check=True, capture_output=True)
    fn = ctypes.CDLL(str(lib)).params
    fn.argtypes, fn.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
    return fn


@pytest.mark.parametrize("name", ["slider_crank", "andrews", "bicycle", "four_bar", "chain_3d"])
def test_the_c_parameter_program_is_the_interpreted_one(name, tmp_path):
    system = mbcomp.assemble(load_model(f"models/{name}.py").build())
    initialize(system)
    tr = trace(system, 3_000_000, program="fun")
    prog = Program(tr.graph, {"fun": tr.groups["fun"]})
    pre = ParamProgram(prog)
    fn = build(prog, tmp_path)
    pv0 = np.array(param_vector(system, param_layout(system)[0]), float)
    outcomes = {0: 0, 1: 0}
    for j in range(pv0.size):  # one parameter at a time, 5 % larger (an axis component: a guard fails)
        pv = pv0.copy()
        pv[j] = pv[j] * 1.05 if pv[j] else 0.05
        h = np.zeros(max(len(prog.hoisted), 1))
        rc = fn(np.ascontiguousarray(pv).ctypes.data, h.ctypes.data)
        try:
            ref = pre.run(pv.tolist())
        except Retrace:
            assert rc == 1  # the same parameter guard fails in C
            outcomes[1] += 1
            continue
        assert rc == 0
        np.testing.assert_array_equal(h[: len(ref)], np.array(ref, float))  # the same IEEE operations
        outcomes[0] += 1
    assert outcomes[0] >= 3 and len(prog.hoisted) > 0, outcomes
