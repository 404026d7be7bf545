"""Fuzzing in the suite: random mechanisms on the compiled default path, every run judged by
the oracle (``fuzz_oracle.py``): success with its invariants held (energy or energy
balance, loop residual, every column finite), or a failed/budget status or a model error
naming a component -- never another exception, a NaN, a hang or a wrong answer.

The budget is fixed (derandomized hypothesis, no example database): four functions of
:data:`N` examples each, so ``pytest -n 2`` spreads them; about 160 mechanisms in all (the
suite's time budget: the FMU tests, then the robot importers and the documentation's gallery
grew; each mechanism is a program compiled afresh, ~0.14 s).
``bench/fuzz.py`` runs thousands with the same generator and oracle.
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings

import mbcomp
from mbcomp.errors import ModelError, SimulationError

from fuzz_mechanisms import build, mechanisms
from fuzz_oracle import RTOL, run

N = 40
FUZZ = settings(max_examples=N, deadline=None, derandomize=True, database=None,
                phases=[Phase.explicit, Phase.generate, Phase.shrink],
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much])


def judge(spec):
    """The oracle on one spec (nothing left out: the reproducers below are of bugs it found,
    fixed)."""
    run(spec)


@FUZZ
@given(mechanisms(max_bodies=8, nasty=False, loops=0.0))
def test_fuzz_trees(spec):
    judge(spec)


@FUZZ
@given(mechanisms(max_bodies=8, nasty=True, loops=0.0))
def test_fuzz_nasty_trees(spec):
    judge(spec)


@FUZZ
@given(mechanisms(max_bodies=5, nasty=False, loops=1.0))
def test_fuzz_loops(spec):
    judge(spec)


@FUZZ
@given(mechanisms(max_bodies=4, nasty=True, loops=0.3))
def test_fuzz_small_nasty(spec):
    judge(spec)


# --- the generator itself -----------------------------------------------------------------
def _body(joint, start, **kw):
    b = dict(parent=-1, offset=None, rot=None, joint=joint, axis=(0.0, 0.0, 1.0), start=start,
             body="RigidBody", m=1.0, arm=None, r_cm=(0.2, 0.0, 0.0), I=((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1)))
    b.update(kw)
    return b


def _four_bodies(misfit, joint="Spherical"):
    """Two spherical pendulums on offsets, their tips joined by a closing joint ``loop``."""
    bodies = [_body("Spherical", {}, offset=(0.3, 0.0, 0.0)),
              _body("Revolute", {"phi0": 0.4}, parent=0, offset=(0.0, -0.5, 0.1), axis=(0.0, 0.0, 3.0)),
              _body("Cylindrical", {"phi0": -0.2, "s0": 0.1}, offset=(-0.3, 0.0, 0.0), axis=(1.0, 1.0, 0.0),
                    rot=(0.9, 0.1, 0.3, 0.0)),
              _body("Revolute", {"phi0": 0.7}, parent=2, offset=(0.0, -0.5, 0.0), axis=(1.0, 0.0, 0.0))]
    bodies[2]["rot"] = tuple(np.array(bodies[2]["rot"]) / np.linalg.norm(bodies[2]["rot"]))
    return {"g": (0.0, -9.81, 0.0), "bodies": bodies, "lines": [], "flanges": [],
            "loop": dict(a=1, b=3, joint=joint, d_a=(0.0, -0.2, 0.0), axis=(0.0, 1.0, 1.0), misfit=misfit,
                         guess=False)}


@pytest.mark.parametrize("joint", ["Spherical", "Revolute"])
def test_loop_closure_is_built_closed(joint):
    """The generator's loop closes at the start: the constraint residual at the tree's start
    values vanishes (the closing frames coincide), and moving frame b by 0.3 m opens it by
    0.3 m."""
    for misfit, expected in ((0.0, 0.0), (0.3, 0.3)):
        system = mbcomp.assemble(build(_four_bodies(misfit, joint)))
        ev = system.evaluate(0.0, system.default_q(), np.zeros(system.nu))
        assert np.linalg.norm(ev.Phi[:3]) == pytest.approx(expected, abs=1e-12)


def test_loop_that_cannot_close_is_named():
    """A loop 5 m beyond the links' reach: initialization fails naming the loop."""
    spec = _four_bodies(5.0)
    spec["loop"]["guess"] = True
    spec["bodies"][2]["start"] = {}  # free to move, and still cannot reach
    out = run(spec)
    assert out.kind == "InitializationError" and "loop" in out.message


def test_conservative_loop_keeps_its_energy():
    """A closed spatial loop with no damper: success, energy within the oracle's bar (checked
    inside :func:`run`), at the suite's tolerance."""
    out = run(_four_bodies(0.0))
    assert out.kind == "success", out.message


# --- reproducers of what the fuzz found ----------------------------------------------------
WELDED = {"g": (0.0, -9.81, 0.0), "bodies": [_body("Weld", {})], "lines": [], "flanges": [], "loop": None}


def test_zero_dof_mechanism_ends_named_or_at_rest():
    """A body welded to the world (no degree of freedom at all): either a result at rest or an
    error naming the body (found by the fuzz as 'the integrator dop853 failed at t=0: the
    number of equations n=0 must be positive', naming nothing; fixed in the driver)."""
    try:
        res = mbcomp.simulate(build(WELDED), t_end=0.2, n_out=5, rtol=RTOL)
    except (ModelError, SimulationError) as exc:
        assert "b0" in str(exc) or "j0" in str(exc)
        return
    assert res.status == "success", res.message
    assert res.time[-1] == pytest.approx(0.2) and np.all(res["b0.r.y"] == 0.0)


def _hinge_at_offset(n=(0.0, 0.0, 1.0), offset=(-0.93, 0.0, 0.0)):
    """A 6 kg point mass right on the axis of a hinge placed at ``offset`` (m) from the world
    origin: the hinge's rotation carries no inertia."""
    from mbcomp.library import FixedTranslation, PointMass, Revolute, World

    m = mbcomp.Model()
    w = m.add("world", World(g=(0, 0, 0)))
    o = m.add("off", FixedTranslation(r=offset))
    j = m.add("hinge", Revolute(n=n, phi0=0.3, w0=0.0))
    b = m.add("bob", PointMass(m=6.0))
    m.connect(w.frame_b, o.frame_a)
    m.connect(o.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


def test_point_mass_on_a_hinge_axis_is_massless():
    """At the origin the massless rotation is diagnosed at initialization, naming the hinge."""
    with pytest.raises(mbcomp.errors.InitializationError, match=r"hinge\.w: this rotation carries no"):
        mbcomp.simulate(_hinge_at_offset(offset=(0.0, 0.0, 0.0)), t_end=0.2, n_out=5)


def test_point_mass_on_an_offset_hinge_axis_is_massless():
    """Found by the fuzz: the same hinge 0.93 m from the origin must be diagnosed the same way
    (its mass matrix is 6 kg x (1e-16 m)^2 of rounding, once compared only with itself; now with
    the size of what moves, ``conditioning.moving_scale``)."""
    with pytest.raises(mbcomp.errors.InitializationError, match=r"hinge\.w: this rotation carries no"):
        mbcomp.simulate(_hinge_at_offset(), t_end=0.2, n_out=5)


SELF_LOOP = {"g": (0.0, 0.0, 0.0), "lines": [], "flanges": [], "bodies": [  # the fuzz's numbers, unrounded
    dict(parent=-1, offset=(0.0, -0.035354409589613923, -0.206108681932714), rot=None, joint="Cylindrical",
         axis=(-0.8456919301613565, 0.48437392631796844, -0.22402468337947662),
         start={"phi0": 1.5e-05, "w0": 0.0, "s0": 0.18740880668043758, "v0": -0.8903777018015906},
         body="PointMass", m=1.0743322256517325, arm=(-0.0333589828355658, 0.1753043874920975, 0.0), r_cm=None,
         I=None),
    dict(parent=0, offset=None, rot=None, joint="Weld", axis=(0.0, 0.0, -1.0), start={}, body="RigidBody",
         m=1.168235723325101, arm=None, r_cm=(0.0, -0.3402034502914762, 0.3087084570109221),
         I=((0.48905681093114794, 0.19686490490609315, 0.0), (0.19686490490609315, 0.27703353337975267, 0.0),
            (0.0, 0.0, 0.502754963080446)))],
    "loop": dict(a=1, b=0, joint="Spherical", d_a=(-0.2583086657651936, 0.031420591271383254, 0.26610560772264447),
                 axis=(0.0, -5.251640879385708, 4.784698386928255), misfit=0.3, guess=True)}


def test_loop_within_one_body_is_named_on_every_backend():
    """Found by the fuzz: a spherical joint closing a loop between two points of one rigid
    body (b1 is welded to b0), 0.3 m apart. Its constraint Jacobian is rounding (1e-17): the
    closure used to step 1e16 m along it and report the loop closed, and the program check
    then met a dependent, inconsistent row set. Now every backend says the loop cannot close."""
    for backend in ("numeric", "auto"):
        with pytest.raises(mbcomp.errors.InitializationError, match=r"loop: the kinematic loop cannot be assembled"):
            mbcomp.simulate(build(SELF_LOOP), t_end=0.3, n_out=31, rtol=RTOL, backend=backend)
    out = run(SELF_LOOP)
    assert out.kind == "InitializationError" and "loop" in out.message


#: found by the fuzz (hypothesis shrinking, issue 30): a 4.9 MN/m spring of zero rest length
#: between two bodies a spherical joint also closes, so 5.6 MN hold the loop
STIFF_LOOP = {'bodies': [{'I': None,
                          'arm': None,
                          'axis': (0.8122809264351181, -1.5285019187055773e-281, -0.583266402726667),
                          'body': 'PointMass',
                          'joint': 'Cylindrical',
                          'm': 0.0,
                          'offset': None,
                          'parent': -1,
                          'r_cm': None,
                          'rot': None,
                          'start': {'phi0': 0.07704710900476619,
                                    's0': 0.3,
                                    'v0': 0.1044386266917734,
                                    'w0': -1.553585245261581e-148}},
                         {'I': None,
                          'arm': (-0.02719926024518633, 0.016897548380749253, 0.09473475128396583),
                          'axis': (0.6998282764374227, 0.0, -0.7143111251398975),
                          'body': 'PointMass',
                          'joint': 'Cylindrical',
                          'm': 4.028556205003355,
                          'offset': (-0.28841568990215255, 0.1475323284207552, -0.3610500951856358),
                          'parent': 0,
                          'r_cm': None,
                          'rot': (0.8881125971586288, 0.027017725207306102, 0.456969803971664, -0.041287474503494605),
                          'start': {'phi0': -3.155269493105675e-84,
                                    's0': 1.2654092155992661e-12,
                                    'v0': -0.564627489739787,
                                    'w0': -2.3918015461738333}},
                         {'I': None,
                          'arm': (0.0, -0.679835296405923, 0.0),
                          'axis': (0.0, -1.0, 0.0),
                          'body': 'PointMass',
                          'joint': 'Prismatic',
                          'm': 0.0055956935935320695,
                          'offset': (-0.24706007904224214, 0.0, 0.0),
                          'parent': 0,
                          'r_cm': None,
                          'rot': None,
                          'start': {'s0': 0.0, 'v0': 0.0}}],
              'flanges': [],
              'g': (0.0, 0.0, 0.0),
              'lines': [{'a': 1, 'b': 0, 'c': 4900811.53425327, 'd': 0.0, 'kind': 'Spring', 's0': 0.0},
                        {'a': 1,
                         'b': 0,
                         'c': 4900811.53425327,
                         'd': 5.669863036092667e-172,
                         'kind': 'SpringDamper',
                         's0': 0.0}],
              'loop': {'a': 1,
                       'axis': (0.0, 1.0, 0.0),
                       'b': 0,
                       'd_a': (-0.15, 0.0, 0.0),
                       'guess': True,
                       'joint': 'Spherical',
                       'misfit': 0.0}}


def test_a_stiff_spring_held_by_a_loop_is_right_on_every_backend():
    """The program check compared the generated accelerations with the dense solve's to 1e-8
    of the result, while both carry rounding of the 5.6 MN forces they cancel: it reported an
    'internal error' on a right program. Now both backends run, agree with each other, and
    stay within the oracle's tolerances of a run 1000 times tighter."""
    runs = [mbcomp.simulate(build(STIFF_LOOP), t_end=0.3, n_out=31, rtol=RTOL, backend=b) for b in ("numeric", "auto")]
    for r in runs:
        assert r.status in ("success", "inaccurate"), r.message
    for name in runs[0].names:
        if name.endswith((".phi", ".s")):
            assert np.allclose(runs[0][name], runs[1][name], rtol=1e-5, atol=1e-7), name
    assert run(STIFF_LOOP).kind in ("success", "inaccurate")
