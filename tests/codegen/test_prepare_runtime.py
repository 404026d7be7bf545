"""The shared C pieces built ahead (``prepare_runtime``): once per process and cache directory,
on threads; a program built after links them; a forked child builds its own instead of
waiting for its parent's threads, which it does not have."""
import multiprocessing
import os

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.codegen.compiler import prepare_runtime

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")


def test_the_runtime_is_built_once_per_process_and_directory(tmp_path):
    a, b = str(tmp_path / "a"), str(tmp_path / "b")
    jobs = prepare_runtime(a)
    objs = jobs[0].result(timeout=300)
    assert objs and all(os.path.exists(o) and os.path.dirname(o) == a for o in objs)
    assert prepare_runtime(a) is jobs                        # asked again: the same build
    other = prepare_runtime(b)
    assert other is not jobs and [os.path.basename(o) for o in other[0].result(timeout=300)] == \
        [os.path.basename(o) for o in objs]                  # the same runtime, in the other directory


def _pendulum():
    m = mbcomp.Model()
    w = m.add("world", mbcomp.library.World())
    j = m.add("j", mbcomp.library.Revolute(phi0=0.5))
    rod = m.add("rod", mbcomp.library.FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", mbcomp.library.PointMass(m=1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def test_a_run_after_the_runtime_was_prepared_is_the_run_of_a_cold_cache(tmp_path, monkeypatch):
    """The C engine runs in both (the prepared runtime linked, not compiled again) and every
    column is the same, bit for bit."""
    runs = []
    for name, prepare in (("cold", False), ("prepared", True)):
        d = str(tmp_path / name)
        monkeypatch.setenv("MBCOMP_CACHE", d)
        if prepare:
            prepare_runtime()[0].result(timeout=300)
            before = set(os.listdir(d))
        res = mbcomp.simulate(_pendulum(), t_end=2.0, rtol=1e-9, atol=1e-11)
        assert res.status == "success" and res.stats["stretches"] > 0 and res.stats["python_steps"] == 0, res.stats
        runs.append(res)
        if prepare:
            made = set(os.listdir(d)) - before
            assert not any(f.startswith("mbrt_") for f in made), sorted(made)   # the runtime was there
    cold, prepared = runs
    assert cold.names == prepared.names
    for name in cold.names:
        np.testing.assert_array_equal(cold[name], prepared[name])


def _child(d, queue):
    objs = prepare_runtime(d)[0].result(timeout=60)
    queue.put(all(os.path.exists(o) for o in objs))


def test_a_forked_child_does_not_wait_for_its_parents_threads(tmp_path):
    ctx = multiprocessing.get_context("fork")
    d = str(tmp_path / "fresh")
    prepare_runtime(d)          # compiling on the parent's threads while it forks
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(d, queue))
    proc.start()
    try:
        assert queue.get(timeout=90) is True
    finally:
        proc.join(timeout=30)
        if proc.is_alive():
            proc.kill()
    assert proc.exitcode == 0
