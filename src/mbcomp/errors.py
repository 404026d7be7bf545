"""Errors a modeller sees: each names the component, the port or parameter, and the fix."""
from __future__ import annotations

__all__ = ["ModelError", "InitializationError", "SimulationError", "SimulationInterrupted", "Problem"]


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


class SimulationInterrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) or SIGTERM stopped :func:`mbcomp.simulate`; the run's results up to
    the last accepted step are kept in :attr:`result` (status ``"interrupted"``).

    It is a :class:`KeyboardInterrupt`, so a script that does not catch it stops as it would
    on Ctrl-C instead of carrying on as if the run had finished; ``except Exception`` does
    not swallow it.

    Attributes
    ----------
    result : mbcomp.simulation.result.Result
        The partial result (``result.message`` says when and by what the run was stopped).
    signal : str
        ``"SIGINT"`` or ``"SIGTERM"``.

    Examples
    --------
    >>> from mbcomp.errors import SimulationInterrupted
    >>> e = SimulationInterrupted(None, "SIGTERM", "interrupted by SIGTERM at t=0.5 s")
    >>> isinstance(e, KeyboardInterrupt), e.signal, str(e)
    (True, 'SIGTERM', 'interrupted by SIGTERM at t=0.5 s')
    """

    def __init__(self, result, signal, message):
        super().__init__(message)
        self.result, self.signal = result, signal

    def __reduce__(self):  # picklable with its result (a study's worker hands it back)
        return type(self), (self.result, self.signal, str(self))
