"""What the runtime's C self-tests share (``test_runtime_c.py``, ``test_runtime_pass_c.py``): the
ctypes mirror of ``mbrt_stats`` and the build of a self-test -- the runtime's sources with a test
file, every warning on, as a shared library or, with the test's ``main``, an executable (to run
under a sanitizer or valgrind, ``extra`` flags)."""
import ctypes
import subprocess

from mbcomp.codegen import c_compiler
from mbcomp.codegen.runtime import RUNTIME_DIR, SOURCES

CC = c_compiler()


class Stats(ctypes.Structure):
    """``mbrt_stats`` (mbrt.h)."""
    _fields_ = [("nfev", ctypes.c_long), ("nstep", ctypes.c_long), ("naccept", ctypes.c_long),
                ("nreject", ctypes.c_long), ("status", ctypes.c_int), ("t", ctypes.c_double),
                ("message", ctypes.c_char * 200)]


def build(outdir, source, stem, main_macro, extra=(), exe=False, defines=()):
    """``(path, completed process)`` of the self-test ``source`` compiled with the runtime in
    ``outdir``: an executable defining ``main_macro`` if ``exe``, else a shared library."""
    src = outdir / f"{stem}.c"
    src.write_text(source)
    out = outdir / ("selftest" if exe else f"lib{stem}.so")
    cmd = [CC, "-std=c99", *defines, "-O2", "-g", "-Wall", "-Wextra", "-pedantic", "-I", str(RUNTIME_DIR),
           *([f"-D{main_macro}"] if exe else ["-shared", "-fPIC"]), *extra,
           *map(str, SOURCES), str(src), "-o", str(out), "-lm"]
    return out, subprocess.run(cmd, capture_output=True, text=True)


#: the flags of a self-test run under AddressSanitizer and UndefinedBehaviorSanitizer
SAN_FLAGS = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-O1"]


def run_under_sanitizers(tmp_path, build_selftest):
    """Build the self-test executable with :data:`SAN_FLAGS` (``build_selftest(outdir,
    extra=..., exe=True)``) and run it: the completed run, or None where this compiler cannot
    build and run a sanitized program at all (the caller skips)."""
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    res = subprocess.run([CC, *SAN_FLAGS, str(probe), "-o", str(tmp_path / "probe")], capture_output=True)
    if res.returncode != 0 or subprocess.run([str(tmp_path / "probe")], capture_output=True).returncode != 0:
        return None
    exe, res = build_selftest(tmp_path, extra=SAN_FLAGS, exe=True)
    assert res.returncode == 0, res.stderr
    return subprocess.run([str(exe)], capture_output=True, text=True, timeout=300,
                          env={"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
