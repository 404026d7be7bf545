"""Stability: steady states, linearization in independent coordinates, eigenvalues, sweeps.

The seed's Chapter 7 for any composed model, holonomic and nonholonomic alike. This module
gathers the analysis done by :mod:`~mbcomp.analysis.steady` (steady states),
:mod:`~mbcomp.analysis.reduced` (the dynamics on the constraint manifold about a state),
:mod:`~mbcomp.analysis.linearization` (state matrix, eigenvalues, classification) and
:mod:`~mbcomp.analysis.sweep` (parameter sweeps), and writes their results as JSON:

* :func:`steady_states` finds states where chosen coordinates are at rest and the others
  move at constant rates (an equilibrium when all rates are zero): every speed's
  acceleration vanishes. Unknown coordinates and rates are searched in ranges by
  multi-start least squares; all distinct solutions are reported with how they were found.
* :func:`linearize` builds the state matrix ``A`` of the perturbation equations
  ``dY/dt = A Y`` (seed eq. 7.14) in independent coordinates: position increments along the
  joint speeds (quaternion joints by rotation vectors), minus the directions that moving
  coordinates take (they must be cyclic) and those the holonomic constraints determine, plus
  the independent speeds. A perturbed state is mapped onto the constraint manifold (Newton on
  the dependent positions, the velocity constraints solved for the dependent speeds) and its
  accelerations come from the full saddle-point system, so the multiplier terms of holonomic
  and nonholonomic constraints are in ``A`` exactly (no null-space shortcut that would drop
  them). Derivatives are exact where a generated program evaluates the model (the tangent
  program of the traced evaluation, :mod:`mbcomp.codegen.eval_tangent`: the manifold map by
  the implicit function theorem, the saddle-point solution differentiated), else central
  differences with Richardson extrapolation (error ~1e-11); ``Linearization.derivatives``
  says which.
  States that influence nothing (zero columns of ``A``: ignorable coordinates such as a
  bicycle's position and heading, conserved speeds) are removed and named; each removes one
  zero root.
* :func:`classify` follows seed Section 7.2: a real root > 0 or a complex root with positive
  real part is unstable; roots on the imaginary axis (the rest stable) are marginally stable;
  all real parts negative is asymptotically stable.
* :func:`sweep` repeats the analysis over a parameter and locates the values where the
  classification changes by root finding: Brent on the largest real part where it changes
  sign; where a real pair meets at zero and leaves along the imaginary axis (conservative
  systems), Brent on its signed square (``+a^2`` unstable, ``-b^2`` marginally stable); else
  bisection on the classification.

Examples
--------
The facade holds no code of its own; a worked linearization (the bead on a spinning ring,
seed Example 7.1) is in :mod:`mbcomp.analysis.linearization`.

>>> import mbcomp, mbcomp.stability as st
>>> from mbcomp.analysis import linearization
>>> st.linearize is linearization.linearize is mbcomp.linearize
True
>>> st.classify([-1.0 + 2.0j, -1.0 - 2.0j]), st.classify([2.0j, -2.0j]), st.classify([0.5, -0.5])
('asymptotically stable', 'marginally stable', 'unstable')
"""

from __future__ import annotations

import json

from .evaluation import BACKENDS, system_for  # noqa: F401  (BACKENDS: a name of this module)
from .linearization import Linearization, classify, linearize
from .steady import SteadyState, parse_steady, steady_states
from .sweep import Sweep, sweep

__all__ = ["SteadyState", "Linearization", "Sweep", "steady_states", "linearize", "classify", "sweep",
           "parse_steady", "system_for", "to_json"]


def to_json(obj, path):
    """Write a :class:`Linearization`, :class:`Sweep` or list of :class:`SteadyState` as JSON.

    Anything else is written as it is (it must be JSON-serializable).

    Examples
    --------
    >>> import json, os, tempfile, numpy as np
    >>> from mbcomp.stability import SteadyState, to_json
    >>> path = os.path.join(tempfile.mkdtemp(), "states.json")
    >>> to_json([SteadyState(np.zeros(1), np.ones(1), 0.0, {"hinge.w": 1.0}, 0.0, "given")], path)
    >>> json.load(open(path))[0]["u"]
    [1.0]
    """
    if isinstance(obj, (Linearization, Sweep)):
        data = obj.to_dict()
    elif isinstance(obj, (list, tuple)) and all(isinstance(x, SteadyState) for x in obj):
        data = [dict(q=x.q.tolist(), u=x.u.tolist(), t=x.t, values=x.values, residual=x.residual, how=x.how)
                for x in obj]
    else:
        data = obj
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1)
