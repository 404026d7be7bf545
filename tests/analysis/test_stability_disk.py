"""Stability of a thin disk rolling upright (models/rolling_disk.py) against the textbook result.

Notation: radius ``r``, mass ``m``, axial and diametral moments ``I_a = m r^2/2``,
``I_d = m r^2/4``, spin ``W``; states ``phi`` (lean.phi), ``psi'`` (heading.w), ``phi'``
(lean.w). Newton-Euler about the centre in the lean frame (derivation in the model file's
docstring), linearized about upright straight rolling:

    J phi'' = m g r phi + (I_a + m r^2) W psi',    J = I_d + m r^2
    I_d psi'' = -I_a W phi'
    Omega' = 0      (axial spin)

so ``A = [[0, 0, 1], [0, 0, -I_a W/I_d], [m g r/J, (I_a + m r^2) W/J, 0]]``. The heading
equation integrates to the conserved combination ``I_d psi' + I_a W phi`` (the left null
vector of ``A``), the zero root's eigenvector is a neighbouring steady turn
(``phi' = 0``, ``m g r phi + (I_a + m r^2) W psi' = 0``), and the other roots are
``+-sqrt(-K/J)`` with ``K = (I_a + m r^2) I_a W^2 / I_d - m g r``: real (unstable) below
``W^2 = g/(3 r)``, imaginary (marginally stable) above; the mass drops out.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small LU solves; threads only cost on a shared machine

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import mbcomp  # noqa: E402
from conftest import load_model  # noqa: E402

DISK = load_model("models/rolling_disk.py")
G = 9.81
R0, M0 = 0.3, 2.0  # build()'s defaults
W_CRIT = np.sqrt(G / (3 * R0))  # 3.3015148038438...


def coefficients(r, m, W):
    """``(I_a, I_d, K, J)`` of the linear lean equation ``J phi'' + K phi = 0``."""
    Ia, Id = m * r * r / 2, m * r * r / 4
    return Ia, Id, (Ia + m * r * r) * Ia * W ** 2 / Id - m * G * r, Id + m * r * r


def analytic_A(r, m, W):
    Ia, Id, _, J = coefficients(r, m, W)
    return np.array([[0.0, 0.0, 1.0],
                     [0.0, 0.0, -Ia * W / Id],
                     [m * G * r / J, (Ia + m * r * r) * W / J, 0.0]])


def ordered(eigs):
    """Eigenvalues sorted by (real, imaginary) part, rounding away numerical noise."""
    return sorted(np.asarray(eigs, complex), key=lambda z: (round(z.real, 6), round(z.imag, 6)))


def test_the_formula_has_the_textbook_critical_spin():
    assert abs(coefficients(R0, M0, W_CRIT)[2]) < 1e-12 * M0 * G * R0
    assert abs(coefficients(0.5, 0.7, np.sqrt(G / 1.5))[2]) < 1e-12 * 0.7 * G * 0.5


@pytest.mark.parametrize("W, expected", [(6.0, "marginally stable"), (2.0, "unstable")])
def test_upright_rolling_linearizes_to_the_lean_equation(W, expected):
    lin = mbcomp.linearize(DISK.build(spin=W))
    # the cyclic coordinates move (x, spin angle) or are removed with the conserved spin rate
    assert sorted(lin.moving) == ["spin.phi", "x.s"]
    assert sorted(lin.removed) == ["heading.phi", "spin.w", "y.s"]
    assert lin.state_names == ["lean.phi", "heading.w", "lean.w"]
    assert lin.classification == expected
    A0 = analytic_A(R0, M0, W)
    np.testing.assert_allclose(lin.A, A0, rtol=0, atol=1e-9 * np.abs(A0).max())

    Ia, Id, K, J = coefficients(R0, M0, W)
    root = np.sqrt(complex(-K / J))
    assert (K > 0) == (expected == "marginally stable")
    np.testing.assert_allclose(ordered(lin.eigenvalues), ordered([0.0, root, -root]), atol=1e-8)

    # the zero root: conserved I_d psi' + I_a W phi (left null vector) ...
    c = np.array([Ia * W, Id, 0.0])
    assert np.abs(c @ lin.A).max() < 1e-10 * np.linalg.norm(c) * np.abs(lin.A).max()
    left = np.linalg.svd(lin.A.T)[2][-1]
    assert abs(abs(left @ c) / np.linalg.norm(c) - 1) < 1e-10
    # ... and its eigenvector: a neighbouring steady turn
    k0 = int(np.argmin(np.abs(lin.eigenvalues)))
    phi, psi_dot, phi_dot = np.real_if_close(lin.eigenvectors[:, k0] / lin.eigenvectors[0, k0])
    assert abs(phi_dot) < 1e-9
    assert abs(M0 * G * R0 * phi + (Ia + M0 * R0 ** 2) * W * psi_dot) < 1e-9 * M0 * G * R0


def test_sweep_locates_the_critical_spin():
    """Below W_crit the real pair +-sqrt(-K/J) is unstable; above it the imaginary pair and
    the zero root are on the imaginary axis (marginally stable): no real part changes sign, so
    the sweep root-finds the signed square of the colliding pair (+a^2 below, -b^2 above)."""
    sw = mbcomp.sweep(lambda W: DISK.build(spin=W), "spin", [2.0, 3.0, 4.0])
    assert sw.classifications == ["unstable", "unstable", "marginally stable"]
    for W, eigs in zip(sw.values, sw.eigenvalues):
        _, _, K, J = coefficients(R0, M0, W)
        assert abs(eigs.real.max() - np.sqrt(max(-K / J, 0.0))) < 1e-8
        assert abs(np.abs(eigs.imag).max() - np.sqrt(max(K / J, 0.0))) < 1e-8
    assert len(sw.changes) == 1
    ch = sw.changes[0]
    # measured: 3.301514803843821 vs 3.301514803843836 (4e-15 relative)
    assert abs(ch["value"] / W_CRIT - 1) < 1e-12, (ch["value"], W_CRIT)
    assert (ch["from"], ch["to"]) == ("unstable", "marginally stable")
    assert ch["method"] == "Brent's method on the signed square of the colliding roots"


def test_radius_moves_the_boundary_and_mass_does_not():
    """r = 0.5 m, m = 0.7 kg: the boundary moves to sqrt(g / (3 r)) = 2.5573 rad/s, bracketed
    to 1e-6 relative; the eigenvalues follow the formula, and do not depend on the mass."""
    r, m = 0.5, 0.7
    Wc = np.sqrt(G / (3 * r))
    below = mbcomp.linearize(DISK.build(r=r, m=m, spin=Wc * (1 - 1e-6)))
    above = mbcomp.linearize(DISK.build(r=r, m=m, spin=Wc * (1 + 1e-6)))
    assert below.classification == "unstable" and above.classification == "marginally stable"
    _, _, K, J = coefficients(r, m, Wc * (1 - 1e-6))
    assert abs(below.eigenvalues.real.max() / np.sqrt(-K / J) - 1) < 1e-4  # ~5.6e-3 1/s
    # the old boundary (r = 0.3) is well inside the stable side now
    lin = mbcomp.linearize(DISK.build(r=r, m=m, spin=W_CRIT))
    _, _, K, J = coefficients(r, m, W_CRIT)
    assert lin.classification == "marginally stable"
    assert abs(np.abs(lin.eigenvalues.imag).max() - np.sqrt(K / J)) < 1e-8
    heavy = mbcomp.linearize(DISK.build(r=r, m=10 * m, spin=W_CRIT))
    np.testing.assert_allclose(ordered(heavy.eigenvalues), ordered(lin.eigenvalues), atol=1e-8)
