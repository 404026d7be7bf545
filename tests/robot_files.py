"""Where the ``example-robot-data`` package keeps its robots (the URDF tests' shared lookup).

``ROBOTS``: the folder holding ``ur_description/``, ``panda_description/``, ...; ``None`` when
the package is not installed (the tests that need it skip, naming ``pip install mbcomp[robots]``).
"""
import os

import pytest

__all__ = ["ROBOTS", "UR5", "needs_robots"]


def _robots_dir():
    try:
        from importlib.metadata import PackageNotFoundError, files
        found = [f for f in (files("example-robot-data") or []) if str(f).endswith("ur5_robot.urdf")]
    except PackageNotFoundError:
        found = []
    if not found:
        return None
    return str(found[0].locate()).split("/ur_description/")[0]


ROBOTS = _robots_dir()
#: the UR5's URDF (None without the package)
UR5 = None if ROBOTS is None else os.path.join(ROBOTS, "ur_description", "urdf", "ur5_robot.urdf")
needs_robots = pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not installed "
                                                         "(pip install mbcomp[robots])")
