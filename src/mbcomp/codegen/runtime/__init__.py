"""Portable C runtime embedded in exported FMUs and mbcomp's compiled engine.

The files in this package are plain C99 sources (libc and libm only) that
generated model code is compiled together with:

``mbrt.h``
    The public API.
``mbrt_linalg.c``
    Dense LU (partial pivoting) and Cholesky factorisations and solves on
    row-major ``double`` arrays, in place.
``mbrt_check.c``, ``mbrt_check.h``
    What every integrator reports and checks alike: the status with its message
    (``mbrt_finish``) and the arguments of an integration (``mbrt_check_integration``).
``mbrt_rk.c``, ``mbrt_rk_internal.h``
    The adaptive explicit Runge--Kutta driver: Hairer's step-size control
    with PI ("Lund") stabilisation and starting-step guess, dense output at
    a caller-given time grid, per-step callback (for projections), argument
    checks and failure reporting.
``mbrt_events.c``
    Events watched by the driver: event functions evaluated after every
    accepted step, a sign change located on the step's continuous extension
    (Brent's method; a return through zero by golden section first), the
    integration ended at the earliest (``MBRT_EVENT``); event functions
    affine in one state entry each (``mbrt_linear_events``: a joint's
    coordinate against its stops); a run's stretches with stops' rebounds
    acted on between them (``mbrt_impacts_integrate``: Newton's restitution
    on one speed row, ``M`` and ``f`` from an evaluation program, a new
    segment started as a new stepper would).
``mbrt_dopri5.c``, ``mbrt_dop853.c``
    The Dormand--Prince 5(4) pair with 4th-order dense output and the
    8(5,3) pair with 7th-order dense output.
``mbrt_mech.c``
    Constrained mechanics over a model's evaluation program (reached through
    a function pointer, ``mbrt_mech``): the D'Alembert right-hand side
    (dependent speeds, ``N^T M N`` by Cholesky, the partition's growth and
    2-norm condition figures), the projection of ``[q, u]`` onto the
    constraint manifold (Gauss--Newton with minimum-norm steps, then the
    minimum-norm speed correction), and the residual and Jacobian of the
    multiplier forms as DAEs (index 1, GGL, index 3).
``mbrt_pass.c``, ``mbrt_pass.h``
    Singular positions passed inside the C loop (``singular="pass"``): the range-space
    solve where the Lagrange program's guard fails, the rows' closest approaches located
    on the integrator's own continuous extension and logged, the integration going on
    without a restart next to them.
``mbrt_radau5.c``, ``mbrt_radau5_step.c``, ``mbrt_radau5_linalg.c``, ``mbrt_radau5_internal.h``
    RADAU5 (Radau IIA of order 5) for stiff ODEs, the whole integration in
    one call: simplified Newton on the real and complex systems, equilibrated
    LU, the filtered error estimate, Gustafsson's controller, Jacobian and LU
    reuse, the collocation polynomial at the output times, resumable across
    calls; exact Jacobians by callback (``mbrt_prog_ode``: a generated
    program's), else forward differences.

The runtime must stay free of Python: an exported FMU carries these sources
(or the object code built from them) and runs where no interpreter exists.
It therefore has no global state and never allocates; the integrators take
a caller-supplied work buffer of ``mbrt_dopri5_work_size(n)`` /
``mbrt_dop853_work_size(n)`` doubles.  Times are in the model's time unit
(seconds for mbcomp models); tolerances are in the units of the state.

Attributes
----------
RUNTIME_DIR : pathlib.Path
    Directory holding the C sources and headers (pass it as ``-I``).
HEADERS : tuple of pathlib.Path
    Header files.
SOURCES : tuple of pathlib.Path
    The ``.c`` files to compile and link together with generated code.

Examples
--------
>>> from mbcomp.codegen.runtime import SOURCES, RUNTIME_DIR
>>> print(" ".join(sorted(p.name for p in SOURCES)))  # doctest: +NORMALIZE_WHITESPACE
mbrt_check.c mbrt_dop853.c mbrt_dopri5.c mbrt_events.c mbrt_linalg.c mbrt_mech.c mbrt_pass.c mbrt_radau5.c
mbrt_radau5_linalg.c mbrt_radau5_step.c mbrt_rk.c
>>> (RUNTIME_DIR / "mbrt.h").is_file()
True
"""

from pathlib import Path

__all__ = ["RUNTIME_DIR", "HEADERS", "SOURCES"]

RUNTIME_DIR = Path(__file__).resolve().parent
HEADERS = tuple(sorted(RUNTIME_DIR.glob("*.h")))
SOURCES = tuple(sorted(RUNTIME_DIR.glob("*.c")))
