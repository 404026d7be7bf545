"""Massless rods between two frame origins: :class:`SphericalSpherical`, :class:`UniversalSpherical`.

Modelica MultiBody's rod joints, written against mbcomp's joint contract. A massless rod of
length ``L`` (m) joins frame_a's origin to frame_b's origin; the rod passes only a force along
itself (it has no mass to accelerate and its ends turn freely about the rod's spin), so the
two frames keep a fixed distance and are otherwise free: 5 degrees of freedom.

**Cut (loop-closing) joint.** One row ``length``, the squared form
``c = (|r_b - r_a|^2 - L^2) / (2 L)`` (m) rather than ``|r_b - r_a| - L``: no square root (the
row and its jets are polynomials in the frames' poses, cheaper to trace and compile, smooth
even through ``r_b = r_a``), and on the rod (``|r_b - r_a| = L``) its gradient is the unit rod
direction, exactly as for the root form, so the multiplier is the rod force there. Output
``f_rod`` (N): the tension, ``> 0`` when the rod pulls the two ends together (pulled, as a
rope could), ``< 0`` when it pushes them apart (in compression). From the row's multiplier
``lam`` (``M du/dt + C^T lam = f``: the row puts ``-lam d / L`` on frame_b, ``d = r_b - r_a``)
it is ``f_rod = lam |d| / L``.

**Tree edge.** Frame_b's motion relative to frame_a in 5 minimal coordinates: the rod's
direction by the two angles of a universal pair at frame_a and frame_b's orientation relative
to the rod by a unit quaternion (a spherical joint at the rod's end). With ``n1 = n_a``
(unit) and ``e0`` the part of ``e_rod`` normal to ``n1`` (unit), the second axis at zero
angles is ``n2 = e0 x n1`` and the rod frame ``A = rot(n1, phi_a) rot(n2, phi_b)`` (frame_a
coordinates; ``A = 1`` at zero angles), so

* rod direction ``e = A e0``: ``phi_a`` turns the rod about ``n1`` (fixed in frame_a),
  ``phi_b`` tilts it towards ``+n1``, about the second axis ``rot(n1, phi_a) n2``;
* ``r_rel = L e``, ``R_rel = A R(Q)``: ``Q`` is frame_b's orientation in the rod frame;
* speeds ``w_a = dphi_a/dt``, ``w_b = dphi_b/dt`` (rad/s) and ``w`` (rad/s), frame_b's angular
  velocity relative to the rod frame, in frame_b axes.

The universal pair is singular where the rod lies along ``n1`` (``phi_b = +-pi/2``): choose
``n_a`` away from the directions the rod sweeps (the default ``n_a = x`` with ``e_rod = -y``
suits a pendulum under the default gravity ``-y`` that swings in any direction but not out
to the x axis). The end of the rod moves on a sphere, so ``Hv u`` is not constant at constant
speeds: these joints give the relative bias accelerations as ``motion_bias(q, u, p)``.

As a tree edge the tension is not an output (the contract gives a tree joint's ``outputs`` no
multiplier): it is the reaction along the rod, ``f_rod = -f . e_b`` with ``f`` the result's
``<joint>.f.x|y|z`` (the force on frame_b through the joint, frame_b axes) and ``e_b`` the rod
direction in frame_b axes.
"""
import numpy as np

from mbcomp import Joint, Param, Rod, Sphere
from mbcomp.errors import Problem
from mbcomp.jets import ScalarJet, local_point
from mbcomp.kinematics import cross, matrix_to_quat, quat_rate, quat_to_matrix, rot_axis
from mbcomp.modeling.free_joint import quat_increment
from mbcomp.roles import split_start

from .checks import rotation_matrix


def _unit(v):
    return v / np.sqrt(v @ v)


def _triad(p):
    """``(n1, n2, e0)``: the first universal axis, the second at zero angles and the rod
    direction at zero angles (unit vectors, frame_a coordinates)."""
    n1 = _unit(np.asarray(p.n_a))
    e = np.asarray(p.e_rod)
    e0 = _unit(e - (e @ n1) * n1)
    return n1, cross(e0, n1), e0


class _RodJoint(Joint):
    """What both rods share: the distance row, the 5-coordinate tree edge, the tension."""

    coordinates = (("phi_a", "rad"), ("phi_b", "rad"), ("Q.w", "1"), ("Q.x", "1"), ("Q.y", "1"), ("Q.z", "1"))
    speeds = (("w_a", "rad/s"), ("w_b", "rad/s"), ("w.x", "rad/s"), ("w.y", "rad/s"), ("w.z", "rad/s"))
    output_units = {"f_rod": "N"}
    L = Param(1.0, unit="m", check="positive", doc="rod length: distance of frame_b's origin from frame_a's")
    n_a = Param((1.0, 0.0, 0.0), unit="1", shape=(3,), check="nonzero",
                doc="first universal axis (phi_a), fixed in frame_a, frame_a coordinates")
    e_rod = Param((0.0, -1.0, 0.0), unit="1", shape=(3,), check="nonzero",
                  doc="rod direction at phi_a = phi_b = 0, frame_a coordinates (its part normal to n_a)")
    phi_a0 = Param(None, unit="rad", kind="start", doc="start angle about n_a (fixed unless a Guess)")
    phi_b0 = Param(None, unit="rad", kind="start", doc="start tilt towards n_a (fixed unless a Guess)")
    R0 = Param(None, unit="1", shape=(3, 3), kind="start", check=rotation_matrix,
               doc="start orientation of frame_b relative to the rod frame (fixed unless a Guess)")
    w_a0 = Param(None, unit="rad/s", kind="start", doc="start rate of phi_a (fixed unless a Guess)")
    w_b0 = Param(None, unit="rad/s", kind="start", doc="start rate of phi_b (fixed unless a Guess)")
    w0 = Param(None, unit="rad/s", shape=(3,), kind="start",
               doc="start angular velocity of frame_b relative to the rod, frame_b axes (fixed unless a Guess)")

    def __init__(self, *, cut=False, **values):
        super().__init__(**values)
        if cut:  # this instance only closes loops (a constraint-only joint: no coordinates of its own)
            self.tree_edge, self.coordinates, self.speeds = False, (), ()

    def check_params(self, p):
        n1, e = _unit(np.asarray(p.n_a, float)), _unit(np.asarray(p.e_rod, float))
        if np.linalg.norm(cross(n1, e)) < 1e-6:
            return [Problem(self.path, f"e_rod = {np.round(p.e_rod, 6).tolist()} is parallel to the universal "
                            f"axis n_a = {np.round(p.n_a, 6).tolist()}, so the rod's zero direction is undefined",
                            "give e_rod normal to n_a (the rod direction at phi_a = phi_b = 0)")]
        return []

    def visuals(self, p, view):
        """The rod from frame_a's origin to frame_b's, a small ball at each end."""
        s = view.scale
        return [Rod(0.012 * s, to="frame_b", color="grey"), Sphere(0.025 * s, color="grey"),
                Sphere(0.025 * s, frame="frame_b", color="grey")]

    # --- tree edge ----------------------------------------------------------------------
    def start(self, p):
        (fa, kfa), (fb, kfb) = split_start(p.phi_a0, 1), split_start(p.phi_b0, 1)
        (wa, kwa), (wb, kwb) = split_start(p.w_a0, 1), split_start(p.w_b0, 1)
        R, kR = split_start(p.R0, 9)
        w, kw = split_start(p.w0, 3)
        Q = matrix_to_quat(R.reshape(3, 3)) if p.R0 is not None else np.array([1.0, 0.0, 0.0, 0.0])
        return (np.concatenate((fa, fb, Q)), np.array([kfa, kfb, kR, kR, kR]),
                np.concatenate((wa, wb, w)), np.array([kwa, kwb, kw, kw, kw]))

    def _rod(self, q, p):
        """Rod frame ``A``, direction ``e``, second axis ``m2`` (frame_a coordinates) and ``n1``."""
        n1, n2, e0 = _triad(p)
        Ra = rot_axis(n1, q[0])
        A = Ra @ rot_axis(n2, q[1])
        return A, A @ e0, Ra @ n2, n1

    def relative(self, q, p):
        A, e, _, _ = self._rod(q, p)
        return A @ quat_to_matrix(q[2:]), p.L * e

    def motion(self, q, p):
        A, e, m2, n1 = self._rod(q, p)
        R = A @ quat_to_matrix(q[2:])
        Hw = np.column_stack((n1, m2, R))
        Hv = np.column_stack((p.L * cross(n1, e), p.L * cross(m2, e), np.zeros((3, 3))))
        return Hw, Hv

    def motion_bias(self, q, u, p):
        """``(bw, bv)``: the rates of ``Hw u`` and ``Hv u`` at constant ``u`` (rad/s^2, m/s^2,
        frame_a coordinates): the second universal axis turning with ``phi_a``, frame_b's spin
        carried by the rod, and the centripetal acceleration of the rod's end."""
        A, e, m2, n1 = self._rod(q, p)
        om = u[0] * n1 + u[1] * m2                      # the rod's angular velocity
        dom = (u[0] * u[1]) * cross(n1, m2)             # its rate at constant speeds
        bw = dom + cross(om, A @ (quat_to_matrix(q[2:]) @ u[2:]))
        bv = p.L * (cross(dom, e) + cross(om, cross(om, e)))
        return bw, bv

    def q_rate(self, q, u, p):
        return np.concatenate((u[:2], quat_rate(q[2:], u[2:])))

    def increment(self, q, du, p):
        return np.concatenate((q[:2] + du[:2], quat_increment(q[2:], du[2:])))

    # --- loop closure -------------------------------------------------------------------
    def constraints(self, a, b, p):
        d = local_point(b, 1) - local_point(a, 0)
        c = d.dot_(d).times(0.5 / p.L)                  # (|d|^2 - L^2) / (2 L)
        return [("length", ScalarJet(c.val - 0.5 * p.L, c.jac, c.dot, c.bias))]

    singularity_reason = ("the rod lies along n_a, where the tree coordinates phi_a, phi_b are singular (a "
                          "coordinate singularity: the rod itself is regular there)")
    singularity_fix = ("choose n_a (fixed in frame_a) away from the directions the rod sweeps, or make the rod a "
                       "pure constraint with cut=True")

    def singularity(self, a, b, p):
        """The sine of the angle between the rod and ``n_a`` (1); ``None`` for an instance made
        ``cut=True``, which has no coordinates to be singular."""
        if not self.tree_edge:
            return None
        d = b.r - a.r
        x = cross(a.R @ _unit(np.asarray(p.n_a)), d)
        return float(np.sqrt((x @ x) / (d @ d)))

    def outputs(self, a, b, p, lam):
        """``f_rod`` (N): the rod's tension from its row's multiplier (only as a cut joint)."""
        if "length" not in lam:
            return {}
        d = b.r - a.r
        return {"f_rod": lam["length"] * np.sqrt(d @ d) / p.L}


class SphericalSpherical(_RodJoint):
    """Massless rod of length ``L`` between a spherical joint at frame_a's origin and one at
    frame_b's origin (Modelica's ``SphericalSpherical``): 5 DOF.

    Cut: one row ``length`` = ``(|r_b - r_a|^2 - L^2) / (2 L)`` (m) and the output ``f_rod``
    (N, > 0: the rod in tension, pulling the ends together). Tree edge: coordinates
    ``phi_a``, ``phi_b`` (rad; the rod's direction by a universal pair at frame_a, axis
    ``n_a`` then the axis normal to ``n_a`` and the rod) and ``Q`` (frame_b in the rod frame),
    speeds ``w_a``, ``w_b`` (rad/s) and ``w`` (rad/s, frame_b axes); see
    :mod:`mbcomp.library.rods` for the conventions. A spherical joint at frame_a has no
    preferred axis: ``n_a`` only places the tree coordinates' singularity (the rod along
    ``n_a``, reported by ``singularity`` on a tree-capable instance), a property of the
    coordinates, not of the joint. The rod's spin about itself is no degree of freedom (it
    has no mass). ``cut=True`` makes this instance a pure constraint (no coordinates, always
    cut, no singularity), e.g. to a body added ``free=True``.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import SphericalSpherical
    >>> rod = SphericalSpherical(L=2.0, phi_a0=np.pi / 2)
    >>> R, r = rod.relative(rod.start(rod.p)[0], rod.p)   # turned 90 deg about x: -y -> -z
    >>> (np.round(r, 12) + 0.0).tolist(), rod.nu
    ([0.0, 0.0, -2.0], 5)
    """


class UniversalSpherical(_RodJoint):
    """Massless rod of length ``L`` with a universal joint at frame_a's origin and a spherical
    joint at frame_b's origin (Modelica's ``UniversalSpherical``): 5 DOF.

    The universal joint's first axis ``n_a`` is fixed in frame_a, its second is normal to
    ``n_a`` and the rod, so the rod cannot spin about itself relative to frame_a: the tree
    coordinates ``phi_a``, ``phi_b`` are the universal joint's two angles and ``Q`` is
    frame_b's orientation relative to the rod itself (in :class:`SphericalSpherical` the rod
    frame is a convention). As a constraint the two rods are the same single ``length`` row
    (the rod's spin is not observable from frame_a and frame_b, and without a rod-fixed frame
    port no torque about the rod can be passed), with the tension ``f_rod`` (N, > 0 pulling
    the ends together): frame_b moves the same under either class. The difference is what
    the tree coordinates mean, and that ``n_a`` is a physical axis here: where the rod lies
    along it the universal joint's two axes align and its angle rates grow without bound
    (Modelica asserts there), which ``singularity`` reports on a tree-capable instance
    (in SphericalSpherical the same place is only a singularity of the chosen coordinates).
    See :mod:`mbcomp.library.rods` for the conventions; ``cut=True`` as for
    SphericalSpherical.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.library import UniversalSpherical
    >>> rod = UniversalSpherical(L=1.0, n_a=(0, 0, 1), e_rod=(1, 0, 0), phi_a0=np.pi / 2, phi_b0=0.0)
    >>> (np.round(rod.relative(rod.start(rod.p)[0], rod.p)[1], 12) + 0.0).tolist()   # x turned 90 deg about z
    [0.0, 1.0, 0.0]
    """

    singularity_reason = ("the rod lies along the universal joint's first axis n_a: its two axes align and its "
                          "angle rates grow without bound")
    singularity_fix = ("choose n_a (fixed in frame_a) away from the directions the rod sweeps, or make the rod a "
                       "pure constraint with cut=True (frame_b's motion itself is regular there)")
