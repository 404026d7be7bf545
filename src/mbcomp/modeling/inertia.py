"""Mass properties of rigid parts: standard shapes, parallel axes, rotation, composition.

A :class:`MassProperties` value describes a rigid part in a reference frame ``F``: its mass
``m`` (kg), its centre of mass ``r_cm`` (m, ``F`` coordinates) and its inertia tensor ``I``
(kg m^2) **about the centre of mass, resolved in** ``F`` **axes** -- exactly what
:class:`mbcomp.library.RigidBody` takes, with ``F`` the body's ``frame_a``
(``RigidBody.from_mass_properties(mp)``).

The shape constructors (:func:`rod`, :func:`box`, :func:`cylinder`, :func:`disk`,
:func:`sphere`, :func:`point_mass`) give homogeneous parts in their own frame: origin at the
centre of mass, axes along the edges / symmetry axis. Parts are moved into a common frame
with :meth:`MassProperties.placed` (origin ``r``, orientation ``R``) and composed with ``+``
(or :func:`combine`); material is removed with ``-`` (a hole). Inertia about another point
is :meth:`MassProperties.about` (parallel-axis theorem), principal moments and axes are
:meth:`MassProperties.principal`.

Bad values raise :class:`mbcomp.ModelError` naming the parameter and the fix.

Examples
--------
A slender rod of mass 2 kg and length 0.6 m along x, hinged at its end:

>>> import numpy as np
>>> from mbcomp.inertia import rod
>>> r = rod(2.0, 0.6, axis="x").placed(r=(0.3, 0, 0))   # frame_a at the rod's end
>>> float(r.about((0, 0, 0))[2, 2])                      # m l^2 / 3
0.24
>>> from mbcomp.inertia import box
>>> whole = box(1.0, 0.2, 0.1, 0.05)
>>> halves = box(0.5, 0.1, 0.1, 0.05).placed(r=(-0.05, 0, 0)) + box(0.5, 0.1, 0.1, 0.05).placed(r=(0.05, 0, 0))
>>> bool(np.allclose(halves.I, whole.I))
True
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError, Problem

__all__ = ["MassProperties", "combine", "steiner", "rod", "box", "cylinder", "disk", "sphere", "point_mass", "inertia_problem"]

_E = np.eye(3)
_HEADER = "bad mass properties"


def _fail(where, what, fix):
    raise ModelError([Problem(where, what, fix)], header=_HEADER)


def _frozen(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def inertia_problem(I):
    """Why ``I`` (3x3, kg m^2) is not a physically realizable inertia tensor, or ``None``.

    The one definition for the whole project (``RigidBody``'s parameter check uses it):
    symmetric, non-negative principal moments, each at most the sum of the other two.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.inertia import inertia_problem
    >>> inertia_problem(np.diag([1.0, 1.0, 3.0]))[:40]
    'principal moments 1, 1, 3 kg m^2 violate'
    >>> inertia_problem(np.diag([1.0, 2.0, 2.5])) is None
    True
    """
    I = np.asarray(I, dtype=float)
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





def steiner(m, d):
    """Parallel-axis term ``m (|d|^2 E - d d^T)`` (kg m^2).

    The inertia of a part about a point ``P`` is ``I_P = I_cm + steiner(m, r_cm - P)``:
    moving the reference point away from the centre of mass only ever *adds* this positive
    semi-definite term; going from ``P`` back to the centre of mass subtracts it.

    Parameters
    ----------
    m : float
        Mass, kg.
    d : array_like, shape (3,)
        Offset between the centre of mass and the point, m (the sign does not matter).

    Examples
    --------
    >>> float(steiner(2.0, (0.0, 0.0, 0.5))[0, 0])
    0.5
    """
    d = np.asarray(d, dtype=float)
    return m * ((d @ d) * _E - np.outer(d, d))


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass, centre of mass and central inertia tensor of a rigid part in a frame ``F``.

    Immutable: every operation returns a new value; the arrays are read-only.

    Parameters
    ----------
    m : float
        Mass, kg, ``>= 0``.
    r_cm : array_like, shape (3,)
        Centre of mass, m, ``F`` coordinates.
    I : array_like, shape (3, 3)
        Inertia tensor about the centre of mass, kg m^2, ``F`` axes: symmetric, positive
        semi-definite, principal moments obeying the triangle inequality.

    Examples
    --------
    >>> mp = MassProperties(2.0, (0.1, 0, 0), np.diag([1e-3, 2e-3, 2e-3]))
    >>> round(float(mp.about((0, 0, 0))[2, 2]), 12)     # 2e-3 + 2 * 0.1^2
    0.022
    """

    m: float
    r_cm: np.ndarray = field(default=(0.0, 0.0, 0.0))
    I: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self):
        try:
            m = float(self.m)
        except (TypeError, ValueError):
            _fail("MassProperties.m", f"mass {self.m!r} is not a number", "give the mass in kg, >= 0")
        if not np.isfinite(m) or m < 0:
            _fail("MassProperties.m", f"mass {m:g} kg is negative or not finite",
                  "give the mass in kg, >= 0 (remove material with `part - hole`, not a negative mass)")
        r = np.array(self.r_cm, dtype=float)
        if r.shape != (3,) or not np.all(np.isfinite(r)):
            _fail("MassProperties.r_cm", f"centre of mass {self.r_cm!r} is not 3 finite numbers",
                  "give the centre of mass in m as (x, y, z), frame F coordinates")
        I = np.array(self.I, dtype=float)
        if I.shape != (3, 3) or not np.all(np.isfinite(I)):
            _fail("MassProperties.I", f"inertia {self.I!r} is not a finite 3x3 array",
                  "give the inertia tensor about the centre of mass in kg m^2, frame F axes, shape (3, 3)")
        msg = inertia_problem(I)
        if msg:
            _fail("MassProperties.I", msg,
                  "give the inertia about the centre of mass (not about another point: use "
                  "MassProperties.from_inertia_about), kg m^2, frame F axes")
        object.__setattr__(self, "m", m)
        object.__setattr__(self, "r_cm", _frozen(r))
        object.__setattr__(self, "I", _frozen(0.5 * (I + I.T)))

    # -- construction ---------------------------------------------------------------
    @classmethod
    def from_inertia_about(cls, m, r_cm, I_point, point=(0.0, 0.0, 0.0)):
        """Mass properties from an inertia tensor given about ``point`` instead of the CM.

        ``I_cm = I_point - steiner(m, r_cm - point)`` (the parallel-axis theorem backwards).

        Parameters
        ----------
        m : float
            Mass, kg.
        r_cm : array_like, shape (3,)
            Centre of mass, m, frame ``F`` coordinates.
        I_point : array_like, shape (3, 3)
            Inertia about ``point``, kg m^2, ``F`` axes.
        point : array_like, shape (3,)
            The reference point of ``I_point``, m, ``F`` coordinates.

        Examples
        --------
        >>> mp = MassProperties.from_inertia_about(3.0, (0, -0.5, 0), np.diag([1.0, 0, 1.0]))
        >>> float(mp.I[0, 0])                               # m l^2/3 - m (l/2)^2 = m l^2/12
        0.25
        """
        d = np.asarray(r_cm, dtype=float) - np.asarray(point, dtype=float)
        return cls(m, r_cm, np.asarray(I_point, dtype=float) - steiner(float(m), d))

    # -- queries -----------------------------------------------------------------------
    def about(self, point=(0.0, 0.0, 0.0)):
        """Inertia tensor about ``point`` (m, ``F`` coordinates), ``F`` axes, kg m^2.

        Parallel-axis theorem: ``I_P = I_cm + m (|d|^2 E - d d^T)``, ``d = r_cm - P``.

        Examples
        --------
        >>> from mbcomp.inertia import sphere
        >>> float(sphere(1.0, 0.1).placed(r=(0, 0, 0.3)).about()[0, 0])   # 2/5 m R^2 + m d^2
        0.094
        """
        return self.I + steiner(self.m, self.r_cm - np.asarray(point, dtype=float))

    def principal(self):
        """Principal moments and axes of the central inertia tensor.

        Returns
        -------
        moments : ndarray, shape (3,)
            Principal moments about the centre of mass, kg m^2, ascending.
        axes : ndarray, shape (3, 3)
            Rotation matrix whose columns are the principal directions (``F`` coordinates),
            right-handed (``det = +1``); ``I = axes @ diag(moments) @ axes.T``. Each of the
            first two columns has its largest component positive; the third is their cross
            product. With equal moments the axes within that eigenspace are arbitrary.

        Examples
        --------
        >>> from mbcomp.inertia import box
        >>> mom, ax = box(12.0, 3.0, 2.0, 1.0).principal()
        >>> mom.tolist()
        [5.0, 10.0, 13.0]
        """
        moments, V = np.linalg.eigh(self.I)
        V = V.copy()
        for k in (0, 1):
            if V[np.argmax(np.abs(V[:, k])), k] < 0:
                V[:, k] = -V[:, k]
        V[:, 2] = np.cross(V[:, 0], V[:, 1])
        return moments, V

    # -- transformation ----------------------------------------------------------------
    def placed(self, r=(0.0, 0.0, 0.0), R=None):
        """The same part described in another frame ``G``.

        ``F`` (the frame this value is given in) sits in ``G`` with origin ``r`` and
        orientation ``R``, where ``R`` maps ``F`` coordinates to ``G`` coordinates
        (``x_G = r + R x_F``; the columns of ``R`` are ``F``'s axes in ``G``). Then
        ``r_cm' = r + R r_cm`` and ``I' = R I R^T``.

        Parameters
        ----------
        r : array_like, shape (3,)
            Origin of ``F`` in ``G`` coordinates, m.
        R : array_like, shape (3, 3), optional
            Proper rotation ``F -> G``; identity when omitted.

        Examples
        --------
        >>> from mbcomp.kinematics import rot_axis
        >>> from mbcomp.inertia import rod
        >>> mp = rod(1.0, 1.0, axis="x").placed(R=rot_axis([0, 0, 1], np.pi / 2))  # now along y
        >>> np.round(np.diag(mp.I), 12).tolist()
        [0.083333333333, 0.0, 0.083333333333]
        """
        r = np.asarray(r, dtype=float)
        if r.shape != (3,) or not np.all(np.isfinite(r)):
            _fail("placed.r", f"origin {r!r} is not 3 finite numbers", "give the origin of F in G coordinates, m")
        if R is None:
            return MassProperties(self.m, r + self.r_cm, self.I)
        R = np.asarray(R, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, _E, atol=1e-9) or np.linalg.det(R) < 0:
            _fail("placed.R", "is not a proper rotation matrix (R R^T = I, det R = +1)",
                  "give the orientation of F in G as a rotation matrix mapping F coordinates to G coordinates")
        return MassProperties(self.m, r + R @ self.r_cm, R @ self.I @ R.T)

    def rotated(self, R):
        """:meth:`placed` with ``r = 0``: ``r_cm' = R r_cm``, ``I' = R I R^T`` (``R``: F -> G)."""
        return self.placed(R=R)

    def shifted(self, r):
        """:meth:`placed` with ``R = E``: the part moved by ``r`` (m)."""
        return self.placed(r=r)

    # -- composition -------------------------------------------------------------------
    def __add__(self, other):
        if not isinstance(other, MassProperties):
            return NotImplemented
        return combine(self, other)

    def __radd__(self, other):  # sum([...]) starts from 0
        if isinstance(other, (int, float)) and other == 0:
            return self
        return NotImplemented

    def __sub__(self, other):
        """Remove material ``other`` (a hole, given in the same frame) from this part."""
        if not isinstance(other, MassProperties):
            return NotImplemented
        m = self.m - other.m
        if m < -1e-12 * max(self.m, 1.0):
            _fail("MassProperties.__sub__", f"the hole's mass {other.m:g} kg exceeds the part's mass {self.m:g} kg",
                  "remove only material that lies inside the part")
        m = max(m, 0.0)
        r = (self.m * self.r_cm - other.m * other.r_cm) / m if m > 0 else np.zeros(3)
        I = self.I + steiner(self.m, self.r_cm - r) - other.I - steiner(other.m, other.r_cm - r)
        msg = inertia_problem(0.5 * (I + I.T))
        if msg:
            _fail("MassProperties.__sub__", f"the remaining part has no real mass distribution ({msg})",
                  "remove only material that lies inside the part, described in the same frame")
        return MassProperties(m, r, I)

    def allclose(self, other, rtol=1e-12, atol=1e-15):
        """True when mass, centre of mass and inertia agree within ``rtol``/``atol``."""
        return bool(np.isclose(self.m, other.m, rtol=rtol, atol=atol)
                    and np.allclose(self.r_cm, other.r_cm, rtol=rtol, atol=atol)
                    and np.allclose(self.I, other.I, rtol=rtol, atol=atol))

    def __repr__(self):
        return (f"MassProperties(m={self.m:g}, r_cm={np.array2string(self.r_cm, precision=6)}, "
                f"I={np.array2string(self.I, precision=6)})")


def combine(*parts):
    """One rigid part made of ``parts`` (all given in the same frame ``F``).

    Total mass, mass-weighted centre of mass, and the inertia about the combined centre of
    mass: ``I = sum_i I_i + steiner(m_i, r_i - r_cm)``. Massless parts contribute their
    inertia only; if everything is massless the centre of mass is put at ``F``'s origin.

    Examples
    --------
    >>> a = point_mass(1.0, (-0.5, 0, 0)); b = point_mass(1.0, (0.5, 0, 0))
    >>> float(combine(a, b).I[1, 1])                    # 2 * 1 * 0.5^2
    0.5
    """
    if not parts:
        _fail("combine", "no parts given", "pass one or more MassProperties")
    for k, p in enumerate(parts):
        if not isinstance(p, MassProperties):
            _fail(f"combine(part {k})", f"{p!r} is not a MassProperties", "build parts with the shape functions")
    m = sum(p.m for p in parts)
    r = sum(p.m * p.r_cm for p in parts) / m if m > 0 else np.zeros(3)
    I = sum(p.I + steiner(p.m, p.r_cm - r) for p in parts)
    return MassProperties(m, r, I)


# -- standard homogeneous shapes (own frame: origin at the CM) ---------------------------

def _mass(shape, m):
    try:
        m = float(m)
    except (TypeError, ValueError):
        _fail(f"{shape}.m", f"mass {m!r} is not a number", "give the mass in kg, >= 0")
    if not np.isfinite(m) or m < 0:
        _fail(f"{shape}.m", f"mass {m:g} kg is negative or not finite", "give the mass in kg, >= 0")
    return m


def _length(shape, name, value, meaning, allow_zero=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        _fail(f"{shape}.{name}", f"{value!r} is not a number", f"give {meaning} in m, > 0")
    ok = v >= 0 if allow_zero else v > 0
    if not (np.isfinite(v) and ok):
        _fail(f"{shape}.{name}", f"{meaning} {v:g} m is not {'>= 0' if allow_zero else '> 0'}",
              f"give {meaning} in m, {'>= 0' if allow_zero else '> 0'}")
    return v


_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def _direction(shape, axis):
    if isinstance(axis, str):
        if axis.lower() not in _AXES:
            _fail(f"{shape}.axis", f"axis {axis!r} is not 'x', 'y' or 'z'",
                  "give 'x', 'y', 'z' or a direction vector (3 numbers, not zero)")
        return np.array(_AXES[axis.lower()])
    n = np.asarray(axis, dtype=float)
    if n.shape != (3,) or not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
        _fail(f"{shape}.axis", f"axis {axis!r} is not a direction",
              "give 'x', 'y', 'z' or a direction vector (3 numbers, not zero)")
    return n / np.linalg.norm(n)


def _axisymmetric(m, axial, transverse, n):
    nn = np.outer(n, n)
    return MassProperties(m, (0.0, 0.0, 0.0), transverse * (_E - nn) + axial * nn)


def point_mass(m, r=(0.0, 0.0, 0.0)):
    """A particle of mass ``m`` (kg) at ``r`` (m): no inertia about its own centre.

    Examples
    --------
    >>> float(point_mass(2.0, (0, 0, 1.0)).about()[0, 0])
    2.0
    """
    return MassProperties(_mass("point_mass", m), r, np.zeros((3, 3)))


def rod(m, length, axis="x"):
    """Slender homogeneous rod, centre at the origin, along ``axis``.

    ``m l^2 / 12`` about every transverse axis, zero about its own axis (the slender-rod
    idealization; use :func:`cylinder` for a rod that spins about its own axis).

    Parameters
    ----------
    m : float
        Mass, kg.
    length : float
        Length, m, > 0.
    axis : {'x', 'y', 'z'} or array_like, shape (3,)
        Direction of the rod in its own frame.

    Examples
    --------
    >>> np.diag(rod(12.0, 1.0, axis="y").I).tolist()
    [1.0, 0.0, 1.0]
    """
    m = _mass("rod", m)
    l = _length("rod", "length", length, "the rod length")
    return _axisymmetric(m, 0.0, m * l * l / 12.0, _direction("rod", axis))


def box(m, a, b, c):
    """Homogeneous rectangular box (cuboid), centre at the origin, edges along x, y, z.

    ``I = m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)``.

    Parameters
    ----------
    m : float
        Mass, kg.
    a, b, c : float
        Edge lengths along x, y and z, m, > 0 (a thin plate is a box with a small ``c``).

    Examples
    --------
    >>> np.diag(box(12.0, 1.0, 2.0, 3.0).I).tolist()
    [13.0, 10.0, 5.0]
    """
    m = _mass("box", m)
    a = _length("box", "a", a, "the edge length along x")
    b = _length("box", "b", b, "the edge length along y")
    c = _length("box", "c", c, "the edge length along z")
    return MassProperties(m, (0.0, 0.0, 0.0), m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b]))


def cylinder(m, radius, length, axis="z", inner_radius=0.0):
    """Homogeneous solid (or thick-walled, ``inner_radius > 0``) circular cylinder.

    Centre at the origin, symmetry axis along ``axis``. With ``s = radius^2 + inner_radius^2``:
    axial ``m s / 2``, transverse ``m (3 s + length^2) / 12``.

    Parameters
    ----------
    m : float
        Mass, kg.
    radius : float
        Outer radius, m, > 0.
    length : float
        Length along the axis, m, > 0.
    axis : {'x', 'y', 'z'} or array_like, shape (3,)
        Symmetry axis in the part's own frame.
    inner_radius : float
        Bore radius, m, ``0 <= inner_radius < radius``.

    Examples
    --------
    >>> np.diag(cylinder(2.0, 1.0, 3.0).I).tolist()
    [2.0, 2.0, 1.0]
    """
    m = _mass("cylinder", m)
    R = _length("cylinder", "radius", radius, "the outer radius")
    L = _length("cylinder", "length", length, "the length along the axis")
    ri = _length("cylinder", "inner_radius", inner_radius, "the bore radius", allow_zero=True)
    if ri >= R:
        _fail("cylinder.inner_radius", f"bore radius {ri:g} m is not smaller than the outer radius {R:g} m",
              "give 0 <= inner_radius < radius (0 for a solid cylinder)")
    s = R * R + ri * ri
    return _axisymmetric(m, m * s / 2.0, m * (3.0 * s + L * L) / 12.0, _direction("cylinder", axis))


def disk(m, radius, axis="z"):
    """Thin homogeneous circular disk: axial ``m r^2 / 2``, diametral ``m r^2 / 4``.

    Parameters
    ----------
    m : float
        Mass, kg.
    radius : float
        Radius, m, > 0.
    axis : {'x', 'y', 'z'} or array_like, shape (3,)
        Disk normal in the part's own frame.

    Examples
    --------
    >>> np.diag(disk(4.0, 1.0, axis="x").I).tolist()
    [2.0, 1.0, 1.0]
    """
    m = _mass("disk", m)
    r = _length("disk", "radius", radius, "the radius")
    return _axisymmetric(m, m * r * r / 2.0, m * r * r / 4.0, _direction("disk", axis))


def sphere(m, radius, hollow=False):
    """Homogeneous solid sphere (``2/5 m r^2``) or thin spherical shell (``hollow``: ``2/3 m r^2``).

    Parameters
    ----------
    m : float
        Mass, kg.
    radius : float
        Radius, m, > 0.
    hollow : bool
        True for a thin shell of that radius.

    Examples
    --------
    >>> float(sphere(5.0, 1.0).I[0, 0])
    2.0
    """
    m = _mass("sphere", m)
    r = _length("sphere", "radius", radius, "the radius")
    k = 2.0 / 3.0 if hollow else 2.0 / 5.0
    return MassProperties(m, (0.0, 0.0, 0.0), k * m * r * r * _E)
