"""The FMU's exact derivatives (issue 33, item 3): the generated C of the Jacobian-vector and
vector-Jacobian products of the programs the FMU carries, and the dependencies its
``<ModelStructure>`` declares.

For each program the FMU runs -- the Lagrange right-hand side ``fun`` (group ``"fun"``), the
output program (``"outputs"``) and, for D'Alembert's Model Exchange states, the velocity
residual of the constraints ``[dPhi/dt[rows]; Psi]`` (the evaluation program's) -- two more
programs are printed, in the core's signature ``int f(q, u, t, d, h, p, w, out)``:

* ``<name>_jvp`` (forward mode): the program replayed with its inputs moved along a direction
  (:func:`mbcomp.codegen.replay.replay`: ``q -> q + eps dq``, ``u -> u + eps du``, the
  external inputs ``d[2+i] -> d[2+i] + eps dd_i``) and differentiated with respect to ``eps``
  alone (:func:`mbcomp.codegen.tangent.tangent`): ``d`` is ``[alpha, beta, inputs (NIN),
  dq (NQ), du (NU), dd (NIN), eps = 0]``, ``out`` the product (one per program output);
* ``<name>_vjp`` (reverse mode, :func:`mbcomp.codegen.adjoint.reverse`): ``d`` is ``[alpha,
  beta, inputs, weights (one per program output)]``, ``out`` the weighted sum of the
  derivatives with respect to ``[q, u, inputs]``.

``fmu_derivatives.c`` (included by the core) combines them into FMI's directional and adjoint
derivatives; with D'Alembert's states it applies the chain rule through the dependent speeds
(``A_d du_d = -(dres/dq dq + A_i dv + dres/dd dd)``). The dependencies are the program's
structure: the state and input nodes in the cone of each output node
(:func:`mbcomp.codegen.tangent.cone`), so a pair declared independent has derivative 0.0
exactly (no node connects them).

Examples
--------
>>> import numpy as np
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.export.derivatives import cone_inputs
>>> with Graph() as g:
...     q0, u0, u1 = g.input("q", 0, 1.0), g.input("u", 0, 2.0), g.input("u", 1, 0.5)
...     f = [u0, np.sin(q0) * u1]
>>> [sorted(s) for s in cone_inputs(g, f)]
[[('u', 0)], [('q', 0), ('u', 1)]]
"""
from __future__ import annotations

from types import SimpleNamespace

from ..codegen.adjoint import reverse
from ..codegen.graph import Sym
from ..codegen.printers import Program
from ..codegen.replay import replay
from ..codegen.tangent import cone, tangent
from ..codegen.toolchain import chunk

__all__ = ["NO_DERIVATIVE", "cone_inputs", "derivative_programs", "no_derivative", "structure"]


def cone_inputs(graph, outputs):
    """Per output node: the set of ``(kind, index)`` of the input nodes (``"q"``, ``"u"``,
    ``"d"``, the time ``"t"``; parameters ``"p"`` left out) it depends on (an empty set for a
    number)."""
    keys, out = graph.keys, []
    for o in outputs:
        if type(o) is not Sym:
            out.append(set())
            continue
        out.append({keys[i][1:] for i in cone(keys, [o.i])
                    if keys[i][0] == "in" and keys[i][1] in ("q", "u", "d", "t")})
    return out


def _jvp(graph, outs, nq, nu, nin, fname):
    """``(C parts, defines)`` of the Jacobian-vector product of ``outs`` (see the module docstring)."""
    base = 2 + nin

    def shift(g2):
        eps = g2.input("d", base + nq + nu + nin, 0.0)
        moved = {}
        for kind, n, off, first in (("q", nq, base, 0), ("u", nu, base + nq, 0), ("d", nin, base + nq + nu, 2)):
            for j in range(n):
                moved[(kind, first + j)] = lambda x, c=g2.input("d", off + j, 0.0): x + eps * c
        return moved, eps

    g2, outs2, eps = replay(graph, outs, shift)
    J = tangent(g2, outs2, [eps])
    prog = Program(g2, {"jvp": [row[0] for row in J]}, guard_groups={"jvp": list(g2.guards)})
    return _printed(prog, "jvp", fname)


def _vjp(graph, outs, nq, nu, nin, fname):
    """``(C parts, defines)`` of the vector-Jacobian product of ``outs`` (module docstring)."""
    g3, outs3, _ = replay(graph, outs, lambda g: ({}, None))
    with g3:
        weights = [g3.input("d", 2 + nin + k, 0.0) for k in range(len(outs3))]
    ins = ([g3.memo.get(("in", "q", k)) for k in range(nq)] + [g3.memo.get(("in", "u", k)) for k in range(nu)]
           + [g3.memo.get(("in", "d", 2 + k)) for k in range(nin)])
    flat = reverse(g3, outs3, weights, ins)
    prog = Program(g3, {"vjp": flat}, guard_groups={"vjp": list(g3.guards)})
    return _printed(prog, "vjp", fname)


def _printed(prog, group, fname):
    parts, n_work = prog.c_parts(group, fname, chunk, n_parts=lambda n: 1)
    up = fname.upper()
    defines = f"#define {up}_NH {max(len(prog.hoisted), 1)}\n#define {up}_NW {max(n_work, 1)}\n"
    return defines + "\n".join(parts) + "\n" + prog.c_params(f"{fname}_params") + "\n"


def _pair(graph, outs, nq, nu, nin, name):
    return _jvp(graph, outs, nq, nu, nin, f"mbd_{name}_jvp") + _vjp(graph, outs, nq, nu, nin, f"mbd_{name}_vjp")


#: the product programs of a model whose outputs cannot be traced: none
_NO_OUTPUT_PRODUCTS = "".join(
    f"#define MBD_OUT_{m.upper()}_NH 1\n#define MBD_OUT_{m.upper()}_NW 1\n"
    f"static int mbd_out_{m}(const double *q, const double *u, double t, const double *d, const double *h,\n"
    f"                       const double *p, double *w, double *out)\n"
    "{ (void)q; (void)u; (void)t; (void)d; (void)h; (void)p; (void)w; (void)out; return 0; }\n"
    f"static int mbd_out_{m}_params(const double *pv, double *h) {{ (void)pv; (void)h; return 0; }}\n"
    for m in ("jvp", "vjp"))


#: the result columns without a derivative where the FMU runs: norms of the constraints'
#: residuals, zero on the constraints (a square root at zero)
NO_DERIVATIVE = ("residual.",)


def no_derivative(names):
    """The positions of the columns ``names`` the FMU gives no derivative of (:data:`NO_DERIVATIVE`)."""
    return [k for k, n in enumerate(names) if n.startswith(NO_DERIVATIVE)]


def derivative_programs(tr_fun, tr_out, tr_eval, res_nodes, nq, nu, nin):
    """The C of the product programs (module docstring) the FMU's derivatives run.

    Parameters
    ----------
    tr_fun : namespace
        The right-hand side's trace (group ``"fun"``).
    tr_out : namespace or None
        The output program's trace (group ``"outputs"``), None when the FMU has no outputs;
        its columns :func:`no_derivative` are left out of the products (zero there, and the
        core refuses them as unknowns).
    tr_eval : namespace or None
        The evaluation program's trace, with D'Alembert's states (else None); ``res_nodes``:
        its velocity-residual nodes ``[dPhi/dt[rows]; Psi]``.
    nq, nu, nin : int
        Coordinates, speeds, external inputs.

    Returns
    -------
    str
        C defining ``mbd_fun_jvp``/``_vjp``, ``mbd_out_jvp``/``_vjp`` and, with ``tr_eval``,
        ``mbd_res_jvp``/``_vjp`` (each with its ``_params``, ``_NH``, ``_NW``).
    """
    c = _pair(tr_fun.graph, list(tr_fun.groups["fun"]), nq, nu, nin, "fun")
    skip = []
    if tr_out is not None:
        skip = no_derivative(list(tr_out.output_names))
        outs = [0.0 if k in set(skip) else o for k, o in enumerate(tr_out.groups["outputs"])]
        c += _pair(tr_out.graph, outs, nq, nu, nin, "out")
    else:
        c += _NO_OUTPUT_PRODUCTS
    c += (f"#define MBD_NSKIP {len(skip)}\n"
          f"static const int MBD_SKIP[] = {{{', '.join(str(k) for k in skip) or '-1'}}};\n")
    if tr_eval is not None:
        c += f"#define MBD_NRES {len(res_nodes)}\n" + _pair(tr_eval.graph, res_nodes, nq, nu, nin, "res")
    return "#define MBD_DERIVATIVES 1\n" + c


def _union(sets):
    """The union of known-position sets, None (all knowns) if one of them is None."""
    return None if any(s is None for s in sets) else set().union(*sets)


def _sorted(s):
    return None if s is None else sorted(s)


def structure(tr_fun, tr_out, tr_eval, res_nodes, nq, nu, nin, select, n_cols, n_rot):
    """The dependencies of the unknowns on the knowns, as positions: ``(der, out)`` with
    ``der[k]`` the sorted known positions the derivative of state ``k`` depends on and
    ``out[s]`` those of output slot ``s`` (``NCOL`` columns, then 4 per rotation); a known
    position is a state's (``0 .. nx-1``, ``nx`` the number of states) or ``nx + i`` for
    input ``i``.

    Without state selection the states are ``[q, u]`` and the dependencies are the cones of
    the nodes. With D'Alembert's states ``[q, v]`` (``select``: ``v`` any ``nu - m`` of the
    speeds, the partition changing at events), a speed in a cone stands for every ``v`` and
    for what the dependent speeds depend on (the residual's coordinates and inputs), and
    every ``der(v[k])`` has the union of the speeds' rows' dependencies. An unknown that
    depends on the time has None (no ``dependencies`` attribute: "on all knowns"; FMI 2.0's
    time is no variable to name).
    """
    ni = len(res_nodes) if select else 0
    nx = nq + (nu - ni if select else nu)

    def position(kind, j):
        return j if kind == "q" else nq + j if kind == "u" else nx + j - 2

    dep_speeds = set()
    if select:
        for s in cone_inputs(tr_eval.graph, res_nodes):
            dep_speeds |= {position(k, j) for k, j in s if k != "u" and (k != "d" or j >= 2)}
        dep_speeds |= set(range(nq, nx))

    def known(s):
        if ("t", 0) in s:  # the time is a known FMI 2.0 has no variable for: "depends on all"
            return None
        out = set()
        for k, j in s:
            if k == "d" and j < 2:
                continue  # the Baumgarte gains: constants of the FMU
            if k == "u" and select:
                out |= dep_speeds
            else:
                out.add(position(k, j))
        return out

    fun = [known(s) for s in cone_inputs(tr_fun.graph, list(tr_fun.groups["fun"]))]
    if select:
        speeds = _union(fun[nq:])
        der = [_sorted(fun[k]) for k in range(nq)] + [_sorted(speeds)] * (nx - nq)
    else:
        der = [_sorted(f) for f in fun]
    out = []
    if tr_out is not None:
        rows = [known(s) for s in cone_inputs(tr_out.graph, list(tr_out.groups["outputs"]))]
        out = [_sorted(rows[k]) for k in range(n_cols)]
        for r in range(n_rot):
            out += [_sorted(_union(rows[n_cols + 9 * r: n_cols + 9 * r + 9]))] * 4
    return SimpleNamespace(der=der, out=out, nx=nx)
