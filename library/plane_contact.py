"""Unilateral contacts: lift-off, free flight, touch-down with an impact, rolling again.

:class:`Unilateral` is the mixin that gives a contact joint (``tree_edge = False``) with a
holonomic row ``normal`` (its gap, m, positive on the open side) its modes, a
:class:`ContactModes` (:mod:`mbcomp.modeling.modes`, ``docs/design/hybrid.md`` *Unilateral
contacts*), when ``unilateral=True``:

* ``"closed"``: the contact's rows (``normal`` and its rolling rows) are in the system, as a
  bilateral contact's; the framework watches the normal row's push and fires ``"release"``
  when it would pull: the contact opens (:class:`~mbcomp.modeling.events.Switch`);
* ``"open"``: none of its rows are in the system (the body flies); the event ``"touch"`` is
  the gap falling through zero, an :class:`~mbcomp.modeling.events.Impact` with Newton's
  ``restitution`` on the normal row (the rolling rows held through it: a perfectly rough
  impact) that closes the contact when the rebound is too small to leave (or ``e = 0``), or
  when the bounces accumulate (Zeno: it rests ``"closed"``).

``unilateral=False`` (the default) keeps the bilateral contact of old: no modes, no events.

:class:`Frictional` adds Coulomb friction to a rolling contact (``friction=ContactFriction(mu_s,
mu_k)``, unilateral only; its :class:`SlidingContactModes`): ``"closed"`` is rolling
(sticking), watched by the friction cone (event ``"slide"``, ``mu_s N - |F_t|`` falling
through zero: ``"slip"``); ``"slip"`` holds the ``normal`` row only, the framework applying ``-mu_k N`` against the slip velocity
(:meth:`~mbcomp.modeling.modes.Modes.slip_friction`), and its event ``"stick"`` (the slip
speed coming to rest) rolls again. A contact with friction starts sliding; the run turns it
to rolling at once where its start's slip speed is zero.
:class:`PlaneContact` is a point or a sphere on a plane, frictionless: its one row is the
normal row.
"""
import numpy as np

from mbcomp import Grid, Joint, Param, Sphere
from mbcomp.jets import ScalarJet, local_point, local_vector
from mbcomp.errors import ModelError, Problem
from mbcomp.modeling.events import ContactRow, Impact, SlipSpeed, Switch
from mbcomp.modeling.modes import Modes
from mbcomp.modeling.shapes import z_to

__all__ = ["Unilateral", "Frictional", "PlaneContact", "ContactModes", "SlidingContactModes"]


def _restitution_ok(e):
    return None if 0 <= e <= 1 else "must be in [0, 1]"


class ContactModes(Modes):
    """The modes ``"closed"``/``"open"`` of a one-sided contact with a ``normal`` row (see the
    module notes).

    Parameters
    ----------
    open0 : bool
        Start open (in flight) rather than closed.
    restitution : float
        Newton's coefficient (1) at touch-down.

    Examples
    --------
    >>> m = ContactModes(open0=False, restitution=0.5)
    >>> m.start, m.holds_rows("open"), m.action("touch", "open"), m.rows("closed")
    ('closed', False, Impact(restitution=0.5, engage='closed'), [ContactRow(name='normal', mu_s=None)])
    """

    def __init__(self, open0, restitution):
        super().__init__("open" if open0 else "closed")
        self.restitution = float(restitution)

    def events(self, q, u, mode):
        """``"touch"``: the gap (m, the ``normal`` row) falling through zero while open."""
        return [("touch", ContactRow("normal"), -1)] if mode == "open" else []

    def action(self, name, mode):
        """Open at a ``"release"``; an impact closing the contact at a ``"touch"``."""
        if name == "release":
            return Switch("open")
        return Impact(self.restitution, engage="closed")

    def rows(self, mode):
        """The ``normal`` row, held while closed."""
        return [ContactRow("normal")] if mode == "closed" else []

    def holds_rows(self, mode):
        """None of the contact's rows while open (the body flies)."""
        return mode != "open"

    def rest(self, name, mode):
        """Closed, where touch-downs chatter."""
        return "closed" if name == "touch" else None


class Unilateral:
    """The modes of a contact with ``unilateral=True`` (:class:`ContactModes`; the module notes).

    Parameters (declared by the contact class): ``unilateral`` (bool), ``restitution`` (1),
    ``open0`` (bool: start open, in flight, the start pose kept as given).

    Examples
    --------
    >>> from mbcomp.library import PlaneContact
    >>> PlaneContact(unilateral=True, restitution=0.5).modes(PlaneContact().p) is None     # two-sided
    True
    >>> c = PlaneContact(unilateral=True, restitution=0.5)
    >>> c.modes(c.p)
    ContactModes(start='closed')
    """

    def modes(self, p):
        if not p.unilateral:
            return super().modes(p)
        return ContactModes(p.open0, p.restitution)


class SlidingContactModes(ContactModes):
    """:class:`ContactModes` with Coulomb friction: ``"closed"`` (rolling, watched by the
    friction cone), ``"slip"`` (sliding, its ``normal`` row held) and ``"open"`` (see the
    module notes).

    Parameters
    ----------
    open0 : bool
        Start open; else sliding (the run rolls it at once where its start's slip speed is 0).
    restitution : float
        Newton's coefficient (1) at touch-down.
    mu_s, mu_k : float
        Static and kinetic friction coefficients (1).

    Examples
    --------
    >>> m = SlidingContactModes(open0=False, restitution=0.0, mu_s=0.4, mu_k=0.3)
    >>> m.start, m.slips, m.rows("closed"), m.slip_friction("slip"), m.slip_friction("closed")
    ('slip', True, [ContactRow(name='normal', mu_s=0.4)], 0.3, None)
    >>> m.action("slide", "closed"), m.action("stick", "slip")
    (Switch(mode='slip'), Switch(mode='closed'))
    """

    #: slides with kinetic friction in mode ``"slip"``
    slips = True

    def __init__(self, open0, restitution, mu_s, mu_k):
        super().__init__(open0, restitution)
        if not open0:
            self.start = "slip"
        self.mu_s, self.mu_k = float(mu_s), float(mu_k)

    def events(self, q, u, mode):
        """``"stick"`` while sliding: the slip speed (m/s) along its direction coming to rest."""
        if mode == "slip":
            return [("stick", SlipSpeed(), -1)]
        return super().events(q, u, mode)

    def action(self, name, mode):
        """Slide when the cone is left (``"slide"``), roll at a ``"stick"``; else as contacts do."""
        if name in ("slide", "stick"):
            return Switch("slip" if name == "slide" else "closed")
        return super().action(name, mode)

    def rows(self, mode):
        """The ``normal`` row, with the friction cone while rolling."""
        if mode not in ("closed", "slip"):
            return super().rows(mode)
        return [ContactRow("normal", mu_s=self.mu_s if mode == "closed" else None)]

    def slip_friction(self, mode):
        """``mu_k`` (1) while sliding (mode ``"slip"``), else None."""
        return self.mu_k if mode == "slip" else None


class Frictional(Unilateral):
    """:class:`Unilateral` with Coulomb friction (parameter ``friction``, a
    :class:`~mbcomp.library.friction.ContactFriction` or None): modes ``"closed"`` (rolling),
    ``"slip"`` and ``"open"`` (see the module notes).

    Examples
    --------
    >>> from mbcomp.library import SphereContact, ContactFriction
    >>> c = SphereContact(r=0.1, unilateral=True, friction=ContactFriction(0.4, 0.3))
    >>> c.modes(c.p)
    SlidingContactModes(start='slip')
    """

    #: the sliding friction's work is dissipated (energy balance)
    dissipative = True

    def friction_problems(self, p):
        """The problems of the ``friction`` parameter (for the contact's ``check_params``)."""
        f = p.friction
        if f is None:
            return []
        from .friction import ContactFriction

        if not isinstance(f, ContactFriction):
            return [Problem(f"{self.path}.friction", f"{f!r} is not a contact's friction",
                            "give ContactFriction(mu_s, mu_k), or None for a contact without slip")]
        if not p.unilateral:
            return [Problem(f"{self.path}.friction", "friction at a contact needs a one-sided contact (its normal "
                            "force limits the friction, and a contact that could pull would have to let go)",
                            "add unilateral=True")]
        return []

    def _friction(self, p):
        probs = self.friction_problems(p)
        if probs:
            raise ModelError(probs)
        return p.friction

    def modes(self, p):
        f = self._friction(p)
        if f is None:
            return super().modes(p)
        return SlidingContactModes(p.open0, p.restitution, f.static, f.kinetic)

    def conserves_energy(self, p):
        return p.friction is None and super().conserves_energy(p)


def friction_param():
    """The ``friction`` parameter of a rolling contact (:class:`Frictional`)."""
    return Param(None, unit="1", kind="any",
                 doc="Coulomb friction with stick/slip events, ContactFriction(mu_s, mu_k) (unilateral only), or None")


def unilateral_params():
    """The three parameters of a unilateral contact (``unilateral``, ``restitution``, ``open0``)."""
    return (Param(False, unit="1", kind="any",
                  doc="True: the contact lifts off where its normal force would pull, flies and lands with an impact"),
            Param(0.0, unit="1", check=_restitution_ok,
                  doc="Newton's restitution coefficient at touch-down (unilateral only)"),
            Param(False, unit="1", kind="any",
                  doc="start open (in flight; the start pose kept as given), unilateral only"))


class PlaneContact(Unilateral, Joint):
    """A point, or a sphere of radius ``r``, on a plane, without friction.

    ``frame_a`` carries the plane (through its origin, normal ``n`` in frame_a coordinates,
    pointing to the body's side); ``frame_b`` is the point or the sphere's centre. One
    holonomic row ``normal`` (m): the centre's height above the plane minus ``r``. The body
    slides freely along the plane and turns freely. Outputs: ``N`` the normal force on the
    body (N, positive pressing), the contact point ``p.x|y|z`` (m, world).

    With ``unilateral=True`` it is a one-sided contact (:class:`Unilateral`): a bouncing ball
    with ``restitution``; ``open0=True`` starts it in flight.

    Examples
    --------
    A ball dropped from 1 m (e = 0.8) hits the ground at ``sqrt(2 h / g)`` and rises to
    ``e^2 h``:

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, PointMass, PlaneContact
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> ball = m.add("ball", PointMass(m=0.5), free=True)
    >>> c = m.add("ground", PlaneContact(r=0.1, unilateral=True, restitution=0.8, open0=True))
    >>> m.connect(w.frame_b, c.frame_a); m.connect(c.frame_b, ball.frame_a)
    >>> res = mbcomp.simulate(m, t_end=1.0, params={"ball.free.r0": (0, 0, 1.1)}, rtol=1e-10, atol=1e-12)
    >>> hit = res.events[0]
    >>> hit.kind, round(hit.time, 9), round(float(np.sqrt(2 / 9.81)), 9)
    ('impact', 0.451523641, 0.451523641)
    >>> round(float(res["ball.r.z"].max(initial=0.0, where=res.time > hit.time)) - 0.1, 3)   # e^2 h (on the output grid)
    0.64
    """

    tree_edge = False
    r = Param(0.0, unit="m", check=lambda r: None if r >= 0 else "must be >= 0", doc="sphere radius (0: a point)")
    n = Param((0.0, 0.0, 1.0), unit="1", shape=(3,), check="nonzero",
              doc="plane normal, frame_a coordinates, pointing to the body's side")
    unilateral, restitution, open0 = unilateral_params()
    output_units = {"N": "N", "p.x": "m", "p.y": "m", "p.z": "m"}

    def visuals(self, p, view):
        """The plane (a grid on frame_a) and, for ``r > 0``, the sphere on frame_b."""
        out = [Grid(R=z_to(p.n), frame="frame_a", floor=False, color="lightgrey")]
        return out + ([Sphere(p.r, frame="frame_b", color="orange")] if p.r > 0 else [])

    def _normal(self, a, p):
        return local_vector(a, np.asarray(p.n, float) / np.linalg.norm(p.n), 0)

    def constraints(self, a, b, p):
        n = self._normal(a, p)
        gap = (local_point(b, 1) - local_point(a, 0)).dot_(n)
        return [("normal", gap - ScalarJet(p.r, np.zeros(12), 0.0, 0.0))]

    def outputs(self, a, b, p, lam):
        n = self._normal(a, p)
        P = b.r - p.r * n.val
        out = {"N": -lam.get("normal", np.nan)}
        out.update({f"p.{ax}": P[i] for i, ax in enumerate("xyz")})
        return out
