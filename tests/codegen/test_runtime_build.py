"""How the C runtime's objects come to be (``codegen/runtime_build.py``, issue 32 item 7): a
machine's first run of the default path compiles no RADAU5 (a library of its own, built at the
first radau5 step in C, stepping the same as before); objects an install built are copied, not
compiled again, and only under the key a run computes; an install never fails for the runtime."""
import os
import subprocess

import numpy as np
import pytest

import mbcomp
from conftest import stop_pendulum
from mbcomp.codegen import c_compiler
from mbcomp.codegen import runtime_build
from mbcomp.codegen.engine import runtime_objects

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _pendulum():  # conftest's pendulum without stops, from 0.5 rad
    return stop_pendulum(limits=None, phi0=0.5)


def _radau_files(d):
    return sorted(f for f in os.listdir(d) if "radau" in f)


def test_the_default_path_builds_no_radau_and_radau_builds_its_own_library(tmp_path, monkeypatch):
    """A run by the default method in a new runtime directory compiles the core only; a radau5
    run then builds RADAU5's three objects and its library there, steps in C, and agrees with
    the default run (both to their tolerance of the closed-loop-free pendulum's swing)."""
    machine = tmp_path / "machine"
    monkeypatch.setenv("MBCOMP_RUNTIME", str(machine))
    monkeypatch.setenv("MBCOMP_CACHE", str(tmp_path / "programs"))
    monkeypatch.setenv("MBCOMP_PREBUILT", "")      # nothing from an install: what is compiled shows
    opts = dict(t_end=2.0, rtol=1e-9, atol=1e-11)
    auto = mbcomp.simulate(_pendulum(), **opts)
    assert auto.status == "success" and auto.stats["stretches"] > 0
    assert _radau_files(machine) == []
    core = {os.path.basename(o).split("_", 2)[2] for o in runtime_objects(c_compiler(), str(machine))}
    assert {"mbcomp_glue.o", "mbrt_rk.o", "mbrt_dopri5.o", "mbrt_dop853.o", "mbrt_mech.o"} <= core
    assert not [o for o in core if "radau" in o]
    rad = mbcomp.simulate(_pendulum(), method="radau5", **opts)
    assert rad.status == "success" and rad.stats["stretches"] >= 1 and rad.stats["python_steps"] == 0, rad.stats
    made = _radau_files(machine)
    assert [f for f in made if f.endswith(".o")] and [f for f in made if f.startswith("mbrt_radau_")]
    np.testing.assert_allclose(rad["hinge.phi"], auto["hinge.phi"], atol=1e-6)


def test_objects_an_install_built_are_copied_not_compiled(tmp_path, monkeypatch):
    """``build_install`` into a directory, then a new runtime directory reading it as the
    install's: every object arrives byte for byte, no compiler runs (one that would raises)."""
    cc = c_compiler()
    pre = tmp_path / "prebuilt"
    made = runtime_build.build_install(str(pre))
    assert len(made) == sum(len(runtime_build.sources(p)) for p in runtime_build.PARTS)
    monkeypatch.setenv("MBCOMP_PREBUILT", str(pre))

    def no_compiler(*a, **k):
        raise AssertionError(f"compiled although the install built it: {a[0]}")
    monkeypatch.setattr(runtime_build.subprocess, "run", no_compiler)
    machine = tmp_path / "machine"
    for part in runtime_build.PARTS:
        for obj in runtime_build.build_objects(cc, str(machine), part):
            assert (pre / os.path.basename(obj)).read_bytes() == open(obj, "rb").read()


def test_an_object_built_for_another_compiler_is_not_taken(tmp_path, monkeypatch):
    """The key names the compiler (and flags, platform, architecture): objects an install built
    with another compiler are not linked; this one's are compiled."""
    pre = tmp_path / "prebuilt"
    runtime_build.build_install(str(pre))
    monkeypatch.setenv("MBCOMP_PREBUILT", str(pre))
    other = tmp_path / "bin"
    other.mkdir()
    (other / "cc2").symlink_to(c_compiler())
    objs = runtime_build.build_objects(str(other / "cc2"), str(tmp_path / "machine"), "radau")
    assert all(not (pre / os.path.basename(o)).exists() for o in objs) and all(os.path.exists(o) for o in objs)


def test_an_install_without_a_working_compiler_builds_nothing_and_does_not_fail(tmp_path, monkeypatch):
    false = subprocess.run(["which", "false"], capture_output=True, text=True).stdout.strip()
    monkeypatch.setenv("CC", false)                # a compiler that fails on every source
    assert runtime_build.build_install(str(tmp_path / "a")) == []
    monkeypatch.delenv("CC")
    monkeypatch.setenv("PATH", str(tmp_path / "nothing"))  # no compiler at all
    assert runtime_build.find_compiler() is None and runtime_build.build_install(str(tmp_path / "b")) == []


def test_a_source_the_compiler_fails_on_is_named_and_nothing_half_built_stays(tmp_path, monkeypatch):
    """A compiler failing on one source: the error names it (and the fix, as a CodegenError from
    the engine); no object of that source is left in the directory, the others are whole."""
    from mbcomp.codegen.graph import CodegenError

    cc = tmp_path / "cc"
    cc.write_text(f'#!/bin/sh\ncase "$*" in *mbrt_linalg.c*) echo "broken here" >&2; exit 1;; esac\n'
                  f'exec {c_compiler()} "$@"\n')
    cc.chmod(0o755)
    monkeypatch.setenv("MBCOMP_PREBUILT", "")
    d = tmp_path / "machine"
    with pytest.raises(CodegenError, match=r"mbrt_linalg\): broken here.*backend='python'"):
        runtime_objects(str(cc), str(d))
    left = os.listdir(d)
    assert not [f for f in left if "linalg" in f] and all(f.endswith(".o") for f in left)
    assert not [f for f in left if os.path.getsize(d / f) == 0]





def _wheel(tmp_path, env):
    """Build mbcomp's wheel from a copy of the source tree (no build isolation: offline, the
    installed setuptools); the names in it."""
    import shutil
    import sys
    import zipfile

    tree = tmp_path / "tree"
    skip = shutil.ignore_patterns("prebuilt", "__pycache__", "*.egg-info", "build")
    for name in ("src", "library"):
        shutil.copytree(os.path.join(ROOT, name), tree / name, ignore=skip)
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy(os.path.join(ROOT, name), tree / name)
    out = tmp_path / "wheel"
    res = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                          str(out), str(tree)], capture_output=True, text=True, env=env, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    (whl,) = out.glob("*.whl")
    return zipfile.ZipFile(whl).namelist()


def test_a_wheel_carries_the_runtime_under_the_keys_a_run_computes_and_builds_without_a_compiler(tmp_path):
    """``setup.py``'s step: the wheel holds every part's objects, named as this machine's run
    names them (so they are copied, not compiled; and the thin call's extension where this
    environment has numpy); with a compiler that fails, the wheel is built all the same,
    without them."""
    names = _wheel(tmp_path / "a", dict(os.environ))
    got = sorted(n.rsplit("/", 1)[1] for n in names if n.startswith("mbcomp/codegen/prebuilt/") and n.endswith(".o"))
    want = sorted(os.path.basename(o) for p in runtime_build.PARTS
                  for _, _, o in runtime_build.object_paths(c_compiler(), "", p))
    assert got == want
    from mbcomp.export.fmu import FMU_SOURCES  # an installed mbcomp exports FMUs: their C is package data

    assert {f"mbcomp/export/{f}" for f in FMU_SOURCES + ("fmi2.c", "fmi3.c")} <= set(names)
    false = subprocess.run(["which", "false"], capture_output=True, text=True).stdout.strip()
    names = _wheel(tmp_path / "b", dict(os.environ, CC=false))
    assert "mbcomp/codegen/runtime_build.py" in names and not [n for n in names if "/prebuilt/" in n]


def test_the_thin_extension_an_install_built_is_the_one_a_run_builds_and_is_copied(tmp_path, monkeypatch):
    """``build_thin_install`` (a new process of this Python, mbcomp from the source tree) makes
    the file this process's :func:`~mbcomp.codegen.thin.extension` would make (its name is the
    key: this Python, this numpy, these headers); a new runtime directory gets it by copy,
    byte for byte, and nothing else of the install's."""
    from mbcomp.codegen import thin

    pre = tmp_path / "prebuilt"
    assert runtime_build.build_thin_install(str(pre), os.path.join(ROOT, "src"))
    (built,) = [f for f in os.listdir(pre) if f.startswith(runtime_build.THIN_PREFIX)]
    thin.forget()
    try:
        assert thin.extension(str(tmp_path / "here")) is not None
    finally:
        thin.forget()
    assert [f for f in os.listdir(tmp_path / "here") if f.startswith(runtime_build.THIN_PREFIX)] == [built]
    monkeypatch.setenv("MBCOMP_PREBUILT", str(pre))
    machine = tmp_path / "machine"
    assert runtime_build.copy_installed_extensions(str(machine)) == [built]
    assert (machine / built).read_bytes() == (pre / built).read_bytes() and os.listdir(machine) == [built]
    assert runtime_build.copy_installed_extensions(str(machine)) == []      # there already: nothing again
