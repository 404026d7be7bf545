"""Old module paths kept importable: ``mbcomp.kinematics`` is ``mbcomp.geometry.kinematics``.

Before the pipeline layout (geometry -> modeling -> assembly -> formulations -> solvers ->
codegen -> simulation -> analysis -> cli) every module sat directly under ``mbcomp``; user
models and libraries import e.g. ``mbcomp.kinematics``, ``mbcomp.jets`` or ``mbcomp.inertia``.
A meta-path finder maps each old name to the module that now holds it, lazily (importing
``mbcomp`` imports none of them) and to the *same* module object, so ``mbcomp.jets.FrameJet is
mbcomp.assembly.jets.FrameJet``.

Examples
--------
>>> import mbcomp.kinematics, mbcomp.geometry.kinematics
>>> mbcomp.kinematics is mbcomp.geometry.kinematics
True
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys

__all__ = ["OLD_PATHS", "install"]

#: old module name (below ``mbcomp``) -> where it lives now
OLD_PATHS = {
    "kinematics": "geometry.kinematics",
    "rotations": "geometry.rotations",
    "relative_motion": "geometry.relative_motion",
    "component": "modeling.component",
    "roles": "modeling.roles",
    "model": "modeling.model",
    "inertia": "modeling.inertia",
    "topology": "assembly.topology",
    "jets": "assembly.jets",
    "system": "assembly.system",
    "initialization": "assembly.initialization",
    "report": "assembly.summary",
    "daeforms": "formulations.dae",
    "symbolic": "codegen.symbolic",  # the one-file codegen, split one file per step
    "result": "simulation.result",
    "simulation.events": "hybrid.events",  # the hybrid layer left simulation/ (issue 30)
    "simulation.modes": "hybrid.stops",
    "simulation.contacts": "hybrid.contacts",
    "simulation.slip": "hybrid.slip",
    "simulation.stickslip": "hybrid.friction",
    "hybrid.modes": "hybrid.stops",  # rows held on a joint's own coordinate; modeling.modes keeps its name
    "simulation.stops": "simulation.endings",  # "stop" is a joint's end stop only (issue 30 item 9)
    "stability": "analysis.stability",
    "workprecision": "analysis.workprecision",
}


class _AliasLoader(importlib.abc.Loader):
    def __init__(self, target):
        self.target = target

    def create_module(self, spec):
        return importlib.import_module(self.target)

    def exec_module(self, module):  # the target module is already executed
        pass


class _AliasFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        head, _, leaf = fullname.partition(".")
        if head != "mbcomp" or leaf not in OLD_PATHS:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(f"mbcomp.{OLD_PATHS[leaf]}"))


def install():
    """Put the finder on ``sys.meta_path`` once."""
    if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, _AliasFinder())
