"""Timing helpers of ``bench/peers.py`` and its cases: CPU time per call, CPU budgets, the
tolerance sweep to a target error, a fresh compile cache.

Every time here is CPU time (``time.process_time``, or :func:`peers.cpu_clock.cpu` where a
compiler's child processes count); medians of repeats.
"""
import math
import os
import shutil
import signal
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from .cpu_clock import cpu

__all__ = ["per_call", "batch_seconds", "OverBudget", "cpu_budget", "Try", "sweep", "fresh_cache"]


def per_call(f, batch_time=0.05, repeats=5):
    """CPU seconds per call of ``f()``: median over ``repeats`` batches of about ``batch_time``."""
    c0 = cpu()
    f()
    first = cpu() - c0
    if first > 0.2:  # a slow call: a few single calls are enough
        times = [first]
        for _ in range(2):
            c0 = time.process_time()
            f()
            times.append(time.process_time() - c0)
        return float(np.median(times))
    n = 1
    while True:
        c0 = time.process_time()
        for _ in range(n):
            f()
        dt = time.process_time() - c0
        if dt >= batch_time or n >= 1 << 18:
            break
        n *= 2
    times = [dt / n]
    for _ in range(repeats - 1):
        c0 = time.process_time()
        for _ in range(n):
            f()
        times.append((time.process_time() - c0) / n)
    return float(np.median(times))


def batch_seconds(f, batch_time=0.05, repeats=3):
    """CPU seconds per call of a short ``f()`` (a build of microseconds), compiler processes
    included: the median of ``repeats`` batches of about ``batch_time``. One call is not
    timed alone: under load this VM's process clock stalls for up to ms and then catches up,
    and single sub-millisecond builds read as exactly 0."""
    times = []
    for _ in range(repeats):
        n, c0 = 0, cpu()
        while True:
            f()
            n += 1
            dt = cpu() - c0
            if dt >= batch_time or n >= 1000:
                break
        times.append(dt / n)
    return float(np.median(times))


class OverBudget(BaseException):
    """A run used more CPU than allowed (a BaseException: no ``except Exception`` keeps it)."""


class cpu_budget:
    """Context: raise :class:`OverBudget` after ``seconds`` of CPU time (SIGPROF timer)."""

    def __init__(self, seconds):
        self.seconds = seconds

    def __enter__(self):
        def handler(signum, frame):
            raise OverBudget()

        self.old = signal.signal(signal.SIGPROF, handler)
        signal.setitimer(signal.ITIMER_PROF, self.seconds)

    def __exit__(self, *exc):
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, self.old)
        return False


@dataclass
class Try:
    """One timed run at one tolerance setting: CPU s, max error, rhs calls, failure or note."""
    setting: float
    cpu_s: float = math.nan
    err: float = math.nan
    nfev: float = math.nan
    fail: str = ""
    note: str = ""


def sweep(run, start, budget, stop=26, target=1e-8, repeats=3):
    """Tighten the setting 10^(-k/2), k = start.. until ``run(setting).err <= target``.

    Returns ``(passing Try or None, note, k)``; a passing run under 1 s is timed ``repeats``
    times (median; at least 7 times under 0.05 s). Gives up when a run exceeds ``budget`` CPU s, fails, or when the last
    two runs (each over 0.05 s) extrapolate (cost ~ error^-p) to more than 3 budgets."""
    tries = []
    for k in range(start, stop + 1):
        s = 10 ** (-k / 2)
        try:
            with cpu_budget(budget):
                t = run(s)
        except OverBudget:
            return None, f"over the {budget:g} s budget at setting {s:.0e}", k
        if t.fail:
            return None, f"failed at setting {s:.0e}: {t.fail}", k
        tries.append(t)
        if t.err <= target:
            if t.cpu_s < 1.0:  # a short run: the median of three (of seven under 50 ms, where a shared
                # machine's scheduling moves single runs by 2x)
                n = repeats if t.cpu_s >= 0.05 else max(repeats, 7)
                t.cpu_s = float(np.median([t.cpu_s] + [run(s).cpu_s for _ in range(n - 1)]))
            return t, "", k
        if len(tries) >= 2:
            a, z = tries[-2], tries[-1]
            # cost ~ error^-p from runs long enough to time (shorter ones are the clock's noise)
            if z.err < a.err and z.cpu_s > a.cpu_s > 0.05:
                p = math.log(z.cpu_s / a.cpu_s) / math.log(a.err / z.err)
                need = z.cpu_s * (z.err / target) ** p
                if need > 3 * budget:
                    return None, f"error {z.err:.0e} at setting {s:.0e}; {target:g} extrapolates to ~{need:.2g} s", k
    return None, f"error {tries[-1].err:.0e} at the tightest setting", stop


class fresh_cache:
    """Context: a new empty ``MBCOMP_CACHE`` directory (so the C compiler really runs), removed
    on exit; ``mbcomp.simulate``'s own compilations use it too."""

    def __enter__(self):
        self.old = os.environ.get("MBCOMP_CACHE")
        self.path = tempfile.mkdtemp(prefix="mbcomp-peers-")
        os.environ["MBCOMP_CACHE"] = self.path
        return self.path

    def __exit__(self, *exc):
        if self.old is None:
            os.environ.pop("MBCOMP_CACHE", None)
        else:
            os.environ["MBCOMP_CACHE"] = self.old
        shutil.rmtree(self.path, True)
        return False
