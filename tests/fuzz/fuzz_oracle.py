"""The fuzz oracle: how every run of a random mechanism may end, and what it must hold.

:func:`run` builds a spec (:mod:`fuzz_mechanisms`), simulates it on the default path (compiled
program, ``dop853``) and classifies the end:

* ``"success"`` / ``"inaccurate"``: every column finite; a conservative system
  (:func:`mbcomp.assembly.conservation.nonconservative` empty) keeps ``energy.total`` within
  :data:`ENERGY_RTOL` times ``rtol`` (floor :data:`ENERGY_FLOOR`) of the energy the motion
  exchanges (largest kinetic energy plus the range of the potential one) for "success"; a driven
  or damped one keeps ``energy.balance`` (when results carry it) as close, on the run's output
  grid or on one 10 or 100 times finer (the work is a quadrature over that grid); the position
  residual stays under :data:`RESIDUAL` times the mechanism's size;
* ``"failed"`` / ``"budget"`` status, or a ``ModelError`` (``InitializationError``) or
  ``SimulationError`` raised: the message names a component of the model;
* anything else -- another exception type, a NaN, an unnamed failure, an invariant broken --
  raises :class:`Violation`.

Examples
--------
>>> spec = {"g": (0.0, -9.81, 0.0), "bodies": [dict(parent=-1, offset=None, rot=None,
...          joint="Revolute", axis=(0.0, 0.0, 1.0), start={"phi0": 0.3, "w0": 0.0},
...          body="PointMass", m=1.0, arm=(0.0, -1.0, 0.0), r_cm=None, I=None)],
...         "lines": [], "flanges": [], "loop": None}
>>> run(spec, t_end=0.2, n_out=11).kind
'success'
"""
from __future__ import annotations

import inspect
import re
from dataclasses import dataclass

import numpy as np

import mbcomp
from mbcomp.assembly.conservation import nonconservative
from mbcomp.errors import InitializationError, ModelError, SimulationError

from fuzz_mechanisms import build

__all__ = ["run", "Outcome", "Violation", "ENERGY_RTOL", "ENERGY_FLOOR", "RESIDUAL"]

#: the energy (balance) of a "success" may stray by this many rtol of the energy exchanged:
#: 10 times the library's own alarm (100 rtol over a tenth of the run), here over every point
ENERGY_RTOL = 1e3
#: ... and at least this share of it (the alarm's floor, 1e-5, times 10)
ENERGY_FLOOR = 1e-4
#: the position residual (m) of a success stays below this share of the mechanism's size
RESIDUAL = 1e-4

RTOL, ATOL = 1e-6, 1e-8
EPS = float(np.finfo(float).eps)
#: the finest output grid (intervals) the energy balance is checked on
MAX_GRID = 100_000
#: a run whose energy strays is still right when its coordinates and speeds stay within this
#: many of their tolerances (atol + rtol |y|) of a run 1000 times tighter: a stiff element held
#: by a constraint (a 4.9 MN/m spring in a loop, 5.6 MN on the closure) turns a loop residual
#: of 4.5e-11 m into 2.5e-4 J, which no energy bar on the motion's 0.024 J can tell from drift.
#: The global error adds the local errors of every step, which the tolerance bounds one at a
#: time: the same spring with its rest length at zero ends 26 tolerances off after 0.3 s
MOTION_SPAN = 100.0
_BUDGET = "max_wall_time" in inspect.signature(mbcomp.simulate).parameters


class Violation(AssertionError):
    """A run that ended in a way the oracle forbids."""


@dataclass
class Outcome:
    """How one run ended: ``kind`` (``success``, ``inaccurate``, ``failed``, ``budget``,
    ``ModelError``, ``InitializationError``, ``SimulationError``) and its message."""

    kind: str
    message: str = ""


def _names(model):
    """The component names a message may name (the world excepted: too generic a word)."""
    return {n.split(".")[0] for n in model.components()} - {"world"}


def _named(message, names):
    return any(re.search(rf"(?<![\w]){re.escape(n)}(?![\w])", message) for n in names)


def _size(spec):
    """A length scale of the mechanism (m): 1 plus every offset and centre."""
    s = 1.0
    for b in spec["bodies"]:
        for v in (b["offset"], b["r_cm"]):
            s += float(np.linalg.norm(v)) if v is not None else 0.0
    return s


def _energy_tol(res, rtol):
    """The energy (J) a "success" may stray by: the rtol share of what the motion exchanges
    (and of the work and dissipation), plus round-off on the energies' own size."""
    T, V = np.asarray(res["energy.kinetic"]), np.asarray(res["energy.potential"])
    scale = float(np.max(T) + np.ptp(V))
    scale += sum(float(np.max(np.abs(res[c]))) for c in ("energy.work", "energy.dissipated") if c in res.names)
    return max(ENERGY_RTOL * rtol, ENERGY_FLOOR) * scale + 1e3 * EPS * (float(np.max(np.abs(T) + np.abs(V))) + scale) \
        + 1e-12


def _drift(x):
    x = np.asarray(x, float)
    return float(np.max(np.abs(x - x[0])))


def _balance_held(res, system, rtol, atol, t_end):
    """Whether the energy balance of a driven or damped run holds: on the run's grid, or --
    its work and dissipation being quadratures over the output grid -- on a grid 10 times
    finer, then on one of 100 times as many points or 16 per integrator step (a stiff spring's
    oscillation), at most :data:`MAX_GRID` (a balance that does not converge to zero is a wrong
    power or energy); when no grid up to that resolves the power, the run's energy must agree
    with a run 1000 times tighter."""
    n, steps = len(res.time) - 1, int(res.stats.get("steps", 0))
    for grid in (n, 10 * n, min(max(100 * n, 16 * steps), MAX_GRID)):
        if grid > n:
            res = mbcomp.simulate(system, t_end=t_end, n_out=grid + 1, rtol=rtol, atol=atol)
            if res.status != "success":
                return True, ""
        drift, tol = _drift(res["energy.balance"]), _energy_tol(res, rtol)
        if drift <= tol:
            return True, ""
    # no grid resolves the power (a stiff spring ringing faster than MAX_GRID samples): the
    # quadrature cannot tell, so the motion itself is judged -- by a run 1000 times tighter
    ref = mbcomp.simulate(system, t_end=t_end, n_out=len(res.time), rtol=rtol * 1e-3, atol=atol * 1e-3)
    off = float(np.max(np.abs(res["energy.total"] - ref["energy.total"]))) if ref.status == "success" else np.inf
    if off <= tol or (motion := _motion_off(res, system, rtol, atol, ref)) <= MOTION_SPAN:
        return True, ""
    return False, (f"driven/damped system: energy balance off by {drift:.3g} J > {tol:.3g} J at {len(res.time)} "
                   f"points, the energy differs from a run at rtol {rtol * 1e-3:g} by {off:.3g} J and the motion by "
                   f"{motion:.3g} tolerances")


def _motion_off(res, system, rtol, atol, ref=None):
    """The largest distance of ``res``'s coordinates and speeds from a run 1000 times tighter
    (``ref``, made if not given, on the same output grid), each in units of the tolerance it
    is held to, ``atol + rtol |y|``; infinite if that run does not reach the same end."""
    if ref is None or len(ref.time) != len(res.time):
        ref = mbcomp.simulate(system, t_end=float(res.time[-1]), n_out=len(res.time), rtol=rtol * 1e-3,
                              atol=atol * 1e-3)
    if ref.status not in ("success", "inaccurate") or len(ref.time) != len(res.time):
        return np.inf
    worst = 0.0
    for name in list(system.q_names) + list(system.u_names):
        if name in res.names and name in ref.names:
            a, b = np.asarray(res[name], float), np.asarray(ref[name], float)
            worst = max(worst, float(np.max(np.abs(a - b) / (atol + rtol * np.abs(b)))))
    return worst


def _check_success(res, system, spec, rtol, atol):
    """The invariants of a run that reached t_end."""
    bad = [n for n in res.names if not np.all(np.isfinite(np.asarray(res[n], float)))]
    if bad or not np.all(np.isfinite(res.time)):
        raise Violation(f"{res.status} with non-finite columns {bad[:6]}")
    if res.status == "success" and not nonconservative(system):
        drift, tol = _drift(res["energy.total"]), _energy_tol(res, rtol)
        if drift > tol and (off := _motion_off(res, system, rtol, atol)) > MOTION_SPAN:
            raise Violation(f"conservative system: energy drifted {drift:.3g} J > {tol:.3g} J with status success, "
                            f"and the motion is {off:.3g} tolerances off a run 1000 times tighter")
    elif res.status == "success" and "energy.balance" in res.names:
        ok, why = _balance_held(res, system, rtol, atol, float(res.time[-1]))
        if not ok:
            raise Violation(why)
    if "residual.position" in res.names and len(res.time):
        resid = float(np.max(res["residual.position"]))
        if resid > RESIDUAL * _size(spec):
            raise Violation(f"{res.status} with the loop open by {resid:.3g} (> {RESIDUAL * _size(spec):.3g})")


def run(spec, t_end=0.3, n_out=31, max_wall_time=5.0, rtol=RTOL, atol=ATOL):
    """Build and simulate ``spec``; the :class:`Outcome`, or :class:`Violation` raised."""
    model = None
    try:
        model = build(spec)
        system = mbcomp.assemble(model)
        extra = {"max_wall_time": max_wall_time} if _BUDGET else {}
        res = mbcomp.simulate(system, t_end=t_end, n_out=n_out, rtol=rtol, atol=atol, **extra)
    except (ModelError, SimulationError) as exc:
        kind = type(exc).__name__ if isinstance(exc, (InitializationError, SimulationError)) else "ModelError"
        if model is None:
            raise Violation(f"{kind} raised while building the spec itself: {exc}") from exc
        if not _named(str(exc), _names(model)):
            raise Violation(f"{kind} names no component of the model: {exc}") from exc
        return Outcome(kind, str(exc))
    except Exception as exc:  # the oracle's point: any other exception is a finding
        raise Violation(f"unexpected {type(exc).__name__}: {exc}") from exc
    if res.status in ("success", "inaccurate"):
        _check_success(res, system, spec, rtol, atol)
        return Outcome(res.status, res.message)
    if res.status in ("failed", "budget"):
        if not _named(res.message, _names(model)):
            raise Violation(f"status {res.status} names no component: {res.message}")
        return Outcome(res.status, res.message)
    raise Violation(f"unexpected status {res.status!r}: {res.message}")
