"""Impacts acted on inside the C loop (issue 32 item 5): a stop's plain rebound is Newton's
restitution on the joint's own speed row computed in the runtime (``mbrt_impacts_integrate``),
the run restarted there as a new stepper would be, so a run of bounces is one C call.

Held to the Python actions (``hybrid.steppers.C_IMPACTS = False``: the same run with every
action in Python) -- the same steps, evaluations and events, the columns and records to 1e-12
(the impulse and the kinetic energies are the same sums in another order) -- and to closed
forms: a mass dropped onto a floor (bounce times ``t1 (1 + 2 sum e^j)``, the speed after ``-e``
times before, ``1 - e^2`` of the kinetic energy lost), its Zeno accumulation (settled at rest,
not a hang) and chattering (settled by the ``CHATTER`` rule through the Python action)."""
import numpy as np
import pytest

import mbcomp
from conftest import stop_pendulum
from mbcomp.codegen import c_compiler
from mbcomp.errors import ModelError
from mbcomp.hybrid import steppers
from mbcomp.hybrid.events import CHATTER
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, RigidBody, World

pytestmark = pytest.mark.skipif(not c_compiler(), reason="no C compiler")

G = 9.81


def drop(e=0.5, h=1.0, mass=2.0, hi=5.0):
    """A mass on a vertical slider dropped from ``h`` onto a stop at s = 0 (gravity -z)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, -G)))
    s = m.add("s", Prismatic(n=(0, 0, 1), s0=h, v0=0.0, limits=(0.0, hi), restitution=e))
    b = m.add("b", PointMass(m=mass))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return m


def chain(e=0.7):
    """Three links in a vertical plane (1 kg at 0.5 m each), a stop at +-0.3 rad on the middle
    hinge: its impacts change every speed (M full)."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -G, 0)))
    prev = w.frame_b
    for i, (phi0, w0) in enumerate([(0.6, 0.0), (0.0, -4.0), (-0.4, 3.0)]):
        lim = dict(limits=(-0.3, 0.3), restitution=e) if i == 1 else {}
        j = m.add(f"j{i + 1}", Revolute(phi0=phi0, w0=w0, **lim))
        rod = m.add(f"rod{i + 1}", FixedTranslation(r=(0, -0.5, 0)))
        bob = m.add(f"bob{i + 1}", PointMass(m=1.0))
        m.connect(prev, j.frame_a)
        m.connect(j.frame_b, rod.frame_a)
        m.connect(rod.frame_b, bob.frame_a)
        prev = rod.frame_b
    return m


def rotor(e=0.8):
    """A rotor (J = 2) between stops at +-0.5 rad from 0 at 1 rad/s: both stops, two events."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    j = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=1.0, limits=(-0.5, 0.5), restitution=e))
    b = m.add("disk", RigidBody(m=1.0, I=np.diag([1.0, 1.0, 2.0])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def both(monkeypatch, build, **kw):
    """The run with the impacts acted on in C, and with every action in Python."""
    monkeypatch.setattr(steppers, "C_IMPACTS", True)
    c = mbcomp.simulate(build(), **kw)
    monkeypatch.setattr(steppers, "C_IMPACTS", False)
    py = mbcomp.simulate(build(), **kw)
    return c, py


def assert_same_run(c, py, tol=1e-7):
    """The same outcome and events (kinds; times within 1e-9 s, details within ``tol``
    relative) and the columns within ``tol`` of their scale: the runs' steps are the same up
    to the last bits of the speeds after each impact (M^-1 c^T by the runtime's Cholesky
    against LAPACK's), which may move a later step, so they agree to the tolerances (rtol
    1e-10 here), not to rounding. The impact map itself is compared to 1e-12 below."""
    assert (c.status, c.message) == (py.status, py.message)
    assert [(x.component, x.name, x.kind) for x in c.events] == [(x.component, x.name, x.kind) for x in py.events]
    for a, b in zip(c.events, py.events):
        assert abs(a.time - b.time) <= 1e-9 * max(1.0, abs(b.time))
        assert a.detail.keys() == b.detail.keys()
        for k, v in b.detail.items():
            if isinstance(v, float):
                assert abs(a.detail[k] - v) <= tol * max(1.0, abs(v)), (k, a.detail[k], v)
            else:
                assert a.detail[k] == v
    np.testing.assert_array_equal(c.time, py.time)
    for name in py.names:
        x, y = np.asarray(c[name], float), np.asarray(py[name], float)
        scale = max(1.0, float(np.max(np.abs(y), initial=0.0)))
        assert np.max(np.abs(x - y), initial=0.0) <= tol * scale, name


@pytest.mark.parametrize("method", ["dop853", "dopri5", "auto"])
@pytest.mark.parametrize("case", ["pendulum", "rotor", "drop", "chain"])
def test_c_actions_agree_with_the_python_actions(monkeypatch, case, method):
    build, t_end = {"pendulum": (stop_pendulum, 5.0), "rotor": (rotor, 6.0), "drop": (lambda: drop(e=0.8), 2.5),
                    "chain": (chain, 3.0)}[case]
    c, py = both(monkeypatch, build, t_end=t_end, method=method, rtol=1e-10, atol=1e-12, n_out=201)
    assert len([x for x in py.events if x.kind == "impact"]) >= 3
    assert c.stats["stretches"] < py.stats["stretches"]  # the rebounds were acted on inside C calls
    assert abs(c.stats["steps"] - py.stats["steps"]) <= 0.05 * py.stats["steps"]
    assert_same_run(c, py)


def test_the_impact_map_is_the_python_impulse():
    """Each impact the C loop acts on (a 3-link chain, a stop on its middle joint: M full)
    gives the speeds after and the energy lost of the Python impulse solve
    (:func:`mbcomp.hybrid.stops.impact_speeds`) at the same state, to 1e-12."""
    from mbcomp.codegen import compile_system
    from mbcomp.codegen.c_events import LinearEvents, LinearImpacts
    from mbcomp.hybrid.active import mode_rows
    from mbcomp.hybrid.stops import impact_speeds

    system = compile_system(mbcomp.assemble(chain()), "c")
    eng, mech = system.evaluator.integrator(0.0, 0.0), system.evaluator.dae_program(1).mech
    q0, u0 = np.array([0.6, 0.0, -0.4]), np.array([0.0, -4.0, 3.0])  # the chain's start
    watch = LinearEvents(eng, index=[1, 1], sign=[1.0, -1.0], at=[-0.3, 0.3], direction=[-1, -1], tol=1e-13)
    imp = LinearImpacts(eng, mech, iu=[1, 1], sign=[1.0, -1.0], e=[0.7, 0.7], comp=[0, 0])
    t_out = np.linspace(0.05, 3.0, 60)
    out = imp.integrate(watch, 8, 0.0, np.concatenate((q0, u0)), t_out, 1e-10, 1e-12, chunk=16, tol_scale=1e-13,
                        max_stretches=10)
    assert len(out.impacts) >= 3
    for t, k, before, after, loss in out.impacts:
        rows = mode_rows(system, {"j2": "lo" if k == 0 else "hi"})
        u_plus, _, lost = impact_speeds(system, t, before[:3], before[3:], rows, 0.7)
        np.testing.assert_array_equal(after[:3], before[:3])
        np.testing.assert_allclose(after[3:], u_plus, rtol=0, atol=1e-12 * np.abs(u_plus).max())
        assert abs(loss - lost) <= 1e-12 * max(1.0, lost)
        speed = (1.0 if k == 0 else -1.0) * before[4]
        assert speed < 0 and (1.0 if k == 0 else -1.0) * after[4] == pytest.approx(-0.7 * speed, rel=1e-12)


def test_a_bouncing_mass_keeps_the_closed_form(monkeypatch):
    """Dropped from 1 m, e = 0.5: impacts at t1 (1 + 2 (e + ... + e^k)), t1 = sqrt(2 h / g);
    each rebound -e times the speed before; (1 - e^2) of the kinetic energy lost."""
    e, mass = 0.5, 2.0
    monkeypatch.setattr(steppers, "C_IMPACTS", True)
    r = mbcomp.simulate(drop(e=e, mass=mass), t_end=1.3, rtol=1e-11, atol=1e-13, n_out=131)
    assert r.status == "success"
    hits = [x for x in r.events if x.kind == "impact"]
    t1 = np.sqrt(2.0 / G)
    exact = t1 * (1.0 + 2.0 * np.cumsum([0.0] + [e ** (k + 1) for k in range(len(hits) - 1)]))
    assert len(hits) >= 5
    np.testing.assert_allclose([x.time for x in hits], exact, rtol=0, atol=1e-9)
    for x in hits:
        v = x.detail["speed_before"]
        assert x.detail["speed_after"] == pytest.approx(-e * v, rel=1e-12)
        assert x.detail["energy_loss"] == pytest.approx((1.0 - e * e) * 0.5 * mass * v * v, rel=1e-12)


def test_zeno_ends_at_rest_not_a_hang(monkeypatch):
    """Past the accumulation t1 (1 + e) / (1 - e) the mass rests on its stop (the rebound below
    the resting height is the Python action's: engaged at rest), as the Python actions do."""
    e, t1 = 0.5, np.sqrt(2.0 / G)
    c, py = both(monkeypatch, lambda: drop(e=e), t_end=2.0, rtol=1e-10, atol=1e-12, n_out=101)
    assert_same_run(c, py)
    assert c.status == "success" and c.events[-1].kind in ("rest", "engage")
    settled = c.events[-1].time
    assert settled < t1 * (1 + e) / (1 - e) and settled > t1 * (1 + e) / (1 - e) - 1e-3
    assert abs(c["s.s"][-1]) < 1e-9 and abs(c["s.v"][-1]) < 1e-9


def test_chattering_is_settled_by_the_python_rule(monkeypatch):
    """e = 0.9 and a resting height far below the rebounds: the impacts come ever closer; after
    CHATTER shrinking intervals the C loop hands the impact to the Python action, which settles
    the stop at rest (a "rest" record), exactly as without the C actions."""
    c, py = both(monkeypatch, lambda: drop(e=0.9), t_end=20.0, rtol=1e-12, atol=1e-16, n_out=21)
    assert_same_run(c, py)
    kinds = [x.kind for x in c.events]
    assert kinds.count("impact") == CHATTER + 2 and kinds[-1] == "rest"


def test_a_full_log_hands_the_next_impact_to_python(monkeypatch):
    """Two impacts logged per C call at most: the third is acted on in Python, the C loop goes
    on after it; the run is the same."""
    monkeypatch.setattr(steppers, "IMPACT_LOG", 2)
    c, py = both(monkeypatch, lambda: drop(e=0.8), t_end=3.5, rtol=1e-10, atol=1e-12, n_out=11)
    assert len(c.events) >= 6
    assert_same_run(c, py)


def test_restitution_outside_the_unit_interval_is_refused():
    with pytest.raises(ModelError, match="restitution"):
        mbcomp.simulate(drop(e=1.2), t_end=1.0)


def test_the_c_loop_refuses_a_bad_description():
    """The C loop's own check: a restitution outside [0, 1], or events not matching."""
    from mbcomp.codegen.c_events import LinearImpacts

    with pytest.raises(ValueError, match=r"must lie in \[0, 1\]"):
        LinearImpacts(_FakeEngine(), None, [0], [1.0], [1.5], [0])
    with pytest.raises(ValueError, match="one entry per watched event"):
        LinearImpacts(_FakeEngine(), None, [0, 0], [1.0], [0.5], [0])


class _FakeEngine:
    """An engine whose library is never reached: the description is refused before."""
    n = 2

    class bound:  # noqa: N801 - the attribute path LinearImpacts reads
        class code:  # noqa: N801
            dll = None
