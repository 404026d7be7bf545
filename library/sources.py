"""Ground frames and the gravity field."""
import numpy as np

from mbcomp import Frame, Grid, Ground, Param
from mbcomp.modeling.shapes import z_to

from .checks import rotation_matrix


class World(Ground):
    """The inertial frame at the world origin and a uniform gravity field.

    Parameters
    ----------
    g : (3,) m/s^2, world coordinates
        Gravity acceleration; the default points along -y (y up, as in Modelica).

    Examples
    --------
    >>> from mbcomp.library import World
    >>> World(g=(0, 0, -9.81)).p.g
    array([ 0.  ,  0.  , -9.81])
    """

    frame_b = Frame("the world frame (origin, world axes)", optional=True)
    g = Param((0.0, -9.81, 0.0), unit="m/s^2", shape=(3,), doc="gravity acceleration, world coordinates")

    def pose(self, p):
        return np.eye(3), np.zeros(3)

    def gravity(self, p):
        return p.g

    def visuals(self, p, view):
        """The floor: a grid normal to gravity (to z without gravity), moved down by the scene to
        below the motion; none where a contact draws the ground (``view.covered``)."""
        if view.covered("frame_b"):
            return []
        up = -np.asarray(p.g, dtype=float)
        return [Grid(R=z_to(up if np.linalg.norm(up) > 0 else (0.0, 0.0, 1.0)), color="lightgrey")]


class Fixed(Ground):
    """A frame fixed in the world at position ``r`` with orientation ``R``.

    Examples
    --------
    >>> from mbcomp.library import Fixed
    >>> Fixed(r=(1, 0, 0)).p.r
    array([1., 0., 0.])
    """

    r = Param((0.0, 0.0, 0.0), unit="m", shape=(3,), doc="origin position, world coordinates")
    R = Param(np.eye(3), unit="1", shape=(3, 3), doc="orientation, frame -> world", check=rotation_matrix)

    def pose(self, p):
        return p.R, p.r
