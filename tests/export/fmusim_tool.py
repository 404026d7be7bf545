"""The Modelica Reference-FMUs' ``fmusim``: a second FMU importer, independent of FMPy.

Found as ``$MBCOMP_FMUSIM``, on ``PATH``, or built once per test process from the sources
beside the checkout (``../shared/tools/fmusim/build.sh``: two seconds against Debian's
libxml2, minizip and SUNDIALS, which ``.ci/run`` installs). :func:`run` simulates an FMU with
it and reads its CSV.
"""
import csv
import functools
import os
import pathlib
import shutil
import subprocess
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = ROOT.parent / "shared" / "tools" / "fmusim" / "build.sh"


@functools.lru_cache(maxsize=None)
def fmusim():
    """``(path, None)`` of a working ``fmusim``, or ``(None, why not)``."""
    given = os.environ.get("MBCOMP_FMUSIM") or shutil.which("fmusim")
    if given:
        return given, None
    if not BUILD.exists():
        return None, f"no fmusim: $MBCOMP_FMUSIM unset, none on PATH, and no {BUILD} to build it from"
    out = pathlib.Path(tempfile.mkdtemp(prefix="mbcomp_fmusim_"))
    done = subprocess.run(["bash", str(BUILD), str(out)], capture_output=True, text=True)
    if done.returncode != 0:
        return None, ("no fmusim: its build failed (apt-get install -y libxml2-dev zlib1g-dev libminizip-dev "
                      f"libsundials-dev gives what it needs): {done.stderr.strip()[-300:]}")
    return str(out / "fmusim"), None


def run(path, interface, t_end, variables, tolerance=1e-10, points=100):
    """fmusim's run of the FMU ``path`` as ``interface`` (``"me"``: its CVODE; ``"cs"``: the FMU's
    own integrator) to ``t_end`` (s), ``points`` output intervals; ``{"time": ..., name: ...}``
    for ``variables``. Raises ``AssertionError`` with fmusim's own words when it fails."""
    exe, why = fmusim()
    assert exe, why
    out = pathlib.Path(tempfile.mkdtemp(prefix="fmusim_run_")) / "out.csv"
    cmd = [exe, "--interface-type", interface, "--stop-time", repr(t_end), "--output-interval", repr(t_end / points),
           "--tolerance", repr(tolerance), "--output-file", str(out), "--log-level", "error"]
    if interface == "me":
        cmd += ["--solver", "cvode"]
    for v in variables:
        cmd += ["--output-variable", v]
    done = subprocess.run(cmd + [str(path)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"fmusim failed ({done.returncode}): {done.stdout[-600:]} {done.stderr[-600:]}"
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    head = [h.strip().strip('"') for h in rows[0]]
    data = np.array([[float(x) for x in r] for r in rows[1:] if r], float)
    return {h: data[:, k] for k, h in enumerate(head)}
