"""Surfaces a ball rolls on: the geometry :class:`~mbcomp.library.SphereContact` needs.

A surface is fixed in the axes of the contact's ``frame_a`` (the world's frame: a fixed
surface; a body's frame: a moving one). For a ball of radius ``r`` the centre ``c`` runs on
the *offset surface* at distance ``r`` along the normal, so the contact's holonomic row is

    G(x) - r = 0,   x = R_a^T (c - o_a)   (the centre in frame_a coordinates, m)

with ``G`` the signed distance of ``x`` from the surface (positive on the ball's side). Each
surface gives ``G``, its gradient ``n`` (the unit normal at the foot point, pointing to the
ball) and its Hessian ``K = dn/dx`` (1/m; the curvature of the offset surface, zero along
``n``), all in frame_a coordinates, by :meth:`Surface.distance`. From these
:func:`surface_rows` builds the contact's jets exactly: the row's rate is
``n . dx/dt``, its bias ``n . d2x/dt2 + dx/dt . K dx/dt``; the contact point is
``P = c - r n`` and the two no-slip rows are taken along the unit tangents
``t1 = unit(e - (e.n) n)``, ``t2 = n x t1`` for a reference axis ``e`` fixed in frame_a
(:attr:`Surface.ref`; the basis is singular only where ``n`` is parallel to ``e``).

* :class:`Plane`: ``G = n . (x - o)``, ``K = 0`` (what the contact does without a surface);
* :class:`SphereSurface`: ``G = R - |x - C|`` inside (a bowl), ``|x - C| - R`` outside (a dome);
* :class:`CylinderSurface`: the same with the distance from the axis;
* :class:`TorusSurface`: the same with the distance from the core circle (radius ``R``) and
  the tube radius ``a``;
* :class:`HeightField`: ``z = h(x, y)``, the ball above it; the foot point by Newton's method
  on ``|x - (X, Y, h(X, Y))|^2`` from the point below the centre (a fixed number of steps,
  unrolled, so a generated program traces it), ``h``'s gradient and Hessian by the
  second-order jet :class:`HeightJet`, ``K`` by the implicit function theorem.

All of it is plain arithmetic on numbers or traced scalars (no branch on a value), so a model
with a surface compiles like any other; a surface is a constant of the generated program.
"""
import numpy as np

from mbcomp import Grid, Mesh, SimulationError
from mbcomp.jets import ScalarJet, VecJet, is_traced, slip_velocity, velocity_along
from mbcomp.kinematics import cross
from mbcomp.modeling.shapes import z_to

from . import surface_patches as patches

__all__ = ["HeightJet", "Surface", "Plane", "SphereSurface", "CylinderSurface", "TorusSurface", "HeightField",
           "surface_rows", "surface_geometry", "tangent_distance"]

_E = np.eye(3)


def _vec3(v, what):
    a = np.asarray(v, float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what}={v!r} must be three finite numbers (frame_a coordinates)")
    return a


def _axis(v, what):
    a = _vec3(v, what)
    n = np.linalg.norm(a)
    if n == 0.0:
        raise ValueError(f"{what}={v!r} must not be zero -> give a direction such as (0, 0, 1)")
    return a / n


def _positive(v, what):
    x = float(v)
    if not np.isfinite(x) or x <= 0.0:
        raise ValueError(f"{what}={v!r} must be a positive length in m")
    return x


def _normal_to(k):
    """A unit vector perpendicular to ``k``: the frame axis least aligned with it, projected."""
    e = _E[int(np.argmin(np.abs(k)))]
    e = e - (e @ k) * k
    return e / np.linalg.norm(e)


def _outer(u, v):
    return np.array([[u[i] * v[j] for j in range(3)] for i in range(3)])


class Surface:
    """Base class of the surfaces (see the module's text): subclasses define :meth:`distance`
    and :attr:`ref`, and compare equal when their geometry is equal (a generated program is
    reused for an equal surface).

    Examples
    --------
    >>> from mbcomp.library.surfaces import Surface, Plane
    >>> isinstance(Plane(), Surface), Plane() == Plane((0, 0, 1))
    (True, True)
    """

    #: the tangent reference axis ``e`` (frame_a coordinates, unit)
    ref = _E[0]

    def distance(self, x):
        """``(G, n, K, err)`` at the point ``x`` (m, frame_a coordinates): signed distance (m),
        unit normal, its derivative ``dn/dx`` (1/m, 3x3) and the foot point's error bound (m;
        0 for closed forms)."""
        raise NotImplementedError

    def problem(self, r):
        """Why a ball of radius ``r`` (m) does not fit this surface, or None."""
        return None

    def visuals(self, r, view):
        """How the surface looks under a ball of radius ``r`` (m): a translucent triangulated
        patch on frame_a (:meth:`patch`) around where the ball's centre went
        (``view.track("frame_a", "frame_b")``), sized by ``view.scale`` (m) before a run."""
        track = view.track("frame_a", "frame_b") if hasattr(view, "track") else None
        points = self.patch(r, view.scale, None if track is None else np.asarray(track, float))
        return [Mesh.from_grid(points, frame="frame_a", color="lightgrey", opacity=0.45)]

    def patch(self, r, scale, track):
        """A grid of points on the surface (m, frame_a; shape (m, n, 3)) for a ball of radius
        ``r`` whose centre went through ``track`` ((k, 3), frame_a, or None); ``scale`` (m);
        the library's surfaces use :mod:`mbcomp.library.surface_patches`."""
        raise NotImplementedError(f"{type(self).__name__} has no patch to draw -> define patch(r, scale, track)")

    def _key(self):
        return (type(self).__name__,) + tuple(tuple(np.ravel(v)) if isinstance(v, np.ndarray) else v
                                             for v in vars(self).values())

    def __eq__(self, other):
        return type(other) is type(self) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        args = ", ".join(f"{k}={tuple(v) if isinstance(v, np.ndarray) else v!r}" for k, v in vars(self).items())
        return f"{type(self).__name__}({args})"


class Plane(Surface):
    """The plane through ``origin`` with unit normal ``n`` (frame_a coordinates, pointing to
    the ball's side): ``G = n . (x - origin)``, ``K = 0``. Tangent reference: the frame axis
    most nearly in the plane (``t1 = x, t2 = y`` for ``n = z``), as the contact without a surface.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.surfaces import Plane
    >>> G, n, K, err = Plane(n=(0, 0, 2)).distance(np.array([1.0, 2.0, 0.5]))
    >>> float(G), n.tolist()
    (0.5, [0.0, 0.0, 1.0])
    """

    def __init__(self, n=(0.0, 0.0, 1.0), origin=(0.0, 0.0, 0.0)):
        self.n = _axis(n, "Plane: n")
        self.origin = _vec3(origin, "Plane: origin")
        self.ref = _normal_to(self.n)

    def distance(self, x):
        return (x - self.origin) @ self.n, self.n, np.zeros((3, 3)), 0.0

    def visuals(self, r, view):
        """A grid through ``origin`` normal to ``n``, fitted by the scene to the motion."""
        return [Grid(r=self.origin, R=z_to(self.n), frame="frame_a", floor=False, color="lightgrey")]


class _Round(Surface):
    """Sphere, cylinder and torus: the distance ``s`` from a core (point, line, circle) with
    gradient ``m`` and Hessian ``S``; inside, ``G = radius - s``, outside ``G = s - radius``."""

    def _side(self, s, m, S, radius):
        if self.inside:
            return radius - s, -m, -S, 0.0
        return s - radius, m, S, 0.0

    def problem(self, r):
        rad = self._radius()
        if self.inside and not r < rad:
            return (f"the ball (r = {r:g} m) does not fit inside {self!r} (radius {rad:g} m) -> use a smaller ball "
                    f"or a larger surface")
        return None


class SphereSurface(_Round):
    """A sphere of radius ``R`` (m) about ``center`` (frame_a coordinates, m): a bowl with the
    ball inside (``inside=True``) or a dome with the ball outside. The centre runs on the
    sphere of radius ``R - r`` (inside) or ``R + r``: the row is ``R - r - |c - C|`` (inside).
    ``pole`` (frame_a coordinates) is the bowl's axis: the tangent basis is singular only on
    the equator 90 degrees from it, where ``n`` is along the reference axis.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.surfaces import SphereSurface
    >>> bowl = SphereSurface(R=1.0, center=(0, 0, 1.0))
    >>> G, n, K, err = bowl.distance(np.array([0.0, 0.0, 0.1]))   # 0.1 m above the bottom
    >>> round(float(G), 12), (n + 0.0).tolist(), round(float(K[0, 0]), 12)   # K = -1/(R - G) across
    (0.1, [0.0, 0.0, 1.0], -1.111111111111)
    """

    def __init__(self, R=1.0, center=(0.0, 0.0, 0.0), inside=True, pole=(0.0, 0.0, 1.0)):
        self.R = _positive(R, "SphereSurface: R")
        self.center = _vec3(center, "SphereSurface: center")
        self.inside = bool(inside)
        self.pole = _axis(pole, "SphereSurface: pole")
        self.ref = _normal_to(self.pole)

    def _radius(self):
        return self.R

    def distance(self, x):
        d = x - self.center
        s = np.sqrt(d @ d)
        u = d / s
        return self._side(s, u, (_E - _outer(u, u)) / s, self.R)

    patch = patches.sphere_cap


class CylinderSurface(_Round):
    """A circular cylinder of radius ``R`` (m) about the line through ``center`` along ``axis``
    (frame_a coordinates): the ball inside (a pipe; a half-pipe is its lower half) or outside.
    The row is ``R - r - rho`` (inside), ``rho`` the centre's distance from the axis. Tangents:
    ``t1 = axis``, ``t2 = n x axis`` (never singular).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.surfaces import CylinderSurface
    >>> pipe = CylinderSurface(R=0.5, axis=(1, 0, 0), center=(0, 0, 0.5))
    >>> G, n, K, err = pipe.distance(np.array([3.0, 0.0, 0.2]))
    >>> round(float(G), 12), (n + 0.0).tolist(), abs(float(K[0, 0]))   # no curvature along the axis
    (0.2, [0.0, 0.0, 1.0], 0.0)
    """

    def __init__(self, R=1.0, axis=(1.0, 0.0, 0.0), center=(0.0, 0.0, 0.0), inside=True):
        self.R = _positive(R, "CylinderSurface: R")
        self.axis = _axis(axis, "CylinderSurface: axis")
        self.center = _vec3(center, "CylinderSurface: center")
        self.inside = bool(inside)
        self.ref = self.axis

    def _radius(self):
        return self.R

    def distance(self, x):
        k = self.axis
        d = x - self.center
        dp = d - (d @ k) * k
        s = np.sqrt(dp @ dp)
        u = dp / s
        return self._side(s, u, (_E - _outer(k, k) - _outer(u, u)) / s, self.R)

    patch = patches.half_pipe


class TorusSurface(_Round):
    """A torus about ``axis`` through ``center`` (frame_a coordinates): core circle of radius
    ``R`` (m), tube radius ``a`` (m). ``inside=True``: the ball rolls inside the tube (a ring
    channel); ``False``: on its outer surface (e.g. around the top circle). With ``s`` the
    centre's distance from the core circle, the row is ``a - r - s`` (inside) or
    ``s - a - r``. The tangent reference is perpendicular to ``axis``: the basis is singular
    only at the two points of the tube's equator where ``n`` is along it.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.surfaces import TorusSurface
    >>> ring = TorusSurface(R=2.0, a=0.5, inside=False)
    >>> G, n, K, err = ring.distance(np.array([2.0, 0.0, 0.6]))   # 0.1 m above the top circle
    >>> round(float(G), 12), n.tolist()
    (0.1, [0.0, 0.0, 1.0])
    """

    def __init__(self, R=2.0, a=0.5, axis=(0.0, 0.0, 1.0), center=(0.0, 0.0, 0.0), inside=True):
        self.R = _positive(R, "TorusSurface: R")
        self.a = _positive(a, "TorusSurface: a")
        if not self.a < self.R:
            raise ValueError(f"TorusSurface: tube radius a={a!r} must be smaller than the core radius R={R!r}")
        self.axis = _axis(axis, "TorusSurface: axis")
        self.center = _vec3(center, "TorusSurface: center")
        self.inside = bool(inside)
        self.ref = _normal_to(self.axis)

    def _radius(self):
        return self.a

    def distance(self, x):
        k = self.axis
        d = x - self.center
        dp = d - (d @ k) * k
        rho = np.sqrt(dp @ dp)
        u = dp / rho
        e = d - self.R * u  # from the nearest core-circle point to x
        s = np.sqrt(e @ e)
        m = e / s
        T = _E - _outer(k, k) - _outer(u, u)  # the circumferential direction's projector
        return self._side(s, m, (_E - _outer(m, m) - (self.R / rho) * T) / s, self.a)

    patch = patches.whole_torus


class HeightJet:
    """A number with its gradient and Hessian in the two surface coordinates ``(x, y)``:
    second-order forward differentiation of a height function ``h(x, y)``.

    ``val`` is the value, ``g = (d/dx, d/dy)``, ``H = (d2/dx2, d2/dxdy, d2/dy2)``. Arithmetic
    ``+ - * / **`` with numbers and other jets, and the numpy functions ``np.sqrt``,
    ``np.sin``, ``np.cos``, ``np.tan``, ``np.exp``, ``np.log``, ``np.tanh``, ``np.sinh``,
    ``np.cosh``, ``np.arctan`` apply the chain rule to second order; values may be numbers or
    traced scalars (a generated program traces ``h``).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library.surfaces import HeightJet
    >>> x, y = HeightJet.variables(0.3, -0.2)
    >>> z = x * x * y + np.sin(y)          # h = x^2 y + sin y
    >>> float(z.g[0]), round(float(z.H[1]), 12), round(float(z.H[2]), 12)   # 2 x y, 2 x, -sin y
    (-0.12, 0.6, 0.198669330795)
    """

    __slots__ = ("val", "g", "H")

    def __init__(self, val, g=(0.0, 0.0), H=(0.0, 0.0, 0.0)):
        self.val, self.g, self.H = val, tuple(g), tuple(H)

    @classmethod
    def variables(cls, x, y):
        """The coordinates ``x, y`` (m) as jets."""
        return cls(x, (1.0, 0.0)), cls(y, (0.0, 1.0))

    @staticmethod
    def _lift(o):
        if isinstance(o, HeightJet):
            return o
        if isinstance(o, np.ndarray):
            return None
        return HeightJet(o)

    def __add__(self, o):
        o = self._lift(o)
        if o is None:
            return NotImplemented
        return HeightJet(self.val + o.val, (self.g[0] + o.g[0], self.g[1] + o.g[1]),
                         tuple(a + b for a, b in zip(self.H, o.H)))

    __radd__ = __add__

    def __neg__(self):
        return HeightJet(-self.val, (-self.g[0], -self.g[1]), tuple(-a for a in self.H))

    def __pos__(self):
        return self

    def __sub__(self, o):
        o = self._lift(o)
        return NotImplemented if o is None else self + (-o)

    def __rsub__(self, o):
        o = self._lift(o)
        return NotImplemented if o is None else o + (-self)

    def __mul__(self, o):
        o = self._lift(o)
        if o is None:
            return NotImplemented
        (a, (ax, ay), (axx, axy, ayy)), (b, (bx, by), (bxx, bxy, byy)) = (self.val, self.g, self.H), (o.val, o.g, o.H)
        return HeightJet(a * b, (a * bx + b * ax, a * by + b * ay),
                         (a * bxx + b * axx + 2.0 * ax * bx, a * bxy + b * axy + ax * by + ay * bx,
                          a * byy + b * ayy + 2.0 * ay * by))

    __rmul__ = __mul__

    def _chain(self, f0, f1, f2):
        """``f(self)`` from ``f, f', f''`` at ``self.val``."""
        gx, gy = self.g
        hxx, hxy, hyy = self.H
        return HeightJet(f0, (f1 * gx, f1 * gy), (f1 * hxx + f2 * gx * gx, f1 * hxy + f2 * gx * gy, f1 * hyy + f2 * gy * gy))

    def recip(self):
        r = 1.0 / self.val
        return self._chain(r, -r * r, 2.0 * r * r * r)

    def __truediv__(self, o):
        o = self._lift(o)
        return NotImplemented if o is None else self * o.recip()

    def __rtruediv__(self, o):
        o = self._lift(o)
        return NotImplemented if o is None else o * self.recip()

    def __pow__(self, k):
        if isinstance(k, HeightJet):
            return (self.log() * k).exp()
        if isinstance(k, np.ndarray):
            return NotImplemented
        if k == 2:
            return self * self
        if k == 1:
            return self
        v = self.val
        return self._chain(v ** k, k * v ** (k - 1), k * (k - 1) * v ** (k - 2))

    def __rpow__(self, c):
        return (self * np.log(c)).exp()

    def sqrt(self):
        s = np.sqrt(self.val)
        return self._chain(s, 0.5 / s, -0.25 / (s * self.val))

    def exp(self):
        e = np.exp(self.val)
        return self._chain(e, e, e)

    def log(self):
        r = 1.0 / self.val
        return self._chain(np.log(self.val), r, -r * r)

    def sin(self):
        s, c = np.sin(self.val), np.cos(self.val)
        return self._chain(s, c, -s)

    def cos(self):
        s, c = np.sin(self.val), np.cos(self.val)
        return self._chain(c, -s, -c)

    def tan(self):
        t = np.tan(self.val)
        d = 1.0 + t * t
        return self._chain(t, d, 2.0 * t * d)

    def tanh(self):
        t = np.tanh(self.val)
        d = 1.0 - t * t
        return self._chain(t, d, -2.0 * t * d)

    def sinh(self):
        s, c = np.sinh(self.val), np.cosh(self.val)
        return self._chain(s, c, s)

    def cosh(self):
        s, c = np.sinh(self.val), np.cosh(self.val)
        return self._chain(c, s, c)

    def arctan(self):
        d = 1.0 / (1.0 + self.val * self.val)
        return self._chain(np.arctan(self.val), d, -2.0 * self.val * d * d)


class HeightField(Surface):
    """The surface ``z = h(x, y)`` (frame_a coordinates, m), the ball on its ``+z`` side.

    ``h`` is a function of two coordinates written with arithmetic and numpy functions (it is
    called with :class:`HeightJet` arguments, for its gradient and Hessian, and traced in a
    generated program); it must be smooth and single-valued. The foot point ``(X, Y)`` of the
    centre ``c`` minimizes ``|c - (X, Y, h(X, Y))|^2``: ``newton_steps`` Newton steps from
    ``(c_x, c_y)``, unrolled. Newton's method converges quadratically, so from a start
    ``e0`` away (about ``r |grad h|``) the error after ``k`` steps is of order
    ``e0 (e0 kappa)^(2^k - 1)`` (``kappa`` the curvature): machine precision after 3 to 4
    steps for a ball smaller than the curvature radius; the default 6 leaves a margin. A
    numeric evaluation raises an error naming the contact if the last step still moved the foot
    point by more than 1e-9 m (increase ``newton_steps``; the ball may also be larger than
    the surface's curvature radius, where the foot point is not unique).

    With ``hx, hy`` the slopes and ``Hh`` the Hessian of ``h`` at the foot point:
    ``n = (-hx, -hy, 1) / W``, ``W = sqrt(1 + hx^2 + hy^2)``; ``G = (c - P_s) . n``; and
    ``K = dn/dc = (I - n n^T) / W * M * A^-1 [I | grad h]`` with ``M = -[Hh; 0]`` (3x2) and
    ``A = I + grad h grad h^T + (h - c_z) Hh`` (implicit function theorem on the foot point's
    equation). Tangent reference: x (a height field's normal is never horizontal).

    Examples
    --------
    A spherical bowl of radius 1 m written as a height field gives the sphere's distance:

    >>> import numpy as np
    >>> from mbcomp.library.surfaces import HeightField, SphereSurface
    >>> cap = HeightField(lambda x, y: 1.0 - np.sqrt(1.0 - x**2 - y**2))
    >>> c = np.array([0.2, -0.1, 0.15])
    >>> G, n, K, err = cap.distance(c)
    >>> Gs, ns, Ks, _ = SphereSurface(R=1.0, center=(0, 0, 1.0)).distance(c)
    >>> bool(abs(G - Gs) < 1e-14 and np.allclose(n, ns, atol=1e-14) and np.allclose(K, Ks, atol=1e-12))
    True
    """

    def __init__(self, h, newton_steps=6):
        if not callable(h):
            raise ValueError(f"HeightField: h={h!r} must be a function h(x, y) -> height in m")
        self.h = h
        self.newton_steps = int(newton_steps)
        if self.newton_steps < 1:
            raise ValueError(f"HeightField: newton_steps={newton_steps!r} must be at least 1")

    def _eval(self, X, Y):
        try:
            z = self.h(*HeightJet.variables(X, Y))
        except TypeError as exc:
            raise TypeError(f"HeightField: h={getattr(self.h, '__name__', self.h)} is called with HeightJet numbers (for "
                            f"its slope and curvature) and must be written with arithmetic and numpy functions "
                            f"(np.sqrt, not math.sqrt; no float(), no if on x or y): {exc}") from exc
        return z if isinstance(z, HeightJet) else HeightJet(z)

    def distance(self, x):
        cx, cy, cz = x[0], x[1], x[2]
        X, Y, step = cx, cy, 0.0
        for _ in range(self.newton_steps):
            z = self._eval(X, Y)
            (hx, hy), (hxx, hxy, hyy), dz = z.g, z.H, z.val - cz
            g1, g2 = X - cx + dz * hx, Y - cy + dz * hy
            a11, a12, a22 = 1.0 + hx * hx + dz * hxx, hx * hy + dz * hxy, 1.0 + hy * hy + dz * hyy
            det = a11 * a22 - a12 * a12
            dX, dY = (a22 * g1 - a12 * g2) / det, (a11 * g2 - a12 * g1) / det
            X, Y = X - dX, Y - dY
            step = dX * dX + dY * dY
        z = self._eval(X, Y)
        (hx, hy), (hxx, hxy, hyy), dz = z.g, z.H, z.val - cz
        W = np.sqrt(1.0 + hx * hx + hy * hy)
        n = np.array([-hx / W, -hy / W, 1.0 / W])
        G = (cx - X) * n[0] + (cy - Y) * n[1] - dz * n[2]
        a11, a12, a22 = 1.0 + hx * hx + dz * hxx, hx * hy + dz * hxy, 1.0 + hy * hy + dz * hyy
        det = a11 * a22 - a12 * a12
        Ainv = np.array([[a22, -a12], [-a12, a11]]) / det
        B = np.array([[1.0, 0.0, hx], [0.0, 1.0, hy]])
        M = -np.array([[hxx, hxy], [hxy, hyy], [0.0, 0.0]])
        K = ((_E - _outer(n, n)) / W) @ (M @ (Ainv @ B))
        err = step if is_traced(step) else float(np.sqrt(step))
        return G, n, K, err

    patch = patches.height_grid

    def _key(self):
        return ("HeightField", self.h, self.newton_steps)

    def __repr__(self):
        return f"HeightField({getattr(self.h, '__name__', 'h')}, newton_steps={self.newton_steps})"


class _Geometry:
    """The jets of a ball on a surface (see :func:`surface_rows`)."""

    __slots__ = ("normal", "n", "P", "t1", "t2", "err")

    def __init__(self, normal, n, P, t1, t2, err):
        self.normal, self.n, self.P, self.t1, self.t2, self.err = normal, n, P, t1, t2, err


def _direction(v, vdot):
    """A direction for :func:`~mbcomp.jets.velocity_along` or a point for
    :func:`~mbcomp.jets.slip_velocity`: both read only its value and rate."""
    return VecJet(v, None, vdot, None)


def surface_geometry(surface, a, b, r):
    """The geometry of a ball of radius ``r`` (m) centred at frame_b's origin on ``surface``
    fixed in frame_a: the holonomic row ``G(x) - r`` as a :class:`~mbcomp.jets.ScalarJet`
    (exact value, gradient, rate and bias from ``n`` and ``K``), the normal ``n``, the contact
    point ``P = c - r n`` and the unit tangents ``t1, t2`` (value and rate), and the foot
    point's error bound (m)."""
    d = b.r - a.r
    ddot = b.v - a.v
    vrel = ddot - cross(a.w, d)  # the centre's velocity relative to frame_a (world axes)
    G, nl, Kl, err = surface.distance(a.R.T @ d)
    n = a.R @ nl
    Kv = a.R @ (Kl @ (a.R.T @ vrel))
    ndot = cross(a.w, n) + Kv
    acc = b.a - a.a - cross(a.alpha, d) - 2.0 * cross(a.w, ddot) + cross(a.w, cross(a.w, d))
    jac = np.concatenate((-n, cross(n, d), n, np.zeros(3)))
    normal = ScalarJet(G - r, jac, n @ vrel, n @ acc + vrel @ Kv)
    e = a.R @ surface.ref
    edot = cross(a.w, e)
    en = e @ n
    m = e - en * n
    mdot = edot - (edot @ n + e @ ndot) * n - en * ndot
    L = np.sqrt(m @ m)
    t1 = m / L
    t1dot = (mdot - (t1 @ mdot) * t1) / L
    t2, t2dot = cross(n, t1), cross(ndot, t1) + cross(n, t1dot)
    P = _direction(b.r - r * n, b.v - r * ndot)
    return _Geometry(normal, n, P, _direction(t1, t1dot), _direction(t2, t2dot), err)


def surface_rows(surface, a, b, r, who="contact"):
    """The contact's rows on ``surface``: ``[("normal", row)]`` and the velocity rows
    ``[("slip_1", g1), ("slip_2", g2)]`` (no slip along ``t1``, ``t2`` at ``P``), with the
    geometry. ``who`` names the contact in the error raised by a numeric evaluation whose
    height-field foot point did not converge.

    Examples
    --------
    A ball of radius 0.1 m resting at the bottom of a bowl of radius 1 m, at rest: the rows
    and their rates vanish, and the normal row's gradient on the ball is the normal ``z``.

    >>> import numpy as np
    >>> from mbcomp.jets import FrameJet
    >>> from mbcomp.library.surfaces import SphereSurface, surface_rows
    >>> a = FrameJet.ground(nu=0); b = FrameJet.ground(nu=0, r=[0, 0, 0.1])
    >>> rows, vrows, geo = surface_rows(SphereSurface(R=1.0, center=(0, 0, 1.0)), a, b, 0.1)
    >>> abs(round(float(rows[0][1].val), 15)), rows[0][1].jac[6:9].tolist(), geo.P.val.tolist()
    (0.0, [0.0, 0.0, 1.0], [0.0, 0.0, 0.0])
    """
    geo = surface_geometry(surface, a, b, r)
    if not is_traced(geo.err) and geo.err > 1e-9:
        raise SimulationError(f"{who}: the foot point on {surface!r} did not converge in {surface.newton_steps} "
                              f"Newton steps (last step {geo.err:.2g} m) -> give HeightField(..., newton_steps=...) "
                              f"more steps, or check that the ball is smaller than the surface's curvature radius")
    slip = slip_velocity(a, b, geo.P)
    return ([("normal", geo.normal)],
            [("slip_1", velocity_along(slip, geo.t1)), ("slip_2", velocity_along(slip, geo.t2))], geo)


def tangent_distance(surface, a, b, r):
    """``|e x n|`` (numeric): the sine of the angle between the surface normal at the contact
    and the tangent reference axis, 0 where the tangent basis is undefined."""
    geo = surface_geometry(surface, a, b, r)
    return float(np.linalg.norm(cross(a.R @ surface.ref, geo.n)))
