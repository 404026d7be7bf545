"""One-dimensional elements on joint axes: springs, dampers, actuators, prescribed motion.

Connect them to a 1-DOF joint's ``axis`` flange (moves with the joint coordinate) and, for
two-flange elements, its ``support`` flange (the joint's zero, fixed to frame_a). A force
put on ``axis`` acts on frame_b along/about the joint axis, with the reaction on frame_a.
"""
import numpy as np

from mbcomp import Drive, Flange, FlangeElement, Param
from mbcomp.errors import Problem, SimulationError
from mbcomp.jets import is_traced

from .laws import as_number, describe, law_problems, number


class _TwoFlange(FlangeElement):
    flange_a = Flange("first flange (e.g. a joint's support)")
    flange_b = Flange("second flange (e.g. a joint's axis)")
    #: result names of the law's value and of the relative coordinate and rate
    columns = ("tau", "phi_rel", "w_rel")
    output_units = {"tau": "N m", "phi_rel": "rad", "w_rel": "rad/s"}

    def outputs(self, t, states, p):
        """The law's torque or force (> 0 opposes a positive relative motion), the relative
        coordinate ``flange_b - flange_a`` and its rate."""
        (sa, va), (sb, vb) = states["flange_a"], states["flange_b"]
        return dict(zip(self.columns, (self.law(sb - sa, vb - va, p), sb - sa, vb - va)))

    def flange_forces(self, t, states, p):
        (sa, va), (sb, vb) = states["flange_a"], states["flange_b"]
        f = self.law(sb - sa, vb - va, p)  # > 0 opposes a positive relative motion
        return {"flange_a": f, "flange_b": -f}


class RotationalSpring(_TwoFlange):
    """Linear torsional spring: torque ``c (phi_rel - phi_rel0)`` with ``phi_rel = phi_b - phi_a``.

    Examples
    --------
    >>> from mbcomp.library import RotationalSpring
    >>> RotationalSpring(c=5.0).p.c
    5.0
    """

    c = Param(1.0, unit="N m/rad", doc="spring rate", check="nonnegative")
    phi_rel0 = Param(0.0, unit="rad", doc="unstretched relative angle")
    axis_kind = "rotational"
    conservative = True

    def law(self, s, v, p):
        return p.c * (s - p.phi_rel0)

    def potential(self, states, p):
        return 0.5 * p.c * (states["flange_b"][0] - states["flange_a"][0] - p.phi_rel0) ** 2


class RotationalDamper(_TwoFlange):
    """Linear torsional damper: torque ``d w_rel``.

    Examples
    --------
    >>> from mbcomp.library import RotationalDamper
    >>> RotationalDamper(d=0.1).p.d
    0.1
    """

    d = Param(0.0, unit="N m s/rad", doc="damping coefficient", check="nonnegative")
    axis_kind = "rotational"
    dissipative = True

    def conserves_energy(self, p):
        return p.d == 0.0

    def law(self, s, v, p):
        return p.d * v


class RotationalSpringDamper(RotationalSpring):
    """Torsional spring and damper in parallel.

    Examples
    --------
    >>> from mbcomp.library import RotationalSpringDamper
    >>> RotationalSpringDamper(c=1.0, d=0.2).p.d
    0.2
    """

    d = Param(0.0, unit="N m s/rad", doc="damping coefficient", check="nonnegative")
    dissipative = True

    def conserves_energy(self, p):
        return p.d == 0.0

    def law(self, s, v, p):
        return p.c * (s - p.phi_rel0) + p.d * v


class TranslationalSpringDamper(_TwoFlange):
    """Linear spring and damper along a slider axis: force ``c (s_rel - s_rel0) + d v_rel``.

    Examples
    --------
    >>> from mbcomp.library import TranslationalSpringDamper
    >>> TranslationalSpringDamper(c=100.0).p.c
    100.0
    """

    c = Param(0.0, unit="N/m", doc="spring rate", check="nonnegative")
    d = Param(0.0, unit="N s/m", doc="damping coefficient", check="nonnegative")
    s_rel0 = Param(0.0, unit="m", doc="unstretched relative position")
    axis_kind = "translational"
    dissipative = True
    columns = ("f", "s_rel", "v_rel")
    output_units = {"f": "N", "s_rel": "m", "v_rel": "m/s"}

    def conserves_energy(self, p):
        return p.d == 0.0

    def law(self, s, v, p):
        return p.c * (s - p.s_rel0) + p.d * v

    def potential(self, states, p):
        return 0.5 * p.c * (states["flange_b"][0] - states["flange_a"][0] - p.s_rel0) ** 2


class _Actuator(FlangeElement):
    flange_b = Flange("the driven flange (a joint's axis)")
    #: the law's arguments after t (coordinate, rate) and the unit of what it returns
    law_args = ("s", "v")
    law_unit = "N"

    def check_params(self, p):
        return law_problems(self, p, {self.value_name: ("t", *self.law_args)})

    def outputs(self, t, states, p):
        """The torque or force the law gives (``tau`` or ``f``)."""
        return {self.value_name: self.flange_forces(t, states, p)["flange_b"]}

    def flange_forces(self, t, states, p):
        s, v = states["flange_b"]
        law = getattr(p, self.value_name)
        val = law(t, s, v) if callable(law) else law
        if is_traced(val):  # a traced run (mbcomp.symbolic, code generation): no number to check
            return {"flange_b": val}
        out = as_number(val)
        if not np.isfinite(out):
            x, y = self.law_args
            raise SimulationError(f"{self.path}: the {self.value_name} law returned {describe(val)} at "
                                  f"t={number(t)} ({x}={number(s)}, {y}={number(v)}); it must return one finite "
                                  f"number ({self.law_unit}) -> fix the law")
        return {"flange_b": out}


class Torque(_Actuator):
    """Torque on a rotational flange: a constant or a law ``tau(t, phi, w)``.

    The seed's motor law ``Md = M0 - dM*w`` is one line:

    Examples
    --------
    >>> from mbcomp.library import Torque
    >>> M0, dM = 1.0, 0.5
    >>> motor = Torque(tau=lambda t, phi, w: M0 - dM * w)
    >>> motor.p.tau(0.0, 0.0, 2.0)
    0.0
    """

    value_name = "tau"
    axis_kind = "rotational"
    law_args = ("phi", "w")
    law_unit = "N m"
    output_units = {"tau": "N m"}
    tau = Param(0.0, unit="N m", kind="law", doc="torque about the axis, or tau(t, phi, w)")


class Force(_Actuator):
    """Force on a translational flange: a constant or a law ``f(t, s, v)``.

    Examples
    --------
    >>> from mbcomp.library import Force
    >>> Force(f=lambda t, s, v: -3.0 * s).p.f(0, 1.0, 0)
    -3.0
    """

    value_name = "f"
    axis_kind = "translational"
    output_units = {"f": "N"}
    f = Param(0.0, unit="N", kind="law", doc="force along the axis, or f(t, s, v)")


def _law_key(law):
    """Hashable identity of a law value (numbers and strings by value, callables by id)."""
    try:
        hash(law)
        return law
    except TypeError:
        return id(law)


class PrescribedMotion(Drive):
    """Prescribes the coordinate of the joint axis on ``flange_b``: ``s = s(t)``.

    A rheonomic constraint: the joint's degree of freedom is removed, and the force or
    torque needed to impose the motion is the joint's reaction along its axis (output
    ``tau``/``f`` of the drive). ``s`` is a number, a string in ``t`` (``"0.1*sin(2*t)"``),
    or a callable; a callable must either accept a sympy symbol (so mbcomp differentiates it
    once) or come with ``v`` and ``a`` callables.

    Examples
    --------
    >>> from mbcomp.library import PrescribedMotion
    >>> d = PrescribedMotion(s="0.5*t**2")
    >>> d.motion(2.0, d.p)
    (2.0, 2.0, 1.0)
    """

    s = Param(0.0, unit="m or rad", kind="any", doc="coordinate law s(t)")
    v = Param(None, unit="m/s or rad/s", kind="any", doc="rate law ds/dt (optional)")
    a = Param(None, unit="m/s^2 or rad/s^2", kind="any", doc="acceleration law (optional)")

    def __init__(self, **values):
        super().__init__(**values)
        self._cache = {}

    def _laws(self, p):
        """(s, v, a) callables for the law in ``p``, derived once per distinct law."""
        key = (_law_key(p.s), _law_key(p.v), _law_key(p.a))
        if key not in self._cache:
            self._cache[key] = self._derive(p)
        return self._cache[key]

    @staticmethod
    def _derive(p):
        if p.v is not None and p.a is not None and callable(p.s):
            return (p.s, p.v, p.a), None
        import sympy as sp  # here, not at the top: only a law to differentiate needs sympy (0.35 s to import)

        t = sp.Symbol("t", real=True)
        try:
            if callable(p.s):
                expr = sp.sympify(p.s(t))
            else:
                expr = sp.sympify(p.s, locals={"t": t})
            if expr.free_symbols - {t}:
                return None, f"s(t) has unknown symbols {sorted(map(str, expr.free_symbols - {t}))}"
        except Exception as exc:  # numpy functions on a symbol, bad strings
            return None, f"s(t) could not be differentiated symbolically ({type(exc).__name__}: {exc})"
        fs = [sp.lambdify(t, e, "numpy") for e in (expr, sp.diff(expr, t), sp.diff(expr, t, 2))]
        return tuple(fs), None

    def check_params(self, p):
        wrong = law_problems(self, p, {"s": ("t",), "v": ("t",), "a": ("t",)})
        if wrong:
            return wrong
        laws, why = self._laws(p)
        if why:
            return [Problem(f"{self.path}.s", why,
                            "write s with sympy functions or as a string in t, or pass v= and a= callables")]
        return []

    def motion(self, t, p):
        laws, why = self._laws(p)
        if why:
            raise ValueError(f"{self.path}.s: {why}")
        if is_traced(t):  # traced time (mbcomp.symbolic, code generation): keep the expressions
            return tuple(f(t) for f in laws)
        return tuple(self._number(f(t), name, t) for f, name in zip(laws, "sva"))

    def _number(self, val, name, t):
        """``val`` as a float, or the error naming this drive, the law and what it returned."""
        out = as_number(val)
        if np.isfinite(out):
            return out
        raise SimulationError(f"{self.path}: the {name} law returned {describe(val)} at t={number(t)}; it must return "
                              "one finite number (m or rad, and their rates) -> fix the law")
