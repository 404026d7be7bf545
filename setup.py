"""The install's one build step beyond pyproject.toml: mbcomp's C runtime compiled ahead.

``pip install .`` (a wheel) and ``pip install -e .`` run setuptools' ``build_py``; this one
also compiles the runtime's objects (``src/mbcomp/codegen/runtime_build.py``, loaded by its
path: it needs only the standard library, and mbcomp's dependencies are not there yet) into
the package's ``codegen/prebuilt/`` directory -- the source tree's for an editable install, the
wheel's otherwise -- and, where the environment has numpy already, the thin call's extension
(``mbcomp.codegen.thin``; built by this Python outside the isolated build, whose numpy it needs). A run that misses an object in its runtime directory copies it from there
instead of compiling it, so a machine's first run does not wait for the compiler (issue 32
item 7, ``docs/design/generated-programs.md``, "Cold start").

The step never fails an install: without a C compiler, or where it fails, nothing is built and
the first run compiles the runtime as it did before. The objects are named by a hash of their
sources, compiler, flags, platform and architecture, so objects built elsewhere are never
linked.
"""
import importlib.util
import os
import sys

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))


def _runtime_build():
    path = os.path.join(HERE, "src", "mbcomp", "codegen", "runtime_build.py")
    spec = importlib.util.spec_from_file_location("_mbcomp_runtime_build", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class BuildPyWithRuntime(build_py):
    """``build_py``, then the runtime's objects into ``mbcomp/codegen/prebuilt``."""

    def run(self):
        super().run()
        try:
            rb = _runtime_build()
            if getattr(self, "editable_mode", False):  # the package is the source tree
                target = str(rb.PREBUILT_DIR)
            else:
                target = os.path.join(self.build_lib, "mbcomp", "codegen", "prebuilt")
            made = rb.build_install(target)
            thin = made and rb.build_thin_install(target, os.path.join(HERE, "src"))
            print(f"mbcomp: {len(made)} runtime objects{' and the thin extension' if thin else ''} built ahead "
                  f"in {target}", file=sys.stderr)
        except Exception as exc:  # noqa: BLE001 - an install never fails for the runtime
            print(f"mbcomp: the C runtime was not built at install ({exc}); the first run compiles it",
                  file=sys.stderr)


setup(cmdclass={"build_py": BuildPyWithRuntime})
