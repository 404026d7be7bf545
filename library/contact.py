"""Rolling contact: wheels and balls rolling without slip on a plane carried by any body.

A contact is a constraint-only joint (``tree_edge = False``: no coordinates, always cut)
between the body carrying the plane (``frame_a``; the plane passes through its origin with
normal ``n``) and the rolling body (``frame_b`` at the wheel's or ball's centre). It writes

* one holonomic row ``normal``: the contact point lies on the plane;
* two nonholonomic rows: the material points of the two bodies at the contact point have
  the same velocity along the plane (no slip), built with :func:`mbcomp.jets.slip_velocity`.

The normal velocity of the material points is the rate of the holonomic row, so the three
rows together say the contact point is at rest relative to the plane. Reactions come from
the rows' multipliers: ``N`` (normal force on the rolling body, N, positive when pressing)
and two friction components (N) in the plane, reported as ``<contact>.N``, ``.F_long``,
``.F_lat`` (disk) or ``.F_1``, ``.F_2`` (ball), with the contact point ``.p.x|y|z``
(m, world coordinates). The composites :class:`RollingDisk` and :class:`RollingSphere` add
the body, a free joint and start values given in rolling terms.
"""
import numpy as np

from mbcomp import Box, Cylinder, Grid, Joint, Model, Param, SimulationError, Sphere
from mbcomp.errors import Problem
from mbcomp.jets import ScalarJet, VecJet, is_traced, local_point, local_vector, slip_velocity, velocity_along
from mbcomp.kinematics import cross, rot_axis
from mbcomp.modeling.shapes import z_to

from .joints import FreeMotion
from .parts import RigidBody
from .plane_contact import Frictional, friction_param, unilateral_params
from .surfaces import Plane, Surface, surface_geometry, surface_rows, tangent_distance

_E = np.eye(3)


def _unit(v):
    return np.asarray(v, float) / np.linalg.norm(v)


def _tangents(n):
    """Plane directions ``t1, t2 = n x t1`` for the unit normal ``n``: ``t1`` is the frame axis
    most nearly in the plane (x first), projected onto it; ``x, y`` for ``n = z``."""
    e = _E[int(np.argmin(np.abs(n)))]
    t1 = _unit(e - (e @ n) * n)
    return t1, np.cross(n, t1)


def _lift_off(name, t, outputs):
    """The note of a contact whose normal force ``N`` pulls: from when a real one would lift off."""
    N = outputs.get("N")
    if N is None or not np.nanmin(N, initial=0.0) < 0.0:
        return []
    k = int(np.argmax(N < 0.0))
    return [f"{name}.N < 0 from t = {t[k]:.4g} s: the contact pulls the body onto the plane there "
            f"(contacts are bilateral; a real wheel or ball would lift off)"]


def _rim_step(surface, cl, al, u, r):
    """One Newton step on the rim angle ``psi`` towards the rim point deepest in the surface:
    ``f(psi) = G(c + r u(psi))`` with ``f' = r n . s``, ``f'' = r^2 s . K s - r n . u``
    (``s = axis x u`` the rim tangent); ``u`` moves to ``unit(u + delta s)``, ``delta = -f'/f''``
    (Newton in ``tan(psi)``: quadratic). All in frame_a coordinates; returns ``(u, delta)``."""
    _, n, K, _ = surface.distance(cl + r * u)
    s = cross(al, u)
    delta = -(n @ s) / (r * (s @ (K @ s)) - n @ u)
    v = u + delta * s
    return v / np.sqrt(v @ v), delta


def rim_point(surface, cl, al, r, steps):
    """The rim point of a disk (centre ``cl``, unit axis ``al``, radius ``r`` in m; frame_a
    coordinates) that touches ``surface``: the point of the rim circle with the least signed
    distance ``G``, where the surface normal ``n`` is perpendicular to the rim tangent. Start:
    ``u = -unit(n0 - (n0 . al) al)`` with ``n0`` the normal at the foot point of the centre
    (exact on a plane and a sphere, and for a disk in a plane normal to a cylinder's axis, where
    the centre's normal line meets the rim); then ``steps`` Newton steps
    (unrolled: a generated program traces them). Returns ``(u, delta)``: the unit direction
    from the centre to the rim point and the Newton step still left there (rad; the error
    estimate, of order the square of the last step taken).

    Examples
    --------
    A disk of radius 0.2 m, its axis tilted 0.5 rad from x, centre 0.7 m from the centre of a
    sphere of radius 1 m (a dome): the rim point found is the nearest point of the rim.

    >>> import numpy as np
    >>> from mbcomp.library.contact import rim_point
    >>> from mbcomp.library.surfaces import SphereSurface
    >>> c, ax = np.array([0.0, 0.2, 1.1]), np.array([np.cos(0.5), np.sin(0.5), 0.0])
    >>> u, delta = rim_point(SphereSurface(R=1.0, inside=False), c, ax, 0.2, steps=5)
    >>> e1 = np.cross(ax, [0, 0, 1.0]); e1 /= np.linalg.norm(e1); e2 = np.cross(ax, e1)
    >>> ring = [c + 0.2 * (np.cos(t) * e1 + np.sin(t) * e2) for t in np.linspace(0, 2 * np.pi, 200001)]
    >>> bool(np.linalg.norm(c + 0.2 * u) <= min(np.linalg.norm(ring, axis=1)) + 1e-12 and abs(delta) < 1e-14)
    True
    """
    _, n0, _, _ = surface.distance(cl)
    v = (n0 @ al) * al - n0
    u = v / np.sqrt(v @ v)
    for _ in range(steps):
        u, _ = _rim_step(surface, cl, al, u, r)
    return u, _rim_step(surface, cl, al, u, r)[1]


class _Rim:
    """A disk's contact with a surface: the holonomic row, the contact point ``P`` and the
    rolling directions ``lng``, ``lat`` (value and rate) -- see :func:`rim_geometry`."""

    __slots__ = ("normal", "n", "P", "lng", "lat", "delta", "curv")

    def __init__(self, normal, n, P, lng, lat, delta, curv):
        self.normal, self.n, self.P, self.lng, self.lat = normal, n, P, lng, lat
        self.delta, self.curv = delta, curv


def _dir(v, vdot):
    """A point or a direction as :func:`slip_velocity` and :func:`velocity_along` read it (value and rate)."""
    return VecJet(v, None, vdot, None)


def rim_geometry(surface, a, b, r, axis, steps):
    """The jets of a thin disk (radius ``r``, m; spin axis ``axis`` in frame_b coordinates,
    centre at frame_b's origin) touching ``surface`` (fixed in frame_a's axes).

    With ``u(psi)`` the rim direction (fixed in the disk for fixed ``psi``) and
    ``f(psi, t) = G(c + r u(psi))``, the row is ``Phi(t) = f(psi*(t), t)`` at the rim point
    ``f_psi = 0`` (:func:`rim_point`). Its rate is ``f_t`` (envelope theorem: ``psi*`` does not
    enter to first order): ``n . vrel``, ``vrel`` the disk's material point at ``P`` relative to
    frame_a's, so ``jac`` is that of a material point. Its bias is
    ``f_tt + f_tpsi psi*'`` with ``psi*' = -f_tpsi / f_psipsi`` (implicit function theorem),
    ``f_tt = n . acc + vrel . K vrel``, ``f_tpsi = r (s . K vrel + n . ((w_b - w_a) x s))``,
    ``f_psipsi = r^2 s . K s - r n . u``. ``psi*'`` also gives the rates of ``P = c + r u``,
    of ``lng = u x axis`` (the rolling direction) and of ``lat = n x lng``.
    """
    Ra = a.R
    aw = b.R @ axis
    u, delta = rim_point(surface, Ra.T @ (b.r - a.r), Ra.T @ aw, r, steps)
    G, nl, Kl, _ = surface.distance(Ra.T @ (b.r - a.r) + r * u)
    K = lambda v: Ra @ (Kl @ (Ra.T @ v))  # noqa: E731 -- dn/dx in world axes
    uw, n = Ra @ u, Ra @ nl
    s = cross(aw, uw)
    rho = r * uw
    P = b.r + rho
    d = P - a.r
    vb = b.v + cross(b.w, rho)
    vrel = vb - a.v - cross(a.w, d)
    ab = b.a + cross(b.alpha, rho) + cross(b.w, cross(b.w, rho))
    acc = ab - a.a - cross(a.alpha, d) - 2.0 * cross(a.w, vb - a.v) + cross(a.w, cross(a.w, d))
    Ks = K(s)
    curv = r * (s @ Ks) - n @ uw  # f_psipsi / r
    f_tpsi = r * (Ks @ vrel + n @ cross(b.w - a.w, s))
    psi_dot = -f_tpsi / (r * curv)
    bias = n @ acc + vrel @ K(vrel) + f_tpsi * psi_dot
    normal = ScalarJet(G, np.concatenate((-n, cross(n, d), n, cross(rho, n))), n @ vrel, bias)
    Pdot = vb + (r * psi_dot) * s
    udot = cross(b.w, uw) + psi_dot * s
    lng = cross(uw, aw)
    lng_dot = cross(udot, aw) + cross(uw, cross(b.w, aw))
    ndot = cross(a.w, n) + K(Pdot - a.v - cross(a.w, d))
    lat, lat_dot = cross(n, lng), cross(ndot, lng) + cross(n, lng_dot)
    return _Rim(normal, n, _dir(P, Pdot), _dir(lng, lng_dot), _dir(lat, lat_dot), delta, curv)


class DiskContact(Frictional, Joint):
    """A thin disk (knife-edge wheel) of radius ``r`` rolling without slip on a plane.

    ``frame_a`` carries the plane (through its origin, normal ``n`` in frame_a coordinates,
    pointing to the wheel's side); ``frame_b`` is the wheel's centre with spin axis ``axis``
    (frame_b coordinates). The contact point is the rim point nearest the plane,
    ``P = c + r (axis x l)`` with ``l = unit(axis x n)`` the rolling direction (where the
    centre goes for a positive spin about ``axis``). Rows: ``normal`` (holonomic, m),
    ``longitudinal`` along ``l`` and ``lateral`` along ``n x l`` (nonholonomic, m/s). The
    wheel may lean and turn; it may not lie flat (``axis`` parallel to ``n``).

    Outputs: ``N`` normal force on the wheel (N), ``F_long``, ``F_lat`` friction force on the
    wheel along ``l`` and ``n x l`` (N), contact point ``p.x|y|z`` (m, world).

    ``surface`` (a :mod:`mbcomp.library.surfaces` object fixed in frame_a's axes, in place of
    the plane ``n``): ``Plane``, ``SphereSurface``, ``CylinderSurface``, ``TorusSurface`` or
    ``HeightField``. The contact point is then the rim point deepest in the surface (least
    signed distance ``G``; there the surface normal ``n`` is perpendicular to the rim tangent),
    found by ``rim_steps`` Newton steps on the rim angle from the normal at the centre's foot
    point (:func:`rim_point`; quadratic convergence, exact from the start on a plane or a
    sphere and for a disk in a plane normal to a cylinder's axis). The ``normal``
    row is ``G(P)`` (m), ``l = u x axis`` with ``u`` from the centre to ``P``, and its jets
    are exact (envelope and implicit function theorems, :func:`rim_geometry`). The disk must
    be smaller than the surface's curvature radius along the rim; a numeric evaluation stops
    with an error naming the contact if the rim point is not found to 1e-10 m.

    Examples
    --------
    A wheel of radius 0.3 m on the ground, joined by the contact and nothing else (it floats
    in the tree with an implicit free joint): 6 speeds, 1 holonomic and 2 velocity rows.

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, DiskContact, FreeMotion, RigidBody
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> free = m.add("free", FreeMotion(r0=(0, 0, 0.3), v0=(1.5, 0, 0), w0=(0, 5.0, 0)))
    >>> wheel = m.add("wheel", RigidBody(m=2.0, I=np.diag([0.045, 0.09, 0.045])))
    >>> c = m.add("contact", DiskContact(r=0.3))
    >>> m.connect(w.frame_b, free.frame_a); m.connect(free.frame_b, wheel.frame_a)
    >>> m.connect(w.frame_b, c.frame_a); m.connect(c.frame_b, wheel.frame_a)
    >>> res = mbcomp.simulate(m, t_end=0.5)
    >>> round(float(res["contact.N"][0]), 6)  # the wheel's weight: 2 kg * 9.81 m/s^2
    19.62
    """

    tree_edge = False
    r = Param(0.3, unit="m", doc="wheel radius", check="positive")
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), check="nonzero",
              doc="plane normal, frame_a coordinates, pointing to the wheel's side")
    axis = Param((0.0, 1.0, 0.0), unit="1", shape=(3,), check="nonzero", doc="spin axis, frame_b coordinates")
    surface = Param(None, unit="1", kind="any",
                    doc="surface in frame_a's axes (mbcomp.library.surfaces; m) in place of the plane n, or None")
    rim_steps = Param(6, unit="1", kind="any", doc="Newton steps for the rim point on a surface (an integer >= 0)")
    unilateral, restitution, open0 = unilateral_params()  # one-sided: lift-off, flight, touch-down (Unilateral)
    friction = friction_param()  # stick (rolling) and slip with Coulomb friction (Frictional)

    draws_body = True

    def visuals(self, p, view):
        """The wheel: a disk of radius ``r`` about the spin axis with a bar across it (so the spin
        shows), on frame_b (the wheel draws no shape of its own); the plane or the surface, on frame_a."""
        R = z_to(p.axis)
        wheel = [Cylinder(p.r, 0.08 * p.r, R=R, frame="frame_b", color="darkgrey"),
                 Box((1.9 * p.r, 0.15 * p.r, 0.1 * p.r), R=R, frame="frame_b", color="silver")]
        if p.surface is not None:  # a translucent patch where the disk rolls (surfaces.Surface.visuals)
            return wheel + p.surface.visuals(p.r, view)
        return wheel + [Grid(R=z_to(p.n), frame="frame_a", floor=False, color="lightgrey")]

    def check_params(self, p):
        s, k = p.surface, p.rim_steps
        out = self.friction_problems(p)
        if not (isinstance(k, (int, np.integer)) and not isinstance(k, bool) and k >= 0):
            out.append(Problem(f"{self.path}.rim_steps", f"{k!r} is not a whole number >= 0", "give e.g. rim_steps=6"))
        if s is None:
            return out
        if not isinstance(s, Surface):
            return out + [Problem(f"{self.path}.surface", f"{s!r} is not a surface",
                                  "give a surface of mbcomp.library.surfaces (SphereSurface, CylinderSurface, "
                                  "TorusSurface, HeightField, Plane) or None for the plane n")]
        why = s.problem(float(p.r)) if not is_traced(p.r) else None  # worded for a ball
        why = why.replace("ball", "disk") if why else None
        return out + ([Problem(f"{self.path}.surface", why, "change r or the surface")] if why else [])

    def _rim(self, a, b, p):
        """The rim geometry on ``p.surface`` (no Newton step on a plane: the start is exact),
        checked when numeric: the rim point found, and a minimum of ``G`` along the rim."""
        steps = 0 if isinstance(p.surface, Plane) else int(p.rim_steps)
        geo = rim_geometry(p.surface, a, b, p.r, _unit(p.axis), steps)
        if is_traced(geo.delta):
            return geo
        if not geo.curv > 0.0:
            raise SimulationError(f"{self.path}: the disk (r = {p.r:g} m) is more curved than {p.surface!r} along its "
                                  f"rim, so its deepest rim point is not a contact point -> use a smaller disk or a "
                                  f"flatter surface")
        if not abs(geo.delta) * p.r < 1e-10:
            raise SimulationError(f"{self.path}: the rim point on {p.surface!r} was not found in {steps} Newton "
                                  f"steps (last step {abs(geo.delta) * p.r:.2g} m) -> give DiskContact(rim_steps=...) "
                                  f"more steps, or a disk smaller than the surface's curvature radius")
        return geo

    singularity_reason = ("the disk lies flat on the plane (spin axis parallel to the plane normal), where its "
                          "contact point is undefined")
    singularity_fix = "keep the disk from falling flat (more spin or speed, a smaller lean, a shorter run)"

    def singularity(self, a, b, p):
        """``|axis x n|``: the cosine of the lean from upright (``n`` the normal at the contact);
        0 when the disk lies flat."""
        if p.surface is not None:
            n = self._rim(a, b, p).n
            return float(np.linalg.norm(np.cross(n, b.R @ _unit(p.axis))))
        return float(np.linalg.norm(np.cross(a.R @ _unit(p.n), b.R @ _unit(p.axis))))

    def _geometry(self, a, b, p):
        n = local_vector(a, _unit(p.n), 0)
        ax = local_vector(b, _unit(p.axis), 1)
        L = ax.cross_(n)
        s = L.dot_(L).val
        if not is_traced(s) and s < 1e-16:
            raise SimulationError(f"{self.path}: the disk lies flat on the plane (spin axis parallel to the plane "
                                  f"normal), where its contact point is undefined -> start it leaning less than 90 "
                                  f"degrees, or model a flat-lying disk with a different contact")
        lng = L.unit()
        P = local_point(b, 1) + ax.cross_(lng).times(p.r)
        return n, P, lng, n.cross_(lng)

    def constraints(self, a, b, p):
        if p.surface is not None:
            return [("normal", self._rim(a, b, p).normal)]
        n, P, _, _ = self._geometry(a, b, p)
        return [("normal", (P - local_point(a, 0)).dot_(n))]

    def velocity_constraints(self, a, b, p):
        if p.surface is not None:
            geo = self._rim(a, b, p)
            P, lng, lat = geo.P, geo.lng, geo.lat
        else:
            _, P, lng, lat = self._geometry(a, b, p)
        slip = slip_velocity(a, b, P)
        return [("longitudinal", velocity_along(slip, lng)), ("lateral", velocity_along(slip, lat))]

    def outputs(self, a, b, p, lam):
        P = self._rim(a, b, p).P if p.surface is not None else self._geometry(a, b, p)[1]
        out = {"N": -lam.get("normal", np.nan), "F_long": -lam.get("longitudinal", np.nan),
               "F_lat": -lam.get("lateral", np.nan)}
        if p.friction is not None:  # the sliding friction's power: the run fills it in (mbcomp.hybrid.slip)
            out["power"] = 0.0
        out.update({f"p.{ax}": P.val[i] for i, ax in enumerate("xyz")})
        return out

    def result_notes(self, name, t, outputs):
        """A bilateral contact holds the wheel: where ``N < 0`` a real wheel would lift off (a
        unilateral one does, ``unilateral=True``)."""
        return [] if self.p.unilateral else _lift_off(name, t, outputs)


class SphereContact(Frictional, Joint):
    """A ball of radius ``r`` rolling without slip on a plane.

    ``frame_a`` carries the plane (through its origin, normal ``n`` in frame_a coordinates,
    pointing to the ball's side); ``frame_b`` is the ball's centre. The contact point is
    ``P = c - r n``. Rows: ``normal`` (holonomic, m) and ``slip_1``, ``slip_2`` along the
    plane directions ``t1``, ``t2 = n x t1`` (nonholonomic, m/s), ``t1`` the frame_a axis
    most nearly in the plane, projected onto it (``t1 = x, t2 = y`` for ``n = z``).

    Outputs: ``N`` normal force on the ball (N), ``F_1``, ``F_2`` friction force on the ball
    along ``t1``, ``t2`` (N), contact point ``p.x|y|z`` (m, world).

    ``surface`` (a :mod:`mbcomp.library.surfaces` object fixed in frame_a's axes, in place of
    the plane ``n``): :class:`~mbcomp.library.surfaces.SphereSurface` (a bowl or a dome),
    ``CylinderSurface``, ``TorusSurface``, ``HeightField`` (``z = h(x, y)``) or ``Plane``. The
    centre then runs on the offset surface: the ``normal`` row is the centre's signed distance
    from the surface minus ``r`` (m), the contact point ``P = c - r n`` with ``n`` the surface
    normal at the foot point, and ``slip_1``, ``slip_2`` are taken along the unit tangents
    ``t1 = unit(e - (e.n) n)``, ``t2 = n x t1`` (``e`` the surface's reference axis; see the
    module :mod:`mbcomp.library.surfaces`). The run stops where ``n`` meets ``e``, the
    tangent basis's singularity (90 degrees from a bowl's pole).

    Examples
    --------
    >>> from mbcomp.library import SphereContact
    >>> c = SphereContact(r=0.1)
    >>> c.tree_edge, c.nq
    (False, 0)

    A ball of radius 0.1 m in a spherical bowl of radius 1 m (its bottom at the origin):

    >>> import mbcomp
    >>> from mbcomp.library import World, FreeMotion, RigidBody
    >>> from mbcomp.library.surfaces import SphereSurface
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> free = m.add("free", FreeMotion(r0=(0, 0, 0.1), v0=(0.2, 0, 0), w0=(0, 2.0, 0)))
    >>> ball = m.add("ball", RigidBody(m=1.0, I=0.004 * np.eye(3)))
    >>> bowl = m.add("bowl", SphereContact(r=0.1, surface=SphereSurface(R=1.0, center=(0, 0, 1.0))))
    >>> m.connect(w.frame_b, free.frame_a); m.connect(free.frame_b, ball.frame_a)
    >>> m.connect(w.frame_b, bowl.frame_a); m.connect(bowl.frame_b, ball.frame_a)
    >>> res = mbcomp.simulate(m, t_end=0.5, backend="numeric")
    >>> c = np.array([res[f"ball.r.{k}"][-1] for k in "xyz"])
    >>> round(float(np.linalg.norm(c - (0, 0, 1.0))), 9)   # the centre stays on the radius R - r
    0.9
    """

    tree_edge = False
    r = Param(0.1, unit="m", doc="ball radius", check="positive")
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), check="nonzero",
              doc="plane normal, frame_a coordinates, pointing to the ball's side")
    surface = Param(None, unit="1", kind="any",
                    doc="surface in frame_a's axes (mbcomp.library.surfaces; m) in place of the plane n, or None")
    unilateral, restitution, open0 = unilateral_params()  # one-sided: lift-off, flight, touch-down (Unilateral)
    friction = friction_param()  # stick (rolling) and slip with Coulomb friction (Frictional)

    draws_body = True

    def visuals(self, p, view):
        """The ball: a sphere of radius ``r`` with a band (so the spin shows) on frame_b (the ball
        draws no shape of its own); the plane or the surface, on frame_a."""
        ball = [Sphere(p.r, frame="frame_b", color="orange"),
                Cylinder(1.02 * p.r, 0.2 * p.r, frame="frame_b", color="white")]
        if p.surface is not None:  # a translucent patch where the ball rolls (surfaces.Surface.visuals)
            return ball + p.surface.visuals(p.r, view)
        return ball + [Grid(R=z_to(p.n), frame="frame_a", floor=False, color="lightgrey")]

    singularity_reason = ("the surface normal at the contact is along the surface's tangent reference axis, where "
                          "the contact's tangent basis is undefined")
    singularity_fix = "keep the ball nearer the bowl's pole (SphereSurface(pole=...)) or pick a surface whose basis fits"

    def check_params(self, p):
        s, out = p.surface, self.friction_problems(p)
        if s is None:
            return out
        if not isinstance(s, Surface):
            return out + [Problem(f"{self.path}.surface", f"{s!r} is not a surface",
                                  "give a surface of mbcomp.library.surfaces (SphereSurface, CylinderSurface, "
                                  "TorusSurface, HeightField, Plane) or None for the plane n")]
        why = s.problem(float(p.r)) if not is_traced(p.r) else None
        return out + ([Problem(f"{self.path}.surface", why, "change r or the surface")] if why else [])

    @property
    def has_singularity(self):
        """Only a curved surface's tangent basis has a singular position."""
        return self.p.surface is not None

    def singularity(self, a, b, p):
        """``|e x n|``: the sine of the angle between the normal and the surface's reference axis."""
        return None if p.surface is None else tangent_distance(p.surface, a, b, p.r)

    def _geometry(self, a, b, p):
        n0 = _unit(p.n)
        n = local_vector(a, n0, 0)
        P = local_point(b, 1) - n.times(p.r)
        t1, t2 = _tangents(n0)
        return n, P, local_vector(a, t1, 0), local_vector(a, t2, 0)

    def constraints(self, a, b, p):
        if p.surface is not None:
            return surface_rows(p.surface, a, b, p.r, self.path)[0]
        n, P, _, _ = self._geometry(a, b, p)
        return [("normal", (P - local_point(a, 0)).dot_(n))]

    def velocity_constraints(self, a, b, p):
        if p.surface is not None:
            return surface_rows(p.surface, a, b, p.r, self.path)[1]
        _, P, t1, t2 = self._geometry(a, b, p)
        slip = slip_velocity(a, b, P)
        return [("slip_1", velocity_along(slip, t1)), ("slip_2", velocity_along(slip, t2))]

    def outputs(self, a, b, p, lam):
        P = surface_geometry(p.surface, a, b, p.r).P if p.surface is not None else self._geometry(a, b, p)[1]
        out = {"N": -lam.get("normal", np.nan), "F_1": -lam.get("slip_1", np.nan), "F_2": -lam.get("slip_2", np.nan)}
        if p.friction is not None:  # the sliding friction's power: the run fills it in (mbcomp.hybrid.slip)
            out["power"] = 0.0
        out.update({f"p.{ax}": P.val[i] for i, ax in enumerate("xyz")})
        return out

    def result_notes(self, name, t, outputs):
        """A bilateral contact holds the ball: where ``N < 0`` a real ball would lift off (a
        unilateral one does, ``unilateral=True``)."""
        return [] if self.p.unilateral else _lift_off(name, t, outputs)


def _numbers(owner, **values):
    out = {}
    for k, v in values.items():
        try:
            arr = np.asarray(v, float)
        except (TypeError, ValueError):
            arr = np.array(np.nan)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{owner}: parameter {k}={v!r} must be a finite number (or numbers) -> fix: pass e.g. {k}=0.0")
        out[k] = arr
    return out


class RollingDisk(Model):
    """A thin disk of radius ``r`` and mass ``m`` rolling without slip on a plane.

    A composite: ``free`` (:class:`FreeMotion` from the plane frame to the centre),
    ``wheel`` (:class:`RigidBody`) and ``contact`` (:class:`DiskContact`). Connect its port
    ``plane`` to the frame carrying the plane (the world's, a tilted :class:`FixedRotation`,
    a moving platform); the plane is that frame's x-y plane, the disk on its +z side. Port
    ``center`` is the wheel's frame: x the rolling direction and z towards the top of the
    disk at zero lean and spin, y the spin axis.

    Start values are rolling coordinates in the plane frame: contact point ``x0, y0`` (m),
    ``heading0`` (rad, rolling direction from x about z), ``lean0`` (rad, rotation of the
    disk about the rolling direction; 0 upright), and the rates ``heading_rate0``,
    ``lean_rate0``, ``spin_rate0`` (rad/s; spin relative to the heading-and-lean frame, so
    the centre moves forward at ``r (spin_rate0 + heading_rate0 sin lean0)``). The centre's
    velocity is set by rolling, so the start is consistent with all three contact rows.

    Parameters
    ----------
    r : float
        Radius (m).
    m : float
        Mass (kg).
    I : array_like (3, 3), optional
        Inertia about the centre, wheel-frame axes (kg m^2); default a uniform thin disk,
        ``diag(m r^2/4, m r^2/2, m r^2/4)``.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, RollingDisk
    >>> mdl = mbcomp.Model(); w = mdl.add("world", World(g=(0, 0, -9.81)))
    >>> disk = mdl.add("disk", RollingDisk(r=0.5, m=1.0, spin_rate0=10.0))
    >>> mdl.connect(w.frame_b, disk.plane)
    >>> res = mbcomp.simulate(mdl, t_end=0.2)
    >>> round(float(res["disk.wheel.v.x"][-1]), 9)  # upright, straight: r * spin rate
    5.0
    """

    def __init__(self, r=0.3, m=1.0, I=None, x0=0.0, y0=0.0, heading0=0.0, lean0=0.0,
                 heading_rate0=0.0, lean_rate0=0.0, spin_rate0=0.0):
        super().__init__()
        v = _numbers("RollingDisk", r=r, m=m, x0=x0, y0=y0, heading0=heading0, lean0=lean0,
                     heading_rate0=heading_rate0, lean_rate0=lean_rate0, spin_rate0=spin_rate0)
        if I is None:
            I = np.diag([0.25, 0.5, 0.25]) * float(v["m"]) * float(v["r"]) ** 2
        R = rot_axis(_E[2], float(v["heading0"])) @ rot_axis(_E[0], float(v["lean0"]))
        rc = R @ np.array([0.0, 0.0, float(v["r"])])  # centre relative to the contact point
        w = (float(v["heading_rate0"]) * _E[2] + float(v["lean_rate0"]) * R[:, 0]
             + float(v["spin_rate0"]) * R[:, 1])  # world (plane-frame) angular velocity
        vc = np.cross(w, rc)  # rolling: the contact point is at rest
        r0 = np.array([float(v["x0"]), float(v["y0"]), 0.0]) + rc
        self.add("contact", DiskContact(r=float(v["r"])))
        self.add("free", FreeMotion(r0=r0, R0=R, v0=vc, w0=R.T @ w))
        self.add("wheel", RigidBody(m=float(v["m"]), I=I))
        self.connect(self["free"].frame_b, self["wheel"].frame_a)
        self.connect(self["contact"].frame_b, self["wheel"].frame_a)
        self.connect(self["free"].frame_a, self["contact"].frame_a)
        self.expose("plane", self["contact"].frame_a)
        self.expose("center", self["wheel"].frame_a)


class RollingSphere(Model):
    """A ball of radius ``r`` and mass ``m`` rolling without slip on a plane.

    A composite: ``free`` (:class:`FreeMotion` from the plane frame to the centre),
    ``ball`` (:class:`RigidBody`) and ``contact`` (:class:`SphereContact`). Connect ``plane``
    to the frame carrying the plane (its x-y plane, the ball on the +z side); ``center`` is
    the ball's frame. Start values in the plane frame: contact point ``x0, y0`` (m), centre
    velocity ``v0 = (vx, vy)`` (m/s) and spin about the normal ``spin_rate0`` (rad/s); the
    rolling angular velocity follows from no slip, ``w = z x v / r + spin z``.

    Parameters
    ----------
    r, m : float
        Radius (m) and mass (kg).
    I : array_like (3, 3), optional
        Inertia about the centre (kg m^2); default a solid ball, ``2/5 m r^2``.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, RollingSphere
    >>> mdl = mbcomp.Model(); w = mdl.add("world", World(g=(0, 0, -9.81)))
    >>> ball = mdl.add("ball", RollingSphere(r=0.1, m=0.5, v0=(1.0, 0.0)))
    >>> mdl.connect(w.frame_b, ball.plane)
    >>> res = mbcomp.simulate(mdl, t_end=0.5)
    >>> round(float(res["ball.ball.r.x"][-1]), 9)  # level plane: uniform rolling
    0.5
    """

    def __init__(self, r=0.1, m=1.0, I=None, x0=0.0, y0=0.0, v0=(0.0, 0.0), spin_rate0=0.0):
        super().__init__()
        v = _numbers("RollingSphere", r=r, m=m, x0=x0, y0=y0, v0=v0, spin_rate0=spin_rate0)
        if v["v0"].shape != (2,):
            raise ValueError(f"RollingSphere: parameter v0={v0!r} must be two numbers (vx, vy) in the plane, m/s")
        rr, mm = float(v["r"]), float(v["m"])
        if I is None:
            I = np.eye(3) * 0.4 * mm * rr ** 2
        vc = np.array([v["v0"][0], v["v0"][1], 0.0])
        w = np.cross(_E[2], vc) / rr + float(v["spin_rate0"]) * _E[2]
        self.add("contact", SphereContact(r=rr))
        self.add("free", FreeMotion(r0=(float(v["x0"]), float(v["y0"]), rr), R0=np.eye(3), v0=vc, w0=w))
        self.add("ball", RigidBody(m=mm, I=I))
        self.connect(self["free"].frame_b, self["ball"].frame_a)
        self.connect(self["contact"].frame_b, self["ball"].frame_a)
        self.connect(self["free"].frame_a, self["contact"].frame_a)
        self.expose("plane", self["contact"].frame_a)
        self.expose("center", self["ball"].frame_a)
