"""Batches: many parameter sets and start states of one model in one compiled call.

:func:`batch` runs every row of a table of parameter values (``"rod.m"``, ``"crank_joint.phi0"``:
masses, lengths, start values alike) through the path :func:`mbcomp.simulate` takes for a
smooth model -- consistent initialization in Python, then the Lagrange program integrated by
the C engine -- except that the integrations of all runs are one C call
(:func:`mbcomp.codegen.batch.run_batch`), on POSIX threads with the GIL released, each run
with its own error control and the stretches ``simulate`` makes, so each run gives the numbers
``simulate`` gives (the tests hold them to 1e-12). Python prepares the next block of runs
(initialization, the parameter program) while C integrates the previous one; where the
initializations are the bottleneck (a closed loop's Newton closure), forked worker processes
make them, blocks ahead (:mod:`mbcomp.analysis.batch_starts`; the same starts, bit for bit).
The requested output columns come from the output program (:mod:`mbcomp.codegen.outputs`) over
each run's grid.

What a batch does not do, and says so: models with events (stops, contacts, friction modes),
external inputs, drives whose law is not traced, ``stabilization="projection"`` and methods
other than ``dop853``/``dopri5`` are refused before anything runs (use :func:`mbcomp.study`,
which runs :func:`mbcomp.simulate` per run); the accuracy alarms of ``simulate``'s
post-processing (``"inaccurate"``) and its run monitors are not evaluated; columns only the
post-processing makes (energy balance, momenta, model output functions) are not offered. A run
whose program guard fails (a law's other branch, a singular solve) is finished by
:func:`mbcomp.simulate` (``fallback=True``, listed in ``stats["simulate_reruns"]``), as
``simulate`` itself would go on on its Python path there; a run that fails otherwise keeps
what it reached (NaN after) with its status and message, and the other runs are kept.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen import c_compiler
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
>>> j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.1)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> if c_compiler():
...     b = mbcomp.batch(m, {"j.phi0": [0.01, 0.02], "rod.r": [(0, -1.0, 0), (0, -4.0, 0)]}, t_end=2.006,
...                      n_out=3, outputs=["j.f.y"], threads=2)
...     # small swings: the period is 2 pi sqrt(L / g), 2.006 s for 1 m, twice that for 4 m
...     print(b.status.tolist(), np.round(b["j.phi"][:, -1], 3).tolist(), b["j.f.y"].shape)
... else:
...     print(['success', 'success'], [0.01, -0.02], (2, 3))
['success', 'success'] [0.01, -0.02] (2, 3)
"""
from __future__ import annotations

import concurrent.futures
import difflib
import time

import numpy as np

from ..assembly.outputs import output_values
from ..errors import SimulationInterrupted
from ..geometry.kinematics import matrix_to_quat
from ..hybrid.active import start_modes
from ..simulation.endings import Terminated, sigterm_interrupts
from ..simulation.setup import check_model, check_numbers, output_times, system_of
from .batch_result import STATUS_OF, BatchResult, OneRun
from .batch_starts import ForkedStarts, fork_workers, run_form, start_or_message

__all__ = ["batch", "BatchResult", "BLOCK"]

#: runs per C call: Python prepares the next block while C integrates this one
BLOCK = 64
#: how much the C threads lower their own priority (Linux nice steps): the Python thread preparing
#: the next block keeps its core, the C threads take the rest and all of it once Python is done
NICE = 5
#: what the start workers add to a run's CPU time (s): the parent rebuilding each run's system,
#: the transfer, two processes' caches -- measured 0.2 ms (numeric starts) to 0.4 ms (by the
#: evaluation program) on the slider-crank; they pay only beyond it (:meth:`_Runner._workers_pay`)
WORKER_COST = 4e-4
#: the methods a batch integrates (the C engine's)
METHODS = {"dop853": 8, "dopri5": 5}


def batch(model, table, *, t_end=1.0, t_start=0.0, outputs=None, rtol=1e-8, atol=1e-10, n_out=None, dt_out=None,
          method="dop853", stabilization=None, alpha=10.0, beta=10.0, max_step=np.inf, max_steps=None,
          threads=None, processes=None, fallback=True, initialization="simulate", reduce=None, block=BLOCK,
          cache_dir=None):
    """Run a model once per row of ``table``, all integrations in one compiled call.

    Parameters
    ----------
    model : Model or MultibodySystem
        A smooth model (no events, no external inputs; see the module notes).
    table : dict, pandas.DataFrame or list of dict
        ``{"component.parameter": values}``, one value per run (a vector parameter such as
        ``"rod.r"`` one vector per run); start values (``"joint.phi0"``, ``"joint.w0"``) are
        parameters like any other and go through consistent initialization per run. Or the
        runs themselves, ``[{"component.parameter": value}, ...]`` (every run naming the same
        parameters; empty dicts: runs of the model as it is).
    t_end, t_start : float
        Time span of every run (s).
    outputs : list of str or "all", optional
        Result columns besides the states (reactions, poses, energies, joints' outputs,
        aliases) from the output program; ``"all"`` for every column it has.
    rtol, atol, n_out, dt_out, method, stabilization, alpha, beta, max_step
        As for :func:`mbcomp.simulate` (``method`` ``"dop853"`` or ``"dopri5"``;
        ``stabilization`` ``"baumgarte"`` (default) or ``"none"``).
    max_steps : int, optional
        Attempted steps per run at most; a run that needs more ends with status ``"budget"``.
    threads : int, optional
        Threads integrating runs at once (default: this machine's cores).
    processes : int, optional
        Worker processes making the runs' consistent starts (forked from this one, Linux;
        the same code on the same numbers, so the same starts), blocks ahead of the C
        threads; 0: in this process, between the C calls. Default: this machine's cores
        for :data:`~mbcomp.analysis.batch_starts.MIN_FORKED_RUNS` runs or more, none in a
        daemon process (a Dask or multiprocessing worker) or for fewer runs.
    fallback : bool
        Finish a run whose program guard fails with :func:`mbcomp.simulate` (default); else
        report it ``"failed"``.
    initialization : {"simulate", "program"}
        What evaluates the constraints in each run's consistent initialization: ``"simulate"``
        (default) the numeric evaluation ``simulate`` uses, so each run starts, and ends, bit
        for bit where ``simulate``'s does; ``"program"`` the compiled evaluation program (made
        once): about twice as fast on a loop's Newton closure (the slider-crank's), the start
        equal to rounding (1e-15 measured), so a run may differ from ``simulate``'s by up to
        its error tolerance (a step accepted on the other side of the threshold).
    reduce : callable, optional
        ``reduce(run)`` called on each run as it ends (``run``: a
        :class:`~mbcomp.analysis.batch_result.OneRun` -- ``run["column"]``, ``run.time``,
        ``run.status`` -- or, for a run finished by ``simulate``, its ``Result``); the values
        are ``res.reduced`` and the output columns are then not kept for every run (the
        memory of a large batch with many columns), only the states.
    block : int
        Runs per C call.
    cache_dir : str, optional
        Where compiled programs are cached.

    Returns
    -------
    BatchResult
        ``res["joint1.phi"]`` is ``(n_runs, n_out)``; ``res.status``, ``res.message`` per run.
        Every run's states at every output time are kept (``n_runs x n_out x (nq + nu)``
        doubles, 40 MB for 1,000 runs of the 5-link pendulum at 501 points), and each
        requested output column is ``n_runs x n_out`` more: choose ``n_out`` for large batches.
    """
    t0 = time.perf_counter()
    check_model(model)
    stabilization = _check_request(method, stabilization, initialization, t_start=t_start, t_end=t_end, rtol=rtol,
                                   atol=atol, alpha=alpha, beta=beta, n_out=n_out, dt_out=dt_out, max_step=max_step,
                                   max_steps=max_steps)
    system = system_of(model, None, "c")
    if initialization == "program" and system.backend == "c":
        from ..codegen import compile_system

        system = compile_system(system.with_evaluator(None), "c", cache_dir=cache_dir)
    if system.backend != "c":
        raise ValueError("the model's laws cannot be traced into a C program (see the warning above), so a batch "
                         "cannot run it -> use mbcomp.study(...) (simulate per run on the numeric path)")
    values, n_runs = _table(system, table)
    _refuse_events(system)
    request = dict(t_start=float(t_start), t_end=float(t_end), rtol=float(rtol), atol=atol, method=method,
                   stabilization=stabilization, alpha=float(alpha), beta=float(beta), n_out=n_out, dt_out=dt_out,
                   max_step=max_step)
    runner = _Runner(system, request, values, n_runs, outputs, max_steps, threads, cache_dir, reduce)
    runner.workers = fork_workers(n_runs, processes)
    _interruptible(runner, max(1, int(block)))
    res = runner.result()
    if fallback:
        _rerun(res, system, values, request, reduce)
    res.stats["wall_time"] = time.perf_counter() - t0
    return res


def _check_request(method, stabilization, initialization, **numbers):
    """The stabilization to use; a ``ValueError`` (``RuntimeError`` without a C compiler)
    naming the argument and the fix for what a batch cannot do, before anything is built."""
    if method not in METHODS:
        raise ValueError(f"method={method!r}: a batch integrates with the C engine's 'dop853' or 'dopri5' -> use one "
                         "of them, or mbcomp.study(...) to run simulate per run with any method")
    stabilization = "baumgarte" if stabilization is None else stabilization
    if stabilization not in ("baumgarte", "none"):
        raise ValueError(f"stabilization={stabilization!r}: a batch runs 'baumgarte' or 'none' (the projection after "
                         "every step needs a second program per thread) -> use mbcomp.study(..., stabilization="
                         f"{stabilization!r})")
    if initialization not in ("simulate", "program"):
        raise ValueError(f"initialization={initialization!r}: use 'simulate' (the numeric evaluation, starts bit for "
                         "bit simulate's) or 'program' (the compiled evaluation program: faster, equal to rounding)")
    check_numbers(h=None, max_wall_time=None, **numbers)
    if not numbers["t_end"] > numbers["t_start"]:
        raise ValueError(f"t_end ({numbers['t_end']}) must be greater than t_start ({numbers['t_start']})")
    from ..codegen import c_compiler

    if c_compiler() is None:
        raise RuntimeError("mbcomp.batch needs a C compiler (gcc or cc on PATH, or $CC) -> install one, or use "
                           "mbcomp.study(...) (simulate per run)")
    return stabilization


def _interruptible(runner, block):
    """``runner.run(block)``; Ctrl-C or SIGTERM stop every run at its next stretch and raise
    :class:`~mbcomp.errors.SimulationInterrupted` carrying the :class:`BatchResult` of what
    finished (the runs stopped or never started are ``"interrupted"``)."""
    try:
        with sigterm_interrupts():
            runner.run(block)
    except (KeyboardInterrupt, Terminated) as exc:
        sig = "SIGTERM" if isinstance(exc, Terminated) else "SIGINT"
        for i in np.flatnonzero(runner.c_status == -1):
            if not runner.message[i]:  # not started, or its block not stored whole (an error row keeps its error)
                runner.status[i], runner.message[i] = "interrupted", f"not run: the batch was interrupted by {sig}"
                runner.Y[i] = np.nan
        res = runner.result()
        done = int(sum(s == "success" for s in res.status))
        raise SimulationInterrupted(res, sig, f"batch interrupted by {sig}: {done} of {len(res)} runs finished "
                                              "(their results are in .result)") from None


def _table(system, table):
    """``({name: per-run values}, n_runs)`` from a dict or DataFrame; a ``ValueError`` naming an
    unknown component or parameter (with the close names), a value of the wrong shape, or
    columns of unequal lengths."""
    if hasattr(table, "columns") and hasattr(table, "to_dict") and not isinstance(table, dict):
        table = {str(c): list(table[c]) for c in table.columns}
    if isinstance(table, (list, tuple)) and all(isinstance(r, dict) for r in table):  # one dict per run
        keys = {tuple(sorted(r)) for r in table}
        if len(keys) > 1:
            raise ValueError(f"table given as runs: every run must name the same parameters, not {sorted(keys)}")
        if not table or not next(iter(keys)):
            return {}, len(table)
        table = {k: [r[k] for r in table] for k in table[0]}
    if not isinstance(table, dict) or not table:
        raise TypeError(f"table must be a dict (or DataFrame) of 'component.parameter' -> one value per run, not "
                        f"{table!r:.60}")
    params = {c: vars(ns) for c, ns in system.P.items()}
    out, lengths = {}, {}
    for name, col in table.items():
        comp, _, par = str(name).rpartition(".")
        if comp not in params:
            close = difflib.get_close_matches(comp or name, list(params), n=3)
            raise ValueError(f"table column {name!r}: no component {comp or name!r} in the model"
                             + (f" (did you mean {', '.join(close)}?)" if close else "")
                             + " -> name parameters '<component>.<parameter>', e.g. 'link1.m'; build() arguments "
                             "change the structure: use mbcomp.study(build, ...) for those")
        if par not in params[comp]:
            raise ValueError(f"table column {name!r}: component {comp!r} has no parameter {par!r}; its parameters: "
                             f"{', '.join(sorted(params[comp]))}")
        default = params[comp][par]
        if callable(default) or isinstance(default, str):
            raise ValueError(f"table column {name!r}: {par!r} is a law or text, not a number; a batch changes "
                             "numbers only (a law changes the program) -> use mbcomp.study(...)")
        shape = np.shape(default)
        try:
            vals = [np.asarray(v, float) for v in col]
        except (TypeError, ValueError):
            raise ValueError(f"table column {name!r}: values must be numbers (shape {shape})") from None
        bad = [i for i, v in enumerate(vals) if v.shape != shape or not np.isfinite(v).all()]
        if bad:
            raise ValueError(f"table column {name!r}, run {bad[0]}: {col[bad[0]]!r} is not a finite value of shape "
                             f"{shape} (the parameter's default is {default!r})")
        out[name], lengths[name] = [float(v) if not shape else v for v in vals], len(vals)
    if len(set(lengths.values())) != 1:
        raise ValueError(f"table columns have different lengths: {lengths} -> give one value per run in every column")
    n = next(iter(lengths.values()))
    if n < 1:
        raise ValueError("table has no runs (its columns are empty)")
    return out, n


def _refuse_events(system):
    """A ``ValueError`` for what the C batch cannot run: joints with modes (events), external
    inputs; each with the fix."""
    modes = start_modes(system)
    if modes:
        raise ValueError(f"a batch runs smooth models only: {', '.join(sorted(modes))} have modes (stops, contacts or "
                         "friction: events change the equations during a run) -> use mbcomp.study(model, grid, ...), "
                         "which runs mbcomp.simulate per run")
    from ..modeling.inputs import Input

    inputs = sorted({v.name for ns in system.P.values() for v in vars(ns).values() if isinstance(v, Input)})
    if inputs:
        raise ValueError(f"a batch cannot run a model with external inputs ({', '.join(inputs)}): they are Python "
                         "functions of time, called at every step -> use mbcomp.simulate(..., inputs=...) per run")


class _Runner:
    """The runs of one batch: prepared in Python block by block, integrated in C (the next
    block prepared while C integrates), their output columns computed as each block ends."""

    def __init__(self, system, request, values, n_runs, outputs, max_steps, threads, cache_dir, reduce=None):
        import os

        self.system, self.req, self.values, self.n_runs = system, request, values, n_runs
        self.outputs, self.max_steps = outputs, int(max_steps or 0)
        self.threads = int(threads or os.cpu_count() or 1)
        self.cache_dir = cache_dir
        self.T = output_times(request["t_start"], request["t_end"], request["n_out"], request["dt_out"])
        self.n = system.nq + system.nu
        self.Y = np.full((n_runs, len(self.T), self.n), np.nan)
        self.status = np.array(["error"] * n_runs, dtype=object)
        self.message = [""] * n_runs
        self.t_reached = np.full(n_runs, request["t_start"])
        self.counts = np.zeros((n_runs, 5), np.int_)
        self.c_status = np.full(n_runs, -1)  # the batch runner's code per run (-1: not integrated)
        self.groups = {}  # (row mask, table's zero pattern) -> (code, gains, output program or None)
        self.columns = None  # name -> (n_runs, n_t), made when the first output program is
        self.wanted = None
        self.times = dict(setup_time=0.0, integrate_time=0.0, c_cpu_time=0.0, outputs_time=0.0)
        self.stop = np.zeros(1, np.intc)
        self.reduce = reduce
        self.reduced = [None] * n_runs if reduce is not None else None
        self.workers = 0  # processes to fork for the starts: 0 none, None decided by measuring
        self.used_workers = 0
        self.start_cpu = 0.0  # CPU seconds of this thread making the starts (what decides the workers)
        self.group_cpu = 0.0  # ... of which making the groups' programs
        self.cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        self.nice = NICE

    def params_of(self, i):
        return {name: col[i] for name, col in self.values.items()}

    # --- Python: a run's start ----------------------------------------------------------------
    def prepare(self, i, start=None):
        """``(key, h, p, y0, system, form)`` of run ``i``, or None (its status says why).
        ``start``: its ``(y0, row mask, message)`` made by a worker process
        (:class:`~mbcomp.analysis.batch_starts.ForkedStarts`), or None: made here."""
        if start is None:
            s, form, y0, message = start_or_message(self.system, self.params_of(i), self.req)
        else:
            y0, mask, message = start
            if message is None:
                s = self.system.with_params(self.params_of(i))
                s.row_mask = mask
                form = run_form(s, self.req)
        if message is not None:
            self.message[i] = message
            return None
        rm = s.row_mask
        # what decides the program besides the row mask: which table entries are exactly zero
        # (the zero pattern is baked; see mbcomp.codegen.tracer.param_layout)
        zeros = tuple((np.asarray(col[i]) != 0).tobytes() for col in self.values.values())
        key = (None if rm is None or rm.all() else rm.tobytes(), zeros)
        hp = self._hoisted(key, s, form, y0)
        if hp is None:
            self.message[i] = ("the C engine cannot run this parameter set (it changes a decision baked into the "
                               "program, which was traced again without an engine) -> simulate it")
            return None
        return (hp[0], hp[1], hp[2], y0, s, form)

    def _hoisted(self, key, s, form, y0):
        """``(group key, h, p)`` for run system ``s``: the program's hoisted values and parameter
        vector. Runs of one group share the row mask and the table's zero pattern, hence the
        program's structure (its signature) with the group's first run, whose program the
        engine itself gave (:meth:`~mbcomp.formulations.LagrangeIndex1.compiled_integrator`);
        a parameter guard failing (``Retrace``) makes the engine trace another program."""
        from ..codegen.graph import Retrace
        from ..codegen.tracer import param_vector

        group = self.groups.get(key)
        if group is not None:
            code = group[0]
            try:
                pv = param_vector(s, code.layout)
                return key, np.array(list(code.pre.run(pv)) + [0.0]), np.array(pv + [0.0])
            except Retrace:
                pass
        c0 = time.thread_time()  # a group's programs (traced, compiled): not a start's cost
        integ = form.compiled_integrator()
        if integ is None:
            self.group_cpu += time.thread_time() - c0
            if not self.groups:
                raise ValueError("the C engine cannot integrate this model (a drive law or input needs Python per "
                                 "call, or the program has no Lagrange right-hand side) -> use mbcomp.study(...) "
                                 "(simulate per run)")
            return None
        bound = integ.bound
        gkey = key if group is None else (key, id(bound.code))
        if gkey not in self.groups:
            self.groups[gkey] = (bound.code, tuple(integ.d), self._output_program(s, form, y0))
        self.group_cpu += time.thread_time() - c0
        return gkey, bound.hbuf.copy(), bound.pbuf.copy()

    def _output_program(self, s, form, y0):
        """The output program of a group: ``"evaluator"`` -- the system's own
        (:meth:`~mbcomp.codegen.evaluator.ProgramEvaluator.output_grid`, what ``simulate``'s
        post-processing calls, kept per structure across calls) when it makes one for this grid
        (100 points or more, or made before) -- else one built here; None without outputs."""
        if not self.outputs:
            return None
        from ..codegen.outputs import OutputProgram

        gains = form.output_gains()
        grid = s.evaluator.output_grid(self.T, np.tile(y0, (len(self.T), 1)), gains)
        if grid is not None:
            self._check_outputs(s, grid[0], list(grid[2]))
            return "evaluator"
        prog = OutputProgram.build(s, "c", baumgarte=gains is not None, cache_dir=self.cache_dir)
        if prog is None:
            raise ValueError("the output program cannot be traced at this model's trace point -> ask for the "
                             "states only (outputs=None), or use mbcomp.study(...)")
        self._check_outputs(s, prog.names, prog.rotation_paths)
        return prog

    def _check_outputs(self, s, names, rotation_paths):
        have = list(names) + [f"{p}.Q.{a}" for p in rotation_paths for a in "wxyz"]
        aliases = dict(s.topology.flat.aliases)
        wanted = have if self.outputs == "all" else list(self.outputs)
        states = set(s.q_names) | set(s.u_names)
        for name in wanted:
            real = aliases.get(name, name)
            if real not in have and real not in states:
                close = difflib.get_close_matches(name, have + list(aliases), n=5)
                raise ValueError(f"outputs: no column {name!r} in the output program"
                                 + (f" (similar: {', '.join(close)})" if close else "")
                                 + "; columns made only by simulate's post-processing (energy balance, momenta, "
                                 "model output functions) are not in a batch -> use mbcomp.simulate or study")
        if self.wanted is None:
            self.wanted = [(n, aliases.get(n, n)) for n in wanted if aliases.get(n, n) not in states]
            self.columns = {} if self.reduce is not None else {
                n: np.full((self.n_runs, len(self.T)), np.nan) for n, _ in self.wanted}

    # --- the pipeline ---------------------------------------------------------------------------
    def run(self, block):
        """Every run, block by block: block ``k + 1`` is prepared while C integrates block ``k``.
        The starts are made here, or by worker processes blocks ahead of the C threads
        (:class:`~mbcomp.analysis.batch_starts.ForkedStarts`: asked for, from the second run on;
        by default from the third block on when :meth:`_workers_pay`). Stopped (Ctrl-C, an
        error), the C runs stop at their next stretch and the blocks in flight are stored as
        they ended (their finished runs kept)."""
        pools = [concurrent.futures.ThreadPoolExecutor(1)]  # the thread calling C (a new one at a fork)
        flight = []  # (job, prepared) submitted and not stored yet, oldest first
        starts = None
        decided = self.workers is not None
        try:
            for a, b in block_ranges(self.n_runs, block):
                t0, c0 = time.perf_counter(), time.thread_time()
                if starts is not None:
                    prepared = [(i, self.prepare(i, st)) for i, st in zip(range(a, b), starts.take(a, b))]
                elif a == 0 and self.workers and self.n_runs > 1:
                    prepared = [(0, self.prepare(0))]  # made here: the workers inherit the programs it made
                    starts = self._starts(1, block, pools)
                    prepared += [(i, self.prepare(i, st)) for i, st in zip(range(1, b), starts.take(1, b))]
                else:
                    prepared = [(i, self.prepare(i)) for i in range(a, b)]
                self.times["setup_time"] += time.perf_counter() - t0
                self.start_cpu += time.thread_time() - c0
                flight.append((pools[-1].submit(self._integrate, [(i, p) for i, p in prepared if p is not None]),
                               prepared))
                if len(flight) > 1:
                    self._finish(*flight[0])
                    flight.pop(0)
                    if not decided and b < self.n_runs:
                        decided = True
                        if self._workers_pay(b):
                            starts = self._starts(b, block, pools)
            while flight:
                self._finish(*flight[0])
                flight.pop(0)
        except BaseException:  # Ctrl-C or an error: the C runs stop at their next stretch
            self.stop[0] = 1
            for pool in pools:
                pool.shutdown(wait=True)
            for job, prepared in flight:
                if job.done() and job.exception() is None:
                    self._finish(job, prepared)
            raise
        finally:
            if starts is not None:
                starts.close()
            for pool in pools:
                pool.shutdown(wait=True)

    def _starts(self, first, block, pools):
        """The starts of the runs from ``first`` on, made by worker processes. The C threads
        then run at this process's priority (a new thread calls them: the old one keeps its
        lowered priority): nothing of this process's needs a core more than they do, and other
        processes' load takes no more from them than from any other thread."""
        self.used_workers = self.workers or self.cores
        starts = ForkedStarts(self.system, self.values, self.req, first, self.n_runs, block, self.used_workers)
        if self.nice:
            self.nice = 0
            pools.append(concurrent.futures.ThreadPoolExecutor(1))
        return starts

    def _workers_pay(self, prepared):
        """Whether worker processes make the batch faster, measured on the ``prepared`` runs
        started here and those integrated: with ``k`` cores, a start's CPU time here ``P`` and a
        run's CPU time in C ``C`` (CPU times: other processes' load does not decide), a batch
        takes about ``max(P, (P + C) / k)`` a run with the starts here, ``(P + C + W) / k`` with
        them in workers (:data:`WORKER_COST` ``W``): workers when ``(k - 1) P > C + W`` (a
        closed loop's Newton closure, ~2 ms, against 0.6 ms in C; not the same closure by the
        evaluation program, 0.9 ms, nor an open chain's start, 0.5 ms against 1.1 ms)."""
        done = int(np.sum(self.c_status != -1))
        k = min(self.threads, self.cores)
        if not done or k < 2:
            return False
        return (k - 1) * (self.start_cpu - self.group_cpu) / prepared > self.times["c_cpu_time"] / done + WORKER_COST

    def _integrate(self, ready):
        """The C call(s) of one block (one per group of equal programs); in a worker thread."""
        from ..codegen.batch import run_batch

        t0 = time.perf_counter()
        req, out = self.req, {}
        by_group = {}
        for i, p in ready:
            by_group.setdefault(p[0], []).append((i, p))
        for gkey, runs in by_group.items():
            code, gains, _ = self.groups[gkey]
            H = np.array([p[1] for _, p in runs])
            P = np.array([p[2] for _, p in runs])
            Y0 = np.array([p[3] for _, p in runs])
            hmax = req["max_step"] if np.isfinite(req["max_step"]) else 0.0
            out[gkey] = ([i for i, _ in runs], run_batch(
                code, METHODS[req["method"]], H, P, Y0, self.T, req["rtol"], req["atol"], gains=gains, hmax=hmax,
                max_steps=self.max_steps, threads=self.threads, stop=self.stop, nice=self.nice,
                cache_dir=self.cache_dir))
        return out, time.perf_counter() - t0

    def _finish(self, job, prepared):
        """Store a finished block: states, statuses, counters, then its output columns."""
        out, seconds = job.result()
        self.times["integrate_time"] += seconds
        for gkey, (idx, r) in out.items():
            self.times["c_cpu_time"] += r.cpu_time
            self.Y[idx] = r.Y
            self.t_reached[idx] = r.t_reached
            self.counts[idx] = r.counts
            for k, i in enumerate(idx):
                code = self.c_status[i] = int(r.status[k])
                self.status[i] = STATUS_OF[code]
                self.message[i] = "reached t_end" if code == 0 else (
                    f"the integrator {self.req['method']} stopped at t={r.t_reached[k]:.9g} s: {r.messages[k]} "
                    f"({_why(code)})")
        t0 = time.perf_counter()
        for i, p in prepared:
            cols = self._outputs(i, p) if p is not None and self.wanted else {}
            if self.reduce is not None:
                self.reduced[i] = self.reduce(self.one_run(i, cols))
            else:
                for name, arr in cols.items():
                    self.columns[name][i] = arr
        self.times["outputs_time"] += time.perf_counter() - t0

    def one_run(self, i, cols):
        """Run ``i`` as a :class:`OneRun`: its states, aliases of them and the columns ``cols``."""
        names = list(self.system.q_names) + list(self.system.u_names)
        series = {n: self.Y[i, :, j] for j, n in enumerate(names)}
        series.update({a: series[v] for a, v in self.system.topology.flat.aliases.items() if v in series})
        series.update(cols)
        return OneRun(self.T, series, self.status[i], self.message[i], self.params_of(i))

    def _outputs(self, i, p):
        """Run ``i``'s requested columns over the output times it reached (the output program;
        a point where its guard fails by the numeric route)."""
        gkey, _, _, _, s, form = p
        prog = self.groups[gkey][2]
        reached = int(np.isfinite(self.Y[i]).all(axis=1).sum())
        if prog is None or reached == 0:
            return {}
        T, Y, gains = self.T[:reached], self.Y[i, :reached], form.output_gains()
        grid = s.evaluator.output_grid(T, Y, gains) if prog == "evaluator" else prog.grid(s, T, Y, gains)
        if grid is None:  # the evaluator's program did not hold for these values (traced again: none)
            self.message[i] += "; its output columns could not be computed (no output program for its values)"
            return {}
        names, V, quats, ok = grid
        col = {n: V[j] for j, n in enumerate(names)}
        col.update({f"{path}.Q.{a}": Q[:, j] for path, Q in quats.items() for j, a in enumerate("wxyz")})
        for k in np.flatnonzero(~ok):
            try:
                vals, rots = output_values(s, T[k], Y[k, :s.nq], Y[k, s.nq:], *(gains or (0.0, 0.0)),
                                           baumgarte=gains is not None)
            except Exception as exc:  # noqa: BLE001 - a singular point: its columns stay NaN, said once
                self.message[i] += f"; output columns at t={T[k]:g} s could not be computed ({type(exc).__name__})"
                continue
            for name, v in vals.items():
                if name in col:
                    col[name][k] = v
            for path, R in rots.items():
                Q = matrix_to_quat(R)
                for j, a in enumerate("wxyz"):
                    if f"{path}.Q.{a}" in col:
                        col[f"{path}.Q.{a}"][k] = Q[j]
        out = {}
        for name, real in self.wanted:
            out[name] = np.full(len(self.T), np.nan)
            out[name][:reached] = col[real]
        return out

    def result(self):
        """The :class:`BatchResult`."""
        names = list(self.system.q_names) + list(self.system.u_names)
        cols = {n: np.ascontiguousarray(self.Y[:, :, j]) for j, n in enumerate(names)}
        aliases = dict(self.system.topology.flat.aliases)
        for alias, var in aliases.items():
            if var in cols and (self.outputs == "all" or alias in (self.outputs or ())):
                cols[alias] = cols[var]
        cols.update(self.columns or {})
        c = self.counts
        stats = dict(runs=self.n_runs, failed=int(sum(s != "success" for s in self.status)), threads=self.threads,
                     method=self.req["method"], rtol=self.req["rtol"], atol=self.req["atol"], nfev=c[:, 0].copy(),
                     nsteps=c[:, 2].copy(), nreject=c[:, 3].copy(), c_calls=c[:, 4].copy(),
                     c_status=self.c_status.copy(), simulate_reruns=[], processes=self.used_workers,
                     **self.times)
        return BatchResult(self.T, cols, self.status, self.message, self.values, self.t_reached, stats, self.reduced)


def block_ranges(n_runs, block):
    """The blocks of runs, ``[(a, b)]``: ``block`` runs each, but a quarter and a half of it at
    the start (the C threads begin sooner) and a half, a quarter and an eighth at the end (less
    C left to do after the last start is made), when there are runs enough.

    Examples
    --------
    >>> [b - a for a, b in block_ranges(300, 64)]
    [16, 32, 64, 64, 64, 4, 32, 16, 8]
    >>> block_ranges(5, 64)
    [(0, 5)]
    """
    head = [max(1, block // 4), max(1, block // 2)]
    tail = [max(1, block // 2), max(1, block // 4), max(1, block // 8)]
    middle = n_runs - sum(head) - sum(tail)
    if middle < block:
        sizes = [block] * (n_runs // block) + ([n_runs % block] if n_runs % block else [])
    else:
        sizes = head + [block] * (middle // block) + ([middle % block] if middle % block else []) + tail
    edges = np.cumsum([0] + sizes)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _why(code):
    from ..codegen.batch import STATUS

    return STATUS.get(code, "unknown")


def _rerun(res, system, values, req, reduce=None):
    """Finish with :func:`mbcomp.simulate` each run whose program guard failed in C (``simulate``
    goes on on its Python path there): its states and columns replace the batch's."""
    from ..simulation.driver import simulate

    for i in np.flatnonzero(res.stats["c_status"] == 1):
        params = {name: col[i] for name, col in values.items()}
        r = simulate(system, t_end=req["t_end"], t_start=req["t_start"], params=params, method=req["method"],
                     rtol=req["rtol"], atol=req["atol"], stabilization=req["stabilization"], alpha=req["alpha"],
                     beta=req["beta"], n_out=req["n_out"], dt_out=req["dt_out"], max_step=req["max_step"])
        res.replace_run(i, r, f"run by simulate after the C program's guard failed ({res.message[i]}): {r.message}")
        res.stats["simulate_reruns"].append(i)
        if reduce is not None:
            res.reduced[i] = reduce(r)
