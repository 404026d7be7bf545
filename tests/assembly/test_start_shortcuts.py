"""The shortcuts that keep a short run's fixed cost down give what the long way gives.

``directions`` screens with the eigenvalues alone, initialization hands the closure's
evaluation on to the speeds, the accuracy alarm's tolerance energy takes the start's
evaluation, the summary takes the structure's constraint row names: each against the long
way, exactly (the results of a run are the same bits either way; an ill-conditioned ratio far
from the limits, which only the warning's text shows to three digits, to rounding)."""
import numpy as np
import pytest

import mbcomp
from mbcomp.assembly.conditioning import ILL_CONDITIONED, MASSLESS, directions
from mbcomp.assembly.initialization import initialize
from mbcomp.simulation.accuracy import tolerance_energy
from tests.conftest import load_model


def _reference(Mr, scale=0.0):
    """``directions`` the long way: every eigenvalue and vector of ``Mr``."""
    w, V = np.linalg.eigh(0.5 * (Mr + Mr.T))
    top = max(w[-1] if w.size else 0.0, scale, 0.0)
    small = w <= MASSLESS * top
    if small.any() or top == 0.0:
        return V[:, small | (top == 0.0)], None
    ratio = w[0] / top
    return V[:, :0], (float(ratio) if ratio < ILL_CONDITIONED else None)


@pytest.mark.parametrize("smallest", [1.0, 1e-3, 1e-7, 3e-8, 2e-8, 1.5e-8, 1e-8, 1e-10, 2e-12, 1e-12, 5e-13, 0.0])
@pytest.mark.parametrize("n", [3, 40])
def test_screened_directions_are_the_eigh_directions(smallest, n):
    """Across both limits (ill-conditioned at sqrt(eps), massless at 1e-12) and near them."""
    rng = np.random.default_rng(n)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    w = np.geomspace(1.0, 10.0, n)
    w[0] = smallest * w[-1]
    Mr = (Q * w) @ Q.T
    got, ref = directions(Mr), _reference(Mr)
    # the decisions exactly; an ill-conditioned ratio far from both limits comes from the
    # eigenvalues alone (eigh's differ by n eps of the largest), the warning's text the same
    assert (got[1] is None) == (ref[1] is None)
    if ref[1] is not None:
        assert got[1] == pytest.approx(ref[1], rel=n * 4 * np.finfo(float).eps / ref[1])
        assert f"{got[1]:.3g}" == f"{ref[1]:.3g}"
    assert got[0].shape == ref[0].shape
    np.testing.assert_array_equal(got[0], ref[0])
    if smallest == 0.0:
        assert got[0].shape[1] == 1  # the massless direction is still found
    if 1e-12 < smallest < 1e-8:
        assert got[1] is not None and got[1] < ILL_CONDITIONED  # and the warning still rings


def test_start_evaluation_is_the_evaluation_at_the_start():
    """The evaluation initialization keeps (handed from the closure to the speeds) is the one a
    new evaluation at the start gives, and the tolerance energy taking it is the same number."""
    s = mbcomp.assemble(load_model("models/slider_crank.py").build())
    init = initialize(s)
    system, ev = init.start
    assert system is s
    fresh = s.evaluate(0.0, init.q, init.u)
    for name in ("M", "f", "Phi", "Phid", "C", "B"):
        np.testing.assert_array_equal(getattr(ev, name), getattr(fresh, name), err_msg=name)
    Y = np.array([np.concatenate((init.q, init.u)), np.concatenate((init.q, init.u + 0.1))])
    t = np.array([0.0, 0.1])
    assert tolerance_energy(s, t, Y, 1e-6, 1e-8, ev) == tolerance_energy(s, t, Y, 1e-6, 1e-8)
    moved = Y.copy()
    moved[0, 0] += 1e-3  # not the start: the known evaluation is not taken
    assert tolerance_energy(s, t, moved, 1e-6, 1e-8, ev) == tolerance_energy(s, t, moved, 1e-6, 1e-8)


def test_summary_row_names_are_the_evaluated_ones():
    """A warm structure's summary (row names kept per structure) is the cold one's, with a loop
    and its redundant rows (Bricard's linkage)."""
    model = load_model("models/bricard.py")
    cold = mbcomp.simulate(model.build(), t_end=1e-3, n_out=2)
    warm = mbcomp.simulate(model.build(), t_end=1e-3, n_out=2)
    assert "redundant constraint rows dropped" in cold.summary
    assert warm.summary == cold.summary
    assert warm.system.constraint_names(all_rows=True) == cold.system.constraint_names(all_rows=True)
    names = warm.system.constraint_names(all_rows=True)
    ev = warm.system.evaluate_numeric(0.0, warm.system.default_q(), np.zeros(warm.system.nu), masked=False)
    assert names == [f"{e.name}.{r}" for e, rows, _ in ev.local for r in rows]


def test_a_wrapped_evaluator_gets_its_own_masked_evaluation():
    """An evaluator whose masked evaluations differ from its unmasked ones (a hybrid mode adds
    held rows or friction to masked ones only) is asked again at the start: the closure's
    unmasked evaluation is not taken for it."""
    from mbcomp.hybrid.active import ForcesAdded, WrappingEvaluator

    class PushWhenMasked(WrappingEvaluator):
        def evaluate(self, t, q, u, masked=True):
            ev = self.inner.evaluate(t, q, u, masked)
            return ForcesAdded(ev, np.asarray(ev.f, float) + 1.0) if masked else ev

        def rebind(self, system, laws=False):
            return PushWhenMasked(self.inner.rebind(system, laws))

    base = mbcomp.assemble(load_model("models/n_link_pendulum.py").build(N=3))
    s = base.with_evaluator(lambda new: PushWhenMasked(base.evaluator))
    init = initialize(s)
    ev = init.start[1]
    np.testing.assert_array_equal(ev.f, s.evaluate(0.0, init.q, init.u).f)
    np.testing.assert_array_equal(ev.f, base.evaluate(0.0, init.q, init.u).f + 1.0)
