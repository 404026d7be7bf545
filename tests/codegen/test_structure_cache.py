"""The structure-keyed program cache (codegen/structure_key.py): a model rebuilt with other
parameter or start values reuses the programs of the first run and gives the cold run's
result; a change of structure (a zero that becomes nonzero, another law, another joint type,
another connection, a drive's number, an input's start) does not reuse them."""
import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import compile_system
from mbcomp.codegen.structure_key import STRUCTURES, structure_key
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Prismatic, Revolute, Torque, World


def double_pendulum(m2=1.0, r2=(0.0, -1.0, 0.0), phi0=0.5, second=Revolute, tau=None, swap=False, drive=None,
                    torque_input=None):
    """Two links on hinges about z; ``second`` the second joint's class; ``tau`` a torque law on
    the first hinge; ``drive`` a PrescribedMotion law driving the first hinge; ``swap``
    connects the second rod's ends the other way round; ``torque_input`` an Input on the first hinge."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j1 = m.add("j1", Revolute(phi0=phi0))
    r1 = m.add("r1", FixedTranslation(r=(0.0, -1.0, 0.0)))
    b1 = m.add("b1", PointMass(m=1.0))
    j2 = m.add("j2", second(**({"phi0": 0.2} if second is Revolute else {"n": (1.0, 0.0, 0.0), "s0": 0.1})))
    r2c = m.add("r2", FixedTranslation(r=r2))
    b2 = m.add("b2", PointMass(m=m2))
    m.connect(w.frame_b, j1.frame_a)
    m.connect(j1.frame_b, r1.frame_a)
    m.connect(r1.frame_b, b1.frame_a)
    m.connect(r1.frame_b, j2.frame_a)
    if swap:
        m.connect(j2.frame_b, r2c.frame_b)
        m.connect(r2c.frame_a, b2.frame_a)
    else:
        m.connect(j2.frame_b, r2c.frame_a)
        m.connect(r2c.frame_b, b2.frame_a)
    if tau is not None or torque_input is not None:
        t = m.add("tq", Torque(tau=tau if tau is not None else torque_input))
        m.connect(t.flange_b, j1.axis)
    if drive is not None:
        d = m.add("d", PrescribedMotion(s=drive))
        m.connect(d.flange_b, j1.axis)
    return m


def run(model, backend="python", **kw):
    return mbcomp.simulate(model, t_end=0.3, n_out=7, rtol=1e-10, atol=1e-12, backend=backend, **kw)


def cold(model, backend="python", **kw):
    STRUCTURES.clear()
    return run(model, backend, **kw)


def states(res):
    return np.column_stack([res[n] for n in res.system.q_names + res.system.u_names])


def reused(res):
    return res.system.stats.get("structure_cache")


@pytest.mark.parametrize("backend", ["python", "c"])
def test_other_parameter_and_start_values_reuse_the_programs(backend):
    cold(double_pendulum(), backend)
    warm = run(double_pendulum(m2=2.5, r2=(0.0, -0.7, 0.0), phi0=0.9), backend)
    assert reused(warm) == "hit"
    ref = cold(double_pendulum(m2=2.5, r2=(0.0, -0.7, 0.0), phi0=0.9), backend)
    assert reused(ref) == "miss"
    assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12
    # and not the first model's motion
    first = run(double_pendulum(), backend)
    assert np.max(np.abs(states(first) - states(ref))) > 1e-3


def law(t, phi, w):
    return -0.5 * w + 0.3


def other_law(t, phi, w):
    return 0.8 * np.sin(t)


@pytest.mark.parametrize("changed", [
    dict(r2=(0.3, -1.0, 0.0)),          # a zero that becomes nonzero
    dict(tau=other_law),                # another law
    dict(second=Prismatic),             # another joint type
    dict(swap=True),                    # another connection
])
def test_a_changed_structure_is_not_reused(changed):
    base = dict(tau=law)
    k0, _ = structure_key(mbcomp.assemble(double_pendulum(**base)), "python")
    k1, _ = structure_key(mbcomp.assemble(double_pendulum(**{**base, **changed})), "python")
    assert k0 != k1
    assert structure_key(mbcomp.assemble(double_pendulum(**base, m2=3.0)), "python")[0] == k0
    cold(double_pendulum(**base))
    warm = run(double_pendulum(**{**base, **changed}))
    assert reused(warm) == "miss"
    ref = cold(double_pendulum(**{**base, **changed}))
    assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12


def test_the_same_law_object_is_reused_and_the_law_drives_the_motion():
    cold(double_pendulum(tau=law))
    warm = run(double_pendulum(tau=law, m2=1.7))
    assert reused(warm) == "hit"
    ref = cold(double_pendulum(tau=law, m2=1.7))
    assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12


def test_a_drive_number_is_part_of_the_structure():
    """A drive's law is traced into the right-hand side with its numbers as constants."""
    cold(double_pendulum(drive="0.3*sin(2*t)"), "c")
    warm = run(double_pendulum(drive="0.5*sin(2*t)"), "c")
    assert reused(warm) == "miss"
    t = warm.time
    assert np.max(np.abs(warm["j1.phi"] - 0.5 * np.sin(2 * t))) <= 1e-9


def test_an_input_start_is_part_of_the_structure():
    cold(double_pendulum(torque_input=mbcomp.Input("u", unit="N m", start=0.0)))
    warm = run(double_pendulum(torque_input=mbcomp.Input("u", unit="N m", start=3.0)))
    assert reused(warm) == "miss"
    ref = cold(double_pendulum(torque_input=mbcomp.Input("u", unit="N m", start=3.0)))
    assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12


def test_a_drive_number_given_as_a_runtime_parameter_is_not_the_baked_one():
    """``params=`` changing a drive's law on a compiled system: the right-hand side that holds
    the first law's numbers is not reused."""
    system = compile_system(mbcomp.assemble(double_pendulum(drive="0.3*sin(2*t)")), "c", lazy=True)
    res = mbcomp.simulate(system, t_end=0.3, n_out=7, params={"d.s": "0.5*sin(2*t)"})
    assert np.max(np.abs(res["j1.phi"] - 0.5 * np.sin(2 * res.time))) <= 1e-9


K = 0.5


def global_law(t, phi, w):
    return -K * w


def test_a_law_reading_a_changed_global_is_traced_again():
    """A law's global is traced into the program as a constant: changing it is a new structure."""
    global K
    K = 0.5
    cold(double_pendulum(tau=global_law))
    K = 3.0
    try:
        warm = run(double_pendulum(tau=global_law))
        assert reused(warm) == "miss"
        ref = cold(double_pendulum(tau=global_law))
        assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12
        again = run(double_pendulum(tau=global_law, m2=2.0))   # the same K: reused
        assert reused(again) == "hit"
    finally:
        K = 0.5


def test_a_callable_object_is_keyed_by_its_state():
    class Damping:
        def __init__(self, c):
            self.c = c

        def __call__(self, t, phi, w):
            return -self.c * w

    a, b = Damping(0.5), Damping(2.0)
    ka = structure_key(mbcomp.assemble(double_pendulum(tau=a)), "python")[0]
    kb = structure_key(mbcomp.assemble(double_pendulum(tau=b)), "python")[0]
    assert ka != kb
    import functools

    def lin(c, t, phi, w):
        return -c * w
    kp = structure_key(mbcomp.assemble(double_pendulum(tau=functools.partial(lin, 0.5))), "python")[0]
    kq = structure_key(mbcomp.assemble(double_pendulum(tau=functools.partial(lin, 2.0))), "python")[0]
    assert kp != kq  # a partial's arguments are not in its __dict__: keyed by identity


def module_law(t, phi, w):
    return -SETTINGS.K * w   # a constant read through a module


SETTINGS = __import__("types").ModuleType("settings")
SETTINGS.K = 0.5


def test_a_law_reading_a_changed_module_attribute_is_traced_again():
    """``cfg.K`` is traced as a constant too: the attribute's value is part of the structure."""
    SETTINGS.K = 0.5
    first = cold(double_pendulum(tau=module_law))
    SETTINGS.K = 3.0
    try:
        warm = run(double_pendulum(tau=module_law))
        assert reused(warm) == "miss"
        ref = cold(double_pendulum(tau=module_law))
        assert np.max(np.abs(states(warm) - states(ref))) <= 1e-12
        assert np.max(np.abs(states(warm) - states(first))) > 1e-3   # the damping changed the motion
    finally:
        SETTINGS.K = 0.5


def test_a_changed_class_constant_of_a_component_is_another_structure():
    """A component's class constant its equations read (here a torque gain) is structure."""
    class GainTorque(Torque):
        GAIN = 1.0

    def law(t, phi, w):   # one law object for both models: only the class constant differs
        return -GainTorque.GAIN * w

    def model():
        m = double_pendulum()
        t = m.add("tq", GainTorque(tau=law))
        m.connect(t.flange_b, m["j1"].axis)
        return m

    k1 = structure_key(mbcomp.assemble(model()), "python")[0]
    assert structure_key(mbcomp.assemble(model()), "python")[0] == k1   # the same structure: one key
    GainTorque.GAIN = 2.0
    k2 = structure_key(mbcomp.assemble(model()), "python")[0]
    assert k1 != k2
