"""A pendulum chain whose bobs slide on stiff springs: the stiff benchmark and test model.

N links on hinges about z (``j0 .. j<N-1>``); link ``k`` is a massless rod of length ``L``
along its hinge frame's x axis (``rod<k>``), at whose end a slider along the same axis
(``s<k>``) carries a point mass ``m`` (``bob<k>``) held by a spring ``c`` (N/m) and a damper
``d`` (N s/m) on the slider's own coordinate (``k<k>``: force ``-(c s + d ds/dt)``); the
next hinge sits on the bob. A spring ``c_tie`` (N/m, rest length ``tie_length`` m) ties the
last bob to the world origin; gravity ``(0, -g, 0)``. Start: hinge 0 at 0.6 rad, hinge k at
0.1 k rad, sliders at 1e-3 m, at rest.

With ``d`` large (``d = 1e5``: modes near ``-c/d = -10`` and ``-d/m = -1e5`` 1/s against the
pendulum's few 1/s) the stiffness is dissipative, the case implicit methods are for; with
``d`` small (``d = 1``, the default) the sliders ring at ``sqrt(c/m)`` = 1000 rad/s, an
oscillatory stiffness every method must resolve.

Run: ``mbcomp simulate models/spring_chain.py --out spring_chain.csv``

Examples
--------
>>> import mbcomp
>>> s = mbcomp.assemble(build(N=3))
>>> s.nq, s.nu
(6, 6)
"""
from mbcomp import Model
from mbcomp.library import FixedTranslation, PointMass, Prismatic, Revolute, Spring, TranslationalSpringDamper, World

SIMULATION = dict(t_end=1.0, rtol=1e-6, atol=1e-8)


def start(N):
    """``(phi0, s0)`` of every link: rad, m."""
    return [0.6 if k == 0 else 0.1 * k for k in range(N)], [1e-3] * N


def build(N=4, c=1e6, d=1.0, m=1.0, L=0.5, c_tie=100.0, tie_length=0.5, g=9.81):
    """The Model (see the module notes); SI units throughout."""
    phi0, s0 = start(N)
    mod = Model()
    w = mod.add("world", World(g=(0, -g, 0)))
    prev = w.frame_b
    for k in range(N):
        j = mod.add(f"j{k}", Revolute(n=(0, 0, 1), phi0=phi0[k]))
        rod = mod.add(f"rod{k}", FixedTranslation(r=(L, 0, 0)))
        s = mod.add(f"s{k}", Prismatic(n=(1, 0, 0), s0=s0[k]))
        bob = mod.add(f"bob{k}", PointMass(m=m))
        sp = mod.add(f"k{k}", TranslationalSpringDamper(c=c, d=d))
        mod.connect(prev, j.frame_a)
        mod.connect(j.frame_b, rod.frame_a)
        mod.connect(rod.frame_b, s.frame_a)
        mod.connect(s.frame_b, bob.frame_a)
        mod.connect(s.support, sp.flange_a)
        mod.connect(s.axis, sp.flange_b)
        prev = s.frame_b
    tie = mod.add("tie", Spring(c=c_tie, s_unstretched=tie_length))
    mod.connect(prev, tie.frame_a)
    mod.connect(w.frame_b, tie.frame_b)
    return mod
