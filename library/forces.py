"""Force elements between frames (point to point) and applied world-frame loads."""
import numpy as np

from mbcomp import ForceElement, Frame, Helix, Param, Rod
from mbcomp.errors import SimulationError
from mbcomp.jets import is_traced

from .laws import describe, law_problems, number


class _LineForce(ForceElement):
    """Force along the line from frame_a's origin to frame_b's origin."""

    frame_a = Frame("first attachment point (frame origin)")
    frame_b = Frame("second attachment point (frame origin)")

    def _line(self, frames):
        a, b = frames["frame_a"], frames["frame_b"]
        d = b.r - a.r
        L = np.sqrt(d @ d)
        if not is_traced(L) and L < 1e-12:
            raise SimulationError(f"{self.path}: the attachment points coincide (length 0), so the force "
                                  "direction is undefined -> fix: attach frame_a and frame_b at distinct points")
        e = d / L
        return L, e @ (b.v - a.v), e

    def tension(self, L, Ldot, p):
        raise NotImplementedError

    def visuals(self, p, view):
        """A coil from frame_a's origin to frame_b's (a rod for a damper alone)."""
        if getattr(p, "c", None) is None:
            return [Rod(0.012 * view.scale, color="black")]
        return [Helix(0.03 * view.scale, turns=10, color="red")]

    output_units = {"f": "N", "length": "m", "length_rate": "m/s"}

    def outputs(self, t, frames, p):
        """``f`` (N): the tension (> 0 pulls the points together); ``length`` (m) and its rate
        ``length_rate`` (m/s)."""
        L, Ldot, _ = self._line(frames)
        return {"f": self.tension(L, Ldot, p), "length": L, "length_rate": Ldot}

    def wrenches(self, t, frames, p):
        L, Ldot, e = self._line(frames)
        f = self.tension(L, Ldot, p)  # > 0 pulls the points together
        z = np.zeros(3)
        return {"frame_a": (f * e, z), "frame_b": (-f * e, z)}


class Spring(_LineForce):
    """Linear translational spring between two frame origins.

    Tension ``c (L - s_unstretched)``; potential ``c (L - s_unstretched)^2 / 2``.

    Examples
    --------
    >>> from mbcomp.library import Spring
    >>> Spring(c=100.0, s_unstretched=0.5).p.c
    100.0
    """

    c = Param(1.0, unit="N/m", doc="spring rate", check="nonnegative")
    s_unstretched = Param(0.0, unit="m", doc="rest length", check="nonnegative")
    conservative = True

    def tension(self, L, Ldot, p):
        return p.c * (L - p.s_unstretched)

    def potential(self, frames, p):
        d = frames["frame_b"].r - frames["frame_a"].r
        return 0.5 * p.c * (np.sqrt(d @ d) - p.s_unstretched) ** 2


class Damper(_LineForce):
    """Linear translational damper between two frame origins: tension ``d dL/dt``.

    Examples
    --------
    >>> from mbcomp.library import Damper
    >>> Damper(d=2.0).p.d
    2.0
    """

    d = Param(0.0, unit="N s/m", doc="damping coefficient", check="nonnegative")
    dissipative = True

    def conserves_energy(self, p):
        return p.d == 0.0

    def tension(self, L, Ldot, p):
        return p.d * Ldot


class SpringDamper(Spring):
    """Spring and damper in parallel: tension ``c (L - s_unstretched) + d dL/dt``.

    Examples
    --------
    >>> from mbcomp.library import SpringDamper
    >>> SpringDamper(c=10.0, d=0.5, s_unstretched=1.0).p.d
    0.5
    """

    d = Param(0.0, unit="N s/m", doc="damping coefficient", check="nonnegative")
    dissipative = True

    def conserves_energy(self, p):
        return p.d == 0.0

    def tension(self, L, Ldot, p):
        return p.c * (L - p.s_unstretched) + p.d * Ldot


def _law(value, t, state, path, what):
    out = value(t, state) if callable(value) else value
    arr = np.asarray(out) if isinstance(out, (tuple, list, np.ndarray)) else None
    if arr is not None and arr.dtype == object and arr.shape == (3,) and any(map(is_traced, arr)):
        return arr  # traced run (mbcomp.symbolic)
    try:
        vec = np.asarray(arr, dtype=float) if arr is not None else None
    except (TypeError, ValueError):
        vec = None  # None or a string among the entries
    if vec is None or vec.shape != (3,) or not np.all(np.isfinite(vec)):
        unit = "N" if what == "force" else "N m"
        where = ", ".join(number(x) for x in state.r)
        raise SimulationError(f"{path}: the {what} law returned {describe(out)} at t={number(t)} "
                              f"(frame at r=({where})); it must "
                              f"return 3 finite numbers ({unit}, world coordinates) -> fix the law")
    return vec


def _check(comp, p, name):
    return law_problems(comp, p, {name: ("t", "frame")})


class WorldForce(ForceElement):
    """Force on frame_b's origin, world coordinates: a constant or a law ``f(t, frame)``
    of time and the frame's state (:class:`mbcomp.roles.FrameState`).

    Examples
    --------
    >>> from mbcomp.library import WorldForce
    >>> push = WorldForce(f=lambda t, frame: (0.0, 0.0, -10.0 * frame.v[2]))
    >>> callable(push.p.f)
    True
    """

    external = True
    frame_b = Frame("frame the force acts on (at its origin)")
    f = Param((0.0, 0.0, 0.0), unit="N", shape=(3,), kind="law", doc="force, world coordinates, or f(t, frame)")

    def check_params(self, p):
        return _check(self, p, "f")

    output_units = {"f.x": "N", "f.y": "N", "f.z": "N"}

    def outputs(self, t, frames, p):
        """The force (N, world coordinates) as ``f.x|y|z``."""
        f = _law(p.f, t, frames["frame_b"], self.path, "force")
        return {f"f.{a}": f[k] for k, a in enumerate("xyz")}

    def wrenches(self, t, frames, p):
        return {"frame_b": (_law(p.f, t, frames["frame_b"], self.path, "force"), np.zeros(3))}


class WorldTorque(ForceElement):
    """Torque on frame_b, world coordinates: a constant or a law ``tau(t, frame)``.

    Examples
    --------
    >>> from mbcomp.library import WorldTorque
    >>> WorldTorque(tau=(0, 0, 1.0)).p.tau
    array([0., 0., 1.])
    """

    external = True
    frame_b = Frame("frame the torque acts on")
    tau = Param((0.0, 0.0, 0.0), unit="N m", shape=(3,), kind="law", doc="torque, world coordinates, or tau(t, frame)")

    def check_params(self, p):
        return _check(self, p, "tau")

    output_units = {"tau.x": "N m", "tau.y": "N m", "tau.z": "N m"}

    def outputs(self, t, frames, p):
        """The torque (N m, world coordinates) as ``tau.x|y|z``."""
        tau = _law(p.tau, t, frames["frame_b"], self.path, "torque")
        return {f"tau.{a}": tau[k] for k, a in enumerate("xyz")}

    def wrenches(self, t, frames, p):
        return {"frame_b": (np.zeros(3), _law(p.tau, t, frames["frame_b"], self.path, "torque"))}
