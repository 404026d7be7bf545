"""Unilateral contacts: lift-off, free flight, touch-down with an impact, rolling again.

:class:`Unilateral` is the mixin that gives a contact joint (``tree_edge = False``) with a
holonomic row ``normal`` (its gap, m, positive on the open side) the modes of the event
framework (:mod:`mbcomp.modeling.events`, ``docs/architecture.md`` *Events and modes*) when
``unilateral=True``:

* ``"closed"``: the contact's rows (``normal`` and its rolling rows) are in the system, as a
  bilateral contact's; the framework watches the normal row's push and fires ``"release"``
  when it would pull: the contact opens (:class:`~mbcomp.modeling.events.Switch`);
* ``"open"``: none of its rows are in the system (the body flies); the event ``"touch"`` is
  the gap falling through zero, an :class:`~mbcomp.modeling.events.Impact` with Newton's
  ``restitution`` on the normal row (the rolling rows held through it: a perfectly rough
  impact) that closes the contact when the rebound is too small to leave (or ``e = 0``), or
  when the bounces accumulate (Zeno: ``rest_mode`` is ``"closed"``).

``unilateral=False`` (the default) keeps the bilateral contact of old: no modes, no events.

:class:`Frictional` adds Coulomb friction to a rolling contact (``friction=ContactFriction(mu_s,
mu_k)``, unilateral only): ``"closed"`` is rolling (sticking), watched by the friction cone
(event ``"slide"``, ``mu_s N - |F_t|`` falling through zero: ``"slip"``); ``"slip"`` holds the
``normal`` row only, the framework applying ``-mu_k N`` against the slip velocity
(:meth:`~mbcomp.modeling.roles.Joint.slip_friction`), and its event ``"stop"`` (the slip
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
from mbcomp.modeling.shapes import z_to

__all__ = ["Unilateral", "Frictional", "PlaneContact"]


def _restitution_ok(e):
    return None if 0 <= e <= 1 else "must be in [0, 1]"


class Unilateral:
    """Modes ``"closed"``/``"open"`` of a contact with a ``normal`` row (see the module notes).

    Parameters (declared by the contact class): ``unilateral`` (bool), ``restitution`` (1),
    ``open0`` (bool: start open, in flight, the start pose kept as given).

    Examples
    --------
    >>> from mbcomp.library import PlaneContact
    >>> c = PlaneContact(unilateral=True, restitution=0.5)
    >>> c.start_mode(c.p), c.holds_rows(c.p, "open"), c.on_event("touch", c.p, "open")
    ('closed', False, Impact(restitution=0.5, engage='closed'))
    """

    def start_mode(self, p):
        if not p.unilateral:
            return None
        return "open" if p.open0 else "closed"

    def events(self, q, u, p, mode):
        if not p.unilateral or mode != "open":
            return []
        return [("touch", ContactRow("normal"), -1)]

    def on_event(self, name, p, mode):
        if name == "release":
            return Switch("open")
        return Impact(float(p.restitution), engage="closed")

    def mode_rows(self, p, mode):
        return [ContactRow("normal")] if p.unilateral and mode == "closed" else []

    def holds_rows(self, p, mode):
        return not (p.unilateral and mode == "open")

    def rest_mode(self, name, p, mode):
        return "closed" if name == "touch" else None


class Frictional(Unilateral):
    """:class:`Unilateral` with Coulomb friction (parameter ``friction``, a
    :class:`~mbcomp.library.friction.ContactFriction` or None): modes ``"closed"`` (rolling),
    ``"slip"`` and ``"open"`` (see the module notes).

    Examples
    --------
    >>> from mbcomp.library import SphereContact, ContactFriction
    >>> c = SphereContact(r=0.1, unilateral=True, friction=ContactFriction(0.4, 0.3))
    >>> c.start_mode(c.p), c.mode_rows(c.p, "closed"), c.slip_friction(c.p, "slip")
    ('slip', [ContactRow(name='normal', mu_s=0.4)], 0.3)
    >>> c.on_event("slide", c.p, "closed"), c.on_event("stop", c.p, "slip")
    (Switch(mode='slip'), Switch(mode='closed'))
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

    def start_mode(self, p):
        if self._friction(p) is None or p.open0:
            return super().start_mode(p)
        return "slip"

    def events(self, q, u, p, mode):
        if mode == "slip":
            return [("stop", SlipSpeed(), -1)]
        return super().events(q, u, p, mode)

    def on_event(self, name, p, mode):
        if name in ("slide", "stop"):
            return Switch("slip" if name == "slide" else "closed")
        return super().on_event(name, p, mode)

    def mode_rows(self, p, mode):
        f = self._friction(p)
        if f is None or mode not in ("closed", "slip"):
            return super().mode_rows(p, mode)
        return [ContactRow("normal", mu_s=f.static if mode == "closed" else None)]

    def slip_friction(self, p, mode):
        """``mu_k`` (1) while sliding (mode ``"slip"``), else None."""
        f = self._friction(p)
        return f.kinetic if f is not None and mode == "slip" else None

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
