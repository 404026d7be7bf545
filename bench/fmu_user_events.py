"""FMUs with user events (export_fmu(..., events=[f])) against closed forms and mbcomp.simulate.

The cases of tests/export/test_fmu_user_events.py: a mass in free fall on a Prismatic with the
terminal event ``s - h`` falling (closed form: it ends at sqrt(2 h / g)), a pendulum with a
rising event on its speed (non-terminal) and the angle falling with ``terminal=2``, and a door
whose hinge declares a ``Latch`` (its one event's action ``End``). Each is exported (FMI 3.0 and
2.0) and run by FMPy as Model Exchange (CVODE at rtol 1e-14) and as Co-Simulation (the FMU's
DOP853 at 1e-12, an early return allowed in 3.0); the reference is the closed form or
``mbcomp.simulate(rtol=1e-12, atol=1e-14)``. Printed: the difference of the run's end time (s)
and of ``[q, u]`` there (largest entry).
Needs FMPy and a C compiler. Run: python bench/fmu_user_events.py
"""
import pathlib
import tempfile

import numpy as np

import mbcomp
from mbcomp.export import export_fmu
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, World
from mbcomp.modeling.events import End
from mbcomp.modeling.modes import Modes

G = 9.81


def chain(g, joint, r):
    """world -> joint -> rod r -> 1 kg (2 kg for the pendulum) point mass."""
    m = mbcomp.Model()
    w = m.add("world", World(g=g))
    name, comp = joint
    j = m.add(name, comp)
    rod = m.add("rod", FixedTranslation(r=r))
    bob = m.add("bob", PointMass(m=2.0 if name == "j" else 1.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m


def floor(t, y):
    return y[0] - 0.5


def rising(t, y):
    return y[1]


def second(t, y):
    return y[0]


floor.terminal, floor.direction = True, -1
rising.direction = 1
second.terminal, second.direction = 2, -1


class Latch(Modes):
    def events(self, q, u, mode):
        return [("latched", 1.0 - q[0], -1)]

    def action(self, name, mode):
        return End("the door latched")


class Door(Revolute):
    def modes(self, p):
        return Latch("open")


def cases():
    fall = lambda: chain((0, 0, -G), ("s", Prismatic(n=(0, 0, 1), s0=1.0)), (0, 0, 0.0))  # noqa: E731
    swing = lambda: chain((0, -G, 0), ("j", Revolute(phi0=0.5)), (0, -1.0, 0))  # noqa: E731
    door = lambda: chain((0, -G, 0), ("hinge", Door(n=(0, 0, 1), phi0=0.0, w0=5.0)), (1.0, 0, 0))  # noqa: E731
    t_ff = np.sqrt(2 * 0.5 / G)
    sw = mbcomp.simulate(swing(), t_end=5.0, events=[rising, second], rtol=1e-12, atol=1e-14)
    dr = mbcomp.simulate(door(), t_end=2.0, rtol=1e-12, atol=1e-14)
    return [("free fall, terminal (closed form)", fall, [floor], 1.0, ["s.s", "s.v"], (t_ff, 0.5, -G * t_ff)),
            ("pendulum, rising + terminal=2", swing, [rising, second], 5.0, ["j.phi", "j.w"],
             (sw.time[-1], sw["j.phi"][-1], sw["j.w"][-1])),
            ("door, Latch (End)", door, None, 2.0, ["hinge.phi", "hinge.w"],
             (dr.time[-1], dr["hinge.phi"][-1], dr["hinge.w"][-1]))]


def main():
    from fmpy import simulate_fmu

    tmp = pathlib.Path(tempfile.mkdtemp())
    print(f"{'model':36s} {'FMI':4s} {'kind':14s} {'|dt_end| (s)':>12s} {'|d[q,u]|':>10s}")
    for label, build, events, stop, names, ref in cases():
        for fmi in ("3.0", "2.0"):
            path = tmp / f"m{fmi[0]}.fmu"
            export_fmu(build(), path, fmi=fmi, derivatives=False, events=events)
            for kind in ("ModelExchange", "CoSimulation"):
                opts = dict(relative_tolerance=1e-14) if kind == "ModelExchange" else {}
                if fmi == "3.0" and kind == "CoSimulation":
                    opts["early_return_allowed"] = True
                r = simulate_fmu(str(path), fmi_type=kind, stop_time=stop, output_interval=0.01, output=names,
                                 **opts)[-1]
                dy = max(abs(r[1] - ref[1]), abs(r[2] - ref[2]))
                print(f"{label:36s} {fmi:4s} {kind:14s} {abs(r[0] - ref[0]):12.2e} {dy:10.2e}")


if __name__ == "__main__":
    main()
