"""Coulomb friction with exact stick/slip switching on a 1-DOF joint's axis.

A :class:`~mbcomp.library.Prismatic` or :class:`~mbcomp.library.Revolute` takes
``friction=SlidingFriction(mu_s, mu_k, normal)`` or ``friction=CoulombBearing(torque_max,
torque_c)``. The joint then has three modes (its :class:`StickSlipModes`, the contract of
:mod:`mbcomp.modeling.modes`; the run's side: :mod:`mbcomp.hybrid.friction`):

* ``"stick"``: a row holds the joint's rate at zero (a
  :class:`~mbcomp.modeling.events.StickRow`); its push, the friction force (N) or torque
  (N m) on the axis, is free up to the static limit ``F_s`` (``mu_s normal``, or
  ``torque_max``) either way. When the load needs more (``F_s - |push|`` falls through zero)
  the joint slips in the direction of the load (events ``"break+"``/``"break-"``);
* ``"slip+"``/``"slip-"``: the kinetic friction ``F_k`` (``mu_k normal``, or ``torque_c``)
  opposes the motion, ``-F_k`` while the speed is positive, ``+F_k`` while negative (a
  constant force per mode: no sign function, no smoothing). When the speed comes to zero
  (event ``"stick"``) the joint sticks, or, when sticking would need more than ``F_s``,
  slips on the other way at once.

The joint starts stuck when its start speed is zero, else slipping that way. The friction's
force and mode are the result's columns ``<joint>.friction`` (N or N m, on the axis, along
it) and ``<joint>.sticking`` (1 or 0); its dissipated energy ``F_k |s - s_slip|`` over every
slip is in ``energy.dissipated``.

The normal force is a parameter (N), not the joint's reaction across the axis: with the
reaction the friction force would depend on the multipliers it changes (an implicit
problem, a fixed point per evaluation, and a stick limit that moves with the load); a
constant normal force is exact for a block on a plane or a shaft with a preloaded bearing.
An end stop and a friction on the same joint are not combined yet (one mode per joint).
:class:`mbcomp.library.BearingFriction` stays the regularized law (``tanh``, no events).
"""
from dataclasses import dataclass

from mbcomp.errors import ModelError, Problem
from mbcomp.modeling.events import StickRow, Switch
from mbcomp.modeling.modes import Modes
from mbcomp.roles import split_start

__all__ = ["SlidingFriction", "CoulombBearing", "ContactFriction", "StickSlipModes"]


class _Coulomb:
    """What a joint's Coulomb friction gives: ``static`` and ``kinetic`` (N or N m)."""

    axis_kind = None

    @property
    def static(self):
        raise NotImplementedError

    @property
    def kinetic(self):
        raise NotImplementedError

    def _check(self, s, k):
        if not (s >= 0.0 and k >= 0.0):
            raise ValueError(f"{type(self).__name__}: the friction coefficients and forces must be >= 0, "
                             f"got static {s:g}, kinetic {k:g}")
        if k > s:
            raise ValueError(f"{type(self).__name__}: the kinetic friction ({k:g}) exceeds the static one ({s:g}); "
                             "a block would stick and slip again at once -> make the kinetic value <= the static")


@dataclass(frozen=True)
class SlidingFriction(_Coulomb):
    """Coulomb friction of a prismatic joint: break-away force ``mu_s normal`` (N), sliding
    force ``mu_k normal`` (N). Pass it as ``Prismatic(friction=...)`` (see the module notes).

    Parameters
    ----------
    mu_s : float
        Static friction coefficient (1).
    mu_k : float
        Kinetic (sliding) friction coefficient (1), ``<= mu_s``; default ``mu_s``.
    normal : float
        Normal force pressing the sliding surfaces together (N), constant.

    Examples
    --------
    >>> f = SlidingFriction(mu_s=0.5, mu_k=0.4, normal=10.0)
    >>> f.static, f.kinetic
    (5.0, 4.0)
    """

    mu_s: float
    mu_k: float = None
    normal: float = 1.0
    axis_kind = "translational"

    def __post_init__(self):
        if self.mu_k is None:
            object.__setattr__(self, "mu_k", self.mu_s)
        if not self.normal >= 0.0:
            raise ValueError(f"SlidingFriction: the normal force must be >= 0 N, got {self.normal:g}")
        self._check(self.mu_s, self.mu_k)

    @property
    def static(self):
        """Break-away force ``mu_s normal`` (N)."""
        return float(self.mu_s * self.normal)

    @property
    def kinetic(self):
        """Sliding force ``mu_k normal`` (N)."""
        return float(self.mu_k * self.normal)


@dataclass(frozen=True)
class CoulombBearing(_Coulomb):
    """Coulomb friction of a revolute joint (a bearing): break-away torque ``torque_max``
    (N m), sliding torque ``torque_c`` (N m). Pass it as ``Revolute(friction=...)``.

    Parameters
    ----------
    torque_max : float
        Largest torque the stuck bearing holds (N m).
    torque_c : float
        Kinetic friction torque while turning (N m), ``<= torque_max``; default
        ``torque_max``.

    Examples
    --------
    >>> CoulombBearing(torque_max=2.0, torque_c=1.5).kinetic
    1.5
    """

    torque_max: float
    torque_c: float = None
    axis_kind = "rotational"

    def __post_init__(self):
        if self.torque_c is None:
            object.__setattr__(self, "torque_c", self.torque_max)
        self._check(self.torque_max, self.torque_c)

    @property
    def static(self):
        """Break-away torque (N m)."""
        return float(self.torque_max)

    @property
    def kinetic(self):
        """Sliding torque (N m)."""
        return float(self.torque_c)


@dataclass(frozen=True)
class ContactFriction(_Coulomb):
    """Coulomb friction at a rolling contact (``SphereContact``, ``DiskContact``): it rolls
    (sticks) while the rolling rows' force stays in the cone ``|F_t| <= mu_s N`` and slides
    with ``-mu_k N`` against the slip velocity otherwise, ``N`` the contact's normal force
    (its row's multiplier, not a parameter). Pass it as ``SphereContact(unilateral=True,
    friction=ContactFriction(mu_s, mu_k))``; the run's side is :mod:`mbcomp.hybrid.slip`.

    Parameters
    ----------
    mu_s : float
        Static friction coefficient (1).
    mu_k : float
        Kinetic friction coefficient (1), ``<= mu_s``; default ``mu_s``.

    Examples
    --------
    >>> f = ContactFriction(0.5, 0.3)
    >>> f.static, f.kinetic
    (0.5, 0.3)
    """

    mu_s: float
    mu_k: float = None
    axis_kind = "contact"

    def __post_init__(self):
        if self.mu_k is None:
            object.__setattr__(self, "mu_k", self.mu_s)
        self._check(self.mu_s, self.mu_k)

    @property
    def static(self):
        """Static coefficient ``mu_s`` (1)."""
        return float(self.mu_s)

    @property
    def kinetic(self):
        """Kinetic coefficient ``mu_k`` (1)."""
        return float(self.mu_k)


def friction_ok(f, kind):
    """The ``friction`` parameter's check for a joint whose axis is ``kind``."""
    if f is None:
        return None
    if not isinstance(f, _Coulomb):
        return "must be SlidingFriction(...) (prismatic) or CoulombBearing(...) (revolute), or None"
    if f.axis_kind != kind:
        want = "SlidingFriction" if kind == "translational" else "CoulombBearing"
        return f"a {kind} axis takes {want}(...), not {type(f).__name__}"
    return None


class StickSlipModes(Modes):
    """The modes of a Coulomb friction on a 1-DOF joint's axis: ``"stick"``, ``"slip+"``,
    ``"slip-"`` (see the module notes).

    Parameters
    ----------
    start : str
        The start mode (``"stick"`` at a zero start speed, else the slip of its sign).
    static, kinetic : float
        The break-away limit ``F_s`` and the kinetic friction ``F_k`` (N, or N m on a
        rotational axis).

    Examples
    --------
    >>> m = StickSlipModes("slip+", static=3.0, kinetic=2.0)
    >>> m.has_force, m.force("slip+"), m.force("stick"), m.action("stick", "slip+")
    (True, -2.0, 0.0, Switch(mode='stick'))
    >>> m.rows("stick")
    [StickRow(name='stick', sign=1.0, at=0.0, limit=3.0)]
    """

    #: kinetic friction on the joint's own speed while it slips
    has_force = True

    def __init__(self, start, static, kinetic):
        super().__init__(start)
        self.static, self.kinetic = float(static), float(kinetic)

    def events(self, q, u, mode):
        """``"stick"``: the slip speed (m/s or rad/s) coming to zero; none while stuck."""
        if mode not in ("slip+", "slip-"):
            return []
        return [("stick", u[0], -1 if mode == "slip+" else 1)]

    def action(self, name, mode):
        """Slip the way the load breaks away (``"break+"``/``"break-"``), stick at a ``"stick"``."""
        return Switch({"break+": "slip+", "break-": "slip-", "stick": "stick"}[name])

    def rows(self, mode):
        """The :class:`~mbcomp.modeling.events.StickRow` holding the rate while stuck."""
        return [StickRow("stick", 1.0, 0.0, limit=self.static)] if mode == "stick" else []

    def force(self, mode):
        """The kinetic friction on the joint's own speed in ``mode`` (N or N m; 0 stuck)."""
        if mode not in ("slip+", "slip-"):
            return 0.0
        return -self.kinetic if mode == "slip+" else self.kinetic


class _Friction:
    """The joint's side of Coulomb friction (:class:`StickSlipModes`), ahead of the stops'
    mixin in the joint's bases: without ``friction`` the joint's modes are the stops'."""

    #: the friction's work is dissipated (energy balance)
    dissipative = True

    def modes(self, p):
        if p.friction is None:
            return super().modes(p)
        wrong = friction_ok(p.friction, self.axis_kind)
        if wrong:
            raise ModelError([Problem(self.__class__.__name__, f"friction= {wrong}", "pass the friction of its axis")])
        if p.limits is not None:
            raise ModelError([Problem(self.__class__.__name__, "stops (limits=) and friction= on one joint are not "
                                      "combined yet", "put the stops on an ElasticStop, or leave one of them out")])
        u, _ = split_start(p.v0 if hasattr(p, "v0") else p.w0, 1)
        v = float(u[0])
        start = "stick" if v == 0.0 else ("slip+" if v > 0.0 else "slip-")
        return StickSlipModes(start, p.friction.static, p.friction.kinetic)

    def conserves_energy(self, p):
        return p.friction is None and super().conserves_energy(p)

    def outputs(self, a, b, p, lam):
        out = super().outputs(a, b, p, lam)
        if p.friction is not None:  # the friction's power: the run fills it in (mbcomp.hybrid.friction)
            out = {**out, "power": 0.0}
        return out
