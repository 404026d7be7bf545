"""A model's structure as a key (modeling/fingerprint.py, FlatModel.structure): parameter
values are not in it; a class constant is, read again whenever a class's namespace changes
(rebound, added, removed, an array changed in place, a base class changed); equal structures
alive at once are one key object."""
import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, PointMass, Revolute, World
from mbcomp.modeling.fingerprint import Key, fingerprint


def structure(joint_class=Revolute, m=1.0, phi0=0.2, attribute=None):
    mdl = mbcomp.Model()
    w = mdl.add("world", World())
    j = mdl.add("j", joint_class(phi0=phi0))
    rod = mdl.add("rod", FixedTranslation(r=(0.0, -1.0, 0.0)))
    b = mdl.add("b", PointMass(m=m))
    mdl.connect(w.frame_b, j.frame_a)
    mdl.connect(j.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, b.frame_a)
    if attribute is not None:
        j.extra = attribute
    return mdl.validate().structure()[0]


def test_parameter_values_are_not_structure_and_equal_structures_are_one_object():
    a, b = structure(m=1.0, phi0=0.2), structure(m=3.0, phi0=-1.0)
    assert a is b and isinstance(a, Key)
    assert structure(attribute=(1, 2)) is structure(attribute=(1, 2))
    assert structure(attribute=(1, 2)) != a and structure(attribute=(1, 3)) != structure(attribute=(1, 2))
    assert structure(attribute=np.array([1.0, 2.0])) != structure(attribute=np.array([1.0, 2.5]))


def test_every_change_of_a_class_namespace_is_another_structure():
    class Base(Revolute):
        GAIN = 1.0
        TABLE = np.array([1.0, 2.0])
        NAMES = ("a", "b")

    class Hinge(Base):
        pass

    keys = [structure(Hinge)]
    assert structure(Hinge) is keys[0]
    Base.GAIN = 2.0                      # a constant rebound (in a base class)
    keys.append(structure(Hinge))
    Base.TABLE[1] = 5.0                  # an array changed in place
    keys.append(structure(Hinge))
    Hinge.OFFSET = 0.5                   # a constant added
    keys.append(structure(Hinge))
    del Base.NAMES                       # one removed
    keys.append(structure(Hinge))
    Base.GAIN = 1.0
    Base.TABLE[1] = 2.0
    del Hinge.OFFSET
    Base.NAMES = ("a", "b")
    keys.append(structure(Hinge))        # all back: the first structure again
    assert len({k.value for k in keys[:-1]}) == len(keys) - 1
    assert keys[-1] == keys[0]
    Base.method = lambda self: 1.0       # behaviour is not data: the same structure
    assert structure(Hinge) == keys[0]


def test_a_fingerprint_takes_what_it_cannot_see_into_by_identity_and_keeps_it():
    class Opaque:
        __slots__ = ("x",)

    refs = []
    o = Opaque()
    assert fingerprint(o, refs) == ("is", o) and refs == [o]
    assert fingerprint({"k": [1.0, (2, "s")]}, []) == fingerprint({"k": [1.0, (2, "s")]}, [])
