"""MJCF mass properties as MuJoCo's compiler computes them: from ``<inertial>`` or from the geoms.

A geom carries ``density * volume`` (``density`` 1000 kg/m^3 by default) or its ``mass``
attribute when given; its inertia about its centre, in its own axes, is the solid's
(MuJoCo's ``mjCGeom::SetInertia``, volume type):

- sphere of radius ``r``: ``2 m r^2 / 5``;
- cylinder of radius ``r``, half length ``h`` (``L = 2 h``): ``m (3 r^2 + L^2) / 12`` across,
  ``m r^2 / 2`` along z;
- capsule: the cylinder of the volume share ``m_c = m - m_s`` plus two hemispheres of mass
  ``m_s = m 4 r / (4 r + 3 L)`` (their volume share), whose transverse inertia about the
  capsule's centre is ``m_s (2 r^2 / 5 + L (3 r + 2 L) / 8)`` (exact: hemisphere centroid
  ``3 r / 8`` beyond the cylinder's end);
- box of half sizes ``a, b, c``: ``m (b^2 + c^2) / 3`` etc.;
- ellipsoid of radii ``a, b, c``: ``m (b^2 + c^2) / 5`` etc.

``fromto`` places a capsule, cylinder, box or ellipsoid between two points: centre at the
midpoint, z along the segment (the shortest rotation from z), half length ``|to - from| / 2``
(size[1] of a capsule or cylinder, size[2] of a box or ellipsoid). A body's geoms in the
compiler's ``inertiagrouprange`` sum to its mass, centre of mass and inertia about it (body
axes, the parallel-axis theorem). A mesh geom weighs its mesh's volume and moments
(:mod:`mbcomp.io.mjcf_mesh`); other shapes carrying mass (height fields, SDFs) are refused:
give the body an ``<inertial>``.
"""
import numpy as np

from .mjcf_frames import numbers, orientation, z_to_vector

__all__ = ["GeomFrame", "geom_frame", "geom_mass", "body_mass_properties", "inertial_element", "scaled_total"]

_SIZES = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}


class GeomFrame:
    """A geom's type, sizes (m, MuJoCo's convention) and placement in its body.

    Attributes
    ----------
    kind : str
        ``sphere``, ``capsule``, ``cylinder``, ``box``, ``ellipsoid``, ``plane``, ``mesh``, ...
    size : (3,) ndarray, m
        Radius / half lengths as MuJoCo reads them (``fromto`` applied).
    pos : (3,) ndarray, m
        Centre, body coordinates.
    R : (3, 3) ndarray
        Geom axes -> body axes.
    attrs : dict
        The geom's attributes with its class's defaults.

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> from mbcomp.io.mjcf_frames import Compiler
    >>> from mbcomp.io.mjcf_inertia import geom_frame
    >>> c = Compiler(ET.fromstring("<mujoco/>"), ".")
    >>> g = geom_frame({"type": "capsule", "fromto": "0 0 0 0 0 2", "size": "0.1"}, c, "geom 'a'")
    >>> g.pos.tolist(), g.size.tolist()
    ([0.0, 0.0, 1.0], [0.1, 1.0, 0.0])
    """

    def __init__(self, kind, size, pos, R, attrs):
        self.kind, self.size, self.pos, self.R, self.attrs = kind, size, pos, R, attrs


def geom_frame(attrs, compiler, what):
    """The :class:`GeomFrame` of a geom's attributes (defaults applied)."""
    kind = attrs.get("type", "sphere")
    size = np.zeros(3)
    if "size" in attrs:
        s = numbers(attrs["size"], None, f"{what} size")
        size[:min(3, s.size)] = s[:3]
    if "fromto" in attrs:
        if kind not in ("capsule", "cylinder", "box", "ellipsoid"):
            raise ValueError(f"MJCF {what}: fromto on a {kind} geom -> MuJoCo reads it on capsule, cylinder, box "
                             "and ellipsoid geoms only; give pos/size instead")
        ft = numbers(attrs["fromto"], 6, f"{what} fromto")
        d = ft[3:] - ft[:3]
        size[1 if kind in ("capsule", "cylinder") else 2] = 0.5 * np.linalg.norm(d)
        return GeomFrame(kind, size, 0.5 * (ft[:3] + ft[3:]), z_to_vector(d), attrs)
    pos = numbers(attrs.get("pos", "0 0 0"), 3, f"{what} pos")
    return GeomFrame(kind, size, pos, orientation(attrs, compiler, what), attrs)


def _volume_inertia(kind, s):
    """``(volume m^3, principal inertia per kg m^2/kg)`` of a solid geom in its own axes."""
    if kind == "sphere":
        r = s[0]
        return 4.0 * np.pi * r ** 3 / 3.0, np.full(3, 2.0 * r * r / 5.0)
    if kind == "cylinder":
        r, L = s[0], 2.0 * s[1]
        across = (3.0 * r * r + L * L) / 12.0
        return np.pi * r * r * L, np.array([across, across, r * r / 2.0])
    if kind == "capsule":
        r, L = s[0], 2.0 * s[1]
        share = 4.0 * r / (4.0 * r + 3.0 * L)  # the two hemispheres' share of the volume (and mass)
        across = (1.0 - share) * (3.0 * r * r + L * L) / 12.0 + share * (2.0 * r * r / 5.0 + L * (3.0 * r + 2.0 * L) / 8.0)
        along = (1.0 - share) * r * r / 2.0 + share * 2.0 * r * r / 5.0
        return np.pi * (r * r * L + 4.0 * r ** 3 / 3.0), np.array([across, across, along])
    sq = s * s
    if kind == "box":
        return 8.0 * s[0] * s[1] * s[2], np.array([sq[1] + sq[2], sq[0] + sq[2], sq[0] + sq[1]]) / 3.0
    if kind == "ellipsoid":
        return 4.0 * np.pi * s[0] * s[1] * s[2] / 3.0, np.array([sq[1] + sq[2], sq[0] + sq[2], sq[0] + sq[1]]) / 5.0
    return 0.0, np.zeros(3)


def geom_mass(g, what, meshes=None):
    """``(m kg, inertia (3, 3) kg m^2 about the geom's centre of mass, that centre (3,) m)`` of
    :class:`GeomFrame` ``g``, both in the geom's axes (``meshes``: the mesh assets,
    :func:`~mbcomp.io.mjcf_shapes.materials_and_meshes`)."""
    a = g.attrs
    if a.get("shellinertia", "false") == "true":
        raise ValueError(f"MJCF {what}: shellinertia='true' (a hollow geom's inertia) is not read -> "
                         "remove it or give the body an <inertial>")
    mass = float(a["mass"]) if "mass" in a else None
    density = float(a.get("density", 1000.0))
    if (mass == 0.0) or (mass is None and density == 0.0):
        return 0.0, np.zeros((3, 3)), np.zeros(3)
    if g.kind == "mesh" and (meshes or {}).get(a.get("mesh")) is not None:
        from .mjcf_mesh import mesh_volume_inertia

        info = meshes[a["mesh"]]
        vol, com, unit = mesh_volume_inertia(info["path"], info["scale"], info["refpos"], info["refquat"],
                                             info["method"], what)
        rho = mass / vol if mass is not None else density
        return rho * vol, rho * unit, com
    if g.kind in ("mesh", "sdf", "hfield"):
        raise ValueError(f"MJCF {what}: a {g.kind} geom carrying mass (density {density:g}"
                         + (f", mass {mass:g}" if mass is not None else "") + "): its volume integrals are not "
                         "computed yet -> give its body an <inertial>, or mass='0' to the geom (or "
                         "inertiagrouprange leaving its group out)")
    if g.kind not in _SIZES:
        return 0.0, np.zeros((3, 3)), np.zeros(3)  # planes and other unbounded shapes: no volume, no mass (as in MuJoCo)
    if np.any(g.size[:_SIZES[g.kind]] <= 0.0):
        raise ValueError(f"MJCF {what}: a {g.kind} needs {_SIZES[g.kind]} positive sizes, got "
                         f"{g.size[:_SIZES[g.kind]].tolist()} -> fix size= (or fromto=)")
    vol, per_kg = _volume_inertia(g.kind, g.size)
    m = mass if mass is not None else density * vol
    return m, np.diag(m * per_kg), np.zeros(3)


def body_mass_properties(parts):
    """``(m, r_cm, I)`` of geoms ``[(m, I about the geom's centre of mass in body axes, that
    centre in body coordinates)]``: the total mass (kg), its centre (m, body coordinates) and
    the inertia about it (kg m^2, body axes); ``None`` when massless."""
    parts = [p for p in parts if p[0] > 0.0]
    if not parts:
        return None
    m = sum(p[0] for p in parts)
    c = sum(p[0] * p[2] for p in parts) / m
    I = np.zeros((3, 3))
    for mi, Ii, pos in parts:
        d = pos - c
        I += Ii + mi * ((d @ d) * np.eye(3) - np.outer(d, d))
    return m, c, 0.5 * (I + I.T)


def inertial_element(el, compiler, what):
    """``(m, r_cm, I)`` of an ``<inertial pos quat mass diaginertia|fullinertia>`` element
    (``I`` about the centre of mass, body axes)."""
    m = float(el.get("mass", "nan"))
    if not m >= 0.0:
        raise ValueError(f"MJCF {what} <inertial>: mass={el.get('mass')!r} must be a number >= 0 -> fix the file")
    pos = numbers(el.get("pos", "0 0 0"), 3, f"{what} inertial pos")
    if el.get("fullinertia") is not None:
        xx, yy, zz, xy, xz, yz = numbers(el.get("fullinertia"), 6, f"{what} fullinertia")
        I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        if any(k in el.attrib for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis")):
            raise ValueError(f"MJCF {what} <inertial>: fullinertia with an orientation -> MuJoCo refuses it; keep one")
        return m, pos, I
    d = numbers(el.get("diaginertia", "0 0 0"), 3, f"{what} diaginertia")
    R = orientation(el.attrib, compiler, f"{what} inertial")
    return m, pos, (R * d) @ R.T


def scaled_total(props, compiler):
    """Every body's ``(m, r_cm, I)`` after ``boundmass``/``boundinertia`` and ``settotalmass``
    (all masses and inertias scaled by one factor, last, as MuJoCo does); ``props`` maps a
    body to its triple or None."""
    out = dict(props)
    if compiler.boundmass > 0.0 or compiler.boundinertia > 0.0:
        for k, mp in out.items():
            m, c, I = mp if mp is not None else (0.0, np.zeros(3), np.zeros((3, 3)))
            w, V = np.linalg.eigh(I)
            w = np.maximum(w, compiler.boundinertia)
            out[k] = (max(m, compiler.boundmass), c, (V * w) @ V.T)
    if compiler.settotalmass > 0.0:
        total = sum(mp[0] for mp in out.values() if mp is not None)
        if total <= 0.0:
            raise ValueError("MJCF <compiler settotalmass>: the model has no mass to scale -> give its bodies mass")
        f = compiler.settotalmass / total
        out = {k: (None if mp is None else (mp[0] * f, mp[1], mp[2] * f)) for k, mp in out.items()}
    return out
