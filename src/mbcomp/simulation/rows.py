"""Constraint rows followed along the motion: the kept rows chosen again where they lose rank.

A loop modelled with more closure equations than it has independent ones (Bricard's linkage,
a planar loop of 3-D joints, a Sarrus linkage) keeps ``r`` of its ``m`` holonomic rows:
consistent initialization chooses them by pivoted QR at the start (``system.row_mask``).
That choice can degrade along the motion while the full set keeps its rank ``r``: the kept
rows of Bricard's linkage lose rank at t = 1.2466 s, where the full five-row Jacobian's four
singular values stay >= 1.2. :class:`RowChoice`, a hook after every accepted step, watches
the kept rows' smallest relative singular value; below :attr:`RowChoice.KEPT_MIN` it asks
pivoted QR of the full Jacobian for the best-conditioned ``r`` rows and, when those are
:attr:`RowChoice.GAIN` times better conditioned, makes them the kept rows and restarts the
stepper from the same ``[q, u]`` (the formulation writes its state in the new rows:
:meth:`mbcomp.formulations.Formulation.rows_changed`). The programs of each row set are
traced once and cached (:mod:`mbcomp.codegen`), so going back and forth costs a restart.
A true singular position -- the *full* Jacobian losing rank -- is not this hook's matter: the
rank monitor (:class:`mbcomp.simulation.monitors.ConstraintRank`) watches the full set.

"""
from __future__ import annotations

import numpy as np

from ..assembly.manifold import pivot_partition
from .monitors import relative_sigma
from .stepping import StepHook

__all__ = ["RowChoice"]


class RowChoice(StepHook):
    """Choose the kept constraint rows again when they lose rank and others do not.

    Parameters
    ----------
    system : MultibodySystem
        Initialized, with rows dropped (``row_mask`` not all true).

    Attributes
    ----------
    changes : list of dict
        Every change: ``t`` (s), ``dropped`` (the row names dropped from then on), ``was``
        (those dropped before), ``sigma_before`` and ``sigma_after`` (the kept rows'
        smallest relative singular value before and after).

    Examples
    --------
    The driver adds one to every run of a model that dropped rows
    (:func:`mbcomp.simulation.driver.hooks_for`); its
    changes are the result's ``stats["row_changes"]``:

    >>> import pathlib, mbcomp
    >>> from mbcomp.simulation.rows import RowChoice
    >>> root = pathlib.Path(mbcomp.__file__).resolve().parents[2]
    >>> bricard = mbcomp.load_model_file(root / "models" / "bricard.py")
    >>> r = mbcomp.simulate(bricard.build(), t_end=1.5, n_out=16)
    >>> [(c["was"], c["dropped"]) for c in r.stats["row_changes"]], r.success
    ([(['joint5.tilt_2'], ['joint5.y'])], True)
    >>> RowChoice.KEPT_MIN, RowChoice.GAIN
    (0.1, 4.0)
    """

    #: look for better rows when the kept rows' sigma_min / sigma_max falls below this
    KEPT_MIN = 0.1
    #: take them when their sigma_min / sigma_max is at least this many times the kept rows'
    GAIN = 4.0

    def __init__(self, system):
        self.system = system
        self.names = system.constraint_names(all_rows=True)
        self.changes = []

    def __call__(self, run):
        sysm, s, form = self.system, run.stepper, run.form
        mask = sysm.row_mask
        end = run.step_end()  # (shared with the run monitors when no projection came between)
        q, u = end.q, end.u
        C = end.rows.C
        kept = relative_sigma(C[mask])
        if kept >= self.KEPT_MIN:
            return
        rows, _ = pivot_partition(C.T, int(mask.sum()), tol=0)
        new = np.zeros_like(mask)
        new[rows] = True
        best = relative_sigma(C[new])
        if np.array_equal(new, mask) or best < self.GAIN * kept:
            return
        self.changes.append(dict(t=float(s.t), dropped=self._dropped(new), was=self._dropped(mask),
                                 sigma_before=kept, sigma_after=best))
        sysm.row_mask = new  # a new object: every cache keyed by the mask sees the change
        run.start(s.t, form.rows_changed(s.t, q, u))
        run.stats["restarts"] += 1

    def _dropped(self, mask):
        return [n for n, k in zip(self.names, mask) if not k]

    def stats(self):
        """``row_changes``: :attr:`changes`."""
        return {"row_changes": list(self.changes)}
