"""Compliant stops on joint axes: a penalty torque beyond the limits, no events.

``ElasticStop`` is the compliant alternative to a joint's rigid stops
(``Revolute(limits=(lo, hi), restitution=e)``, which are located as events and act by
impulses): a :class:`~mbcomp.FlangeElement` between a joint's ``support`` (flange_a) and
``axis`` (flange_b) that pushes back with a spring ``c`` and a damper ``d`` while the
relative angle is beyond ``lo`` or ``hi``, and does nothing between them. The run needs no
events and no modes; the contact's stiffness is in the equations instead (a stiff contact
wants an implicit method, or small steps).

The law is written with ``abs`` only (no ``if`` on a state), so it traces into the
generated program without guards.
"""
from mbcomp import Flange, FlangeElement, Param
from mbcomp.errors import Problem

from .laws import neg, pos, smax, smin

__all__ = ["ElasticStop"]



class ElasticStop(FlangeElement):
    """Compliant rotational stops at ``lo`` and ``hi``: spring and damper beyond the limits.

    With the relative angle ``phi = phi_b - phi_a`` (rad; connect flange_a to a joint's
    ``support`` and flange_b to its ``axis``, so ``phi`` is the joint angle) and its rate
    ``w`` (rad/s), the stop torque ``tau`` (N m, ``> 0`` pushes ``phi`` down) is

    * ``0`` for ``lo <= phi <= hi`` (no contact),
    * beyond ``hi``, with ``tau_c = c (phi - hi)`` and ``tau_d = d w``:
      ``tau = max(0, tau_c + min(tau_c, tau_d))``,
    * below ``lo``, with ``tau_c = c (phi - lo)``: ``tau = min(0, tau_c + max(tau_c, tau_d))``,

    the damping limited as in ``ElastoGear``'s backlash (Modelica's ``ElastoBacklash``): it
    never pulls the axis into the stop (``tau`` keeps the sign of the stop in contact) and
    never exceeds the spring torque, so ``tau`` is continuous in ``phi`` and ``w`` (only the
    stiffness jumps, from 0 to ``c``, at contact). The element applies ``+tau`` to flange_a
    and ``-tau`` to flange_b. Potential energy ``c (phi - hi)^2 / 2`` beyond ``hi``,
    ``c (phi - lo)^2 / 2`` below ``lo``, 0 between; the damping only takes energy out.

    A rotor of inertia ``J`` hitting an undamped stop stays in contact for half a period,
    ``pi sqrt(J / c)`` s, and leaves at the speed it came with; as ``c`` grows the motion
    approaches the rigid stop's with ``restitution = 1``. With damping the rebound's speed
    ratio depends only on ``d / sqrt(c J)`` (the law is linear in ``(phi - hi, w)`` on each
    of its pieces).

    Parameters
    ----------
    lo, hi : float
        Lower and upper limit of ``phi`` (rad), ``lo <= hi``.
    c : float
        Contact stiffness (N m/rad).
    d : float
        Contact damping (N m s/rad), acting only in contact and never pulling.

    Examples
    --------
    >>> from mbcomp.library import ElasticStop
    >>> s = ElasticStop(lo=-0.5, hi=0.5, c=1000.0, d=0.0)
    >>> out = s.flange_forces(0.0, {"flange_a": (0.0, 0.0), "flange_b": (0.51, 2.0)}, s.p)
    >>> round(out["flange_b"], 9), round(s.potential({"flange_a": (0.0, 0.0), "flange_b": (0.51, 2.0)}, s.p), 9)
    (-10.0, 0.05)
    >>> abs(s.flange_forces(0.0, {"flange_a": (0.0, 0.0), "flange_b": (0.2, 2.0)}, s.p)["flange_b"])   # between
    0.0
    """

    axis_kind = "rotational"
    conservative = True
    dissipative = True
    flange_a = Flange("support side (the joint's support flange)")
    flange_b = Flange("moving side (the joint's axis flange)")
    lo = Param(-1.0, unit="rad", doc="lower limit of the relative angle phi_b - phi_a")
    hi = Param(1.0, unit="rad", doc="upper limit of the relative angle phi_b - phi_a")
    c = Param(1e4, unit="N m/rad", doc="contact stiffness beyond the limits", check="nonnegative")
    d = Param(0.0, unit="N m s/rad", doc="contact damping (only in contact, never pulling)", check="nonnegative")
    output_units = {"tau": "N m", "phi_rel": "rad", "w_rel": "rad/s", "penetration": "rad"}

    def check_params(self, p):
        """``lo > hi`` is a problem naming both (the stops would overlap)."""
        if p.lo > p.hi:
            return [Problem(f"{self.path}.lo", f"lo = {p.lo:g} rad is above hi = {p.hi:g} rad",
                            "give lo <= hi (the free range of the relative angle lies between them)")]
        return []

    def conserves_energy(self, p):
        return p.d == 0.0

    @staticmethod
    def relative(states):
        """``(phi, w)``: relative angle ``phi_b - phi_a`` (rad) and its rate (rad/s)."""
        (sa, va), (sb, vb) = states["flange_a"], states["flange_b"]
        return sb - sa, vb - va

    @staticmethod
    def penetration(phi, p):
        """How far ``phi`` is beyond the limits (rad): ``phi - hi > 0``, ``phi - lo < 0``, or 0."""
        return pos(phi - p.hi) + neg(phi - p.lo)

    def torque(self, phi, w, p):
        """Stop torque ``tau`` (N m) of the class's law at relative angle ``phi`` and rate ``w``."""
        tp, tn, td = p.c * pos(phi - p.hi), p.c * neg(phi - p.lo), p.d * w
        return pos(tp + smin(tp, td)) + neg(tn + smax(tn, td))

    def flange_forces(self, t, states, p):
        tau = self.torque(*self.relative(states), p)
        return {"flange_a": tau, "flange_b": -tau}

    def potential(self, states, p):
        phi, _ = self.relative(states)
        return 0.5 * p.c * self.penetration(phi, p) ** 2

    def outputs(self, t, states, p):
        """Stop torque ``tau`` (N m, > 0 at the upper stop), ``phi_rel`` (rad), ``w_rel``
        (rad/s) and ``penetration`` beyond the limits (rad, 0 between them)."""
        phi, w = self.relative(states)
        return {"tau": self.torque(phi, w, p), "phi_rel": phi, "w_rel": w, "penetration": self.penetration(phi, p)}
