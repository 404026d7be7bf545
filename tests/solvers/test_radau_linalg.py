"""RADAU5's iteration matrices (solvers/radau_linalg.py): solves against dense numpy solves,
and the singular cases named (zero row, zero column, rank deficiency)."""
import numpy as np
import pytest

from mbcomp.solvers.radau import GAMMA, MU
from mbcomp.solvers.radau_linalg import IterationMatrices, SingularMatrix


def _badly_scaled_dae(n=7, seed=3):
    """A Jacobian with rows and columns over 12 decades and two algebraic rows."""
    rng = np.random.default_rng(seed)
    J = rng.standard_normal((n, n)) * np.logspace(-6, 6, n)[:, None] * np.logspace(3, -3, n)[None, :]
    mass = np.ones(n)
    mass[-2:] = 0.0
    return J, mass


@pytest.mark.parametrize("h", [1e-6, 1e-3, 0.1])
def test_solves_agree_with_dense_solves_of_both_matrices(h):
    J, mass = _badly_scaled_dae()
    m = IterationMatrices(J, mass, GAMMA, MU, h)
    rng = np.random.default_rng(0)
    b = rng.standard_normal(J.shape[0])
    bc = b + 1j * rng.standard_normal(J.shape[0])
    Mr = np.diag(GAMMA / h * mass) - J
    Mc = np.diag(MU / h * mass) - J
    x, z = m.solve_real(b), m.solve_complex(bc)
    # residuals relative to the matrices' size: backward stable solves (equilibrated LU)
    assert np.linalg.norm(Mr @ x - b) <= 1e-12 * np.linalg.norm(np.abs(Mr) @ np.abs(x))
    assert np.linalg.norm(Mc @ z - bc) <= 1e-12 * np.linalg.norm(np.abs(Mc) @ np.abs(z))
    np.testing.assert_allclose(x, np.linalg.solve(Mr, b), rtol=1e-6)
    np.testing.assert_allclose(z, np.linalg.solve(Mc, bc), rtol=1e-6)
    assert m.h == h


def test_the_inputs_are_left_unchanged():
    J, mass = _badly_scaled_dae()
    J0, mass0 = J.copy(), mass.copy()
    IterationMatrices(J, mass, GAMMA, MU, 0.01)
    np.testing.assert_array_equal(J, J0)
    np.testing.assert_array_equal(mass, mass0)


def test_a_zero_row_and_a_zero_column_are_structural():
    J = np.array([[-1.0, 2.0, 0.0], [0.0, 0.0, 0.0], [3.0, 1.0, 0.0]])
    with pytest.raises(SingularMatrix, match="equation 1 involves no variable") as exc:
        IterationMatrices(J, np.array([1.0, 0.0, 0.0]), GAMMA, MU, 0.1)
    assert exc.value.structural
    with pytest.raises(SingularMatrix, match="variable 2 enters no equation") as exc:
        IterationMatrices(J, np.array([1.0, 1.0, 0.0]), GAMMA, MU, 0.1)
    assert exc.value.structural


def test_a_rank_deficient_algebraic_block_is_reported_by_its_pivot():
    # two algebraic rows that are the same equation: no row or column is zero
    J = np.array([[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 2.0]])
    J[:, 1] = [1.0, 0.0, 0.0]
    with pytest.raises(SingularMatrix, match="rank deficient") as exc:
        IterationMatrices(J, np.array([1.0, 0.0, 0.0]), GAMMA, MU, 0.1)
    assert not exc.value.structural


@pytest.mark.parametrize("h", [1e-6, 1e-3, 0.1])
def test_solve_stages_is_the_real_and_the_complex_solve(h):
    # one call for the Newton iteration's two solves: the numbers of solve_real on R[0] and of
    # solve_complex on R[1] + i R[2], bit for bit, and the solutions solve both matrices
    J, mass = _badly_scaled_dae()
    m = IterationMatrices(J, mass, GAMMA, MU, h)
    R = np.random.default_rng(1).standard_normal((3, J.shape[0]))
    out = np.full_like(R, np.nan)
    m.solve_stages(R, out)
    np.testing.assert_array_equal(out[0], m.solve_real(R[0]))
    z = m.solve_complex(R[1] + 1j * R[2])
    np.testing.assert_array_equal(out[1] + 1j * out[2], z)
    Mc = np.diag(MU / h * mass) - J
    assert np.linalg.norm(Mc @ (out[1] + 1j * out[2]) - (R[1] + 1j * R[2])) <= \
        1e-12 * np.linalg.norm(np.abs(Mc) @ np.abs(z))


def test_the_ode_shortcut_gives_the_same_factors():
    # E = I: the diagonal formed without the products with mass -- the same numbers
    J, _ = _badly_scaled_dae()
    ones = np.ones(J.shape[0])
    b = np.random.default_rng(2).standard_normal(J.shape[0])
    for h in (1e-5, 0.03):
        a, z = IterationMatrices(J, ones, GAMMA, MU, h, ode=True), IterationMatrices(J, ones, GAMMA, MU, h, ode=False)
        np.testing.assert_array_equal(a.solve_real(b), z.solve_real(b))
        np.testing.assert_array_equal(a.solve_complex(b + 1j), z.solve_complex(b + 1j))
