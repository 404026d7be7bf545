"""The shared C pieces (the runtime's objects, the thin call's extension) built ahead by
``prepare_runtime``: once per process and directory, on threads, in the machine's runtime
directory (``$MBCOMP_RUNTIME``), not in each programs' cache; a program built in any cache links
them and computes what it computes with its own runtime; a forked child builds its own instead
of waiting for its parent's threads, which it does not have."""
import multiprocessing
import os

import numpy as np
import pytest

import mbcomp
from conftest import stop_pendulum
from mbcomp.codegen import c_compiler
from mbcomp.codegen.compiler import prepare_runtime
from mbcomp.codegen.toolchain import runtime_directory

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")


def test_the_runtime_is_built_once_per_process_and_directory(tmp_path, monkeypatch):
    a, b = str(tmp_path / "a"), str(tmp_path / "b")
    monkeypatch.setenv("MBCOMP_RUNTIME", a)
    (tmp_path / "programs").mkdir()
    monkeypatch.setenv("MBCOMP_CACHE", str(tmp_path / "programs"))
    jobs = prepare_runtime()
    objs = jobs[0].result(timeout=300)
    assert objs and all(os.path.exists(o) and os.path.dirname(o) == a for o in objs)
    assert prepare_runtime() is jobs                         # asked again: the same build
    assert not os.listdir(tmp_path / "programs")             # nothing of it in the programs' cache
    monkeypatch.setenv("MBCOMP_RUNTIME", b)
    other = prepare_runtime()
    assert other is not jobs and [os.path.basename(o) for o in other[0].result(timeout=300)] == \
        [os.path.basename(o) for o in objs]                  # the same runtime, in the other directory


def test_without_a_writable_runtime_directory_the_programs_cache_holds_it(tmp_path, monkeypatch):
    blocked = tmp_path / "a file"
    blocked.write_text("")
    monkeypatch.setenv("MBCOMP_RUNTIME", str(blocked / "runtime"))   # cannot be made: a file is in the way
    assert runtime_directory(str(tmp_path / "programs")) == str(tmp_path / "programs")


def _pendulum():  # conftest's pendulum without stops, from 0.5 rad
    return stop_pendulum(limits=None, phi0=0.5)


def test_a_new_programs_cache_links_the_machines_runtime_and_computes_the_same(tmp_path, monkeypatch):
    """Two runs in two new programs' caches: the first with a new runtime directory too (all
    compiled), the second with the runtime the first built (none of it compiled again, nothing
    of it in its cache). The C engine runs in both and every column is the same, bit for bit."""
    monkeypatch.setenv("MBCOMP_RUNTIME", str(tmp_path / "machine"))
    runs = []
    for name in ("first", "second"):
        d = tmp_path / name
        monkeypatch.setenv("MBCOMP_CACHE", str(d))
        before = set(os.listdir(tmp_path / "machine")) if runs else None
        res = mbcomp.simulate(_pendulum(), t_end=2.0, rtol=1e-9, atol=1e-11)
        assert res.status == "success" and res.stats["stretches"] > 0 and res.stats["python_steps"] == 0, res.stats
        runs.append(res)
        assert not [f for f in os.listdir(d) if f.startswith("mbrt_")]
        if before is not None:
            assert set(os.listdir(tmp_path / "machine")) == before   # the second compiled no runtime
    first, second = runs
    assert first.names == second.names
    for name in first.names:
        np.testing.assert_array_equal(first[name], second[name])


def _child(queue):
    objs = prepare_runtime()[0].result(timeout=60)
    queue.put(all(os.path.exists(o) for o in objs))


def test_a_forked_child_does_not_wait_for_its_parents_threads(tmp_path, monkeypatch):
    monkeypatch.setenv("MBCOMP_RUNTIME", str(tmp_path / "fresh"))
    ctx = multiprocessing.get_context("fork")
    prepare_runtime()           # compiling on the parent's threads while it forks
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(queue,))
    proc.start()
    try:
        assert queue.get(timeout=90) is True
    finally:
        proc.join(timeout=30)
        if proc.is_alive():
            proc.kill()
    assert proc.exitcode == 0
