"""Seed Sections 4.3-4.5: slider (4 constraints) + spherical joint (3 constraints) = 5 DOF.

Model: ``models/textbook/ex4_3_slider_spherical.py``. Body 1 on the book's slider (translation
along and rotation about world y: a Prismatic and a Revolute on one axis, joined at a massless
frame), body 2 on a ball joint at the end of body 1's arm, gravity -z.

Book: M = 6 N - C = 6*2 - (4 + 3) = 5; with L prescribed motions M = 6 N - C - L (4.5).
``mbcomp info`` counts the slider's massless intermediate frame as a third rigid group and the
two 1-DOF joints with 5 constraint equations each, 6*3 - (5 + 5 + 3) = 5: the same number, the
intermediate frame's 6 coordinates being removed by 6 extra equations. No book error here.

The reaction components that are constraint forces are the ones not identically zero along a
generic motion: 4 for the slider (Rx, Rz, Mx, Mz; the force along and the torque about the
slide axis vanish) and 3 for the ball joint (three forces, no torque). Their values are
checked against the momentum and angular-momentum balances of the bodies they hold.
"""
import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import mbcomp
from conftest import ROOT, load_model
from mbcomp.cli import main
from mbcomp.kinematics import quat_to_matrix

PATH = "models/textbook/ex4_3_slider_spherical.py"
MODEL = load_model(PATH)
P = dict(m1=2.0, a=0.3, m2=1.5, b=0.6, r2=0.02, g=9.81)
G = np.array([0.0, 0.0, -P["g"]])
T_END = 2.0


def info(capsys, *extra):
    assert main(["info", str(ROOT / PATH), *extra]) == 0
    return capsys.readouterr().out


def gruebler(text):
    line = next(ln for ln in text.splitlines() if ln.startswith("degrees of freedom:"))
    dof = int(line.split()[3])
    lhs, rhs = line.split("= 6*")[1].split(" = ")
    N, C, L = (int(x) for x in lhs.replace(" ", "").split("-"))
    assert int(rhs.rstrip(")")) == 6 * N - C - L
    return dof, N, C, L


def test_info_reports_five_dof(capsys):
    out = info(capsys)
    dof, N, C, L = gruebler(out)
    assert dof == 5
    # book: N = 2 bodies, C = 4 (slider) + 3 (ball) = 7
    assert 6 * 2 - (4 + 3) == dof
    # mbcomp: + the slider's massless intermediate frame (6 coordinates), and the slider's
    # Prismatic + Revolute carry 5 + 5 = 10 equations instead of 4 (6 more)
    assert (N, C, L) == (3, 5 + 5 + 3, 0)
    assert (N - 1, C - 6) == (2, 4 + 3)
    # generalized coordinates: r_y, phi and three ball rotations (quaternion, 3 speeds)
    assert "coordinates (6 q, 5 speeds): slider.translation.s, slider.rotation.phi, ball.Q.w" in out


def test_info_prescribed_rotation_removes_one_dof(capsys):
    """Section 4.5: M = 6 N - C - L with the slider's rotation prescribed."""
    dof, N, C, L = gruebler(info(capsys, "-p", "drive_rotation=0.5*sin(3*t)"))
    assert (dof, L) == (4, 1)
    assert dof == 6 * 2 - (4 + 3) - 1


@pytest.fixture(scope="module")
def result():
    r = mbcomp.simulate(MODEL.build(**P), t_end=T_END, rtol=1e-11, atol=1e-12, method="DOP853", n_out=4001)
    assert r.success, r.message
    return r


def vec(r, name):
    return np.column_stack([r[f"{name}.{a}"] for a in "xyz"])


def body_state(r, name, m, r_cm, I):
    """Centre of mass position and velocity, angular momentum about it (world axes) and R."""
    Q = np.column_stack([r[f"{name}.Q.{a}"] for a in "wxyz"])
    R = np.array([quat_to_matrix(q) for q in Q])
    w = vec(r, f"{name}.w")
    c = R @ np.asarray(r_cm, float)
    rc = vec(r, f"{name}.r") + c
    vc = vec(r, f"{name}.v") + np.cross(w, c)
    h = np.einsum("nij,nj->ni", R @ np.asarray(I, float) @ R.transpose(0, 2, 1), w)
    return rc, vc, h, R, w


def bodies(r):
    a, m1, m2, b, r2 = P["a"], P["m1"], P["m2"], P["b"], P["r2"]
    I1 = m1 * a ** 2 / 12.0
    I2t, I2a = m2 * (3 * r2 ** 2 + b ** 2) / 12.0, m2 * r2 ** 2 / 2.0
    return (body_state(r, "body1", m1, (a / 2, 0, 0), np.diag([1e-3 * I1, I1, I1])),
            body_state(r, "body2", m2, (0, 0, -b / 2), np.diag([I2t, I2t, I2a])))


def test_energy_conserved(result):
    r = result
    E = 0.0
    for (rc, vc, h, R, w), m in zip(bodies(r), (P["m1"], P["m2"])):
        E = E + 0.5 * m * np.einsum("ni,ni->n", vc, vc) + 0.5 * np.einsum("ni,ni->n", w, h) - m * rc @ G
    np.testing.assert_allclose(r["energy.total"], E, rtol=1e-12, atol=1e-12)
    assert np.ptp(r["energy.kinetic"]) > 1.0  # energy moves between kinetic and potential
    assert np.ptp(E) < 1e-9 * np.abs(r["energy.kinetic"]).max()
    # a genuinely 3-D motion of all five coordinates
    assert np.ptp(r["r_y"]) > 0.5 and np.ptp(r["phi"]) > 1.0
    for k in "xyz":
        assert np.ptp(r[f"ball.w.{k}"]) > 0.5


def test_momentum_along_the_slide_axis_conserved(result):
    """No force along y acts on the two bodies (frictionless slider, gravity along -z)."""
    (rc1, vc1, *_), (rc2, vc2, *_) = bodies(result)
    Py = P["m1"] * vc1[:, 1] + P["m2"] * vc2[:, 1]
    assert np.ptp(vc2[:, 1]) > 0.3  # the bodies exchange y momentum
    assert np.ptp(Py) < 1e-9 * np.abs(P["m2"] * vc2[:, 1]).max()


def reaction(r, joint):
    return np.column_stack([r[f"{joint}.{q}.{a}"] for q in ("f", "tau") for a in "xyz"])


def n_constraint_reactions(W):
    """Number of independent reaction components along the motion: rank of the (n x 6) time
    series, relative to its largest singular value."""
    s = np.linalg.svd(W / np.abs(W).max(axis=0, initial=1e-300), compute_uv=False)
    return int(np.sum(s > 1e-6 * s[0]))


def test_slider_has_four_constraint_reactions(result):
    r = result
    W = reaction(r, "slider.translation")  # axes parallel to the world: y is the slide axis
    scale = np.abs(W).max()
    assert scale > 1.0
    # free directions: no force along and no torque about the slide axis
    assert np.abs(W[:, 1]).max() < 1e-10 * scale and np.abs(W[:, 4]).max() < 1e-10 * scale
    # Rx, Rz, Mx, Mz are genuine, independent constraint reactions
    for k in (0, 2, 3, 5):
        assert np.ptp(W[:, k]) > 1e-2 * scale
    assert n_constraint_reactions(W[:, [0, 2, 3, 5]]) == 4
    assert n_constraint_reactions(np.where(np.abs(W) < 1e-10 * scale, 0.0, W)) == 4
    # the massless intermediate frame passes the same wrench to the Revolute (its frame_b is
    # turned by phi about y)
    phi = r["phi"]
    c, s = np.cos(phi), np.sin(phi)
    Wr = reaction(r, "slider.rotation")
    for off in (0, 3):
        x, y, z = Wr[:, off], Wr[:, off + 1], Wr[:, off + 2]
        np.testing.assert_allclose(np.column_stack([c * x + s * z, y, -s * x + c * z]), W[:, off:off + 3],
                                   rtol=0, atol=1e-10 * scale)


def test_ball_joint_has_three_constraint_reactions(result):
    W = reaction(result, "ball")
    scale = np.abs(W).max()
    assert np.abs(W[:, 3:]).max() < 1e-10 * scale
    assert n_constraint_reactions(W[:, :3]) == 3


def test_reaction_values_balance_momentum(result):
    """Integrated over time, the reactions change the momenta: for body 2,
    P2(t) - P2(0) = int (R2 f_ball + m2 g) dt; for bodies 1 + 2, P - P0 = int (F + (m1+m2) g) dt
    and H_O - H_O0 = int (r_s x F + M + sum r_cm x m g) dt about the world origin, with F, M the
    slider's reaction (world axes) at its frame (0, r_y, 0). Simpson's rule on the 0.5 ms output
    grid is accurate to about 3e-9 relative (it converges as dt^4), the tolerance is 1e-7."""
    r = result
    t = r.time
    b1, b2 = bodies(r)
    (rc1, vc1, h1, R1, _), (rc2, vc2, h2, R2, _) = b1, b2
    m1, m2 = P["m1"], P["m2"]

    def integral(f):
        return cumulative_simpson(f, x=t, axis=0, initial=0.0)

    f_ball = np.einsum("nij,nj->ni", R2, vec(r, "ball.f"))
    P2 = m2 * vc2
    np.testing.assert_allclose(P2 - P2[0], integral(f_ball + m2 * G), rtol=0, atol=1e-7 * np.abs(P2).max())

    F, Mo = vec(r, "slider.translation.f"), vec(r, "slider.translation.tau")
    Ptot = m1 * vc1 + m2 * vc2
    np.testing.assert_allclose(Ptot - Ptot[0], integral(F + (m1 + m2) * G), rtol=0, atol=1e-7 * np.abs(Ptot).max())
    rs = np.column_stack([np.zeros_like(t), r["r_y"], np.zeros_like(t)])
    H = m1 * np.cross(rc1, vc1) + h1 + m2 * np.cross(rc2, vc2) + h2
    torque = np.cross(rs, F) + Mo + np.cross(rc1, m1 * G) + np.cross(rc2, m2 * G)
    np.testing.assert_allclose(H - H[0], integral(torque), rtol=0, atol=1e-7 * np.abs(H).max())
    assert np.ptp(H, axis=0).min() > 0.1 * np.abs(H).max()  # every component changes
