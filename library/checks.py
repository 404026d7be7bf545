"""Parameter checks shared by library components (return a message or None)."""
from mbcomp.inertia import inertia_problem
from mbcomp.modeling.free_joint import rotation_matrix_problem

rotation_matrix = rotation_matrix_problem  # the framework's check (its free joint uses it too)
inertia_tensor = inertia_problem  # the framework's check: an FMU's parameter rules know it by identity
