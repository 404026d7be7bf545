"""``summary()`` / ``mbcomp info`` describe a system without changing it: the row mask (which
constraint rows are independent, set by consistent initialization) and every other attribute
stay as they were, and the text does not depend on whether the system was initialized."""
import numpy as np

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.assembly.summary import dof_report, summary
from mbcomp.library import FreeMotion, PointMass, Revolute, RigidBody, World
from mbcomp.modeling.free_joint import FreeMotion as FrameworkFreeMotion

from conftest import load_model


def attributes(system):
    return dict(vars(system))


def unchanged(system, before):
    after = attributes(system)
    return after.keys() == before.keys() and all(after[k] is before[k] for k in before)


def test_summary_leaves_an_uninitialized_system_as_it_was():
    system = mbcomp.assemble(load_model("models/slider_crank.py").build())
    before = attributes(system)
    text = system.summary()
    assert unchanged(system, before) and system.row_mask is None
    # the planar loop's three out-of-plane rows are redundant: the description found them anyway
    assert "degrees of freedom: 1 " in text
    assert "redundant constraint rows dropped: rod_joint.z, rod_joint.tilt_1, rod_joint.tilt_2" in text
    assert dof_report(system)["redundant"] == ["rod_joint.z", "rod_joint.tilt_1", "rod_joint.tilt_2"]
    assert unchanged(system, before)


def test_summary_keeps_the_row_mask_of_an_initialized_system_and_says_the_same():
    system = mbcomp.assemble(load_model("models/four_bar.py").build())
    fresh = system.summary()
    init = initialize(system)
    mask = system.row_mask
    assert mask is not None and not mask.all()  # a planar loop: some rows dropped
    before = attributes(system)
    assert system.summary() == fresh == summary(system, init)
    assert unchanged(system, before) and system.row_mask is mask
    np.testing.assert_array_equal(system.row_mask, init.row_mask)


def test_a_model_that_cannot_start_is_described_and_left_alone():
    """A point mass on the hinge axis: the hinge's motion carries no inertia, so consistent
    initialization fails; the summary says why and changes nothing."""
    m = mbcomp.Model()
    w, j, b = m.add("world", World()), m.add("j", Revolute()), m.add("b", PointMass())
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    system = mbcomp.assemble(m)
    before = attributes(system)
    text = system.summary()
    assert "initialization failed: the mechanism has massless degrees of freedom" in text
    assert "degrees of freedom: unknown (initialization failed)" in text
    assert unchanged(system, before)


def test_the_implicit_free_joint_is_the_framework_s_and_the_library_s():
    """A lone body marked free floats on the framework's FreeMotion, which the library re-exports."""
    assert FreeMotion is FrameworkFreeMotion and FreeMotion.__module__ == "mbcomp.modeling.free_joint"
    m = mbcomp.Model()
    m.add("world", World())
    m.add("body", RigidBody(m=2.0, I=np.eye(3)), free=True)
    system = mbcomp.assemble(m)
    (free,) = [e for e in system.topology.edges if e.implicit]
    assert type(free.comp) is FreeMotion and free.name == "body.free" and (system.nq, system.nu) == (7, 6)
    assert "free bodies (implicit free joint from the world: FreeMotion, FreeTranslation for a lone point " \
           "mass): body.free (FreeMotion)" in system.summary()
