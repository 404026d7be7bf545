"""The FMU tests' smallest model: a 2 kg bob on a rod of length ``-r`` m (default 1 m) released
at 0.5 rad, gravity 9.81 m/s^2 along -y (``World``'s default)."""
import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World


def pendulum(r=-1.0):
    """The pendulum (joint ``j``, rod ``rod`` along y by ``r`` m, bob ``bob``)."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, r, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    return m
