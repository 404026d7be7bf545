"""The start of forward sensitivities, ``S(t0) = d y0 / dp`` (for
:mod:`mbcomp.simulation.sensitivity`): what the initialization may move (:func:`free_start`),
how the coordinates move along the speeds (:func:`rate_map`), and the start's derivative by
differencing the initialization itself (:func:`differenced_start`) where the rows leave free
directions and the consistent start reached depends on the initialization's steps.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..assembly.initialization import initialize
from ..errors import InitializationError, ModelError, Problem

__all__ = ["free_start", "rate_map", "differenced_start"]


def free_start(system):
    """Masks ``(qfree, ufree, moves)`` of what the initialization may change: the coordinates and
    the speeds without a fixed start value, and the directions (speed slots) it moves the
    positions along (a quaternion joint: its three, unless a start is fixed).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.simulation.sensitivity_start import free_start
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=0.5))
    >>> b = m.add("b", PointMass(m=1.0)); m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> [x.tolist() for x in free_start(mbcomp.assemble(m))]     # phi0 fixed, the rate free (w0 not given)
    [[False], [True], [False]]
    """
    qfree, ufree, moves = np.ones(system.nq, bool), np.ones(system.nu, bool), np.ones(system.nu, bool)
    for e in system.topology.tree:
        if e.kind != "joint" or e.dof == 0 or e.drive:
            continue
        _, qf, _, uf = e.comp.start(system.P[e.name])
        nu = e.u.stop - e.u.start
        qf, uf = np.broadcast_to(np.asarray(qf, bool), (nu,)), np.broadcast_to(np.asarray(uf, bool), (nu,))
        ufree[e.u], moves[e.u] = ~uf, ~qf
        if e.q.stop - e.q.start == nu:
            qfree[e.q] = ~qf
        else:
            qfree[e.q] = not np.any(qf)
    return qfree, ufree, moves


def differenced_start(numeric, path, name, index, value, t0):
    """``dy0/dp`` by a central difference of the consistent initialization of the numeric
    system ``numeric`` for the parameter ``path.name[index]`` (``index`` None for a scalar) at
    its ``value``: what the start of a run moved to ``value +- h`` is (the initialization closes
    the start to round-off, so the difference is exact to its truncation error, ~1e-10). Used
    where the start's rows do not determine the free coordinates or speeds (a loop of ball
    joints: which consistent start is reached depends on the initialization's steps from the
    guesses, so no formula at the start point gives its derivative).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.simulation.sensitivity_start import differenced_start
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> np.round(differenced_start(mbcomp.assemble(m), "j", "phi0", None, 0.5, 0.0), 9).tolist()
    [1.0, 0.0]
    """
    h = 1e-5 * max(1.0, abs(value))
    ys = []
    for s in (1.0, -1.0):
        v = value + s * h
        if index is not None:
            arr = np.array(getattr(numeric.P[path], name), float)
            arr[index] = v
            v = arr
        try:
            sys2 = numeric.with_params({f"{path}.{name}": v})
        except ModelError:  # an inertia at its triangle inequality: the values as they are, unchecked
            P = dict(numeric.P)
            P[path] = SimpleNamespace(**{**vars(numeric.P[path]), name: v})
            sys2 = numeric.variant(P=P)
        try:
            init = initialize(sys2, t0)
        except InitializationError as exc:
            label = f"{path}.{name}" + ("" if index is None else str(list(index)))
            raise InitializationError(list(exc.problems) + [Problem(
                label, "moves the consistent start, whose derivative is a central difference of the initialization; "
                f"at {label} = {value:.6g} {'+' if s > 0 else '-'} {h:.1g} the start cannot be made consistent",
                "wrap the start values the loop over-specifies in Guess(...), or leave this parameter out")]) from exc
        ys.append(np.concatenate((init.q, init.u)))
    return (ys[0] - ys[1]) / (2 * h)


def rate_map(system, q):
    """``Q = d(dq/dt)/du`` at ``q`` (``(nq, nu)``): how the coordinates move along each speed
    (the identity but for quaternions); ``dq/dt`` is linear in ``u``."""
    if system.nq == system.nu:
        return np.eye(system.nu)
    return np.column_stack([system.q_rate(q, e) for e in np.eye(system.nu)])
