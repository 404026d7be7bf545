"""The FMU's exact derivatives (issue 33, item 3): ``fmi3GetDirectionalDerivative``,
``fmi3GetAdjointDerivative`` and ``fmi2GetDirectionalDerivative`` from the generated tangent
and adjoint programs, and the ``<ModelStructure>`` dependencies.

Checked through FMPy against the FMU's own values: every column of the directional
derivative (unit seeds) against central differences of the FMU's derivatives and outputs
(Richardson-extrapolated; 1e-7 relative to the row's largest entry, or to 1e-3 of the
Jacobian's largest for rows that are rounding noise; measured <= 9e-9, globally <= 2e-10);
the adjoint identity ``<w, J v> = <J^T w, v>``
(1e-12 of ``|w|^T |J| |v|``) and every row of the adjoint against the forward Jacobian; a pair
the model description declares independent has derivative 0.0 exactly; closed forms for the
pendulum (``dw'/dphi = -g cos(phi) / L``, ``dw'/dtau = 1/(m L^2)``). Models: the pendulum
with a torque input (open tree: states ``[q, u]``), the slider-crank (a loop: D'Alembert's
states ``[q, v]`` in Model Exchange, whose derivatives go through the dependent speeds; the
joint speeds ``[q, u]`` in Co-Simulation) and Andrews' mechanism.
"""
import pathlib
import subprocess
import zipfile
from xml.etree import ElementTree

import ctypes

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World

from conftest import load_model

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
import sanitized  # noqa: E402
from fmpy.fmi2 import FMU2Model  # noqa: E402
from fmpy.fmi3 import FMU3Model, FMU3Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

G, L, MASS = 9.81, 1.0, 2.0


def pendulum_with_input(tau=None):
    """A 2 kg bob on a 1 m rod about a hinge (gravity 9.81 m/s^2 along -y), driven by the input
    torque ``tau`` (or the law ``tau``): ``m L^2 w' = tau - m g L sin(phi)``."""
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -L, 0)))
    bob = m.add("bob", PointMass(m=MASS))
    motor = m.add("motor", Torque(tau=mbcomp.Input("tau", unit="N m", start=0.3) if tau is None else tau))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    return m


MODELS = {"pendulum": pendulum_with_input, "slider_crank": lambda: load_model("models/slider_crank.py").build(),
          "andrews": lambda: load_model("models/andrews.py").build()}


@pytest.fixture(scope="module")
def fmu_file(tmp_path_factory):
    root, built = tmp_path_factory.mktemp("fmu_derivatives"), {}

    def get(name, fmi):
        if (name, fmi) not in built:
            path = root / f"{name}{fmi[0]}.fmu"
            export_fmu(MODELS[name](), path, fmi=fmi)
            built[name, fmi] = path
        return built[name, fmi]

    return get


class Opened:
    """An FMU instantiated by FMPy and initialized; ``unknowns`` (the state derivatives and the
    outputs that have derivatives) and ``knowns`` (the states, then the inputs) as value
    references; ``log``: the messages it logged."""

    def __init__(self, path, fmi, cs=False):
        self.md = md = read_model_description(path)
        self.log = []
        iface = md.coSimulation if cs else md.modelExchange
        args = dict(guid=md.guid, unzipDirectory=extract(path), modelIdentifier=iface.modelIdentifier,
                    instanceName="d")
        if fmi == "3.0":
            self.fmu = (FMU3Slave if cs else FMU3Model)(**args)
            self._cb = lambda env, status, cat, msg: self.log.append(msg.decode())
            self.fmu.instantiate(loggingOn=True, logMessage=self._cb)
            self.fmu.enterInitializationMode()
        else:
            from fmpy.fmi2 import FMU2Slave

            self.fmu = (FMU2Slave if cs else FMU2Model)(**args)
            self.fmu.instantiate(loggingOn=True)  # FMPy's logger (printed: 2.0's messages are variadic)
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        if not cs:  # Model Exchange: on to Continuous-Time Mode, where the states are set
            if fmi == "2.0":
                self.fmu.newDiscreteStates()
            self.fmu.enterContinuousTimeMode()
        self.fmi = fmi
        byname = md.modelVariables
        names = {v.name for v in byname}
        # the continuous states (some are outputs too: the joint coordinates and speeds)
        self.states = [v.valueReference for v in byname if f"der({v.name})" in names]
        self.ders = [v.valueReference for v in byname if v.name.startswith("der(")]
        self.outputs = [v.valueReference for v in byname if v.causality == "output"
                        and not v.name.startswith("residual.") and f"der({v.name})" not in names]
        self.inputs = [v.valueReference for v in byname if v.causality == "input"]
        self.unknowns, self.knowns = self.ders + self.outputs, self.states + self.inputs
        self.vr = {v.name: v.valueReference for v in byname}

    def get(self, vrs):
        return np.array(self.fmu.getFloat64(vrs) if self.fmi == "3.0" else self.fmu.getReal(vrs))

    def set(self, vrs, values):
        """Knowns set as an importer does in Continuous-Time Mode: the states by
        SetContinuousStates (the FMI state machine refuses SetFloat64/SetReal on a state after
        initialization), the inputs by SetFloat64/SetReal."""
        values = [float(v) for v in values]
        at = {vr: k for k, vr in enumerate(self.states)}
        if any(vr in at for vr in vrs):
            n = len(self.states)
            buf = (ctypes.c_double * n)()
            self.fmu.getContinuousStates(buf, n)
            for vr, v in zip(vrs, values):
                if vr in at:
                    buf[at[vr]] = v
            self.fmu.setContinuousStates(buf, n)
        rest = [(vr, v) for vr, v in zip(vrs, values) if vr not in at]
        if rest:
            r_vrs, r_vals = [vr for vr, _ in rest], [v for _, v in rest]
            self.fmu.setFloat64(r_vrs, r_vals) if self.fmi == "3.0" else self.fmu.setReal(r_vrs, r_vals)

    def forward(self, seed, unknowns=None, knowns=None):
        unknowns, knowns = unknowns or self.unknowns, knowns or self.knowns
        return np.array(self.fmu.getDirectionalDerivative(unknowns, knowns, list(map(float, seed))))

    def adjoint(self, seed):
        return np.array(self.fmu.getAdjointDerivative(self.unknowns, self.knowns, list(map(float, seed)),
                                                      nSensitivity=len(self.knowns)))

    def jacobian(self):
        n = len(self.knowns)
        return np.column_stack([self.forward(np.eye(n)[k]) for k in range(n)])

    def central(self):
        """The Jacobian by central differences of the FMU's own values, Richardson-extrapolated
        (steps h = 1e-5 and h/2 of the value's magnitude, at least 1e-5: error O(h^4), so the
        differences of Andrews' stiff forces are not truncation-bound); the knowns are restored."""
        x0 = self.get(self.knowns)
        cols = []
        for k in range(len(x0)):
            diffs = []
            for h in (1e-5 * max(1.0, abs(x0[k])), 0.5e-5 * max(1.0, abs(x0[k]))):
                vals = []
                for s in (h, -h):
                    x = x0.copy()
                    x[k] += s
                    self.set(self.knowns, x)
                    vals.append(self.get(self.unknowns))
                diffs.append((vals[0] - vals[1]) / (2 * h))
            cols.append((4.0 * diffs[1] - diffs[0]) / 3.0)
        self.set(self.knowns, x0)
        return np.column_stack(cols)


def row_relative(J, ref, floor=1e-3):
    """The largest ``|J - ref|`` of each row relative to the row's largest ``|ref|`` entry, or to
    ``floor`` times the whole Jacobian's largest where that is more: a row whose derivatives are
    the rounding of larger terms (a reaction's zero component: 1e-15 from terms of 10) is
    compared on the Jacobian's scale, where the differences' rounding (1e-16 |value| / h) is."""
    big = np.abs(ref).max()
    scale = np.maximum(np.abs(ref).max(axis=1), max(floor * big, 1e-300))
    return (np.abs(J - ref).max(axis=1) / scale).max()


CASES = [("pendulum", "3.0"), ("pendulum", "2.0"), ("slider_crank", "3.0"), ("slider_crank", "2.0"),
         ("andrews", "3.0")]


@pytest.mark.parametrize("name,fmi", CASES)
def test_directional_derivatives_match_central_differences(fmu_file, name, fmi):
    f = Opened(fmu_file(name, fmi), fmi)
    for point in range(2):
        if point:  # a second point away from the start: the coordinates moved, the speeds set
            x = f.get(f.states)
            f.set(f.states, x + 0.05 * np.cos(np.arange(len(x)) + 1.0))
        J, Jc = f.jacobian(), f.central()
        assert np.all(np.isfinite(J))
        assert row_relative(J, Jc) < 1e-7, (name, fmi, point, row_relative(J, Jc))


@pytest.mark.parametrize("name", ["pendulum", "slider_crank", "andrews"])
def test_adjoint_identity_and_rows(fmu_file, name):
    f = Opened(fmu_file(name, "3.0"), "3.0")
    J = f.jacobian()
    rng = np.random.default_rng(7)
    for _ in range(5):
        v, w = rng.standard_normal(len(f.knowns)), rng.standard_normal(len(f.unknowns))
        lhs, rhs = w @ f.forward(v), f.adjoint(w) @ v
        assert abs(lhs - rhs) <= 1e-12 * (np.abs(w) @ np.abs(J) @ np.abs(v)), (lhs, rhs)
    JT = np.array([f.adjoint(np.eye(len(f.unknowns))[i]) for i in range(len(f.unknowns))])
    assert row_relative(JT, J) < 1e-12


@pytest.mark.parametrize("name,fmi", CASES)
def test_declared_independent_pairs_have_zero_derivative(fmu_file, name, fmi):
    f = Opened(fmu_file(name, fmi), fmi)
    J = f.jacobian()
    md = f.md
    declared = {u.variable.valueReference: u.dependencies for u in md.derivatives + md.outputs}
    zeros = 0
    for i, vr in enumerate(f.unknowns):
        deps = declared[vr]
        assert deps is not None, f"unknown {vr} declares no dependencies"
        dep_vrs = {d.valueReference for d in deps}
        assert dep_vrs <= set(f.knowns)
        for k, known in enumerate(f.knowns):
            if known not in dep_vrs:
                assert J[i, k] == 0.0, (vr, known, J[i, k])
                zeros += 1
    assert zeros > 0  # the structure is not "everything"
    with zipfile.ZipFile(fmu_file(name, fmi)) as z:
        root = ElementTree.fromstring(z.read("modelDescription.xml"))
    wanted = (["providesDirectionalDerivatives", "providesAdjointDerivatives"] if fmi == "3.0"
              else ["providesDirectionalDerivative"])
    for tag in ("ModelExchange", "CoSimulation"):
        assert all(root.find(tag).get(a) == "true" for a in wanted), (tag, root.find(tag).attrib)
    assert validate_fmu(str(fmu_file(name, fmi))) == []


def test_pendulum_closed_form_and_structure(fmu_file):
    """``w' = (tau - m g L sin(phi)) / (m L^2)``: ``dw'/dphi = -g cos(phi) / L``, ``dw'/dtau =
    1 / (m L^2)``, ``phi' = w``; ``der(j.phi)`` depends on ``j.w`` alone, ``der(j.w)`` on ``j.phi``
    and ``tau`` (and on ``j.w`` in the program: the centripetal terms, whose torque about the
    hinge is zero, are there; at w = 0 their derivative is 0)."""
    f = Opened(fmu_file("pendulum", "3.0"), "3.0")
    vr = f.vr
    phi = f.get([vr["j.phi"]])[0]
    J = f.forward([1.0], unknowns=[vr["der(j.phi)"], vr["der(j.w)"]], knowns=[vr["j.phi"]])
    assert J[0] == 0.0 and abs(J[1] + G * np.cos(phi) / L) < 1e-12
    J = f.forward([1.0], unknowns=[vr["der(j.phi)"], vr["der(j.w)"]], knowns=[vr["tau"]])
    assert J[0] == 0.0 and abs(J[1] - 1.0 / (MASS * L * L)) < 1e-14
    assert f.forward([1.0], unknowns=[vr["der(j.phi)"]], knowns=[vr["j.w"]])[0] == 1.0
    deps = {u.variable.name: sorted(d.name for d in u.dependencies) for u in f.md.derivatives}
    assert deps == {"der(j.phi)": ["j.w"], "der(j.w)": ["j.phi", "j.w", "tau"]}
    assert f.forward([1.0], unknowns=[vr["der(j.w)"]], knowns=[vr["j.w"]])[0] == 0.0


@pytest.mark.parametrize("name", ["pendulum", "slider_crank"])
def test_co_simulation_derivatives_after_a_step(fmu_file, name):
    """Co-Simulation integrates ``[q, u]`` (the slider-crank's v is a joint speed there): the
    derivatives of its outputs and state derivatives at the point after a step."""
    f = Opened(fmu_file(name, "3.0"), "3.0", cs=True)
    f.fmu.doStep(0.0, 0.3)
    J = f.jacobian()
    if name == "pendulum":
        # Step Mode lets no state be set (the FMI state machine), so no differences here: the
        # Model Exchange instance of the same FMU at the same state and time (the same
        # equations, its derivatives checked against differences above) gives the same Jacobian
        m = Opened(fmu_file(name, "3.0"), "3.0")
        m.fmu.setTime(0.3)
        m.set(m.states, f.get(f.states))
        assert m.unknowns == f.unknowns and m.knowns == f.knowns
        assert row_relative(J, m.jacobian()) < 1e-12
    rng = np.random.default_rng(3)
    v, w = rng.standard_normal(len(f.knowns)), rng.standard_normal(len(f.unknowns))
    assert abs(w @ f.forward(v) - f.adjoint(w) @ v) <= 1e-12 * (np.abs(w) @ np.abs(J) @ np.abs(v))


def test_slider_crank_positions_depend_on_coordinates_only(fmu_file):
    """A body's position is a function of the coordinates: declared so (the coordinates its
    position depends on, none for the crank's centre on its axis); velocities depend on v."""
    f = Opened(fmu_file("slider_crank", "3.0"), "3.0")
    deps = {u.variable.name: {d.name for d in u.dependencies} for u in f.md.outputs}
    speeds = {f.md.modelVariables[i].name for i in range(len(f.md.modelVariables))
              if f.md.modelVariables[i].name.startswith("v[")}
    positions = [n for n in deps if ".r_0" in n or n.endswith(".r.x")]
    assert all(not deps[n] & speeds for n in positions) and any(deps[n] for n in positions), positions
    velocities = [n for n in deps if ".v_0" in n or n.endswith(".v.x")]
    assert any(deps[n] & speeds for n in velocities), velocities  # (the crank's centre is on its axis: v = 0)


@pytest.mark.parametrize("fmi", ["3.0", "2.0"])
def test_bad_calls_are_errors_naming_the_reference(fmu_file, fmi):
    f = Opened(fmu_file("slider_crank", fmi), fmi)
    residual = f.vr["residual.velocity"]
    calls = [([f.ders[0]], [0], "value reference 0 is not a known"),  # a parameter as a known
             ([f.ders[0]], [f.ders[0]], f"value reference {f.ders[0]} is not a known"),  # a derivative as a known
             ([residual], [f.states[0]], f"output {residual} (a residual's norm")]
    for unknowns, knowns, message in calls:
        with pytest.raises(FMICallException):
            f.forward([1.0], unknowns=unknowns, knowns=knowns)
        assert fmi == "2.0" or any(message in m for m in f.log), (message, f.log)
    assert f.forward([2.0], unknowns=[f.ders[0]], knowns=[f.states[-1]]).shape == (1,)  # the instance goes on
    # a state that is an output too (the crank's angle) is an unknown: its derivative is the identity
    assert f.forward([2.0, 3.0], unknowns=[f.states[0]], knowns=[f.states[0], f.states[1]]).tolist() == [2.0]
    w = [5.0]
    assert np.array(f.fmu.getAdjointDerivative([f.states[0]], f.states[:2], w, nSensitivity=2)
                    if fmi == "3.0" else [5.0, 0.0]).tolist() == [5.0, 0.0]
    if fmi == "3.0":  # FMPy's default sensitivity size is the unknowns', not the knowns'
        with pytest.raises(FMICallException):
            f.fmu.getAdjointDerivative(f.ders[:1], f.knowns, [1.0])
        assert any("seed and" in m and "sensitivity values" in m for m in f.log), f.log


def test_export_without_derivatives(tmp_path):
    """``derivatives=False``: no capability or dependencies declared, and the derivative functions
    are errors (the FMU is otherwise the same and still valid)."""
    path = tmp_path / "plain.fmu"
    assert export_fmu(pendulum_with_input(), path, derivatives=False)["derivatives"] is False
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as z:
        text = z.read("modelDescription.xml").decode()
    assert "providesDirectionalDerivatives" not in text and "dependencies=" not in text
    f = Opened(path, "3.0")
    with pytest.raises(FMICallException):
        f.forward([1.0], unknowns=f.ders[:1], knowns=f.states[:1])
    assert any("export it with derivatives=True" in m for m in f.log), f.log


def test_time_dependent_unknowns_declare_all_knowns(tmp_path):
    """A law of the time (the motor's ``tau(t, phi, w)``): the time is a known FMI 2.0 has no
    variable for, so ``der(j.w)`` and the outputs that depend on the time declare no
    ``dependencies`` ("all knowns"); ``der(j.phi) = w`` keeps its one; the derivatives still
    match the differences, ``dw'/dw = -0.4 phi / (m L^2)`` included."""
    m = pendulum_with_input(lambda t, phi, w: 0.3 * np.sin(2.0 * t) - 0.4 * w * phi)
    for fmi in ("3.0", "2.0"):
        path = tmp_path / f"timed{fmi[0]}.fmu"
        export_fmu(m, path, fmi=fmi)
        assert validate_fmu(str(path)) == []
        f = Opened(path, fmi)
        deps = {u.variable.name: u.dependencies for u in f.md.derivatives}
        assert deps["der(j.w)"] is None and [d.name for d in deps["der(j.phi)"]] == ["j.w"]
        J, Jc = f.jacobian(), f.central()
        assert row_relative(J, Jc) < 1e-7
        phi = f.get([f.vr["j.phi"]])[0]
        dw = f.forward([1.0], unknowns=[f.vr["der(j.w)"]], knowns=[f.vr["j.w"]])[0]
        assert abs(dw + 0.4 * phi / (MASS * L * L)) < 1e-12, dw


SAN_FLAGS = sanitized.SAN_FLAGS


def test_derivatives_under_asan_ubsan(fmu_file, tmp_path):
    """The slider-crank's FMU sources (D'Alembert's states: the chain rule, the transposed
    solve) with a C harness calling every derivative, ME and CS, and bad calls, under
    AddressSanitizer (leaks too) + UndefinedBehaviorSanitizer; the adjoint identity to 1e-12."""
    cc = c_compiler()
    if not sanitized.usable(tmp_path):
        pytest.skip("AddressSanitizer/UBSan not usable here")
    with zipfile.ZipFile(fmu_file("slider_crank", "3.0")) as z:
        z.extractall(tmp_path / "fmu")
    src = tmp_path / "fmu" / "sources"
    ident = next((tmp_path / "fmu" / "binaries" / "x86_64-linux").glob("*.so")).stem
    harness = pathlib.Path(__file__).with_name("fmu_derivatives_harness.c")
    cmd = [cc, *SAN_FLAGS, f'-DMODEL_C="{ident}.c"', f"-I{src}", str(harness),
           *sanitized.runtime_objects(src), "-o", str(tmp_path / "h"), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-3000:]
    run = subprocess.run([str(tmp_path / "h")], capture_output=True, text=True, timeout=300,
                         env={"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
    assert run.returncode == 0, run.stdout + run.stderr[-3000:]
    assert run.stdout.count("bad calls refused: 5 of 5") == 2 and "runtime error" not in run.stderr, run.stdout


def test_quaternion_at_its_sign_flip_is_refused(tmp_path):
    """The spatial slider-crank starts with the rod turned half a turn: ``rod.Q.w`` is 6e-17, where
    the output quaternion (scalar part >= 0) changes sign, so ``rod.Q.*`` have no derivative (an
    error naming the output; central differences straddle a jump there); every other unknown
    still matches the differences."""
    path = tmp_path / "spatial.fmu"
    export_fmu(load_model("models/spatial_slider_crank.py").build(), path)
    f = Opened(path, "3.0")
    assert abs(f.get([f.vr["rod.Q.w"]])[0]) < 1e-12
    with pytest.raises(FMICallException):
        f.forward([1.0], unknowns=[f.vr["rod.Q.x"]], knowns=f.states[:1])
    assert any(f"output {f.vr['rod.Q.x']} is an orientation quaternion" in m for m in f.log), f.log
    f.unknowns = [u for u in f.unknowns if u not in {f.vr[f"rod.Q.{c}"] for c in "wxyz"}]
    assert row_relative(f.jacobian(), f.central()) < 1e-7
