"""Four-bar linkage passing near its flat (change-point) position (models/four_bar.py).

The geometry ``l1 + l2 = l3 + l4`` with the ground shortened by ``gap``: for ``gap > 0`` a
Grashof crank-rocker whose closest approach to the flat position is exactly ``gap`` (at crank
angle pi, where the rocker reverses ever more abruptly as the gap closes); ``gap = 0`` passes
through the singular position itself.

Independent reference: one degree of freedom and no damping, so the energy integral
``J(phi) phi'^2 / 2 + V(phi) = E`` *is* the equation of motion while the crank turns one way;
``t(phi) = integral sqrt(J / (2 (E - V))) dphi`` with ``J``, ``V`` from the closed-form loop
closure below (complex-step derivatives, no mbcomp code) gives the time at which the crank
reaches each angle mbcomp reports.

The runs use the generated Python program (``backend="python"``), about 8x faster than the
numeric evaluation here; the numeric path gives the same results (checked while writing
these tests, including the failures documented at the end).
"""
import numpy as np
import pytest
from scipy.integrate import quad

import mbcomp
from conftest import load_model

fb = load_model("models/four_bar.py")
TIGHT = dict(rtol=1e-10, atol=1e-12, method="DOP853", backend="python")
PHI0, W0 = np.pi / 2, 8.0  # build() defaults
STATUSES = ("success", "failed")


def run(gap, formulation="lagrange", t_end=0.5, n_out=51, build=None, **kw):
    opts = {**TIGHT, **kw}
    if formulation == "lagrange":
        opts.setdefault("stabilization", "projection")
    model = fb.build(gap=gap, **(build or {}))
    return mbcomp.simulate(model, t_end=t_end, n_out=n_out, formulation=formulation, **opts)


# --- closed-form reference -----------------------------------------------------------------
def points(phi, L):
    """Crank tip B and coupler-rocker pin C (assembly mode +1) at crank angle phi."""
    L1, L2, L3, L4 = L
    B = L2 * np.array([np.cos(phi), np.sin(phi)])
    dx, dy = L1 - B[0], -B[1]
    d = np.sqrt(dx * dx + dy * dy)
    a = (L3 ** 2 - L4 ** 2 + d * d) / (2 * d)
    h = np.sqrt(L3 ** 2 - a * a)
    return B, B + (a * np.array([dx, dy]) + h * np.array([-dy, dx])) / d


def inertia_potential(phi, L, rho=1.0, g=9.81):
    """Generalized inertia J(phi) (kg m^2) and potential V(phi) (J) of the slender-rod linkage."""
    eps = 1e-30
    (B, C), (Bc, Cc) = points(phi, L), points(phi + 1j * eps, L)
    B, C, dB, dC = B.real, C.real, Bc.imag / eps, Cc.imag / eps
    L1, L2, L3, L4 = L
    D = np.array([L1, 0.0])

    def cross(u, v):
        return u[0] * v[1] - u[1] * v[0]

    m2, m3, m4 = rho * L2, rho * L3, rho * L4
    w3, w4 = cross(C - B, dC - dB) / L3 ** 2, cross(C - D, dC) / L4 ** 2
    J = (m2 * dB @ dB / 4 + m2 * L2 ** 2 / 12 + m3 * (dB + dC) @ (dB + dC) / 4 + m3 * L3 ** 2 / 12 * w3 ** 2
         + m4 * dC @ dC / 4 + m4 * L4 ** 2 / 12 * w4 ** 2)
    V = g * (m2 * B[1] / 2 + m3 * (B[1] + C[1]) / 2 + m4 * C[1] / 2)
    return J, V


def reference_times(phi, L):
    """Times (s) at which the exact motion reaches the (increasing) crank angles ``phi``."""
    J0, V0 = inertia_potential(PHI0, L)
    E = 0.5 * J0 * W0 ** 2 + V0

    def dt_dphi(p):
        J, V = inertia_potential(p, L)
        return np.sqrt(J / (2 * (E - V)))

    t = [0.0]
    for a, b in zip(phi[:-1], phi[1:]):
        flat = [k * np.pi for k in range(1, 9, 2) if a < k * np.pi < b]  # near-flat passages
        t.append(t[-1] + quad(dt_dphi, a, b, points=flat or None, epsabs=1e-13, epsrel=1e-12, limit=200)[0])
    return np.array(t)


def rocker_limit(gap):
    """Largest rocker angle (rad): crank and coupler folded, |AC| = l3 - l2 (defaults)."""
    L1, L2, L3, L4 = fb.lengths(gap)
    return np.pi - np.arccos((L1 ** 2 + L4 ** 2 - (L3 - L2) ** 2) / (2 * L1 * L4))


def assembly_mode(res, gap):
    """Sign of the triangle B-C-D's area along the run (+1: the mode the model was built in)."""
    L1, L2, L3, L4 = fb.lengths(gap)
    phi, th4 = res["crank_angle"], res["rocker_angle"]
    Bx, By = L2 * np.cos(phi), L2 * np.sin(phi)
    Cx, Cy = L1 + L4 * np.cos(th4), L4 * np.sin(th4)
    return np.sign((L1 - Bx) * (Cy - By) + By * (Cx - Bx))


def energy_drift(res):
    E = res["energy.total"]
    return float(np.max(np.abs(E - E[0]))) / max(1.0, float(np.max(res["energy.kinetic"])))


def check_physical(res, gap, t_tol):
    """The run passes the (near-)flat position the way the exact motion does."""
    assert res.success, res.message
    phi = res["crank_angle"]
    assert np.all(np.diff(phi) > 0), "the crank must keep turning forward"
    assert phi[-1] > np.pi + 0.5, "the crank must pass the near-flat position at pi"
    np.testing.assert_allclose(res.time, reference_times(phi, fb.lengths(gap)), rtol=0, atol=t_tol)
    assert np.all(assembly_mode(res, gap) > 0), "a linkage with gap > 0 cannot change its assembly mode"
    assert np.max(res["rocker_angle"]) <= rocker_limit(gap) + 1e-9  # the rocker reverses at its limit
    assert np.max(res["residual.position"]) < 1e-10
    assert energy_drift(res) < 1e-8


# --- a comfortable gap ---------------------------------------------------------------------
def test_lengths_and_gap_definition():
    L1, L2, L3, L4 = fb.lengths(1e-3)
    assert (L1, L2, L3) == (1.0 - 1e-3, 0.4, 0.8) and L4 == pytest.approx(0.6)
    assert L3 + L4 - (L1 + L2) == pytest.approx(1e-3)  # largest |BD| misses l3 + l4 by gap
    with pytest.raises(ValueError, match="gap"):
        fb.build(gap=-1e-3)
    with pytest.raises(ValueError, match="change-point"):
        fb.build(l4=0.5)


def test_comfortable_gap_both_formulations_agree_with_the_exact_motion():
    """gap = 1 cm: both reductions pass the near-flat position (twice in 0.5 s: crank angles
    pi and 2 pi), match the energy-integral reference to 1e-8 s and agree with each other."""
    gap = 1e-2
    a = run(gap)
    b = run(gap, "dalembert")
    c = run(gap, stabilization="baumgarte", rtol=1e-8, atol=1e-10, method="RK45")
    for res in (a, b):
        check_physical(res, gap, t_tol=1e-8)
    assert a["crank_angle"][-1] > 2 * np.pi
    for name in ("crank_angle", "rocker_angle", "coupler_joint.w", "pin.w"):
        np.testing.assert_allclose(b[name], a[name], rtol=0, atol=1e-7 * max(1.0, np.abs(a[name]).max()))
    assert b.stats["repartitions"] == 0 and b.stats["independent_speeds"] == ["crank_joint.w"]
    # Baumgarte at moderate tolerances: same motion, loop closed to ~1e-8, energy to ~1e-7
    assert c.success, c.message
    np.testing.assert_allclose(c["crank_angle"], a["crank_angle"], atol=1e-6)
    assert np.max(c["residual.position"]) < 1e-7 and energy_drift(c) < 1e-6


# --- close to the flat position ------------------------------------------------------------
@pytest.mark.parametrize("gap", [1e-4, 1e-8])
def test_near_flat_passage_is_physical_in_both_formulations(gap):
    """A hair's breadth from the flat position (gap 0.1 mm and 10 nm) the projection and
    D'Alembert forms still follow the exact motion: the crank passes, the assembly mode is
    kept and the rocker reverses at its limit angle, energy is conserved. D'Alembert keeps the
    crank as its independent speed throughout: through a change point the crank still
    determines the others (their ratios stay bounded), so no re-partition is needed."""
    a = run(gap, t_end=0.3, n_out=31)
    b = run(gap, "dalembert", t_end=0.3, n_out=31)
    for res in (a, b):
        check_physical(res, gap, t_tol=1e-7)
        th4 = res["rocker_angle"]
        assert th4[-1] < th4.max() - 0.1  # the rocker came back
    assert b.stats["repartitions"] == 0 and b.stats["independent_speeds"] == ["crank_joint.w"]
    np.testing.assert_allclose(b["rocker_angle"], a["rocker_angle"], atol=1e-6)


def test_dalembert_rechooses_a_speed_that_stops_at_the_flat_position():
    """Started with the pin speed (rocker relative to coupler) as the independent one, the
    D'Alembert form must re-choose at the near-flat passage, where that speed goes through
    zero while the crank turns fast; it re-chooses the crank and still matches the Lagrange
    form and conserves energy."""
    gap = 1e-4
    a = run(gap, t_end=0.25, n_out=251)
    p = a["pin.w"]
    k = np.flatnonzero(np.sign(p[1:]) != np.sign(p[:-1]))
    assert k.size == 1 and 0.15 < a.time[k[0]] and abs(a["crank_angle"][k[0]] - np.pi) < 0.05
    before = run(gap, "dalembert", t_end=0.15, n_out=16, independent=["pin.w"])
    assert before.success and before.stats["repartitions"] == 0 and before.stats["independent_speeds"] == ["pin.w"]
    b = run(gap, "dalembert", t_end=0.25, n_out=251, independent=["pin.w"])
    assert b.success, b.message
    assert b.stats["repartitions"] >= 1 and b.stats["independent_speeds"] == ["crank_joint.w"]
    np.testing.assert_allclose(b["crank_angle"], a["crank_angle"], atol=1e-7)
    np.testing.assert_allclose(b["rocker_angle"], a["rocker_angle"], atol=1e-7)
    assert energy_drift(b) < 1e-8 and np.max(b["residual.position"]) < 1e-10


# --- exactly singular ----------------------------------------------------------------------
SWEEP = dict(rtol=1e-8, atol=1e-10, backend="python")  # the tolerances of SIMULATION


@pytest.mark.parametrize("formulation,method,stab", [
    ("lagrange", "RK45", "projection"), ("lagrange", "DOP853", "projection"), ("lagrange", "Radau", "baumgarte"),
    ("dalembert", "DOP853", None)])
def test_passing_exactly_through_the_flat_position_is_reported(formulation, method, stab):
    """gap = 0: at the flat position the motion is not unique (the crank may pass on or
    bounce back; before the singularity monitor, RK45 passed and DOP853 bounced, both
    reporting success). Every formulation must stop there and say why, keeping the results
    up to it (which are right: loop closed, energy kept)."""
    kw = dict(SWEEP, method=method) if stab is None else dict(SWEEP, method=method, stabilization=stab)
    res = run(0.0, formulation, **kw)
    assert res.status == "failed"
    assert "singular position" in res.message and "not unique" in res.message, res.message
    t_stop = float(res.message.split("t=")[1].split(":")[0])
    assert 0.1 < t_stop < 0.25 and res.time[-1] <= t_stop  # the crank reaches pi at ~0.18 s
    assert np.all(np.isfinite(res["crank_angle"])) and res["crank_angle"][-1] < np.pi
    assert np.max(res["residual.position"]) < 1e-7
    assert energy_drift(res) < 1e-5


def test_a_gap_of_1e_12_is_reported_as_singular_not_reversed():
    """gap = 1e-12: Lagrange/Baumgarte/Radau used to reverse the crank here and report success
    (energy error 5e-4 J the only hint); 1e-12 m from flat is a singular position to double
    precision, and it is reported as one."""
    res = run(1e-12, method="Radau", stabilization="baumgarte", **SWEEP)
    assert res.status == "failed" and "singular position" in res.message, res.message


def test_near_flat_run_reports_how_close_it_came():
    """``stats['min_constraint_sigma']`` is the closest relative approach to a singular
    position; for this linkage it scales like sqrt(gap)."""
    s4, s8 = (run(g, method="DOP853", **SWEEP).stats["min_constraint_sigma"] for g in (1e-4, 1e-8))
    assert 50 < s4 / s8 < 200  # sqrt(1e4) = 100


def test_starting_in_the_flat_position_is_reported():
    """Started exactly flat, the closure row along the links is dependent there only; the
    initialization drops it as redundant, and the run must report the singular start as soon
    as that row opens, instead of returning a 2-DOF motion with an open loop."""
    res = run(0.0, t_end=0.2, n_out=21, build=dict(phi0=np.pi), **SWEEP)
    assert res.status == "failed"
    assert "start position is singular" in res.message and "rocker_joint.x" in res.message, res.message
    assert np.max(res["residual.position"]) < 1e-5
