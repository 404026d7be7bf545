"""The door (models/door.py) on its rigid stops with radau5 on the index-3 DAE form.

Every impact restarts the run with a new Radau5 stepper at the stop, ``phi = 0`` up to
round-off. Radau5 used to size its first step by ``0.01 ||q|| / ||dq/dt||`` on the positions
alone (the index-1 rows of the index-3 form), which at a located root is round-off over a
speed, 1e-17 s, and the run failed at the impact ("step size collapsed") at rtol <= 1e-8.
These tests run the door through several impacts and check it against the closed form of
``door.reference`` (impact times, the state at the end) and Newton's restitution law (each
impact keeps ``e^2`` of the kinetic energy).
"""
import numpy as np
import pytest

import mbcomp

DOOR = mbcomp.load_model_file("models/door.py")
E = 0.6            # the door's restitution (models/door.py default)
T_END = 8.0        # s
#: rtol -> the bound on |t_impact - exact| (s)
TIME_TOL = {1e-8: 1e-7, 1e-10: 1e-8}
#: the door pushed shut at 3 rad/s: four impacts in 8 s undamped, three with the damper
CASES = {"undamped": dict(w0=-3.0), "damped": dict(w0=-3.0, damping=1.0)}


def run(params, rtol):
    """The door on radau5, index 3, 8 s, with kinetic energy on a fine output grid."""
    return mbcomp.simulate(DOOR.build(**params), t_end=T_END, method="radau5", index=3, rtol=rtol,
                           atol=rtol * 1e-2, n_out=801)


@pytest.mark.parametrize("rtol", sorted(TIME_TOL))
@pytest.mark.parametrize("case", sorted(CASES))
def test_impact_times_and_end_state_match_the_closed_form(case, rtol):
    """Runs through every impact to ``t_end``; the impact times (the first one included) agree
    with ``door.reference`` to ``TIME_TOL[rtol]`` and the end state ``(phi, w)`` to the angle
    the largest speed (3 rad/s) sweeps in that time."""
    params = CASES[case]
    r = run(params, rtol)
    ref = DOOR.reference(t_end=T_END, **params)
    assert r.status == "success", r.message
    impacts = [x for x in r.events if x.kind == "impact"]
    exact = np.array(ref["impacts"])
    assert len(impacts) == len(exact) >= 3
    assert all(x.component == "hinge" for x in impacts)
    times = np.array([x.time for x in impacts])
    assert abs(times[0] - exact[0]) < TIME_TOL[rtol]
    assert np.max(np.abs(times - exact)) < TIME_TOL[rtol]
    for name, value in ref["values"].items():
        assert abs(r[name][-1] - value) < 3.0 * TIME_TOL[rtol], name


@pytest.mark.parametrize("rtol", sorted(TIME_TOL))
def test_kinetic_energy_after_k_impacts_is_e_to_the_2k(rtol):
    """Undamped (no torque about the vertical hinge), the kinetic energy between the k-th and
    the (k+1)-th impact is ``e^(2k)`` of the start (relative 1e-6), at every output point."""
    r = run(CASES["undamped"], rtol)
    assert r.status == "success", r.message
    times = np.array([x.time for x in r.events if x.kind == "impact"])
    T = r["energy.kinetic"]
    k = np.searchsorted(times, r.time, side="left")   # impacts strictly before each output time
    clear = np.min(np.abs(r.time[:, None] - times[None, :]), axis=1) > 1e-6   # not at an impact instant
    assert len(times) == 4 and np.all(clear[1:])
    np.testing.assert_allclose(T[clear], T[0] * E ** (2 * k[clear]), rtol=1e-6, atol=0)


@pytest.mark.parametrize("rtol", sorted(TIME_TOL))
def test_each_damped_impact_keeps_e_squared_of_the_kinetic_energy(rtol):
    """With the damper the swing loses energy between impacts too; each impact itself
    reverses the hinge speed with ratio ``-e`` and so keeps ``e^2`` of the kinetic energy
    (relative 1e-6), its loss ``(1 - e^2) J w^2 / 2`` with ``J = m width^2 / 3``."""
    r = run(CASES["damped"], rtol)
    assert r.status == "success", r.message
    J = 20.0 * 0.9 ** 2 / 3.0   # kg m^2 about the hinge (models/door.py defaults)
    impacts = [x for x in r.events if x.kind == "impact"]
    assert len(impacts) == 3
    for x in impacts:
        before, after = x.detail["speed_before"], x.detail["speed_after"]
        assert abs((after / before) ** 2 - E ** 2) < 1e-6 * E ** 2
        loss = 0.5 * J * before ** 2 * (1.0 - E ** 2)
        assert abs(x.detail["energy_loss"] - loss) < 1e-6 * loss
