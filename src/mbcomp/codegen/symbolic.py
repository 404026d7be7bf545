"""Symbolic equations of motion: the numeric evaluation traced with sympy scalars.

:func:`equations` runs the same :meth:`~mbcomp.system.MultibodySystem.evaluate` that the
simulation uses, with numpy object arrays whose elements are :class:`SymbolicScalar` (a thin
sympy-backed traced scalar; the protocol is in :mod:`mbcomp.jets`, *Tracing*). Nothing is
derived a second time: the mass matrix, forces and constraint terms come out of the same
jet recursion, so the symbolic and numeric equations agree by construction.

For an open tree the result is ``M(q) du/dt = f(q, u, t)``; a model with cut joints also
gets the loop-closure constraints ``Phi(q, t) = 0`` with their Jacobian ``C`` and bias
``cb`` (``d2Phi/dt2 = C du/dt + cb``), i.e. ``M du/dt = f - C^T lam``, ``C du/dt = -cb``.

Numbers
-------
Parameters keep their numeric values unless ``params`` makes them symbolic
(``params={"rod.m": sympy.Symbol("m")}``). A floating-point number meets the symbols as the
exact rational of its shortest decimal form, ``sympy.Rational(repr(x))`` (``0.1`` -> ``1/10``,
``9.81`` -> ``981/100``): exact arithmetic, no ``nsimplify`` guessing, and exactly the value
the numeric code uses when the decimal is exact in binary. Values the library computes from
numbers (e.g. a normalized axis ``(1, 1, 0)/sqrt(2)``) enter as the rational of their float.

Limits
------
Everything a component computes from the coordinates, speeds or time must be numpy
arithmetic: ``math.sin``, ``float()`` or comparisons (``if phi < 0``) on such values cannot be
traced, and the error names the component. Joint axes and other parameters used in
branches (``perpendicular_pair``) must stay numeric. Quaternion coordinates are taken as unit
quaternions (``|Q| = 1``, as the integration keeps them; ``unit_quaternions=False`` keeps the
numeric code's ``R(Q / |Q|)``). Simplification is per matrix entry, bounded by ``max_ops``
and meant for small models; it is never on the simulation path.

Examples
--------
>>> import sympy as sp
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> mdl = mbcomp.Model(); w = mdl.add("world", World()); j = mdl.add("hinge", Revolute(n=(0, 0, 1)))
>>> rod = mdl.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = mdl.add("bob", PointMass(m=1.0))
>>> mdl.connect(w.frame_b, j.frame_a); mdl.connect(j.frame_b, rod.frame_a); mdl.connect(rod.frame_b, bob.frame_a)
>>> m, l, g = sp.symbols("m l g", positive=True)
>>> eqs = mbcomp.equations(mdl, params={"bob.m": m, "rod.r": (0, -l, 0), "world.g": (0, -g, 0)})
>>> eqs.q, eqs.M, eqs.f
((hinge.phi,), Matrix([[l**2*m]]), Matrix([[-g*l*m*sin(hinge.phi)]]))
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..errors import ModelError, Problem
from ..modeling.blame import blame
from .sympy_scalar import UNIT_NORMS, SymbolicScalar, exact, traced_law, traced_value
from .tracing import q_rates, traced_params, traced_system

__all__ = ["SymbolicScalar", "Equations", "equations", "exact"]


def _matrix(a, shape=None):
    a = np.asarray(a, dtype=object)
    if shape is not None:
        a = a.reshape(shape)
    return sp.Matrix(a.shape[0], a.shape[1] if a.ndim > 1 else 1, [exact(x) for x in a.flat])


# ----------------------------------------------------------------------------- result
@dataclass(frozen=True)
class Equations:
    """Equations of motion of an assembled model in its own coordinates (sympy).

    ``M du/dt = f - C^T lam - B^T mu``, ``C du/dt = -cb`` (loops), ``B du/dt = -Bb``
    (nonholonomic), ``dq/dt = qdot(q, u)``. For an open tree without velocity constraints the
    constraint matrices have no rows and ``M du/dt = f``.

    Attributes
    ----------
    t : sympy.Symbol
        Time (s).
    q, u, ud : tuple of sympy.Symbol
        Coordinates (named as the model's coordinates, e.g. ``crank_joint.phi``), speeds
        (``crank_joint.w``) and speed derivatives (``crank_joint.w.der``), SI units.
    qdot : sympy.Matrix (nq, 1)
        Coordinate rates from the speeds (quaternion kinematics where needed).
    M : sympy.Matrix (nu, nu)
        Mass matrix (kg, kg m, kg m^2 as the speeds dictate).
    f : sympy.Matrix (nu, 1)
        Applied generalized forces minus velocity-product terms.
    T, V : sympy.Expr
        Kinetic and potential energy (J); gravity's potential is zero at the world origin.
    constraint_names, Phi, C, cb, lam
        Loop-closure rows ``"<cut joint>.<row>"``, their residual ``Phi(q, t)``, Jacobian
        ``C`` (``dPhi/dt = C u + dPhi/dt|_u=0``), bias ``cb`` and multiplier symbols.
    nonholonomic_names, B, b, Bb, mu
        Velocity constraints ``B u = b`` with bias ``Bb`` and their multipliers.
    dropped : tuple of str
        Constraint rows that vanish identically (e.g. out-of-plane rows of a planar loop).
    params : dict
        The parameter overrides used (``"component.param" -> value``).
    seconds : float
        Wall time of the derivation (tracing and simplification), s.
    """

    t: sp.Symbol
    q: tuple
    u: tuple
    ud: tuple
    qdot: sp.Matrix
    M: sp.Matrix
    f: sp.Matrix
    T: sp.Expr = sp.S.Zero
    V: sp.Expr = sp.S.Zero
    constraint_names: tuple = ()
    Phi: sp.Matrix = None
    C: sp.Matrix = None
    cb: sp.Matrix = None
    lam: tuple = ()
    nonholonomic_names: tuple = ()
    B: sp.Matrix = None
    b: sp.Matrix = None
    Bb: sp.Matrix = None
    mu: tuple = ()
    dropped: tuple = ()
    params: dict = field(default_factory=dict)
    seconds: float = 0.0

    def symbol(self, name):
        """The symbol named ``name`` among ``t``, ``q``, ``u``, ``ud``, ``lam``, ``mu``.

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic()); b = m.add("b", PointMass())
        >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> mbcomp.equations(m).symbol("s.v")
        s.v
        """
        for s in (self.t, *self.q, *self.u, *self.ud, *self.lam, *self.mu):
            if s.name == name:
                return s
        raise KeyError(f"no symbol {name!r}; coordinates {[s.name for s in self.q]}, speeds {[s.name for s in self.u]}")

    @property
    def residual(self):
        """``M du/dt - f + C^T lam + B^T mu`` (nu x 1): zero along every motion.

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.library import World, Prismatic, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World(g=(-2, 0, 0))); s = m.add("s", Prismatic())
        >>> b = m.add("b", PointMass(m=3.0)); m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
        >>> mbcomp.equations(m).residual
        Matrix([[3*s.v.der + 6]])
        """
        r = self.M * sp.Matrix(self.ud) - self.f
        if self.lam:
            r += self.C.T * sp.Matrix(self.lam)
        if self.mu:
            r += self.B.T * sp.Matrix(self.mu)
        return r

    def __str__(self):
        lines = [f"equations of motion: {len(self.u)} speeds, {len(self.constraint_names)} loop-closure rows, "
                 f"{len(self.nonholonomic_names)} nonholonomic rows ({self.seconds:.2f} s)",
                 f"  q  = {list(self.q)}", f"  u  = {list(self.u)}", f"  M  = {self.M}", f"  f  = {self.f}"]
        if self.constraint_names:
            lines += [f"  Phi = {self.Phi}", f"  C  = {self.C}", f"  cb = {self.cb}"]
        if self.dropped:
            lines.append(f"  identically zero rows dropped: {', '.join(self.dropped)}")
        return "\n".join(lines)



# ----------------------------------------------------------------------------- derivation
def _drive_like(comp):
    return comp.role == "drive" and {"s", "v", "a"} <= set(comp.params())


def _drive_laws(path, p, T):
    """Exact ``(s, v, a)`` of a drive with ``s``/``v``/``a`` parameters (PrescribedMotion's
    contract: ``s`` a number, a string in ``t``, a sympy expression in ``t`` or a callable
    accepting a sympy symbol), as traced scalars; None for three callables ``s``, ``v``,
    ``a`` (they are traced as they are)."""
    s = p.s
    if p.v is not None and p.a is not None and callable(s):
        return None
    try:
        if isinstance(s, SymbolicScalar):
            s = s.expr
        if isinstance(s, sp.Basic):
            expr = s.xreplace({x: T for x in s.free_symbols if x.name == "t"})
        elif isinstance(s, str):
            expr = sp.sympify(s, locals={"t": T})
        elif callable(s):
            expr = exact(s(T))
        else:
            expr = exact(s)
    except Exception as exc:  # noqa: BLE001 - reported with the component's name
        raise ModelError([Problem(f"{path}.s", f"the law s(t) could not be made symbolic ({type(exc).__name__}: {exc})",
                                  "give s as a string or sympy expression in t, or as a callable using sympy "
                                  "functions, or pass traceable s, v and a callables")],
                         header="symbolic equations") from None
    expr = expr.xreplace({x: exact(float(x)) for x in expr.atoms(sp.Float)})
    return tuple(SymbolicScalar(e) for e in (expr, sp.diff(expr, T), sp.diff(expr, T, 2)))


def _drive_motion(T):
    """The drives' motion for :func:`~mbcomp.codegen.tracing.traced_system`: exact laws, or the
    drive's own motion at the traced time."""
    def motion(path, comp, p):
        laws = _drive_laws(path, p, T) if _drive_like(comp) else None
        if laws is not None:
            return laws
        try:
            return tuple(traced_value(x) for x in comp.motion(SymbolicScalar(T), p))
        except Exception as exc:  # noqa: BLE001 - re-raised naming the component
            raise _blame(exc, "the equations of motion") from exc
    return motion


def _traced_params(system, params):
    """The system's parameter values with the overrides ``params`` traced (sympy parts wrapped,
    laws wrapped; a drive's ``s``, ``v``, ``a`` as given, made exact by :func:`_drive_laws`)."""
    owners = system.owners()
    by_comp, probs = {}, []
    for key, value in (params or {}).items():
        path, _, name = key.rpartition(".")
        if path not in owners:
            probs.append(Problem(key, f"no component {path!r} in the model", f"use one of: {', '.join(sorted(owners))}"))
            continue
        decl = owners[path].params()
        if name not in decl:
            probs.append(Problem(key, "no such parameter", f"use one of: {', '.join(decl)}"))
            continue
        par = decl[name]
        if _drive_like(owners[path]) and name in ("s", "v", "a"):
            val = value  # made exact with the drive's laws
        elif callable(value) and not isinstance(value, sp.Basic):
            if par.kind not in ("law", "any"):
                probs.append(Problem(key, "is not a law and cannot be a function", par.hint()))
                continue
            val = traced_law(value)
        elif isinstance(value, str):
            val = value
        else:
            val = traced_value(value)
            if np.shape(val) != par.shape and not (par.kind in ("law", "any") and np.shape(val) == ()):
                probs.append(Problem(key, f"has shape {np.shape(val)}, expected {par.shape or 'a scalar'}", par.hint()))
                continue
        by_comp.setdefault(path, {})[name] = val
    if probs:
        raise ModelError(probs, header="bad symbolic parameters")
    return traced_params(system, by_comp)


def _blame(exc, what):
    b = blame(exc)
    return ModelError([Problem(b.path, f"cannot be traced symbolically while computing {what}: {type(exc).__name__}: {exc}",
                               f"{b.who} must compute with numpy/sympy arithmetic on coordinates, speeds and time "
                               "(np.sin, not math.sin; no float(), no comparisons); keep parameters it branches on "
                               "numeric")], header="symbolic equations")


def _unit_reduce(e, units):
    """``e`` (expanded) with ``w^k`` replaced by ``w^(k mod 2) rest^(k div 2)`` for every pair
    ``(w, rest)`` with ``w^2 = rest``: the normal form modulo ``|Q| = 1`` (degree at most one in
    ``Qw``) and ``sin^2 + cos^2 = 1`` (degree at most one in each ``sin``)."""
    pairs = list(units) + [(s, 1 - sp.cos(s.args[0]) ** 2) for s in e.atoms(sp.sin)]
    for w, rest in pairs:
        pows = {p: w ** (int(p.exp) % 2) * rest ** (int(p.exp) // 2) for p in e.atoms(sp.Pow)
                if p.base == w and p.exp.is_Integer and p.exp >= 2}
        if pows:
            e = sp.expand(e.xreplace(pows))
    return e


def _simplify(e, max_ops, units=(), max_terms=40):
    """Expand and reduce modulo ``sin^2 + cos^2 = 1`` and unit quaternions (this cancels what
    chained rotations produce), then, if at most ``max_terms`` terms remain, ``trigsimp`` for
    the compact form (``sin(2 phi)``); finally pull out common factors if that is shorter. Entries with more than
    ``max_ops`` operations are left as they are."""
    if not isinstance(e, sp.Expr) or e.is_number or sp.count_ops(e) > max_ops:
        return e
    e = _unit_reduce(sp.expand(e), units)
    if len(sp.Add.make_args(e)) <= max_terms:
        e = sp.trigsimp(e)
    f = sp.factor_terms(e, sign=False)
    return f if sp.count_ops(f) < sp.count_ops(e) else e


def _quaternions(system, qs):
    """Symbols ``(Qw, Qx, Qy, Qz)`` of every quaternion among the coordinates (by the library's
    naming ``Q.w, Q.x, Q.y, Q.z``)."""
    out = []
    for e in system.topology.tree:
        names = [n for n, _ in getattr(e.comp, "coordinates", ())]
        for i in range(len(names) - 3):
            if names[i:i + 4] == [names[i][:-1] + c for c in "wxyz"] and names[i].endswith("Q.w"):
                out.append(tuple(qs[e.q.start + i + k] for k in range(4)))
    return out


def equations(model, params=None, simplify=True, drop_zero_rows=True, max_ops=2000,
              unit_quaternions=True) -> Equations:
    """Symbolic equations of motion of a model (sympy), traced from the numeric evaluation.

    Parameters
    ----------
    model : mbcomp.Model or mbcomp.system.MultibodySystem
        The model, or an assembled system (its parameter values are the starting point).
    params : dict, optional
        ``"component.param" -> value`` overrides: sympy symbols or expressions (scalars,
        sequences or ``sympy.Matrix`` of the parameter's shape, e.g. ``"link.I":
        sympy.diag(0, I1, I1)``), numbers, or laws (callables, called with traced arguments).
        A drive law ``"drive.s"`` may be a sympy expression or string in ``t`` with other
        symbols (``Omega*t``); a symbol named ``t`` is the returned ``Equations.t``.
    simplify : bool
        Simplify each entry whose operation count is at most ``max_ops``: ``expand``, reduce
        modulo ``sin^2 + cos^2 = 1`` and ``|Q| = 1`` (``unit_quaternions``), ``trigsimp`` when
        few terms remain, ``factor_terms``. Under 2 s for each of the seed's one- and two-DOF
        examples, about 7 s for a top in quaternions, 20 s for a 5-DOF 3-D chain: meant for
        small models (the simulation never uses it).
    drop_zero_rows : bool
        Leave out constraint rows whose residual, Jacobian and bias are identically zero.
    max_ops : int
        Entries with more operations are left unsimplified.
    unit_quaternions : bool
        Quaternion coordinates are unit (as the integration keeps them): their norm is 1 in
        the equations. ``False`` keeps the normalization ``R(Q / |Q|)`` the numeric code applies
        (much longer expressions; equal on unit quaternions).

    Returns
    -------
    Equations

    Raises
    ------
    ModelError
        Unknown parameters, or a component whose computation cannot be traced (named).

    Examples
    --------
    >>> import sympy as sp
    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass, TranslationalSpringDamper
    >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic(n=(1, 0, 0)))
    >>> b = m.add("b", PointMass(m=2.0)); k = m.add("k", TranslationalSpringDamper(c=50.0, d=0.5))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> m.connect(s.support, k.flange_a); m.connect(s.axis, k.flange_b)
    >>> c = sp.Symbol("c", positive=True)
    >>> eqs = mbcomp.equations(m, params={"k.c": c})
    >>> eqs.M, eqs.f
    (Matrix([[2]]), Matrix([[-c*s.s - s.v/2]]))
    """
    from ..assembly.system import MultibodySystem, assemble

    t0 = _time.perf_counter()
    base = model if isinstance(model, MultibodySystem) else assemble(model)
    T = sp.Symbol("t", real=True)
    qs = tuple(sp.Symbol(n, real=True) for n in base.q_names)
    us = tuple(sp.Symbol(n, real=True) for n in base.u_names)
    quats = _quaternions(base, qs) if unit_quaternions else []
    units = [(w, 1 - x ** 2 - y ** 2 - z ** 2) for w, x, y, z in quats]  # w^2 on the unit sphere
    ev, qdot, T_kin, V_pot = _trace(base, _traced_params(base, params), T, qs, us, quats)

    nu = base.nu
    names = [f"{e.name}.{r}" for e, rows, _ in ev.local for r in rows]
    Phi = [exact(x) for x in ev.Phi]
    C = [[exact(x) for x in row] for row in np.asarray(ev.C).reshape(len(names), nu)]
    cb = [exact(x) for x in ev.cb]
    keep = list(range(len(names)))
    if drop_zero_rows:
        keep = [i for i in keep if not (Phi[i] == 0 and cb[i] == 0 and all(c == 0 for c in C[i]))]
    nh_names = [f"{e.name}.{r}" for e, rows, _ in ev.local_nh for r in rows]
    nh = len(nh_names)

    def simp(m):
        return m.applyfunc(lambda e: _simplify(e, max_ops, units)) if simplify else m

    eqs = Equations(
        t=T, q=qs, u=us, ud=tuple(sp.Symbol(f"{n}.der", real=True) for n in base.u_names), qdot=simp(qdot),
        M=simp(_matrix(ev.M, (nu, nu))), f=simp(_matrix(ev.f, (nu, 1))),
        T=_simplify(exact(T_kin), max_ops, units) if simplify else exact(T_kin),
        V=_simplify(exact(V_pot), max_ops, units) if simplify else exact(V_pot),
        constraint_names=tuple(names[i] for i in keep),
        Phi=simp(sp.Matrix(len(keep), 1, [Phi[i] for i in keep])),
        C=simp(sp.Matrix(len(keep), nu, [c for i in keep for c in C[i]])),
        cb=simp(sp.Matrix(len(keep), 1, [cb[i] for i in keep])),
        lam=tuple(sp.Symbol(f"lambda.{names[i]}", real=True) for i in keep),
        nonholonomic_names=tuple(nh_names), B=simp(_matrix(ev.B, (nh, nu))) if nh else sp.zeros(0, nu),
        b=simp(_matrix(ev.b, (nh, 1))) if nh else sp.zeros(0, 1),
        Bb=simp(_matrix(ev.Bb, (nh, 1))) if nh else sp.zeros(0, 1),
        mu=tuple(sp.Symbol(f"mu.{n}", real=True) for n in nh_names),
        dropped=tuple(names[i] for i in range(len(names)) if i not in keep), params=dict(params or {}), seconds=0.0)
    object.__setattr__(eqs, "seconds", _time.perf_counter() - t0)
    return eqs


def _trace(base, P, T, qs, us, quats):
    """The evaluation, ``dq/dt`` (a sympy column), kinetic and potential energy of ``base``
    traced with parameter values ``P``, time ``T``, coordinates ``qs`` and speeds ``us``;
    the squared norms of the quaternions ``quats`` are 1 while tracing."""
    try:
        system = traced_system(base, P, _drive_motion(T))
    except ModelError:
        raise
    except Exception as exc:  # noqa: BLE001 - re-raised naming the component
        raise _blame(exc, "gravity") from exc
    q = np.array([SymbolicScalar(s) for s in qs] or [], dtype=object)
    u = np.array([SymbolicScalar(s) for s in us] or [], dtype=object)
    token = UNIT_NORMS.set(frozenset(w ** 2 + x ** 2 + y ** 2 + z ** 2 for w, x, y, z in quats))
    try:
        ev = system.evaluate_numeric(SymbolicScalar(T), q, u, masked=False)
        qdot = q_rates(system, q, u)
        T_kin, V_pot = system.energies(ev)
    except ModelError:
        raise
    except Exception as exc:  # noqa: BLE001 - re-raised naming the component
        raise _blame(exc, "the equations of motion") from exc
    finally:
        UNIT_NORMS.reset(token)
    return ev, sp.Matrix(len(qdot), 1, [exact(x) for x in qdot]), T_kin, V_pot
