"""Generated programs: the assembled equations traced once and printed as Python or C; and the
same trace as sympy expressions (:mod:`mbcomp.codegen.symbolic`).

One module per step: :mod:`~mbcomp.codegen.graph` (the traced scalars and their expression
graph; their float arithmetic: :mod:`~mbcomp.codegen.ieee`), :mod:`~mbcomp.codegen.tracing`
(what both tracers share: the traced system, its parameters and drives),
:mod:`~mbcomp.codegen.tracer` (tracing a system into a graph), :mod:`~mbcomp.codegen.printers`
(Python and C source), :mod:`~mbcomp.codegen.toolchain` (the C compiler, its cache and the
compile policy), :mod:`~mbcomp.codegen.compiler` (callables) and
:mod:`~mbcomp.codegen.evaluator` (:func:`compile_system`: the program as a system's evaluator).
"""
from .evaluator import CompiledEvaluation, ProgramEvaluator, compile_system
from .toolchain import c_compiler
from .graph import CodegenError, Graph, Sym

__all__ = ["compile_system", "ProgramEvaluator", "CompiledEvaluation", "CodegenError", "Graph", "Sym", "c_compiler"]
