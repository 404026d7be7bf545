"""Parameter checks shared by library components (return a message or None)."""
import numpy as np


def rotation_matrix(R):
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        return "is not a proper rotation matrix (R R^T = I, det R = +1)"
    return None


def inertia_tensor(I):
    if not np.allclose(I, I.T, atol=1e-12 * max(1.0, np.abs(I).max())):
        return "inertia tensor is not symmetric"
    ev = np.linalg.eigvalsh(0.5 * (I + I.T))
    tol = 1e-12 * max(1.0, np.abs(ev).max())
    if ev.min() < -tol:
        return f"inertia tensor has a negative principal moment {ev.min():g} kg m^2"
    a, b, c = ev
    if a + b < c - tol:
        return (f"principal moments {a:g}, {b:g}, {c:g} kg m^2 violate the triangle inequality "
                f"(no real mass distribution has them: each must be <= the sum of the other two)")
    return None
