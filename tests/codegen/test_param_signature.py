"""The parameter signature alone (codegen/tracer.py param_signature) is param_layout's, on
every model of models/ with and without kept parameters; its zero pattern is the entries'
``!= 0`` (a NaN is nonzero, -0.0 is zero), and the layout lists exactly the nonzero entries."""
import glob
import importlib.util
import os

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen.tracer import param_layout, param_signature
from mbcomp.codegen.tracing import parameter_entries
from mbcomp.library import PointMass, Prismatic, World

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(ROOT, "models", "*.py"))),
                         ids=lambda p: os.path.basename(p)[:-3])
def test_the_signature_alone_is_the_layouts(path):
    spec = importlib.util.spec_from_file_location("sig_" + os.path.basename(path)[:-3], path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    system = mbcomp.assemble(mod.build())
    keep = [(p, n) for p, n, kind, _ in parameter_entries(system) if kind != "start"][::3]
    for kept in ((), keep):
        layout, sig = param_layout(system, kept)
        assert param_signature(system, kept) == sig
        for p, n, idx in layout:  # every runtime entry nonzero, or kept
            v = getattr(system.P[p], n)
            assert (p, n) in kept or (v if idx is None else v[idx]) != 0


def test_the_zero_pattern_is_that_of_not_equal_zero():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0.0, -0.0, -9.81)))
    s = m.add("s", Prismatic(n=(0.0, 0.0, 1.0)))
    b = m.add("b", PointMass(m=2.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    system = mbcomp.assemble(m)
    system.P["world"].g = np.array([np.nan, -0.0, -9.81])
    layout, sig = param_layout(system)
    g = [x for x in sig if x[:2] == ("world", "g")][0]
    assert g[4] == bytes([1, 0, 1]) and param_signature(system) == sig
    assert [idx for p, n, idx in layout if (p, n) == ("world", "g")] == [(0,), (2,)]
