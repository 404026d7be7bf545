"""The one clock of ``bench/peers.py`` and its peer builders: CPU seconds of this process and its
finished children.

Why not ``time.process_time`` alone: building a compiled peer runs a C compiler in a child
process (pydy's Cython, mbcomp's C backend), whose CPU time ``process_time`` does not see.
``getrusage(RUSAGE_CHILDREN)`` adds the children's time once they have been waited for,
which is what a build step does (``os.times`` would too, but ticks in 10 ms). For timing calls
inside this process (no children) it equals ``process_time``.
"""
import resource
import time

__all__ = ["cpu"]


def cpu():
    """CPU seconds (user + system) of this process and of its waited-for children."""
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime
