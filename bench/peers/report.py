"""Tables of ``bench/peers.py``: markdown helpers, the case tables (starts, stiff, events,
Andrews, Exudyn) and the targets of issue 32 item 8 with their measured ratios.

A case's rows are dicts ``who``, ``method``, ``t`` (:class:`peers.timing.Try` or None: not
reached, the reason in ``note``), ``note``. A ratio is CPU time of mbcomp's default call
(warm cache unless said) over the peer's cheapest passing run, both measured in the same run.
"""
import math

__all__ = ["md_table", "num", "case_table", "targets", "TARGETS_DOC"]

#: issue 32 item 8's targets, as the final table words them
TARGETS_DOC = ("default call <= 0.5x Pinocchio + LSODA at N = 5 and N = 20 on all three starts; "
               "<= 1x the MuJoCo + C DOP853 construct; Andrews <= 0.5x pydy Cython + DOP853")


def num(v, fmt):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)


def md_table(header, body):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---:" if i else "---" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


def cheapest(rows, pred):
    """The cheapest passing row satisfying ``pred``, or None."""
    ok = [r for r in rows if r["t"] is not None and pred(r)]
    return min(ok, key=lambda r: r["t"].cpu_s) if ok else None


def case_table(title, rows, base_pred=None):
    """A markdown table of one case; ratios to the cheapest row matching ``base_pred``."""
    base = cheapest(rows, base_pred) if base_pred else None
    body = []
    for r in rows:
        t = r["t"]
        if t is None:
            body.append([r["who"], r["method"], "-", "-", "-", "-", "-", r["note"]])
            continue
        ratio = num(t.cpu_s / base["t"].cpu_s if base else None, ".3g")
        body.append([r["who"], r["method"], f"{t.setting:.0e}", f"{t.err:.1e}", num(float(t.nfev), ".0f"),
                     f"{t.cpu_s:.4f}", ratio, r["note"]])
    ref = f" (ratio to {base['who']} {base['method']})" if base else ""
    return f"\n### {title}{ref}\n\n" + md_table(["who", "method", "setting", "error", "nfev", "CPU s", "ratio",
                                                   "note"], body)


def _ratio(rows, num_pred, den_pred):
    a, b = cheapest(rows, num_pred), cheapest(rows, den_pred)
    if a is None or b is None:
        missing = "mbcomp" if a is None else "the peer"
        rs = [r for r in rows if (num_pred if a is None else den_pred)(r)]
        why = rs[0]["note"] if rs else "not run"
        return None, f"{missing} not measured: {why}"
    return a["t"].cpu_s / b["t"].cpu_s, f"{a['t'].cpu_s:.4f} s / {b['t'].cpu_s:.4f} s"


def _is(who, method=None):
    return lambda r: r["who"] == who and (method is None or r["method"] == method)


def targets(starts, andrews, others):
    """``(targets body, other ratios body)``: rows ``[target, case, ratio, limit, met, detail]``.

    ``starts``: ``{(start, N): (head, rows)}``; ``andrews``: ``(head, rows)`` or None;
    ``others``: ``{case: (head, rows)}`` for the ratios item 8 sets no number for."""
    body, info = [], []
    dflt = _is("mbcomp default call")
    cold = _is("mbcomp default call (cold cache)")

    def add(out, target, case, ratio_detail, limit):
        ratio, detail = ratio_detail
        met = "-" if limit is None else ("not measured" if ratio is None else ("met" if ratio <= limit else "NOT met"))
        out.append([target, case, num(ratio, ".3g"), "-" if limit is None else f"<= {limit:g}", met, detail])

    for (start, N), (head, rows) in sorted(starts.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        case = f"N = {N}, {start}, {num(head.get('t_end'), 'g')} s"
        if head.get("t_end") is None:
            for tgt, lim in (("default <= 0.5x Pinocchio + LSODA", 0.5), ("default <= 1x MuJoCo + C DOP853", 1.0)):
                body.append([tgt, case, "-", f"<= {lim:g}", "not measured", head.get("note", "")])
            continue
        add(body, "default <= 0.5x Pinocchio + LSODA", case, _ratio(rows, dflt, _is("pinocchio", "LSODA")), 0.5)
        add(body, "default <= 1x MuJoCo + C DOP853", case, _ratio(rows, dflt, _is("mujoco + C DOP853")), 1.0)
        add(info, "default, cold cache / Pinocchio + LSODA", case, _ratio(rows, cold, _is("pinocchio", "LSODA")), None)
        add(info, "default / MuJoCo + scipy DOP853", case, _ratio(rows, dflt, _is("mujoco", "DOP853")), None)
    if andrews is not None:
        head, rows = andrews
        add(body, "Andrews: default <= 0.5x pydy Cython + DOP853", "Andrews, 0.03 s, 1e-6",
            _ratio(rows, dflt, _is("sympy Kane + pydy Cython")), 0.5)
        add(info, "Andrews: default, cold cache / pydy Cython + DOP853", "Andrews",
            _ratio(rows, cold, _is("sympy Kane + pydy Cython")), None)
    for case, (head, rows) in others.items():
        if case == "stiff":
            add(info, "stiff: default / Pinocchio + LSODA", "stiff chain", _ratio(rows, dflt, _is("pinocchio", "LSODA")),
                None)
            add(info, "stiff: default, cold cache / Pinocchio + LSODA", "stiff chain",
                _ratio(rows, cold, _is("pinocchio", "LSODA")), None)
            add(info, "stiff: radau5 <= 1x Pinocchio + LSODA (item 4)", "stiff chain",
                _ratio(rows, _is("mbcomp radau5"), _is("pinocchio", "LSODA")), 1.0)
        elif case == "events":
            peer = lambda r: r["who"].startswith("pinocchio")  # noqa: E731
            add(info, "events: default <= 1x Pinocchio + scipy event loop (cheapest; item 5)", "pendulum on a stop",
                _ratio(rows, dflt, peer), 1.0)
            add(info, "events: default, cold cache / Pinocchio + event loop", "pendulum on a stop",
                _ratio(rows, cold, peer), None)
        elif case == "chain3d":
            for key in sorted(k for k in head if k.startswith("t_end_")):
                N = int(key[6:])
                where = f"3-D chain N = {N}, {head[key]:g} s"
                mine = _is(f"mbcomp default call, N = {N}")
                add(info, "3-D: default / Pinocchio + LSODA", where, _ratio(rows, mine, _is(f"pinocchio, N = {N}", "LSODA")),
                    None)
                add(info, "3-D: default / MuJoCo + C DOP853", where, _ratio(rows, mine, _is(f"mujoco + C DOP853, N = {N}")),
                    None)
        elif case == "exudyn":
            add(info, "default / Exudyn DOPRI5 (pendulum N = 5)", "pendulum N = 5, curled, 10 s",
                _ratio(rows, lambda r: r["who"] == "mbcomp default call, pendulum N = 5",
                       lambda r: r["who"].startswith("exudyn pendulum")), None)
            add(info, "default / Exudyn generalized-alpha (slider-crank)", "slider-crank, 10 s, 1e-4",
                _ratio(rows, _is("mbcomp default call, slider-crank"), _is("exudyn slider-crank")), None)
    return body, info
