"""Rigid offsets and mass carriers."""
import numpy as np

from mbcomp import Body, Joint, Param
from mbcomp.jets import rigid_constraints

from .checks import inertia_tensor, rotation_matrix



class _Rigid(Joint):
    """A 0-DOF joint: frame_b fixed relative to frame_a."""

    def offset(self, p):
        return np.eye(3), np.zeros(3)

    def relative(self, q, p):
        return self.offset(p)

    def constraints(self, a, b, p):
        R0, r0 = self.offset(p)
        return rigid_constraints(a, b, R0, r0)


#: a rigid offset's rotation when it has none (shared, read-only: a fresh np.eye(3) was a tenth
#: of a pose pass over a chain)
_EYE = np.eye(3)
_EYE.setflags(write=False)


class FixedTranslation(_Rigid):
    """Massless rigid link: frame_b is frame_a translated by ``r`` (frame_a coordinates).

    Examples
    --------
    >>> from mbcomp.library import FixedTranslation
    >>> FixedTranslation(r=(0.5, 0, 0)).p.r
    array([0.5, 0. , 0. ])
    """

    r = Param((0.0, 0.0, 0.0), unit="m", shape=(3,), doc="origin of frame_b, frame_a coordinates")

    def offset(self, p):
        return _EYE, p.r


class FixedRotation(_Rigid):
    """Massless rigid offset with rotation: ``R_b = R_a R`` and ``r_b = r_a + R_a r``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.kinematics import rot_axis
    >>> from mbcomp.library import FixedRotation
    >>> FixedRotation(R=rot_axis([0, 0, 1], np.pi / 2)).p.R.shape
    (3, 3)
    """

    r = Param((0.0, 0.0, 0.0), unit="m", shape=(3,), doc="origin of frame_b, frame_a coordinates")
    R = Param(np.eye(3), unit="1", shape=(3, 3), doc="orientation of frame_b: frame_b -> frame_a", check=rotation_matrix)

    def offset(self, p):
        return p.R, p.r


class RigidBody(Body):
    """Rigid body: mass ``m``, centre of mass ``r_cm`` and inertia ``I`` about it (frame_a axes).

    ``m = 0`` with ``I = 0`` is a massless link, legal where its motion is determined by
    its neighbours. Standard shapes and composed parts come from :mod:`mbcomp.inertia`
    through :meth:`from_mass_properties`.

    Examples
    --------
    >>> from mbcomp.library import RigidBody
    >>> b = RigidBody(m=2.0, r_cm=(0.5, 0, 0), I=[[0.01, 0, 0], [0, 0.2, 0], [0, 0, 0.2]])
    >>> b.p.m
    2.0
    """

    m = Param(1.0, unit="kg", doc="mass", check="nonnegative")
    r_cm = Param((0.0, 0.0, 0.0), unit="m", shape=(3,), doc="centre of mass, frame_a coordinates")
    I = Param(np.zeros((3, 3)), unit="kg m^2", shape=(3, 3), doc="inertia about the centre of mass, frame_a axes",
              check=inertia_tensor)

    def mass_properties(self, p):
        return p.m, p.r_cm, p.I

    @classmethod
    def from_mass_properties(cls, mp):
        """A rigid body with the mass properties ``mp`` given in its ``frame_a``.

        Parameters
        ----------
        mp : mbcomp.inertia.MassProperties
            Mass (kg), centre of mass (m, frame_a coordinates) and inertia about the centre of
            mass (kg m^2, frame_a axes), e.g. a shape placed where frame_a sees it.

        Examples
        --------
        >>> from mbcomp.inertia import box
        >>> from mbcomp.library import RigidBody
        >>> b = RigidBody.from_mass_properties(box(1.0, 0.1, 0.2, 0.05).placed(r=(0.05, 0.1, 0)))
        >>> b.p.r_cm.tolist()
        [0.05, 0.1, 0.0]
        """
        from mbcomp.inertia import MassProperties  # mbcomp.inertia imports this package lazily too

        if not isinstance(mp, MassProperties):
            raise TypeError(f"RigidBody.from_mass_properties: {mp!r} is not a MassProperties -> fix: build it "
                            f"with mbcomp.inertia (box, cylinder, ... placed/combined), or call "
                            f"RigidBody(m=..., r_cm=..., I=...)")
        return cls(m=mp.m, r_cm=np.array(mp.r_cm), I=np.array(mp.I))


def _symmetric(I):
    """The check of an inertia taken as given: symmetric (to 1e-12 relative), nothing more."""
    I = np.asarray(I, dtype=float)
    if not np.allclose(I, I.T, atol=1e-12 * max(1.0, np.abs(I).max())):
        return "inertia tensor is not symmetric"
    return None


class UncheckedRigidBody(RigidBody):
    """A :class:`RigidBody` whose inertia ``I`` is taken as given: only its symmetry is checked,
    not the triangle inequality of its principal moments nor their sign.

    For imported robot files whose links' inertias no real mass distribution has (rounded or
    hand-written values; ``mbcomp.load_urdf(..., inertia="as_given")``), to reproduce what
    engines that do not check them compute. The mass matrix stays positive definite as long
    as the robot's composite inertias are (initialization checks it as for any model).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import RigidBody, UncheckedRigidBody
    >>> I = np.diag([0.01, 0.01, 0.03])        # 0.01 + 0.01 < 0.03: no real body has it
    >>> UncheckedRigidBody(m=1.0, I=I).problems()  # no problem reported
    []
    >>> RigidBody(m=1.0, I=I).problems()[0].what[:50]
    'parameter principal moments 0.01, 0.01, 0.03 kg m^'
    """

    I = Param(np.zeros((3, 3)), unit="kg m^2", shape=(3, 3), check=_symmetric,
              doc="inertia about the centre of mass, frame_a axes (taken as given: symmetric, else unchecked)")


class PointMass(Body):
    """A particle of mass ``m`` at the origin of frame_a (no rotational inertia).

    Examples
    --------
    >>> from mbcomp.library import PointMass
    >>> PointMass(m=0.5).p.m
    0.5
    """

    m = Param(1.0, unit="kg", doc="mass", check="nonnegative")

    def mass_properties(self, p):
        return p.m, np.zeros(3), np.zeros((3, 3))
