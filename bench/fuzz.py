"""Nightly-style fuzz run: thousands of random mechanisms through the fuzz oracle, outcomes counted.

The generator and the oracle are the test suite's (``tests/fuzz/fuzz_mechanisms.py``,
``tests/fuzz/fuzz_oracle.py``): trees of 1-8 bodies over every joint of the library, offsets,
springs and dampers, flange laws, loop closures and the nasty cases; each run on the compiled
default path ends in success (invariants held), "inaccurate", a failed/budget status or a
model/initialization/simulation error naming a component -- or is a *violation*.

Prints the counts per outcome (model errors by kind) and writes them to a CSV; every violation
is printed with its spec (``build(spec)`` in ``tests/fuzz`` reproduces it).

Run::

    python bench/fuzz.py                      # 3,000 mechanisms, seed 0, 2 processes
    python bench/fuzz.py --n 300 --seed 7 --jobs 1 --csv fuzz.csv
    python bench/fuzz.py --n 200 --seed 5 --jobs 1 --show inaccurate   # each "inaccurate" run, with its spec
"""
from __future__ import annotations

import argparse
import collections
import csv
import multiprocessing
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))


def _chunk(args):
    """Outcomes of ``n`` mechanisms drawn with ``seed``: a list of ``(kind, detail, spec)``."""
    n, seed, t_end, wall, show = args
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hseed

    from fuzz_mechanisms import mechanisms
    from fuzz_oracle import Violation, run

    out = []

    @settings(max_examples=n, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @hseed(seed)
    @given(mechanisms())
    def draw(spec):
        try:
            o = run(spec, t_end=t_end, max_wall_time=wall)
            out.append((o.kind, o.message.splitlines()[0][:400] if o.message else "", spec if o.kind in show else None))
        except Violation as exc:
            out.append(("violation", str(exc)[:400], spec))

    draw()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=3000, help="number of mechanisms (default 3000)")
    ap.add_argument("--seed", type=int, default=0, help="hypothesis seed (default 0)")
    ap.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    ap.add_argument("--t-end", type=float, default=0.3, help="simulated time per mechanism, s (default 0.3)")
    ap.add_argument("--wall", type=float, default=5.0, help="wall-time budget per mechanism, s (default 5)")
    ap.add_argument("--csv", default=str(ROOT / "bench" / "fuzz.csv"), help="counts CSV (default bench/fuzz.csv)")
    ap.add_argument("--show", nargs="*", default=[], metavar="OUTCOME",
                    help="also print the message and spec of these outcomes, e.g. --show inaccurate")
    a = ap.parse_args(argv)
    jobs = max(1, a.jobs)
    sizes = [a.n // jobs + (k < a.n % jobs) for k in range(jobs)]
    tasks = [(s, a.seed * 1000 + k, a.t_end, a.wall, tuple(a.show)) for k, s in enumerate(sizes) if s]
    t0 = time.perf_counter()
    if jobs == 1:
        results = [_chunk(t) for t in tasks]
    else:
        with multiprocessing.get_context("spawn").Pool(jobs) as pool:
            results = pool.map(_chunk, tasks)
    outcomes = [o for r in results for o in r]
    counts = collections.Counter(kind for kind, _, _ in outcomes)
    wall = time.perf_counter() - t0
    print(f"{len(outcomes)} mechanisms in {wall:.0f} s (seed {a.seed}, {jobs} processes)")
    for kind, k in counts.most_common():
        print(f"  {kind:22s} {k:6d}")
    for kind, detail, spec in outcomes:
        if kind == "violation" or kind in a.show:
            print(f"\n{kind.upper()}: {detail}\n  spec = {spec!r}")
    with open(a.csv, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["outcome", "count"])
        for kind, k in counts.most_common():
            w.writerow([kind, k])
    print(f"counts written to {a.csv}")
    return 1 if counts.get("violation") else 0


if __name__ == "__main__":
    sys.exit(main())
