"""Units: parameters given with units are converted to SI once, when the component is made;
wrong dimensions and unknown symbols are problems naming the parameter and both units;
results carry their columns' units (``Result.units``, CSV headers); ``help()`` of a component
lists its parameters with units and defaults."""
import csv
import math
import pydoc

import numpy as np
import pytest

import mbcomp
from mbcomp import Component, Frame, Guess, Param
from mbcomp.library import (FixedTranslation, PointMass, PrescribedMotion, Revolute, RigidBody, RotationalDamper,
                            RotationalSpring, Spring, Torque, World)
from mbcomp.modeling.units import UnitError, parse_unit, per_second, to_unit, unit_exponents, unit_text


# ------------------------------------------------------------------------------------------
# conversions, one by one, against hand-computed SI values
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("text, unit, si", [
    ("250 g", "kg", 0.25),
    ("2.5 kg", "kg", 2.5),
    ("30 deg", "rad", math.pi / 6),
    ("30°", "rad", math.pi / 6),
    ("2 kN/m", "N/m", 2000.0),
    ("1.5 mm", "m", 1.5e-3),
    ("10 µm", "m", 1e-5),
    ("10 um", "m", 1e-5),
    ("3 in", "m", 3 * 0.0254),
    ("2 ft", "m", 0.6096),
    ("90 deg/s", "rad/s", math.pi / 2),
    ("3 rpm", "rad/s", 3 * 2 * math.pi / 60),
    ("1 rev/s", "rad/s", 2 * math.pi),
    ("2 min", "s", 120.0),
    ("1.5 h", "s", 5400.0),
    ("20 ms", "s", 0.02),
    ("36 km/h", "m/s", 10.0),
    ("5 N m/deg", "N m/rad", 5 * 180 / math.pi),
    ("20 N s/mm", "N s/m", 20000.0),
    ("500 kg cm^2", "kg m^2", 0.05),
    ("500 kg*cm**2", "kg m^2", 0.05),
    ("1.5 kN m", "N m", 1500.0),
    ("12 Nm", "N m", 12.0),
    ("3 kJ", "N m", 3000.0),
    ("2 bar", "Pa", 2e5),
    ("1.5 kW", "W", 1500.0),
    ("-9.81 m/s^2", "m/s^2", -9.81),
    ("50 %", "1", 0.5),
    ("0.5", "kg", 0.5),  # a number alone is in the parameter's own unit
    ("5 mm", "m or rad", 0.005),
    ("5 mrad", "m or rad", 0.005),
    ("1 kg/(m s)", "Pa s", 1.0),
])
def test_value_with_unit_to_si(text, unit, si):
    assert to_unit(text, unit) == pytest.approx(si, rel=1e-15, abs=0)


def test_decimal_prefixes_are_correctly_rounded():
    # 10 * 1e-6 is 9.999999999999999e-06 in floating point; the conversion divides by 1e6
    assert to_unit("10 µm", "m") == 1e-5 and to_unit("3 mm", "m") == 0.003


def test_arrays_with_units_both_ways():
    np.testing.assert_array_equal(to_unit("(10, 0, -5) cm", "m"), [0.1, 0.0, -0.05])
    np.testing.assert_array_equal(to_unit("[[1, 0], [0, 2]] g", "kg"), [[1e-3, 0.0], [0.0, 2e-3]])
    assert to_unit(("10 cm", 0, "2 mm"), "m") == [0.1, 0, 0.002]  # plain numbers: already in m


def test_unit_parser_exponents_and_formatting():
    assert parse_unit("N m s/rad") == (1.0, {"kg": 1, "m": 2, "s": -1, "rad": -1})
    assert parse_unit("m/s/s") == parse_unit("m/s^2") == (1.0, {"m": 1, "s": -2})
    assert parse_unit("kg.m2/s2")[1] == parse_unit("J")[1]
    assert unit_exponents("mm") is None and unit_exponents("deg") is None  # scaled: no FMU unit
    assert unit_exponents("m or rad") is None and unit_exponents("furlong") is None
    assert unit_text({"kg": 1, "m": 2, "s": -2}) == "kg m^2/s^2"
    assert per_second("rad/s") == "rad/s^2" and per_second("1") == "1/s"
    for text in ("N m s/rad", "kg m^2", "m/s^2", "W", "Pa"):  # formatting round-trips the exponents
        assert parse_unit(unit_text(unit_exponents(text)))[1] == unit_exponents(text)


def test_angles_are_a_dimension_of_their_own():
    with pytest.raises(UnitError, match=r'"50 Hz" has unit Hz \(frequency\), expected rad/s \(angular velocity\)'):
        to_unit("50 Hz", "rad/s")
    with pytest.raises(UnitError, match=r"has unit deg \(angle\), expected 1 \(dimensionless\)"):
        to_unit("30 deg", "1")


# ------------------------------------------------------------------------------------------
# components: converted once at construction
# ------------------------------------------------------------------------------------------
def test_component_parameters_with_units():
    assert RigidBody(m="250 g").p.m == 0.25
    assert Revolute(phi0="30 deg").p.phi0 == pytest.approx(math.pi / 6, rel=1e-15)
    assert Spring(c="2 kN/m").p.c == 2000.0
    np.testing.assert_array_equal(FixedTranslation(r=("10 cm", 0, 0)).p.r, [0.1, 0.0, 0.0])
    np.testing.assert_array_equal(FixedTranslation(r="(10, 0, 0) cm").p.r, [0.1, 0.0, 0.0])
    g = Revolute(phi0=Guess("30 deg")).p.phi0
    assert isinstance(g, Guess) and g.value == pytest.approx(math.pi / 6, rel=1e-15)
    assert Torque(tau="1.5 kN m").p.tau == 1500.0  # a law's constant value
    assert isinstance(RigidBody(m="250 g").p.m, float)


def test_prescribed_motion_keeps_its_expression_strings():
    # kind "any": "0.1*sin(2*t)" is a law of time, not a value with a unit
    assert PrescribedMotion(s="0.1*sin(2*t)").p.s == "0.1*sin(2*t)"


def test_runtime_overrides_convert_too():
    p = RigidBody(m=1.0).runtime_params({"m": "250 g"})
    assert p.m == 0.25
    with pytest.raises(mbcomp.ModelError, match=r'parameter "1 m" has unit m \(length\), expected kg \(mass\)'):
        RigidBody(m=1.0).runtime_params({"m": "1 m"})


def _pendulum(phi0, w0, m, r_cm, I, c, d):
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, -9.81, 0)))
    j = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0=phi0, w0=w0))
    body = mdl.add("crank", RigidBody(m=m, r_cm=r_cm, I=I))
    spring = mdl.add("spring", RotationalSpring(c=c))
    damper = mdl.add("damper", RotationalDamper(d=d))
    mdl.connect(w.frame_b, j.frame_a)
    mdl.connect(j.frame_b, body.frame_a)
    for el in (spring, damper):
        mdl.connect(j.support, el.flange_a)
        mdl.connect(j.axis, el.flange_b)
    return mdl


def test_simulation_with_units_equals_the_si_one():
    si = _pendulum(math.pi / 6, 2 * math.pi, 0.25, (0.1, 0, 0), np.diag([1e-4, 1e-4, 2e-4]),
                   0.5 * 180 / math.pi, 0.02)
    given = _pendulum("30 deg", "60 rpm", "250 g", ("10 cm", 0, 0), "[[1, 0, 0], [0, 1, 0], [0, 0, 2]] kg cm^2",
                      "0.5 N m/deg", "20 N m ms/rad")
    a = mbcomp.simulate(si, t_end=1.0, n_out=51)
    b = mbcomp.simulate(given, t_end=1.0, n_out=51)
    assert a.success and b.success
    np.testing.assert_allclose(b["hinge.phi"], a["hinge.phi"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b["energy.total"], a["energy.total"], rtol=1e-12, atol=1e-12)
    assert b["hinge.phi"][0] == pytest.approx(math.pi / 6, rel=1e-14)


def test_pint_quantities_when_pint_is_installed():
    pint = pytest.importorskip("pint")
    ureg = pint.UnitRegistry()
    Q = ureg.Quantity
    assert RigidBody(m=Q(250, "g")).p.m == pytest.approx(0.25, rel=1e-15)
    assert Revolute(phi0=Q(30, "deg")).p.phi0 == pytest.approx(math.pi / 6, rel=1e-15)
    assert Revolute(w0=Q(3, "rpm")).p.w0 == pytest.approx(math.pi / 10, rel=1e-15)
    assert Spring(c=Q(2, "kN/m")).p.c == pytest.approx(2000.0, rel=1e-15)
    assert Torque(tau=Q(2, "lbf * ft")).p.tau == pytest.approx(2 * 4.4482216152605 * 0.3048, rel=1e-12)
    np.testing.assert_allclose(FixedTranslation(r=Q(np.array([10.0, 0.0, 5.0]), "cm")).p.r, [0.1, 0, 0.05],
                               rtol=1e-15)
    assert PrescribedMotion(s=Q(30, "deg")).p.s == pytest.approx(math.pi / 6, rel=1e-15)  # "m or rad"
    with pytest.raises(mbcomp.ModelError) as ei:
        _pendulum(0.1, 0.0, Q(30, "deg"), (0.1, 0, 0), np.eye(3) * 1e-4, 1.0, 0.0).validate()
    assert 'crank.m: parameter "30 degree" (pint) has unit rad (angle), expected kg (mass)' in str(ei.value)
    with pytest.raises(mbcomp.ModelError, match=r"has unit 1/s \(frequency\), expected rad/s \(angular velocity\)"):
        _pendulum(0.1, Q(50, "Hz"), 1.0, (0.1, 0, 0), np.eye(3) * 1e-4, 1.0, 0.0).validate()


# ------------------------------------------------------------------------------------------
# errors: collected by validate, naming the parameter, both units and the fix
# ------------------------------------------------------------------------------------------
def test_wrong_dimension_is_a_problem_naming_both_units():
    mdl = _pendulum(0.1, 0.0, "30 deg", (0.1, 0, 0), np.eye(3) * 1e-4, "2 kN/m", 0.0)
    with pytest.raises(mbcomp.ModelError) as ei:
        mdl.validate()
    text = str(ei.value)
    assert ('crank.m: parameter "30 deg" has unit deg (angle), expected kg (mass) -> fix: give m (mass) in kg, '
            '>= 0, or a mass such as "250 g"') in text
    assert ('spring.c: parameter "2 kN/m" has unit kN/m (stiffness), expected N m/rad (rotational stiffness)'
            in text and 'a rotational stiffness such as "5 N m/deg"' in text)
    assert len(ei.value.problems) == 2  # both collected, raised once


def test_unknown_unit_lists_the_known_ones():
    with pytest.raises(mbcomp.ModelError) as ei:
        _pendulum(0.1, 0.0, 1.0, ("3 furlong", 0, 0), np.eye(3) * 1e-4, 1.0, 0.0).validate()
    pr = [p for p in ei.value.problems if p.where == "crank.r_cm"][0]
    assert pr.what.startswith("parameter \"3 furlong\": unknown unit 'furlong'; known: m, g, s, rad")
    assert "with SI prefixes (T, G, M, k, h, da, d, c, m, u, µ, n, p)" in pr.what and "deg, rev, rpm" in pr.what
    assert pr.fix.startswith("give r_cm (centre of mass, frame_a coordinates) as an array of shape (3,) in m")


def test_text_that_is_no_number():
    with pytest.raises(mbcomp.ModelError) as ei:
        _pendulum(0.1, 0.0, "heavy", (0.1, 0, 0), np.eye(3) * 1e-4, 1.0, 0.0).validate()
    assert "crank.m: parameter 'heavy' is not a number (nor a number with a unit, such as \"250 g\")" in str(ei.value)


def test_a_unit_mbcomp_cannot_read_accepts_only_itself():
    class Coil(Component):
        """A coil."""
        frame_a = Frame("where it sits")
        u = Param(1.0, unit="V", doc="voltage")

    assert Coil(u="3 V").p.u == 3.0
    assert Coil(u=3.0).p.u == 3.0
    assert Coil(u="3 mV").problems()[0].what == (
        "parameter \"3 mV\" has unit mV, but the parameter's unit 'V' is not one mbcomp can convert to")


def test_a_non_si_declared_unit_is_the_stored_unit():
    class Gauge(Component):
        """A gauge in millimetres."""
        gap = Param(1.0, unit="mm", doc="gap")

    assert Gauge(gap="2 cm").p.gap == 20.0 and Gauge(gap=3.0).p.gap == 3.0


# ------------------------------------------------------------------------------------------
# results: units per column, CSV headers on request
# ------------------------------------------------------------------------------------------
def _swing():
    mdl = mbcomp.Model()
    w = mdl.add("world", World(g=(0, -9.81, 0)))
    j = mdl.add("hinge", Revolute(n=(0, 0, 1), phi0="30 deg"))
    rod = mdl.add("rod", FixedTranslation(r=(0, "-1 m", 0)))
    bob = mdl.add("bob", PointMass(m="1 kg"))
    mdl.connect(w.frame_b, j.frame_a)
    mdl.connect(j.frame_b, rod.frame_a)
    mdl.connect(rod.frame_b, bob.frame_a)
    mdl.alias("angle", "hinge.phi")
    return mdl


def test_result_units_of_a_pendulum():
    r = mbcomp.simulate(_swing(), t_end=0.2, n_out=5)
    u = r.units
    assert (u["hinge.phi"], u["hinge.w"], u["hinge.w.der"]) == ("rad", "rad/s", "rad/s^2")
    assert (u["hinge.f.x"], u["hinge.tau.z"]) == ("N", "N m")
    assert (u["bob.r.y"], u["bob.v.x"], u["bob.w.z"]) == ("m", "m/s", "rad/s")
    assert u["energy.kinetic"] == u["energy.potential"] == u["energy.total"] == "J"
    assert u["angle"] == "rad"  # an alias has its variable's unit
    assert set(u) <= set(r.names)
    assert "residual.position" not in u  # mixed units: none declared


def test_csv_headers_with_units(tmp_path):
    r = mbcomp.simulate(_swing(), t_end=0.2, n_out=5)
    with open(r.to_csv(tmp_path / "plain.csv")) as fh:
        plain = next(csv.reader(fh))
    with open(r.to_csv(tmp_path / "units.csv", units=True)) as fh:
        header = next(csv.reader(fh))
    assert plain[:1] == ["time"] and "hinge.phi" in plain
    assert header[0] == "time [s]"
    assert "hinge.phi [rad]" in header and "hinge.f.x [N]" in header and "energy.total [J]" in header
    assert "residual.position" in header  # no unit known: the bare name
    assert len(header) == len(plain) == len(r.names) + 1


def test_fmu_and_results_read_one_table():
    from mbcomp.assembly.column_units import column_units
    from mbcomp.export.description import _column_units

    system = mbcomp.assemble(_swing())
    table = column_units(system)
    assert _column_units(system) == {k: (unit_exponents(v), v) for k, v in table.items()}
    assert _column_units(system)["hinge.w.der"] == ({"s": -2, "rad": 1}, "rad/s^2")


# ------------------------------------------------------------------------------------------
# help(): parameters with units, defaults and docs; ports
# ------------------------------------------------------------------------------------------
def test_help_of_a_library_component_lists_parameters_and_ports():
    text = pydoc.render_doc(Revolute, renderer=pydoc.plaintext)
    assert "Parameters\n |  ----------" in text
    assert "n : array (3,), dimensionless, default (0.0, 0.0, 1.0)" in text
    assert "phi0 : float or Guess, rad, optional" in text
    assert "start angle (fixed; wrap in Guess to let init move it)" in text
    assert "axis : Flange, optional" in text and "frame_a : Frame" in text
    # numpydoc's order: the sections come before the examples, which still run
    assert text.index("Parameters") < text.index("Ports") < text.index("Examples")
    text = pydoc.render_doc(RigidBody, renderer=pydoc.plaintext)
    assert "m : float, kg, default 1.0" in text and "mass; >= 0" in text
    assert "I : array (3, 3), kg m^2, default [[0.0, 0.0, 0.0]" in text


def test_help_of_a_user_component():
    class Marker(Component):
        """A marker.

        Examples
        --------
        >>> Marker(size="2 cm").p.size
        0.02
        """
        frame_a = Frame("the marked frame")
        size = Param(0.1, unit="m", doc="drawing size", check="positive")

    doc = Marker.__doc__
    assert "size : float, m, default 0.1\n    drawing size; > 0" in doc
    assert "Ports\n-----\nframe_a : Frame\n    the marked frame" in doc
    assert doc.index("Parameters") < doc.index("Examples")


def test_a_class_documenting_its_own_parameters_keeps_them():
    # World writes its own Parameters section: kept as written, no second one
    assert World.__doc__.count("Parameters\n----------") == 1
    assert "g : (3,) m/s^2, world coordinates" in World.__doc__
    assert "Ports\n-----\nframe_b : Frame, optional" in World.__doc__
