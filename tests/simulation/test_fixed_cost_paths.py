"""The paths that took the fixed and per-call costs out of ``simulate`` (issue 32, items 1-2):
the right-hand side in one C call (codegen/thin.py) gives the ctypes path's values bit for
bit and hands every failure to the full path, which says what went wrong; a small output
grid takes the output program a run of the structure made already; the columns' units are
made once per structure."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.column_units import column_units
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.codegen.structure_key import STRUCTURES
from mbcomp.codegen.thin import extension
from mbcomp.errors import SimulationError
from mbcomp.formulations import LagrangeIndex1
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")


def chain(n=3, tau=None):
    m = mbcomp.Model()
    w = m.add("world", World())
    prev = w.frame_b
    for k in range(n):
        j = m.add(f"j{k}", Revolute(phi0=0.3))
        r = m.add(f"r{k}", FixedTranslation(r=(0.0, -0.5, 0.0)))
        b = m.add(f"b{k}", PointMass(m=1.0 + k))
        m.connect(prev, j.frame_a)
        m.connect(j.frame_b, r.frame_a)
        m.connect(r.frame_b, b.frame_a)
        prev = r.frame_b
    if tau is not None:
        t = m.add("tq", Torque(tau=tau))
        m.connect(t.flange_b, m["j0"].axis)
    return m


def branch(t, phi, w):
    return 2.0 if phi > 0.0 else -2.0  # a decision on the state: a guard of the program


def form_of(model):
    system = compile_system(mbcomp.assemble(model), "c", lazy=True)
    return system, LagrangeIndex1(system)


@pytest.mark.skipif(extension() is None, reason="no Python headers here: the ctypes path stays")
def test_the_thin_call_gives_the_ctypes_values_bit_for_bit():
    system, form = form_of(chain(4))
    thin = system.evaluator.lagrange_thin(10.0, 10.0)
    bound = system.evaluator.lagrange_bound()
    rng = np.random.default_rng(3)
    for _ in range(20):
        y = rng.uniform(-2.0, 2.0, 8)
        ref = bound.run_fun(0.7, y, 10.0, 10.0)
        np.testing.assert_array_equal(thin(0.7, y), ref)
        np.testing.assert_array_equal(form.fun(0.7, y), ref)
    # and the gains are the thin call's own: another caller's gains do not reach it
    bound.run_fun(0.7, y, 0.0, 0.0)
    np.testing.assert_array_equal(thin(0.7, y), ref)
    assert form.nfev == 20


@pytest.mark.skipif(extension() is None, reason="no Python headers here: the ctypes path stays")
def test_the_thin_call_hands_failures_to_the_full_path():
    system, form = form_of(chain(2, tau=branch))
    thin = system.evaluator.lagrange_thin(10.0, 10.0)
    assert thin(0.0, np.array([np.nan, 0.0, 0.0, 0.0])) is None
    with pytest.raises(SimulationError, match="non-finite"):
        form.fun(0.0, np.array([np.nan, 0.0, 0.0, 0.0]))
    assert thin(0.0, np.zeros(3)) is None                         # a y of the wrong size
    assert thin(0.0, np.zeros(8)[::2]) is None                    # not contiguous: full path
    # the trace point took phi > 0; phi < 0 fails the guard: the numeric path, -2 N m
    y = np.array([-0.4, 0.1, 0.2, -0.3])
    assert thin(0.0, y) is None
    numeric = LagrangeIndex1(mbcomp.assemble(chain(2, tau=branch)))
    np.testing.assert_allclose(form.fun(0.0, y), numeric.fun(0.0, y), rtol=1e-12, atol=1e-12)
    before = system.stats["fallbacks"]
    form.fun(0.0, y)
    assert system.stats["fallbacks"] == before + 1
    y[0] = 0.4                                                    # back on the traced branch
    np.testing.assert_allclose(thin(0.0, y), numeric.fun(0.0, y), rtol=1e-12, atol=1e-12)


def test_a_small_grid_takes_the_output_program_of_an_earlier_run():
    STRUCTURES.clear()
    kw = dict(t_end=0.2, rtol=1e-10, atol=1e-12, backend="c")
    mbcomp.simulate(chain(3), n_out=101, **kw)                     # makes the output program
    small = mbcomp.simulate(chain(3), n_out=5, **kw)
    assert "n_ops_outputs" in small.system.stats and small.system.stats["structure_cache"] == "hit"
    numeric = mbcomp.simulate(chain(3), n_out=5, **{**kw, "backend": "numeric"})
    for name in ("j1.tau.z", "b2.r.x", "b2.v.y", "energy.total", "j2.w.der"):
        np.testing.assert_allclose(small[name], numeric[name], rtol=1e-7, atol=1e-9, err_msg=name)


def test_the_units_are_the_structures_own():
    STRUCTURES.clear()
    first = mbcomp.simulate(chain(2), t_end=0.01, n_out=3)
    second = mbcomp.simulate(chain(2), t_end=0.01, n_out=3)
    table = column_units(mbcomp.assemble(chain(2)))
    assert second.units == first.units
    assert second.units["j1.tau.z"] == "N m" and second.units["b1.v.x"] == "m/s"
    assert all(second.units[k] == table[k] for k in second.units if k in table)


def test_without_python_headers_the_ctypes_path_gives_the_same_values(monkeypatch, tmp_path):
    """A fresh machine without Python's headers: no extension, no thin call, the same ``fun``."""
    import sysconfig

    from mbcomp.codegen import thin as thin_module

    system, form = form_of(chain(3))
    y = np.linspace(-1.0, 1.0, 6)
    ref = system.evaluator.lagrange_bound().run_fun(0.2, y, 10.0, 10.0)
    paths = dict(sysconfig.get_paths(), include=str(tmp_path))        # no Python.h there
    monkeypatch.setattr(sysconfig, "get_paths", lambda *a, **k: paths)
    thin_module.forget()
    try:
        assert thin_module.extension(str(tmp_path)) is None
        assert system.evaluator.lagrange_thin(10.0, 10.0) is None
        fresh = LagrangeIndex1(system)
        np.testing.assert_array_equal(fresh.fun(0.2, y), ref)
        assert fresh.nfev == 1
    finally:
        monkeypatch.undo()
        thin_module.forget()
