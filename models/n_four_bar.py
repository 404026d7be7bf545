"""The N-four-bar mechanism: a chain of N parallelograms passing through flat positions.

The IFToMM multibody benchmark problem: ``N + 1`` uniform cranks of length ``L`` (m) pinned to
the ground at ``x = 0, L, ..., N L`` and ``N`` couplers of the same length joining the tips of
neighbouring cranks -- ``2 N + 1`` links, all of mass ``m`` (kg), gravity ``g`` along -y.
Every crank starts vertical (angle ``pi/2`` from +x) and the first turns at ``w0`` (rad/s);
the chain moves as one parallelogram, every crank at the same angle ``theta`` and every coupler
level, with one degree of freedom, so its motion is the exact one-degree-of-freedom equation

    J theta'' = -g cos(theta) m L ((N + 1) / 2 + N),   J = m L^2 ((N + 1) / 3 + N)

(a crank's moment of inertia about its pivot is m L^2 / 3, a level coupler translates with
the tips). Whenever ``theta`` is a multiple of ``pi`` every link lies on the ground line: the
closure Jacobian loses rank there (the flat position, a singular position), and the
mechanism passes it about once a second with the defaults. ``simulate(..., singular="pass")``
goes through those instants; ``"stop"`` (the default) reports the first one.

Modelled with 3-D revolute joints about z: the assembler cuts ``N`` joints to close the
loops and drops their out-of-plane rows as redundant (``mbcomp info``).

Run::

    mbcomp simulate models/n_four_bar.py -p N=2 --singular pass --out n_four_bar.csv
    mbcomp info models/n_four_bar.py -p N=40

Examples
--------
>>> import mbcomp
>>> s = mbcomp.assemble(build(N=2))
>>> s.nq, len(s.constraint_names(all_rows=True))   # 5 links on hinges; 2 cut hinges, 5 rows each
(5, 10)
"""
import numpy as np

from mbcomp import Guess, Model
from mbcomp.library import Fixed, FixedTranslation, Revolute, RigidBody, World

SIMULATION = dict(t_end=20.0, rtol=1e-8, atol=1e-10, singular="pass")


def rod(m, L):
    """A uniform slender rod of mass ``m`` (kg) and length ``L`` (m) along its frame's x axis,
    from the frame's origin."""
    return RigidBody(m=m, r_cm=(L / 2, 0.0, 0.0), I=np.diag([1e-9, m * L ** 2 / 12, m * L ** 2 / 12]))


def exact_rate(theta, N=2, L=1.0, m=1.0, g=9.81):
    """``theta''`` (rad/s^2) of the one-degree-of-freedom reduction at crank angle ``theta``."""
    J = m * L ** 2 * ((N + 1) / 3 + N)
    return -g * np.cos(theta) * m * L * ((N + 1) / 2 + N) / J


def build(N=2, L=1.0, m=1.0, g=9.81, w0=1.0):
    """``N`` parallelograms of links of length ``L`` (m) and mass ``m`` (kg), gravity ``g``
    (m/s^2) along -y, the first crank starting vertical at ``w0`` (rad/s, fixed)."""
    if int(N) != N or N < 1:
        raise ValueError(f"N={N!r}: the number of parallelograms must be an integer >= 1")
    N = int(N)
    model = Model()
    world = model.add("world", World(g=(0.0, -float(g), 0.0)))
    tips = []
    for k in range(N + 1):
        start = dict(phi0=np.pi / 2, w0=w0) if k == 0 else dict(phi0=Guess(np.pi / 2))
        pivot = model.add(f"crank{k}_pivot", Revolute(n=(0, 0, 1), **start))
        if k == 0:
            model.connect(world.frame_b, pivot.frame_a)
        else:
            ground = model.add(f"ground{k}", Fixed(r=(k * L, 0.0, 0.0)))
            model.connect(ground.frame_b, pivot.frame_a)
        crank = model.add(f"crank{k}", rod(m, L))
        tip = model.add(f"crank{k}_tip", FixedTranslation(r=(L, 0.0, 0.0)))
        model.connect(pivot.frame_b, crank.frame_a)
        model.connect(pivot.frame_b, tip.frame_a)
        tips.append(tip)
    for k in range(1, N + 1):
        a = model.add(f"coupler{k}_a", Revolute(n=(0, 0, 1), phi0=Guess(-np.pi / 2)))
        coupler = model.add(f"coupler{k}", rod(m, L))
        end = model.add(f"coupler{k}_end", FixedTranslation(r=(L, 0.0, 0.0)))
        b = model.add(f"coupler{k}_b", Revolute(n=(0, 0, 1), phi0=Guess(np.pi / 2)))
        model.connect(tips[k - 1].frame_b, a.frame_a)
        model.connect(a.frame_b, coupler.frame_a)
        model.connect(a.frame_b, end.frame_a)
        model.connect(end.frame_b, b.frame_a)
        model.connect(b.frame_b, tips[k].frame_b)
    model.alias("theta", "crank0_pivot.phi")
    return model
