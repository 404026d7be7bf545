"""How the command line words what it prints: an error as one line, the eigenvalues that
decide a classification, the exit status of a command a signal stopped.

``mbcomp stability`` and its ``--sweep`` print the first two, ``mbcomp simulate`` and ``mbcomp
study`` exit with the last, so they live here, below the commands.

Examples
--------
>>> from mbcomp.cli.messages import dominant_eigenvalues, one_line
>>> dominant_eigenvalues([-1.0, 1e-12 + 2j, 1e-12 - 2j])
'+0+2j, +0-2j'
>>> one_line(ValueError("a\\n  b"))
'a b'
"""
from __future__ import annotations

import numpy as np

from ..errors import ModelError

__all__ = ["one_line", "dominant_eigenvalues", "EXIT_SIGNAL"]

#: exit status of a command stopped by a signal, the shell's 128 + signal number: Ctrl-C
#: (SIGINT) 130, SIGTERM 143 (the results kept so far written)
EXIT_SIGNAL = {"SIGINT": 130, "SIGTERM": 143}


def one_line(exc):
    """An error as one line: a ModelError's header and every problem, joined by ``;``.

    Examples
    --------
    >>> from mbcomp.errors import ModelError, Problem
    >>> one_line(ModelError([Problem("a.m", "is negative", "give m >= 0"), Problem("b", "x", "y")]))
    'model has problems: a.m: is negative -> fix: give m >= 0; b: x -> fix: y'
    """
    problems = getattr(exc, "problems", None)
    if isinstance(exc, ModelError) and problems:
        head = str(exc).splitlines()[0].rstrip(":")
        head = head.rsplit(" (", 1)[0] if head.endswith(")") else head
        return f"{head}: " + "; ".join(" ".join(str(p).split()) for p in problems)
    return " ".join(str(exc).split())


def _complex(z):
    return f"{z.real:+.6g}" if z.imag == 0 else f"{z.real:+.6g}{z.imag:+.6g}j"


def dominant_eigenvalues(eigs):
    """The eigenvalues (1/s) whose real part is (within the classification tolerance) the
    largest, as text (at most four; parts below the tolerance print as 0; ``"-"`` if none)."""
    e = np.asarray(eigs, complex)
    e = e[np.isfinite(e)]
    if not e.size:
        return "-"
    tol = 1e-7 * (1.0 + np.abs(e).max())  # the classification's: parts below it print as 0
    sel = e[e.real >= e.real.max() - tol]
    sel = np.where(np.abs(sel.real) <= tol, 0.0, sel.real) + 1j * np.where(np.abs(sel.imag) <= tol, 0.0, sel.imag)
    return ", ".join(_complex(z) for z in sel[:4]) + (", ..." if sel.size > 4 else "")
