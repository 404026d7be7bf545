"""A C harness driving an FMU's own sources, built with AddressSanitizer and UBSan (the event
tests' shared plumbing): the FMU unzipped, its model file found, the harness compiled with
every warning against it and the runtime's C, then run with leak detection.

``build(fmu, harness, tmp_path)`` returns the executable, or calls ``pytest.skip`` where this
compiler cannot build a sanitized program; ``run(exe, *args)`` runs it and asserts that no
sanitizer spoke. The template's ``MODEL_C`` is replaced by the model file's name.

The runtime's C (``mbrt_*.c``, the same in every FMU) is compiled with the sanitizers once per
machine and source text (:func:`runtime_objects`: a directory keyed by the sources' hash and the
flags, shared by the test workers): it took 2.6 s of every sanitized build.
"""
import hashlib
import os
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

import pytest

from mbcomp.codegen import c_compiler

SAN_FLAGS = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-O1", "-g"]
ENV = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"}


def usable(tmp_path, flags=SAN_FLAGS):
    """Whether this compiler builds a program with the sanitizer ``flags``."""
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    return subprocess.run([c_compiler(), *flags, str(probe), "-o", str(tmp_path / "probe")],
                          capture_output=True).returncode == 0


def runtime_objects(sources, flags=SAN_FLAGS):
    """The object files of the runtime's C in ``sources`` (an FMU's ``sources`` folder) compiled
    with ``flags`` and ``-Wall -Wextra``, made once per source text and flags (a directory under
    the temporary folder, written whole and renamed into place: workers racing keep one)."""
    files = sorted(Path(sources).glob("mbrt_*.c"))
    key = hashlib.sha256(repr(flags).encode() + b"".join(f.name.encode() + f.read_bytes() for f in files))
    done = Path(tempfile.gettempdir()) / f"mbcomp-sanitized-runtime-{key.hexdigest()[:16]}"
    if not done.is_dir():
        work = Path(tempfile.mkdtemp(prefix=done.name + "-"))
        for f in files:
            res = subprocess.run([c_compiler(), *flags, "-std=c99", "-Wall", "-Wextra", "-c", str(f), "-I", str(sources),
                                  "-o", str(work / (f.stem + ".o"))], capture_output=True, text=True)
            assert res.returncode == 0 and "warning" not in res.stderr, res.stderr[-3000:]
        try:
            os.rename(work, done)
        except OSError:  # another worker put its copy there first
            shutil.rmtree(work, ignore_errors=True)
    return sorted(map(str, done.glob("*.o")))


def build(fmu, harness, tmp_path, quiet=("fmu_", "fmi3.c", "mbrt_mech")):
    """The harness ``harness`` (C text) built against the sources of ``fmu`` with the sanitizers
    and ``-Wall -Wextra``; asserts it compiles and that no warning names the files ``quiet``."""
    cc = c_compiler()
    if not usable(tmp_path):
        pytest.skip("this compiler cannot build a sanitized program")
    src = tmp_path / "src"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(src)
    sources = src / "sources"
    model_c = [p for p in sources.glob("*.c") if not p.name.startswith(("fmu_", "fmi", "mbrt_"))]
    assert len(model_c) == 1, model_c
    (sources / "harness.c").write_text(harness.replace("MODEL_C", model_c[0].name))
    exe = tmp_path / "harness"
    res = subprocess.run([cc, *SAN_FLAGS, "-std=c99", "-Wall", "-Wextra", str(sources / "harness.c"),
                          *runtime_objects(sources), "-o", str(exe), "-lm"],
                         capture_output=True, text=True, cwd=sources)
    assert res.returncode == 0, res.stderr[-3000:]
    assert not any(q in res.stderr for q in quiet), res.stderr[-3000:]  # no warning in the FMU's C
    return exe


def run(exe, *args):
    """The harness run (``subprocess.CompletedProcess``); asserts no sanitizer report."""
    out = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=300,
                         env={**os.environ, **ENV})
    assert "runtime error" not in out.stderr and "Sanitizer" not in out.stderr, out.stderr[-3000:]
    return out
