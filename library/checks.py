"""Parameter checks shared by library components (return a message or None)."""
import numpy as np

from mbcomp.inertia import inertia_problem


def rotation_matrix(R):
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        return "is not a proper rotation matrix (R R^T = I, det R = +1)"
    return None


def inertia_tensor(I):
    return inertia_problem(I)
