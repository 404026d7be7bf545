"""Generated programs: the assembled equations traced once and printed as Python or C;
and the same trace as sympy expressions (:mod:`mbcomp.codegen.symbolic`).
"""
from .program import *  # noqa: F401,F403
from .program import CodegenError, CompiledEvaluation, CompiledSystem, Graph, Sym, c_compiler, compile_system

__all__ = ["compile_system", "CompiledSystem", "CompiledEvaluation", "CodegenError", "Graph", "Sym", "c_compiler"]
