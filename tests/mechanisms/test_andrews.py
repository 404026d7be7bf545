"""Andrews' squeezing mechanism (models/andrews.py) against the published problem.

Reference: Hairer & Wanner, Solving ODEs II, sec. VII.7, and the IVP test set problem
``andrews`` (shared/reference/andrews.md; the numbers in models/data/andrews.json). The model is composed from
library components; its tree coordinates are the published angles, so the assembled mass
matrix, forces and constraints can be compared entry by entry with the published formulas
(implemented independently below), and the trajectory with the published reference solution.
"""
import json
import pathlib

import numpy as np
import pytest

import mbcomp
from mbcomp.formulations import LagrangeIndex1
from mbcomp.initialization import initialize

from conftest import load_model

AND = load_model("models/andrews.py")
# a copy of shared/reference/andrews.json (published data), so a clean checkout has it
REF = json.loads((pathlib.Path(__file__).resolve().parents[2] / "models" / "data" / "andrews.json").read_text())
P = REF["parameters"]
NAMES = REF["coordinates"]  # published order: beta, Theta, gamma, Phi, delta, Omega, epsilon
JOINT = dict(beta="hinge_O", Theta="hinge_F", gamma="hinge_B", Phi="hinge_G", delta="hinge_A_AG",
             Omega="hinge_H", epsilon="hinge_A_AH")
Q0 = np.array([float(REF["initial_values_as_printed"][n]) for n in NAMES])
W0 = np.array([float(REF["initial_values_as_printed"][f"w_{n} (=d2{n}/dt2)"]) for n in NAMES])
LAM0 = np.array([float(REF["initial_values_as_printed"][f"lambda_{i}"]) for i in range(1, 7)])
REF_T = REF["reference_t_0.03"]
Q1 = np.array([REF_T[n] for n in NAMES])
QD1 = np.array([REF_T[f"d{n}/dt"] for n in NAMES])
W1 = np.array([REF_T[f"w_{n} (=d2{n}/dt2)"] for n in NAMES])
LAM1 = np.array([REF_T[f"lambda_{i}"] for i in range(1, 7)])


def published(q, qd, p=P):
    """M(q), f(q, qdot), g(q), G(q) exactly as coded in the IVP test set (andrews.md)."""
    be, th, ga, ph, de, om, ep = q
    bed, thd, gad, phd, ded, omd, epd = qd
    m1, m2, m3, m4, m5, m6, m7 = (p[f"m{i}"] for i in range(1, 8))
    i1, i2, i3, i4, i5, i6, i7 = (p[f"i{i}"] for i in range(1, 8))
    (xa, ya, xb, yb, xc, yc, c0, d, da, e, ea, rr, ra, l0, ss, sa, sb, sc, sd, ta, tb, u, ua, ub, zf, zt, fa,
     mom) = (p[k] for k in ("xa", "ya", "xb", "yb", "xc", "yc", "c0", "d", "da", "e", "ea", "rr", "ra", "l0",
                            "ss", "sa", "sb", "sc", "sd", "ta", "tb", "u", "ua", "ub", "zf", "zt", "fa", "mom"))
    sin, cos = np.sin, np.cos
    M = np.zeros((7, 7))
    M[0, 0] = m1 * ra ** 2 + m2 * (rr ** 2 - 2 * da * rr * cos(th) + da ** 2) + i1 + i2
    M[1, 0] = M[0, 1] = m2 * (da ** 2 - da * rr * cos(th)) + i2
    M[1, 1] = m2 * da ** 2 + i2
    M[2, 2] = m3 * (sa ** 2 + sb ** 2) + i3
    M[3, 3] = m4 * (e - ea) ** 2 + i4
    M[4, 3] = M[3, 4] = m4 * ((e - ea) ** 2 + zt * (e - ea) * sin(ph)) + i4
    M[4, 4] = m4 * (zt ** 2 + 2 * zt * (e - ea) * sin(ph) + (e - ea) ** 2) + m5 * (ta ** 2 + tb ** 2) + i4 + i5
    M[5, 5] = m6 * (zf - fa) ** 2 + i6
    M[6, 5] = M[5, 6] = m6 * ((zf - fa) ** 2 - u * (zf - fa) * sin(om)) + i6
    M[6, 6] = m6 * ((zf - fa) ** 2 - 2 * u * (zf - fa) * sin(om) + u ** 2) + m7 * (ua ** 2 + ub ** 2) + i6 + i7
    xd = sd * cos(ga) + sc * sin(ga) + xb
    yd = sd * sin(ga) - sc * cos(ga) + yb
    lang = np.sqrt((xd - xc) ** 2 + (yd - yc) ** 2)
    force = -c0 * (lang - l0) / lang
    fx, fy = force * (xd - xc), force * (yd - yc)
    f = np.array([
        mom - m2 * da * rr * thd * (thd + 2 * bed) * sin(th),
        m2 * da * rr * bed ** 2 * sin(th),
        fx * (sc * cos(ga) - sd * sin(ga)) + fy * (sd * cos(ga) + sc * sin(ga)),
        m4 * zt * (e - ea) * ded ** 2 * cos(ph),
        -m4 * zt * (e - ea) * phd * (phd + 2 * ded) * cos(ph),
        -m6 * u * (zf - fa) * epd ** 2 * cos(om),
        m6 * u * (zf - fa) * omd * (omd + 2 * epd) * cos(om),
    ])
    ex, ey = rr * cos(be) - d * cos(be + th), rr * sin(be) - d * sin(be + th)  # point E via the rod
    g = np.array([
        ex - ss * sin(ga) - xb, ey + ss * cos(ga) - yb,
        ex - e * sin(ph + de) - zt * cos(de) - xa, ey + e * cos(ph + de) - zt * sin(de) - ya,
        ex - zf * cos(om + ep) - u * sin(ep) - xa, ey - zf * sin(om + ep) + u * cos(ep) - ya,
    ])
    G = np.zeros((6, 7))
    g11, g12 = -rr * sin(be) + d * sin(be + th), d * sin(be + th)
    g21, g22 = rr * cos(be) - d * cos(be + th), -d * cos(be + th)
    G[0, :3] = g11, g12, -ss * cos(ga)
    G[1, :3] = g21, g22, -ss * sin(ga)
    G[2, [0, 1, 3, 4]] = g11, g12, -e * cos(ph + de), -e * cos(ph + de) + zt * sin(de)
    G[3, [0, 1, 3, 4]] = g21, g22, -e * sin(ph + de), -e * sin(ph + de) - zt * cos(de)
    G[4, [0, 1, 5, 6]] = g11, g12, zf * sin(om + ep), zf * sin(om + ep) - u * cos(ep)
    G[5, [0, 1, 5, 6]] = g21, g22, -zf * cos(om + ep), -zf * cos(om + ep) - u * sin(ep)
    spring_V = 0.5 * c0 * (lang - l0) ** 2
    return M, f, g, G, spring_V


@pytest.fixture(scope="module")
def system():
    s = mbcomp.assemble(AND.build())
    init = initialize(s)
    return s, init


def _perm(s):
    """Model speed index of each published coordinate."""
    return [s.u_names.index(f"{JOINT[n]}.w") for n in NAMES]


def _to_model(s, x):
    out = np.empty(7)
    out[_perm(s)] = x
    return out


def test_structure_tree_coordinates_are_the_published_angles(system):
    s, init = system
    topo = s.topology
    assert sorted(topo.cut) == ["pin_E_EG", "pin_E_HE", "pin_E_triangle"]
    assert sorted(s.q_names) == sorted(f"{j}.phi" for j in JOINT.values())
    # 3 planar loops of 3-D revolutes: 15 rows, the 9 out-of-plane ones redundant; 7 - 6 = 1 DOF
    assert len(init.dropped) == 9 and all(r.endswith((".z", ".tilt_1", ".tilt_2")) for r in init.dropped)
    assert init.rank == 6
    # initialization kept the published start (no Newton step was needed)
    np.testing.assert_array_equal(init.q[_perm(s)], Q0)
    assert init.iterations == 0 and np.all(init.u == 0)


def test_initial_state_matches_published_equations(system):
    """Loop residual ~0; M, f, constraints, accelerations and constraint forces at the
    published start reproduce the published values."""
    s, init = system
    perm = _perm(s)
    q, u = init.q, init.u
    ev_all = s.evaluate(0.0, q, u, masked=False)
    assert np.abs(ev_all.Phi).max() < 1e-15  # m; the published values close the loops
    M, f, g, G, _ = published(Q0, np.zeros(7))
    assert np.abs(g).max() < 1e-15
    ev = s.evaluate(0.0, q, u)
    np.testing.assert_allclose(ev.M[np.ix_(perm, perm)], M, rtol=1e-12, atol=1e-12 * np.abs(M).max())
    np.testing.assert_allclose(ev.f[perm], f, rtol=1e-12, atol=1e-12 * np.abs(f).max())
    # the kept constraint rows are the published g rotated into the rod frame (rows x, y of each pin)
    names = s.constraint_names()
    assert sorted(names) == sorted(f"{p}.{ax}" for p in ("pin_E_triangle", "pin_E_EG", "pin_E_HE") for ax in "xy")
    ang = Q0[0] + Q0[1]  # rod frame orientation beta + Theta
    R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    for k, pin in enumerate(("pin_E_triangle", "pin_E_EG", "pin_E_HE")):
        rows = [names.index(f"{pin}.x"), names.index(f"{pin}.y")]
        # Phi = R_rod^T (E_other - E_rod) = -R_rod^T g  ->  R_rod C = -G (columns permuted)
        np.testing.assert_allclose(R @ ev.C[rows][:, perm], -G[2 * k:2 * k + 2], atol=1e-14)
    ud, lam = LagrangeIndex1(s).solve(ev, stabilize=False)
    scale = np.abs(W0).max()
    np.testing.assert_allclose(ud[perm], W0, rtol=1e-10, atol=1e-10 * scale)
    assert abs(ud[perm][0] - 14222.4439199541138) < 1e-8 * 14222.44
    assert abs(ud[perm][1] + 10666.8329399655854) < 1e-8 * 10666.83
    # constraint forces on the coordinates: model C^T lam equals published G^T lambda
    np.testing.assert_allclose((ev.C.T @ lam)[perm], G.T @ LAM0, rtol=1e-10,
                               atol=1e-10 * np.abs(G.T @ LAM0).max())


def test_mass_matrix_forces_and_accelerations_at_other_states(system):
    """At the reference state t = 0.03 (large rates: velocity-product terms matter) and at a
    random state, the model's M(q), f(q, u) are the published ones; at the reference state
    the accelerations and constraint forces match the published reference (which carries
    ~1e-7..1e-6 relative error)."""
    s, _ = system
    perm = _perm(s)
    rng = np.random.default_rng(7)
    for q_pub, qd_pub in ((Q1, QD1), (rng.uniform(-np.pi, np.pi, 7), rng.uniform(-500, 500, 7))):
        q, u = _to_model(s, q_pub), _to_model(s, qd_pub)
        ev = s.evaluate(0.0, q, u)
        M, f, g, G, _ = published(q_pub, qd_pub)
        np.testing.assert_allclose(ev.M[np.ix_(perm, perm)], M, rtol=1e-12, atol=1e-12 * np.abs(M).max())
        np.testing.assert_allclose(ev.f[perm], f, rtol=1e-11, atol=1e-11 * np.abs(f).max())
        # constraint values hold off the manifold too: |Phi| per pin = |g| per pair
        ev_all = s.evaluate(0.0, q, u, masked=False)
        phi = ev_all.Phi.reshape(3, 5)[:, :2]
        np.testing.assert_allclose(np.linalg.norm(phi, axis=1), np.linalg.norm(g.reshape(3, 2), axis=1),
                                   rtol=1e-12, atol=1e-17)
    q, u = _to_model(s, Q1), _to_model(s, QD1)
    ev = s.evaluate(0.03, q, u)
    ud, lam = LagrangeIndex1(s).solve(ev, stabilize=False)
    np.testing.assert_allclose(ud[perm], W1, rtol=0, atol=2e-6 * np.abs(W1).max())
    _, _, _, G, _ = published(Q1, QD1)
    np.testing.assert_allclose((ev.C.T @ lam)[perm], G.T @ LAM1, rtol=0, atol=2e-6 * np.abs(G.T @ LAM1).max())


# Tolerances: DOP853 at rtol=1e-9, atol=1e-11 gives relative position errors at t = 0.03 of
# ~3e-10 (Lagrange + projection) and ~2e-9 (D'Alembert), 50x below the 1e-7 asked; at
# rtol=1e-7 the Lagrange error is 1.4e-7, so 1e-8 is the loosest rtol that passes. Radau
# (scipy) passes too (1e-6/1e-8: 3e-8; 1e-8/1e-10: 6e-10) but needs 10-20x the evaluations
# of DOP853 here: its embedded error estimate is of low order, so at tight tolerances it
# takes ~10x the steps; it is left out to keep the test fast.
# The DAE pairs keep the multipliers as unknowns (index 3 under Radau IIA, index 2 = GGL under
# IDA) and run on the generated Python program (backend="python"), which gives the numeric
# path's numbers ~10x faster. IDA's BDF error at rtol 1e-8 is 1.3e-7, so it runs at 1e-10.
TOL = dict(rtol=1e-9, atol=1e-11, n_out=61)
PAIRS = {"lagrange-projection-DOP853": dict(formulation="lagrange", stabilization="projection", method="DOP853"),
         "dalembert-DOP853": dict(formulation="dalembert", method="DOP853"),
         "index3-radau5": dict(method="radau5", index=3, stabilization="none", backend="python"),
         "index2-GGL-IDA": dict(method="ida", index=2, stabilization="none", backend="python", rtol=1e-10,
                                atol=1e-12)}


@pytest.fixture(scope="module")
def runs():
    return {k: mbcomp.simulate(AND.build(), t_end=0.03, **{**TOL, **kw}) for k, kw in PAIRS.items()}


@pytest.mark.parametrize("pair", list(PAIRS))
def test_reference_solution_at_t_003(runs, pair):
    res = runs[pair]
    assert res.success and res.status == "success", res.message
    assert res.time[-1] == pytest.approx(0.03, abs=1e-15)
    errs = {n: abs(res[n][-1] - REF_T[n]) / abs(REF_T[n]) for n in NAMES}
    assert max(errs.values()) < 1e-7, errs
    # the crank has turned ~2.5 revolutions: a nontrivial run
    assert res["beta"][-1] - res["beta"][0] > 15.0
    # at step ends the loop is closed to the solver's tolerance; the other output points of the
    # DAE pairs are interpolated (their residual is the interpolation error)
    assert res["residual.position"][-1] < 1e-10
    assert res["residual.position"].max() < (1e-10 if "DOP853" in pair else 1e-6)
    assert res.stats["cpu_time"] > 0 and res.stats["nfev"] > 0


@pytest.mark.parametrize("pair", list(PAIRS))
def test_energy_balance_with_torque_work(runs, pair):
    """No damping: kinetic + spring energy - mom * (beta - beta(0)) is constant, while the
    torque's work itself grows to ~0.5 J."""
    res = runs[pair]
    # the model's potential is exactly the spring's (no gravity), from the published D position
    Vs = np.array([published(np.array([res[n][k] for n in NAMES]), np.zeros(7))[4] for k in range(len(res.time))])
    np.testing.assert_allclose(res["energy.potential"], Vs, rtol=1e-12, atol=1e-15)
    work = P["mom"] * (res["beta"] - res["beta"][0])
    H = res["energy.total"] - work
    assert work[-1] > 0.5
    assert res["energy.kinetic"].max() > 0.1
    assert np.abs(H - H[0]).max() < 2e-8 * work[-1], np.abs(H - H[0]).max()
