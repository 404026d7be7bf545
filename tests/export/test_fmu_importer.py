"""What an importer sees of an mbcomp FMU (issue 33, item 4): calls out of the FMI state
machine are refused naming the call and the mode; bad parameter values are refused naming the
variable and mbcomp's own rule; messages name variables; one default tolerance; the joint
coordinates and speeds are outputs; named units.

The calls are made through FMPy's low-level classes (its ``simulate_fmu`` only makes legal
sequences); the FMU's messages reach FMPy's default logger, which prints them (``capfd``).
"""
import ctypes
import math

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.library import Revolute, RigidBody, World

from test_fmu import pendulum

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

VERSIONS = ["3.0", "2.0"]


def body_pendulum():
    """A rigid body (1 kg, centre of mass 0.5 m out, inertia diag(0.1, 0.2, 0.25) kg m^2) on a hinge."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    b = m.add("body", RigidBody(m=1.0, r_cm=(0.5, 0, 0), I=np.diag([0.1, 0.2, 0.25])))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, b.frame_a)
    return m


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """``built(name, fmi)``: the path of the FMU of ``pendulum()`` or ``body_pendulum()``, built once."""
    root, cache = tmp_path_factory.mktemp("importer"), {}

    def get(name, fmi):
        if (name, fmi) not in cache:
            path = root / f"{name}{fmi[0]}.fmu"
            export_fmu({"pendulum": pendulum, "body": body_pendulum}[name](), path, fmi=fmi, derivatives=False)
            cache[name, fmi] = path
        return cache[name, fmi]
    return get


class Instance:
    """An FMPy instance of the FMU at ``path`` (``kind`` "me" or "cs"), with the model
    description's value references by name (``vr["j.phi"]``)."""

    def __init__(self, path, fmi, kind):
        from fmpy.fmi2 import FMU2Model, FMU2Slave
        from fmpy.fmi3 import FMU3Model, FMU3Slave

        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        iface = self.md.modelExchange if kind == "me" else self.md.coSimulation
        cls = {("3.0", "me"): FMU3Model, ("3.0", "cs"): FMU3Slave, ("2.0", "me"): FMU2Model,
               ("2.0", "cs"): FMU2Slave}[fmi, kind]
        self.fmi, self.kind = fmi, kind
        self.fmu = cls(guid=self.md.guid, unzipDirectory=extract(str(path)), modelIdentifier=iface.modelIdentifier,
                       instanceName="it")
        self.fmu.instantiate(loggingOn=True)

    def init(self, tolerance=None):
        if self.fmi == "2.0":
            self.fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(tolerance=tolerance, startTime=0.0)

    def get(self, *names):
        vrs = [self.vr[n] for n in names]
        return self.fmu.getFloat64(vrs) if self.fmi == "3.0" else self.fmu.getReal(vrs)

    def set(self, name, value):
        if self.fmi == "3.0":
            self.fmu.setFloat64([self.vr[name]], [value])
        else:
            self.fmu.setReal([self.vr[name]], [value])

    def step(self, t, h):
        self.fmu.doStep(t, h)

    def derivatives(self, n):
        dx = (ctypes.c_double * n)()
        (self.fmu.getContinuousStateDerivatives if self.fmi == "3.0" else self.fmu.getDerivatives)(dx, n)
        return list(dx)


def refused(capfd, call, *texts):
    """``call()`` fails (FMPy raises on the error status) and the FMU's message has ``texts``."""
    capfd.readouterr()
    with pytest.raises(Exception):
        call()
    out = capfd.readouterr()
    said = out.out + out.err
    for text in texts:
        assert text in said, (text, said)
    return said


def fmi_name(fmi, call):
    return ("fmi3" if fmi == "3.0" else "fmi2") + call


# --- 1. the FMI state machine ------------------------------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_co_simulation_calls_out_of_the_state_machine_are_refused(fmi, built, capfd):
    """DoStep before initialization, in Initialization Mode and after Terminate, reading values
    before EnterInitializationMode: errors naming the call and the mode. The legal sequence
    still steps the pendulum, and Reset makes the instance new."""
    it = Instance(built("pendulum", fmi), fmi, "cs")
    do_step = fmi_name(fmi, "DoStep")
    refused(capfd, lambda: it.step(0.0, 0.1), f"{do_step} is not allowed in Instantiated", "Step Mode")
    refused(capfd, lambda: it.get("j.phi"), "is not allowed in Instantiated")
    it.init()
    refused(capfd, lambda: it.step(0.0, 0.1), f"{do_step} is not allowed in Initialization Mode")
    again = it.fmu.enterInitializationMode if fmi == "2.0" else it.init
    refused(capfd, again, f"{fmi_name(fmi, 'EnterInitializationMode')} is not allowed in Initialization Mode")
    it.fmu.exitInitializationMode()
    phi0 = it.get("j.phi")[0]
    it.step(0.0, 0.1)
    phi1 = it.get("j.phi")[0]
    # the hinge swings down: phi'' = -(g/L) sin(phi) at rest, so phi1 ~ 0.5 - g sin(0.5) h^2 / 2
    assert phi0 == 0.5 and phi1 == pytest.approx(0.5 - 9.81 * math.sin(0.5) * 0.1 ** 2 / 2, rel=1e-2)
    it.fmu.terminate()
    refused(capfd, lambda: it.step(0.1, 0.1), f"{do_step} is not allowed in Terminated")
    assert it.get("j.phi")[0] == phi1  # reading after Terminate is allowed
    it.fmu.reset()
    it.init()
    it.fmu.exitInitializationMode()
    it.step(0.0, 0.1)
    assert it.get("j.phi")[0] == phi1  # the same step again after Reset
    it.fmu.terminate()
    it.fmu.freeInstance()


@pytest.mark.parametrize("fmi", VERSIONS)
def test_model_exchange_calls_out_of_the_state_machine_are_refused(fmi, built, capfd):
    it = Instance(built("pendulum", fmi), fmi, "me")
    derivatives = "GetContinuousStateDerivatives" if fmi == "3.0" else "GetDerivatives"
    refused(capfd, lambda: it.fmu.setTime(0.0), f"{fmi_name(fmi, 'SetTime')} is not allowed in Instantiated",
            "Event Mode, Continuous-Time Mode")
    refused(capfd, lambda: it.derivatives(2), f"{fmi_name(fmi, derivatives)} is not allowed in Instantiated")
    it.init()
    x = (ctypes.c_double * 2)(0.5, 0.0)
    refused(capfd, lambda: it.fmu.setContinuousStates(x, 2),
            f"{fmi_name(fmi, 'SetContinuousStates')} is not allowed in Initialization Mode")
    it.fmu.exitInitializationMode()  # -> Event Mode
    refused(capfd, lambda: it.fmu.completedIntegratorStep(),
            f"{fmi_name(fmi, 'CompletedIntegratorStep')} is not allowed in Event Mode")
    if fmi == "2.0":
        it.fmu.newDiscreteStates()
    else:
        it.fmu.updateDiscreteStates()
    it.fmu.enterContinuousTimeMode()
    it.fmu.setTime(0.0)
    x = (ctypes.c_double * 2)(1.0, 0.25)
    it.fmu.setContinuousStates(x, 2)
    # the legal sequence computes the pendulum's law: phi' = w, w' = -(g/L) sin(phi)
    dphi, dw = it.derivatives(2)
    assert dphi == 0.25 and dw == pytest.approx(-9.81 * math.sin(1.0), rel=1e-12)
    it.fmu.terminate()
    refused(capfd, lambda: it.fmu.setTime(1.0), f"{fmi_name(fmi, 'SetTime')} is not allowed in Terminated")
    refused(capfd, lambda: it.fmu.terminate(), f"{fmi_name(fmi, 'Terminate')} is not allowed in Terminated")
    assert it.derivatives(2)[1] == dw  # evaluating after Terminate is allowed
    it.fmu.freeInstance()


# --- 2. bad parameter values: mbcomp's rules, in C ----------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_a_bad_parameter_value_is_refused_naming_the_variable_and_mbcomps_rule(fmi, built, capfd):
    """A negative mass is refused when set (not "DOP853: rhs returned 1" later); NaN is refused
    as not finite (not "export the model again"); a zero hinge axis breaks Revolute.n's rule
    (all three entries together, at ExitInitializationMode); mbcomp itself says the same."""
    it = Instance(built("pendulum", fmi), fmi, "cs")
    refused(capfd, lambda: it.set("bob.m", -2.0), "bob.m = -2 kg: must be >= 0 (the mbcomp rule of PointMass.m)")
    with pytest.raises(mbcomp.ModelError, match="must be >= 0"):
        mbcomp.assemble(pendulum(), {"bob.m": -2.0})
    refused(capfd, lambda: it.set("rod.r[2]", float("nan")), "rod.r[2] = nan: must be finite")
    it.set("j.n[3]", 0.0)  # one entry of the axis: the rule is the vector's
    it.init()
    refused(capfd, it.fmu.exitInitializationMode, "j.n: must not be zero (the mbcomp rule of Revolute.n)")
    it.fmu.freeInstance()
    # a good value is taken: a point mass's motion does not depend on it (to rounding)
    r = fmpy.simulate_fmu(str(built("pendulum", fmi)), fmi_type="CoSimulation", stop_time=1.0,
                          start_values={"bob.m": 5.0}, output=["j.phi"])
    ref = fmpy.simulate_fmu(str(built("pendulum", fmi)), fmi_type="CoSimulation", stop_time=1.0, output=["j.phi"])
    assert float(np.max(np.abs(r["j.phi"] - ref["j.phi"]))) < 1e-12 and r["j.phi"].min() < -0.49


@pytest.mark.parametrize("fmi", VERSIONS)
def test_an_inertia_tensor_breaking_mbcomps_rule_is_refused(fmi, built, capfd):
    """The inertia tensor's rule (mbcomp.inertia.inertia_problem) checked in C over the tensor's
    entries, the baked zeros included: principal moments 0.1, 0.2, 0.4 break the triangle
    inequality; a negative moment is refused; mbcomp refuses the same tensors."""
    path = built("body", fmi)
    for entry, value, text in (("body.I[3,3]", 0.4, "violate the triangle inequality"),
                               ("body.I[1,1]", -0.1, "negative principal moment -0.1 kg m^2")):
        it = Instance(path, fmi, "cs")
        it.set(entry, value)
        it.init()
        refused(capfd, it.fmu.exitInitializationMode, "body.I in kg m^2: ", text, "(the mbcomp rule of RigidBody.I)")
        it.fmu.freeInstance()
        I = np.diag([0.1, 0.2, 0.25])
        I[(0, 0) if entry == "body.I[1,1]" else (2, 2)] = value
        with pytest.raises(mbcomp.ModelError, match=text.split(" -0.1")[0]):
            mbcomp.assemble(body_pendulum(), {"body.I": I})
    # a tensor that keeps the rule (0.1, 0.2, 0.3) runs, and as mbcomp does
    r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=1.0, start_values={"body.I[3,3]": 0.3},
                          output=["j.phi"], relative_tolerance=1e-10)
    ref = mbcomp.simulate(body_pendulum(), t_end=1.0, n_out=11, rtol=1e-11, atol=1e-13,
                          params={"body.I": np.diag([0.1, 0.2, 0.3])})
    assert abs(np.interp(1.0, r["time"], r["j.phi"]) - ref["j.phi"][-1]) < 1e-8


@pytest.mark.parametrize("fmi", VERSIONS)
def test_a_broken_baked_decision_names_the_changed_variables(fmi, built, capfd):
    """The hinge axis reversed keeps Revolute.n's rule but breaks a decision baked into the
    program: the guard's message stays, and names what changed from the export."""
    it = Instance(built("pendulum", fmi), fmi, "cs")
    it.set("j.n[3]", -1.0)
    it.init()
    refused(capfd, it.fmu.exitInitializationMode, "export the model again with these values",
            "j.n[3] = -1 (exported: 1)")
    it.fmu.freeInstance()


# --- 3. messages name variables -----------------------------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_messages_name_the_variables(fmi, built, capfd):
    it = Instance(built("pendulum", fmi), fmi, "cs")
    refused(capfd, lambda: it.set("der(j.phi)", 1.0), "der(j.phi) cannot be set")
    it.init()
    it.fmu.exitInitializationMode()
    said = refused(capfd, lambda: it.set("bob.m", 3.0), "bob.m is a parameter fixed after initialization")
    said += refused(capfd, lambda: it.set("start.j.phi", 1.0), "start.j.phi is a parameter fixed after initialization")
    said += refused(capfd, lambda: it.set("j.phi", 1.0), "the state j.phi can be set only before")
    assert "value reference" not in said and "parameter 0" not in said
    it.fmu.terminate()
    it.fmu.freeInstance()


# --- 4. one default tolerance -------------------------------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_co_simulation_without_a_tolerance_runs_at_the_advertised_one(fmi, built):
    """The model description's DefaultExperiment tolerance is the FMU's own default: a
    Co-Simulation run given no tolerance is the run given that one, bit for bit (and not the
    run at 1e-8, the FMU's old default)."""
    path = built("pendulum", fmi)
    md = read_model_description(str(path))
    advertised = md.defaultExperiment.tolerance
    assert float(advertised) == 1e-12
    start = {v.name: v.start for v in md.modelVariables}["solver.tolerance"]
    assert float(start) == 1e-12

    def run(tolerance):
        it = Instance(path, fmi, "cs")
        it.init(tolerance)
        it.fmu.exitInitializationMode()
        out = []
        for k in range(20):
            it.step(0.1 * k, 0.1)
            out.append(it.get("j.phi", "j.w"))
        it.fmu.terminate()
        it.fmu.freeInstance()
        return np.array(out)

    none, same, loose = run(None), run(float(advertised)), run(1e-8)
    assert np.array_equal(none, same)
    assert not np.array_equal(none, loose)


# --- 5. joint coordinates and speeds are outputs ------------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_joint_coordinates_and_speeds_are_outputs(fmi, built, tmp_path):
    """A tool that wires only outputs sees the joints' coordinates and speeds: the states are
    outputs too (open tree: [q, u]; with a loop the coordinates, the speeds being computed
    outputs), FMPy records them by default (it records the outputs) and they move as mbcomp's."""
    from conftest import load_model

    path = built("pendulum", fmi)
    md = read_model_description(str(path))
    causality = {v.name: v.causality for v in md.modelVariables}
    assert causality["j.phi"] == causality["j.w"] == "output"
    assert {"j.phi", "j.w"} <= {o.variable.name for o in md.outputs}
    assert validate_fmu(str(path)) == []
    ref = mbcomp.simulate(pendulum(), t_end=2.0, n_out=101, rtol=1e-11, atol=1e-13)
    for fmi_type in ("CoSimulation", "ModelExchange"):
        r = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=2.0, output_interval=0.02,
                              relative_tolerance=1e-10)  # no output list: FMPy records the outputs
        for var in ("j.phi", "j.w"):
            assert float(np.max(np.abs(np.interp(ref.time, r["time"], r[var]) - ref[var]))) < 1e-6, (fmi_type, var)
    crank = tmp_path / "crank.fmu"
    info = export_fmu(load_model("models/slider_crank.py").build(), crank, fmi=fmi, derivatives=False)
    assert info["state_outputs"] == ["crank_joint.phi", "slider_joint.s", "pin.phi"]  # not v[1]
    assert validate_fmu(str(crank)) == []
    r = fmpy.simulate_fmu(str(crank), fmi_type="ModelExchange", stop_time=1.0, output_interval=0.01,
                          relative_tolerance=1e-10)
    assert {"crank_joint.phi", "crank_joint.w", "slider_joint.s"} <= set(r.dtype.names) and "v[1]" not in r.dtype.names
    ref = mbcomp.simulate(load_model("models/slider_crank.py").build(), t_end=1.0, n_out=101, rtol=1e-11, atol=1e-13)
    for var in ("crank_joint.phi", "crank_joint.w"):
        assert float(np.max(np.abs(np.interp(ref.time, r["time"], r[var]) - ref[var]))) < 1e-4, var


# --- 6. named units, descriptions, nominal and min ----------------------------------------------

@pytest.mark.parametrize("fmi", VERSIONS)
def test_named_units_descriptions_nominals_and_bounds(fmi, built):
    """The model description declares N, N.m, J, rad/s2, ... with their base units and uses
    them; states and outputs are described; the states carry their nominals, a mass min 0."""
    path = built("body", fmi)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    var = {v.name: v for v in md.modelVariables}
    assert var["j.f.x"].unit == "N" and var["j.tau.z"].unit == "N.m" and var["energy.total"].unit == "J"
    assert var["j.w.der"].unit == "rad/s2" and var["body.I[3,3]"].unit == "kg.m2" and var["j.w"].unit == "rad/s"
    base = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert (base["N"].kg, base["N"].m, base["N"].s) == (1, 1, -2)
    assert (base["J"].kg, base["J"].m, base["J"].s) == (base["N.m"].kg, base["N.m"].m, base["N.m"].s) == (1, 2, -2)
    assert not [v.name for v in md.modelVariables if v.unit and "/s2" in v.unit and v.unit.startswith("kg")]
    assert var["j.phi"].description == "coordinate of joint j (a state)"
    assert var["j.f.x"].description.startswith("reaction force of the joint, x component")
    assert all(v.description for v in md.modelVariables if v.causality == "output")
    assert float(var["body.m"].min) == 0.0 and var["j.phi"].nominal is not None
    assert float(var["j.phi"].nominal) == 1.0  # an angle: 1 rad


# --- 7. every parameter entry tunable, or listed with the reason ---------------------------------

def test_every_parameter_entry_tunable_or_listed_with_the_reason(built, tmp_path, capfd):
    """By default the zeros are folded into the program and the export lists them with the
    reason; ``tunable="all"`` makes every entry a parameter: a centre of mass moved off the
    rod's line (a zero at export) moves the body as mbcomp does, and the inertia tensor's
    off-diagonal terms are parameters under its rule (one set alone: not symmetric)."""
    info = export_fmu(body_pendulum(), tmp_path / "b.fmu")
    assert "body.r_cm[2]" not in info["parameters"] and "body.I[1,2]" in info["fixed"]
    assert "folded into the program" in info["fixed"]["body.r_cm[2]"]
    path = tmp_path / "all.fmu"
    info = export_fmu(body_pendulum(), path, tunable="all")
    assert not info["fixed"] and {"body.r_cm[2]", "body.I[1,2]", "body.I[2,1]"} <= set(info["parameters"])
    assert validate_fmu(str(path)) == []
    r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=1.0, relative_tolerance=1e-10,
                          start_values={"body.r_cm[2]": 0.2, "body.I[1,2]": 0.01, "body.I[2,1]": 0.01},
                          output=["j.phi"])
    I = np.diag([0.1, 0.2, 0.25])
    I[0, 1] = I[1, 0] = 0.01
    ref = mbcomp.simulate(body_pendulum(), t_end=1.0, n_out=11, rtol=1e-11, atol=1e-13,
                          params={"body.r_cm": (0.5, 0.2, 0.0), "body.I": I})
    plain = mbcomp.simulate(body_pendulum(), t_end=1.0, n_out=11, rtol=1e-11, atol=1e-13)
    assert abs(np.interp(1.0, r["time"], r["j.phi"]) - ref["j.phi"][-1]) < 1e-8
    assert abs(ref["j.phi"][-1] - plain["j.phi"][-1]) > 1e-3  # the moved centre of mass matters (4e-3 rad)
    it = Instance(path, "3.0", "cs")
    it.set("body.I[1,2]", 0.01)
    it.init()
    refused(capfd, it.fmu.exitInitializationMode, "body.I in kg m^2: inertia tensor is not symmetric")
    it.fmu.freeInstance()
    with pytest.raises(ValueError, match="tunable='x'"):
        export_fmu(body_pendulum(), tmp_path / "x.fmu", tunable="x")


def test_a_rotation_matrix_breaking_mbcomps_rule_is_refused(tmp_path, capfd):
    """A FixedRotation's R (30 deg about z): a reflection (R[3,3] = -1) or a stretched entry is
    refused in C as mbcomp's rotation_matrix check refuses it; the rotation itself runs."""
    from mbcomp.library import FixedRotation, PointMass

    def model():
        m = mbcomp.Model()
        w = m.add("world", World())
        j = m.add("j", Revolute(phi0=0.5))
        c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
        rot = m.add("rot", FixedRotation(r=(0, -1.0, 0), R=[[c, -s, 0], [s, c, 0], [0, 0, 1]]))
        bob = m.add("bob", PointMass(m=1.0))
        m.connect(w.frame_b, j.frame_a)
        m.connect(j.frame_b, rot.frame_a)
        m.connect(rot.frame_b, bob.frame_a)
        return m

    path = tmp_path / "rot.fmu"
    info = export_fmu(model(), path)
    assert "rot.R[3,3]" in info["parameters"]
    for entry, value, text in (("rot.R[3,3]", -1.0, "a reflection"), ("rot.R[1,1]", 2.0, "not a rotation matrix")):
        it = Instance(path, "3.0", "cs")
        it.set(entry, value)
        it.init()
        refused(capfd, it.fmu.exitInitializationMode, "rot.R: ", text, "(the mbcomp rule of FixedRotation.R)")
        it.fmu.freeInstance()
    bad = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(mbcomp.ModelError, match="rot.R"):
        mbcomp.assemble(model(), {"rot.R": bad})
    r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=1.0, output=["j.phi"], relative_tolerance=1e-10)
    ref = mbcomp.simulate(model(), t_end=1.0, n_out=11, rtol=1e-11, atol=1e-13)
    assert abs(np.interp(1.0, r["time"], r["j.phi"]) - ref["j.phi"][-1]) < 1e-8
