"""Consistent initialization closes loops on the rows alone (``system.evaluate_rows``) and
makes the full evaluation once at the closure's end (``system.evaluate_from``): the starts,
the row masks, the start evaluations and the errors are bit for bit those of the path that
evaluated everything at every Newton iterate, which an evaluator offering ``evaluate`` only
still takes (:class:`FullOnly` below)."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.system import MultibodySystem
from mbcomp.codegen import compile_system
from mbcomp.errors import InitializationError
from mbcomp.hybrid.active import ModeEvaluator, mode_system
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, World

from conftest import load_model

FIELDS = ("M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi")


class FullOnly:
    """An evaluator with ``evaluate`` only (no rows-only path): the system's evaluations as
    they are, every one full -- initialization as it was before the rows-only closure."""

    capabilities = frozenset()

    def __init__(self, system, wrapped):
        # bound to its system and wrapping no evaluator as ``wrapped`` is (initialization reuses
        # the closure's evaluation only for the system's own evaluator, not a mode's wrapper)
        self.system = system if getattr(wrapped, "system", None) is not None else None
        self.inner, self.inner_evaluator = getattr(wrapped, "inner", None), wrapped

    backend = property(lambda self: self.inner_evaluator.backend)
    stats = property(lambda self: self.inner_evaluator.stats)

    def evaluate(self, t, q, u, masked=True):
        return self.inner_evaluator.evaluate(t, q, u, masked)

    def q_rate(self, q, u):
        return self.inner_evaluator.q_rate(q, u)

    def rebind(self, system, laws=False):
        return FullOnly(system, self.inner_evaluator.rebind(system, laws))


def full_only(system):
    """``system``'s copy whose evaluator answers full evaluations only: its own evaluator
    rebound to the copy (whose row mask initialization sets), or a mode's wrapper as it is
    (its inner evaluator is bound to the mode's base system, masking by that one's mask)."""
    new = system.with_evaluator()
    own = getattr(system.evaluator, "inner", None) is None
    new.evaluator = FullOnly(new, system.evaluator.rebind(new) if own else system.evaluator)
    return new


def bits(init):
    """Everything a start decides, as bytes: ``q``, ``u``, the row mask, the dropped rows,
    the counts, the notes and every field of the start evaluation."""
    ev = init.start[1]
    return (init.q.tobytes(), init.u.tobytes(), np.asarray(init.row_mask).tobytes(), tuple(init.dropped),
            init.iterations, init.rank, init.nonholonomic, tuple(map(str, init.notes)),
            tuple((k, np.shape(getattr(ev, k)), np.asarray(getattr(ev, k), float).tobytes()) for k in FIELDS))


def slider_crank(crank=0.5, rod=mbcomp.Guess(-0.3), slide=mbcomp.Guess(0.7), pin=None, line=0.0, limits=None, w0=2.0):
    """A crank (0.2 m, start rate ``w0`` rad/s), a rod (0.6 m) and a slider on the line
    ``y = line`` (m); the slider's pin (``pin``: its start angle) closes the loop."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    c = m.add("crank", Revolute(n=(0, 0, 1), phi0=crank, w0=w0, **({"limits": limits} if limits else {})))
    a = m.add("a", FixedTranslation(r=(0.2, 0, 0)))
    pa = m.add("pa", PointMass(m=1.0))
    r = m.add("rod", Revolute(n=(0, 0, 1), phi0=rod))
    b = m.add("b", FixedTranslation(r=(0.6, 0, 0)))
    pb = m.add("pb", PointMass(m=1.0))
    base = m.add("base", FixedTranslation(r=(0, line, 0)))
    s = m.add("slide", Prismatic(n=(1, 0, 0), s0=slide))
    p = m.add("pin", Revolute(n=(0, 0, 1), **({} if pin is None else {"phi0": pin})))
    m.connect(w.frame_b, c.frame_a)
    m.connect(c.frame_b, a.frame_a)
    m.connect(a.frame_b, pa.frame_a)
    m.connect(a.frame_b, r.frame_a)
    m.connect(r.frame_b, b.frame_a)
    m.connect(b.frame_b, pb.frame_a)
    m.connect(w.frame_b, base.frame_a)
    m.connect(base.frame_b, s.frame_a)
    m.connect(s.frame_b, p.frame_a)
    m.connect(p.frame_b, b.frame_b)
    return m


def systems():
    """``(name, system)`` of the starts compared: loops from guesses far off and started
    closed, a tree, a start value fixed on the joint that closes the loop, the generated
    program (eager and lazy, as ``simulate`` makes it), a hybrid mode's wrapper."""
    four_bar, andrews = load_model("models/four_bar.py"), load_model("models/andrews.py")
    out = [("slider-crank, guesses", mbcomp.assemble(slider_crank())),
           ("slider-crank, crank far off", mbcomp.assemble(slider_crank(crank=2.9, rod=mbcomp.Guess(1.0)))),
           ("slider-crank, the pin's angle fixed", mbcomp.assemble(slider_crank(crank=mbcomp.Guess(0.5), pin=0.2))),
           ("four-bar 1.4 rad off", mbcomp.assemble(four_bar.build(phi0=0.1))),
           ("Andrews", mbcomp.assemble(andrews.build())),
           ("5-link pendulum", mbcomp.assemble(load_model("models/n_link_pendulum.py").build(N=5)))]
    out += [("slider-crank, program", compile_system(mbcomp.assemble(slider_crank()), "python")),
            ("Andrews, lazy program", compile_system(mbcomp.assemble(andrews.build()), "python", lazy=True))]
    held = mbcomp.assemble(slider_crank(limits=(0.5, 3.0), w0=0.0))
    out.append(("slider-crank on its stop (ModeEvaluator)", mode_system(held, {"crank": "lo"})))
    return out


@pytest.mark.parametrize("name, system", systems(), ids=lambda v: v if isinstance(v, str) else "")
def test_starts_are_bit_for_bit_those_of_full_evaluations(name, system):
    old = full_only(system)
    new_init, old_init = initialize(system), initialize(old)
    assert bits(new_init) == bits(old_init), name
    assert np.array_equal(system.row_mask, old.row_mask)
    if name.endswith("(ModeEvaluator)"):  # the wrapper's masked evaluations carry the held row
        assert isinstance(system.evaluator, ModeEvaluator) and new_init.start[1].Phi[-1] == 0.0
        assert new_init.q[0] == 0.5  # on the stop: the crank angle as fixed
    if name.startswith("slider-crank, guesses"):  # the rod end closed on the slider's line
        assert new_init.iterations > 0 and abs(0.2 * np.sin(0.5) + 0.6 * np.sin(0.5 + new_init.q[1])) < 1e-12


def test_the_rows_are_the_full_evaluations_rows_bit_for_bit():
    """``evaluate_rows`` gives ``evaluate(..., masked=False)``'s rows and ``evaluate_from``
    its evaluation (masked or not) exactly, numeric, by the program, and lazily."""
    andrews = load_model("models/andrews.py")
    s = mbcomp.assemble(andrews.build())
    init = initialize(s)
    assert not init.row_mask.all()  # planar loops of spatial joints: rows dropped, the mask applies
    rng = np.random.default_rng(3)
    q, u = init.q + 0.05 * rng.standard_normal(s.nq), rng.standard_normal(s.nu)
    for system in (s, compile_system(s, "python"), compile_system(s, "python", lazy=True)):
        rows = system.evaluate_rows(0.0, q, u)
        for masked in (False, True):
            ev, again = system.evaluate(0.0, q, u, masked), system.evaluate_from(rows, masked)
            for k in FIELDS:
                assert np.asarray(getattr(ev, k)).tobytes() == np.asarray(getattr(again, k)).tobytes(), (system.backend, k)
        full = system.evaluate(0.0, q, u, masked=False)
        for k in ("Phi", "Phid", "C", "cb"):
            assert getattr(rows, k).tobytes() == np.asarray(getattr(full, k)).tobytes(), k
        assert np.abs(rows.Phi).max() > 1e-3  # off the loop: the rows are not trivially zero


def test_the_newton_iterates_make_no_mass_matrix(monkeypatch):
    """The closure's iterates evaluate the rows alone; full evaluations: one at the closure's
    end and one after the speeds are solved (before: one per iterate, plus two)."""
    full, rows = [], []
    complete, evaluate_rows = MultibodySystem.complete_numeric, MultibodySystem.evaluate_rows_numeric
    evaluate = MultibodySystem.evaluate_numeric
    monkeypatch.setattr(MultibodySystem, "complete_numeric", lambda self, *a: full.append(1) or complete(self, *a))
    monkeypatch.setattr(MultibodySystem, "evaluate_numeric", lambda self, *a: full.append(1) or evaluate(self, *a))
    monkeypatch.setattr(MultibodySystem, "evaluate_rows_numeric", lambda self, *a: rows.append(1) or evaluate_rows(self, *a))
    s = mbcomp.assemble(slider_crank())
    s.row_names()  # the rows' names (one rows-only evaluation), made once per system
    rows.clear()
    init = initialize(s)
    assert init.iterations >= 3 and len(rows) >= init.iterations + 1
    assert len(full) == 2  # the speeds were solved (w0 = 2 rad/s on the crank moves the others)
    assert np.abs(init.u[1:]).max() > 0.5


def test_a_lazy_evaluator_counts_as_before():
    """A lazy program evaluator counts the evaluations it answers numerically towards making
    its program: a rows-only evaluation counts as the full one it stands for, its unmasked
    completion not again, so a run switches to the program where it did before."""
    for model in (slider_crank(), load_model("models/andrews.py").build()):
        s = compile_system(mbcomp.assemble(model), "python", lazy=True)
        old = full_only(s)
        init = initialize(s)
        initialize(old)
        assert s.evaluator.bound is None and s.evaluator.numeric_calls == old.evaluator.inner_evaluator.numeric_calls
        assert s.evaluator.numeric_calls >= init.iterations + 2  # every Newton iterate counted, and the start


def test_errors_are_those_of_full_evaluations():
    """Over-specified fixed start values and a loop that cannot close raise the same errors
    (named joints, residuals) on both paths."""
    cases = [slider_crank(rod=-0.1, slide=0.7),  # crank and rod fixed: the rod end off the line
             slider_crank(line=1.0)]  # the slider's line beyond the crank's and rod's reach
    messages = []
    for model in cases:
        got = []
        for s in (mbcomp.assemble(model), full_only(mbcomp.assemble(model))):
            with pytest.raises(InitializationError) as err:
                initialize(s)
            got.append(str(err.value))
        assert got[0] == got[1]
        messages.append(got[0])
    assert "over-specify" in messages[0] and "rod.phi" in messages[0]
    assert "cannot be assembled" in messages[1]
