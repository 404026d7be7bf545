"""Errors a modeller sees: each names the component, the port or parameter, and the fix."""
from __future__ import annotations

__all__ = ["ModelError", "InitializationError", "SimulationError", "Problem"]


class Problem:
    """One problem found in a model.

    Parameters
    ----------
    where : str
        Component, port or parameter path, e.g. ``"crank.frame_a"``.
    what : str
        What is wrong.
    fix : str
        What the modeller should do.
    """

    def __init__(self, where: str, what: str, fix: str):
        self.where, self.what, self.fix = where, what, fix

    def __str__(self):
        return f"{self.where}: {self.what} -> fix: {self.fix}"

    def __repr__(self):
        return f"Problem({self.where!r}, {self.what!r}, {self.fix!r})"


class ModelError(ValueError):
    """A model that cannot be assembled; ``problems`` lists every problem found.

    Examples
    --------
    >>> from mbcomp.errors import ModelError, Problem
    >>> e = ModelError([Problem("body", "mass -1 kg is negative", "give a mass >= 0")])
    >>> "body: mass -1 kg is negative" in str(e)
    True
    """

    def __init__(self, problems, header="model has problems"):
        self.problems = list(problems)
        lines = [f"{header} ({len(self.problems)}):"] + [f"  - {p}" for p in self.problems]
        super().__init__("\n".join(lines))


class InitializationError(ModelError):
    """Initial conditions that are over-specified or cannot be assembled."""

    def __init__(self, problems, header="consistent initialization failed"):
        super().__init__(problems, header)


class SimulationError(RuntimeError):
    """A failure during integration (singular matrix, step-size collapse, non-finite state).

    The simulation driver catches it and returns a ``Result`` with ``status`` set,
    so results computed up to the failure are never lost.
    """
