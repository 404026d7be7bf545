"""The batch runner (mbcomp.codegen.batch): its threads' priority and CPU time.

A block's C threads run below the Python thread preparing the next block: at the process's
niceness plus ``nice`` -- set, not added, so a thread that calls the runner block after block
stays there instead of sinking to the lowest priority (where any other load on the machine
starves it). The CPU time it reports is its threads' own."""
import os
import sys
import threading
import time

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler, compile_system
from mbcomp.codegen.batch import run_batch
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="the batch runner needs a C compiler")


def pendulum_program():
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return compile_system(mbcomp.assemble(m), "c").evaluator.integrator(0.0, 0.0).bound


def runs(b, n, t_end=1.0):
    y0 = np.column_stack((np.linspace(-1.0, 1.0, n), np.zeros(n)))
    return b.code, 8, np.tile(b.hbuf, (n, 1)), np.tile(b.pbuf, (n, 1)), y0, np.linspace(0.0, t_end, 11), 1e-10, 1e-12


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="thread priorities: Linux")
def test_a_thread_calling_block_after_block_keeps_one_priority():
    b = pendulum_program()
    base = os.getpriority(os.PRIO_PROCESS, os.getpid())
    seen = []

    def blocks():  # the batch's own thread: one call per block
        for _ in range(4):
            run_batch(*runs(b, 4), threads=2, nice=3)
            seen.append(os.getpriority(os.PRIO_PROCESS, threading.get_native_id()))

    t = threading.Thread(target=blocks)
    t.start()
    t.join()
    want = min(19, base + 3)
    assert seen == [want] * 4, (base, seen)   # not base + 3, + 6, + 9, + 12
    assert os.getpriority(os.PRIO_PROCESS, os.getpid()) == base   # the main thread untouched


def test_the_cpu_time_is_the_threads_own():
    b = pendulum_program()
    args = runs(b, 64, t_end=20.0)
    w0 = time.perf_counter()
    one = run_batch(*args, threads=1)
    wall = time.perf_counter() - w0
    two = run_batch(*args, threads=2)
    # one thread: at most its wall time; two threads: the same work (the same steps, counted)
    assert 0 < one.cpu_time <= wall * 1.05 + 1e-3
    np.testing.assert_array_equal(one.counts, two.counts)
    assert 0.5 * one.cpu_time < two.cpu_time < 2.0 * one.cpu_time + 1e-3
