"""FMU export, first stage (issue 17): FMI 3.0 and 2.0, Model Exchange and Co-Simulation of
the Lagrange index-1 ODE.

Each exported FMU is validated by FMPy (``validate_fmu(path) == []``) and run by FMPy as
Model Exchange (FMPy's CVODE over the FMU's derivatives) and as Co-Simulation (the FMU's own
DOP853); its motion must be mbcomp's own (a tight DOP853 run of the same equations). Also: a tuned parameter changes the motion as in mbcomp, a wrong guid is
refused, a parameter value that breaks a decision baked into the program is refused, and the
binary exports every function of the FMI header of its version.
"""
import copy
import functools
import shutil
import subprocess

import numpy as np
import pytest

import mbcomp
from mbcomp.codegen import c_compiler
from mbcomp.library import FixedTranslation, PointMass, Revolute, World

from conftest import load_model, turntable
from pendulum_model import pendulum

import fmusim_tool

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy.validation import validate_fmu  # noqa: E402

from mbcomp.export import export_fmu  # noqa: E402

#: the functions of the FMI 2.0 header (fmi2Functions.h): common, Model Exchange, Co-Simulation
FMI2_FUNCTIONS = """GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean GetString SetReal
SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate SerializedFMUstateSize SerializeFMUstate
DeSerializeFMUstate GetDirectionalDerivative EnterEventMode NewDiscreteStates EnterContinuousTimeMode
CompletedIntegratorStep SetTime SetContinuousStates GetDerivatives GetEventIndicators GetContinuousStates
GetNominalsOfContinuousStates SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep GetStatus
GetRealStatus GetIntegerStatus GetBooleanStatus GetStringStatus""".split()
#: the functions of the FMI 3.0 header (fmi3Functions.h)
FMI3_FUNCTIONS = """GetVersion SetDebugLogging InstantiateModelExchange InstantiateCoSimulation
InstantiateScheduledExecution FreeInstance EnterInitializationMode ExitInitializationMode EnterEventMode Terminate
Reset GetFloat32 GetFloat64 GetInt8 GetUInt8 GetInt16 GetUInt16 GetInt32 GetUInt32 GetInt64 GetUInt64 GetBoolean
GetString GetBinary GetClock SetFloat32 SetFloat64 SetInt8 SetUInt8 SetInt16 SetUInt16 SetInt32 SetUInt32 SetInt64
SetUInt64 SetBoolean SetString SetBinary SetClock GetNumberOfVariableDependencies GetVariableDependencies
GetFMUState SetFMUState FreeFMUState SerializedFMUStateSize SerializeFMUState DeserializeFMUState
GetDirectionalDerivative GetAdjointDerivative EnterConfigurationMode ExitConfigurationMode GetIntervalDecimal
GetIntervalFraction GetShiftDecimal GetShiftFraction SetIntervalDecimal SetIntervalFraction SetShiftDecimal
SetShiftFraction EvaluateDiscreteStates UpdateDiscreteStates EnterContinuousTimeMode CompletedIntegratorStep SetTime
SetContinuousStates GetContinuousStateDerivatives GetEventIndicators GetContinuousStates
GetNominalsOfContinuousStates GetNumberOfEventIndicators GetNumberOfContinuousStates EnterStepMode
GetOutputDerivatives DoStep ActivateModelPartition""".split()
FUNCTIONS = {"2.0": ["fmi2" + f for f in FMI2_FUNCTIONS], "3.0": ["fmi3" + f for f in FMI3_FUNCTIONS]}
PLATFORM = {"2.0": "linux64", "3.0": "x86_64-linux"}
VERSIONS = ["3.0", "2.0"]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """``fmus(name, fmi, path)``: the FMU of ``pendulum()`` (``name="pendulum"``) or of a model
    file's default build (``"slider_crank"``, ...), FMI ``fmi``, both kinds, exported to a file of
    ``path``'s name and copied to ``path``; returns the export's info. Each is built once per
    module and test process (gcc takes 2-3 s of CPU per FMU) and shared by the tests that run or
    read it; what ``export_fmu`` does with other arguments is tested by calling it."""
    root, built = tmp_path_factory.mktemp("fmus"), {}

    def get(name, fmi, path):
        key = (name, fmi, path.name)
        if key not in built:
            model = pendulum() if name == "pendulum" else load_model(f"models/{name}.py").build()
            src = root / str(len(built)) / path.name
            src.parent.mkdir()
            # the motion, outputs and interfaces tested here do not read the derivative programs,
            # which double a model's C (tests/export/test_fmu_derivatives.py exports with them)
            built[key] = src, export_fmu(model, src, fmi=fmi, derivatives=False)
        src, info = built[key]
        shutil.copyfile(src, path)
        return copy.deepcopy(info)
    return get


@functools.lru_cache(maxsize=None)
def _reference(name, t_end, options):
    model = pendulum() if name == "pendulum" else load_model(f"models/{name}.py").build()
    return mbcomp.simulate(model, t_end=t_end, n_out=101, rtol=1e-11, atol=1e-13, **dict(options))


def reference(name, t_end, **options):
    """mbcomp's own tight run (rtol 1e-11, 101 points) of ``pendulum()`` or a model file's default
    build, which the FMUs must follow: one run per test process serves both FMI versions."""
    return _reference(name, t_end, tuple(sorted(options.items())))


def run_me(path, t_end, outputs, fmi_type="ModelExchange", **kw):
    return fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=t_end, output=outputs,
                             relative_tolerance=1e-10, output_interval=t_end / 100, **kw)


def max_diff(fmu_result, ref, var):
    return float(np.max(np.abs(np.interp(ref.time, fmu_result["time"], fmu_result[var]) - ref[var])))


CASES = [  # model file, simulated time (s), compared variable, agreement as ME, as CS (rad or m)
    ("slider_crank", 10.0, "crank_joint.phi", 1e-5, 1e-7),  # through its dead centres
    ("four_bar", 1.0, "crank_joint.phi", 1e-5, 1e-8),
    ("andrews", 0.03, "hinge_A_AG.phi", 1e-6, 1e-9),
    ("bicycle", 2.0, "free.r.x", 1e-9, 1e-10),  # nonholonomic rolling contacts
    ("chain_3d", 2.0, "joint1.Q.w", 1e-8, 1e-10),  # quaternions
    ("rolling_disk", 2.0, "x.s", 1e-7, 1e-9),  # a nonholonomic rolling contact: rolls 3.6 m
    ("n_link_pendulum", 5.0, "joint3.phi", 1e-7, 1e-9),
]


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name, t_end, var, agree_me, agree_cs", CASES, ids=[c[0] for c in CASES])
def test_the_fmu_is_valid_and_moves_as_mbcomp(name, t_end, var, agree_me, agree_cs, fmi, tmp_path, fmus):
    """ME: FMPy's CVODE at rtol 1e-10 (measured: slider-crank 1.1e-6 rad after 10 s); CS: the
    FMU's DOP853 at the same tolerance (7e-9). The same in fmusim (measured: slider-crank ME
    9.2e-6 rad, CS 2.7e-8; four-bar ME 5.6e-7)."""
    path = tmp_path / f"{name}.fmu"
    info = fmus(name, fmi, path)
    assert validate_fmu(str(path)) == []
    assert var in info["states"] and info["size"] == path.stat().st_size
    ref = reference(name, t_end)
    assert max_diff(run_me(path, t_end, [var]), ref, var) < agree_me
    assert max_diff(run_me(path, t_end, [var], fmi_type="CoSimulation"), ref, var) < agree_cs
    # the second importer, independent of FMPy: the Reference-FMUs' fmusim (its CVODE at the same
    # tolerance; CS the FMU's own DOP853), held to the same agreement
    exe, why = fmusim_tool.fmusim()
    if exe is None:
        pytest.skip(why)
    assert max_diff(fmusim_tool.run(path, "me", t_end, [var]), ref, var) < agree_me
    assert max_diff(fmusim_tool.run(path, "cs", t_end, [var]), ref, var) < agree_cs


@pytest.mark.parametrize("fmi", VERSIONS)
def test_an_fmu_of_one_kind_has_only_that_interface(fmi, tmp_path):
    from fmpy import read_model_description

    export_fmu(pendulum(), tmp_path / "cs.fmu", kind="cs", fmi=fmi, derivatives=False)
    md = read_model_description(str(tmp_path / "cs.fmu"))
    assert md.coSimulation is not None and md.modelExchange is None
    assert validate_fmu(str(tmp_path / "cs.fmu")) == []


@pytest.mark.parametrize("fmi", VERSIONS)
def test_a_tuned_parameter_changes_the_motion_as_in_mbcomp(fmi, tmp_path, fmus):
    path = tmp_path / "pendulum.fmu"
    fmus("pendulum", fmi, path)
    r = run_me(path, 3.0, ["j.phi"], start_values={"rod.r[2]": -2.0})  # a 2 m rod instead of 1 m
    ref = mbcomp.simulate(pendulum(), t_end=3.0, n_out=101, rtol=1e-11, atol=1e-13, params={"rod.r": (0, -2.0, 0)})
    assert max_diff(r, ref, "j.phi") < 1e-7
    short = reference("pendulum", 3.0)
    assert max_diff(r, short, "j.phi") > 0.1  # it is not the 1 m pendulum


@pytest.mark.parametrize("fmi", VERSIONS)
def test_a_parameter_that_breaks_a_baked_decision_is_refused(fmi, tmp_path, capfd, fmus):
    """The hinge axis (0, 0, 1) was generated with decisions baked in (its zero components, its
    direction); reversing it would need another program: the FMU says so, with the fix, instead
    of computing nonsense."""
    path = tmp_path / "pendulum.fmu"
    fmus("pendulum", fmi, path)
    # FMPy's default logger prints (a logger of one's own is FMPy's "experimental" option:
    # for FMI 2.0 it outlived its test and crashed a later instantiation)
    with pytest.raises(Exception, match="ExitInitializationMode"):
        run_me(path, 1.0, ["j.phi"], start_values={"j.n[3]": -1.0}, debug_logging=True)
    out = capfd.readouterr()
    assert "export the model again with these values" in out.out + out.err


@pytest.mark.parametrize("fmi", VERSIONS)
def test_a_wrong_token_is_refused_and_every_function_is_exported(fmi, tmp_path, fmus):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model
    from fmpy.fmi3 import FMU3Model

    path = tmp_path / "pendulum.fmu"
    info = fmus("pendulum", fmi, path)
    md = read_model_description(str(path))
    assert md.guid == info["guid"] and md.guid != "{00000000-0000-0000-0000-000000000000}"
    # the token is a hash of the model description: another pendulum, another token
    other = export_fmu(pendulum(), tmp_path / "other.fmu", fmi=fmi, params={"bob.m": 3.0}, derivatives=False)
    assert other["guid"] != info["guid"]
    unzipped = extract(str(path))
    ident = md.modelExchange.modelIdentifier
    if fmi == "2.0":
        fmu = FMU2Model(guid="{11111111-2222-3333-4444-555555555555}", unzipDirectory=unzipped, modelIdentifier=ident)
        with pytest.raises(Exception):
            fmu.instantiate()
    else:
        fmu = FMU3Model(guid="{11111111-2222-3333-4444-555555555555}", unzipDirectory=unzipped, modelIdentifier=ident)
        with pytest.raises(Exception):
            fmu.instantiate()
    lib = f"{unzipped}/binaries/{PLATFORM[fmi]}/{ident}.so"
    if shutil.which("nm"):
        out = subprocess.run(["nm", "-D", "--defined-only", lib], capture_output=True, text=True, check=True).stdout
        exported = {line.split()[-1] for line in out.splitlines() if line.strip()}
        assert set(FUNCTIONS[fmi]) <= exported
        assert not [s for s in exported if s.startswith(("mbcomp_", "mbrt_", "mb_"))]  # the rest stays inside
        ldd = subprocess.run(["ldd", lib], capture_output=True, text=True).stdout
        assert "libgcc" not in ldd and "python" not in ldd.lower()


def test_bad_choices_say_what_to_choose(tmp_path):
    with pytest.raises(ValueError, match="'3.0' or '2.0'"):
        export_fmu(pendulum(), tmp_path / "x.fmu", fmi="1.0")
    with pytest.raises(ValueError, match="'me'.*'cs'.*'both'"):
        export_fmu(pendulum(), tmp_path / "x.fmu", kind="all")


def test_the_command_line_exports_and_reports(tmp_path, capsys):
    from mbcomp.cli.main import main

    path, model_file = tmp_path / "crank.fmu", load_model("models/slider_crank.py").__file__
    assert main(["export", model_file, "-o", str(path), "-p", "rod_length=0.7"]) == 0
    out = capsys.readouterr().out
    assert "FMI 3.0 Model Exchange + Co-Simulation" in out and "crank.m" in out
    assert "states (4): crank_joint.phi, slider_joint.s, pin.phi, v[1]" in out  # D'Alembert's states
    # build()'s arguments may change the structure, so the FMU bakes them in: the log names them,
    # as given (-p) or as the file's defaults
    fixed = next(line for line in out.splitlines() if line.startswith("fixed at export"))
    assert "rod_length=0.7" in fixed and "crank_length=0.2" in fixed and "export again with -p" in fixed
    assert validate_fmu(str(path)) == []
    assert main(["export", model_file, "-o", str(tmp_path / "x2.fmu"), "--fmi", "2.0", "--kind", "cs"]) == 0
    assert "FMI 2.0 Co-Simulation" in capsys.readouterr().out


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name, t_end, outputs", [
    ("slider_crank", 2.0, {"rod_joint.f.x": 1e-6, "pin.f.y": 1e-6, "energy.total": 1e-8, "crank.Q.z": 1e-8}),
    ("chain_3d", 1.0, {"energy.total": 1e-9, "link2.Q.x": 1e-9, "link1.r.y": 1e-9}),
], ids=["slider_crank", "chain_3d"])
def test_outputs_are_mbcomps_result_columns(name, t_end, outputs, fmi, tmp_path, fmus):
    """The FMU's outputs come from mbcomp's own output program (reactions from the recursive
    sweep and the multipliers, energies, body positions, orientations as quaternions): as the
    FMU moves, they are mbcomp's result columns, in Model Exchange and Co-Simulation."""
    path = tmp_path / f"{name}.fmu"
    info = fmus(name, fmi, path)
    assert set(outputs) <= set(info["outputs"]) and not set(info["outputs"]) & set(info["states"])
    ref = reference(name, t_end)
    for fmi_type in ("CoSimulation", "ModelExchange"):
        r = run_me(path, t_end, list(outputs), fmi_type=fmi_type)
        for var, agree in outputs.items():
            scale = 1.0 + float(np.max(np.abs(ref[var])))
            # ME: FMPy's CVODE carries the state error (1e-6 rad on the slider-crank) into them
            assert max_diff(r, ref, var) < (agree if fmi_type == "CoSimulation" else 100 * agree) * scale, var


def test_chosen_outputs_only(tmp_path):
    from fmpy import read_model_description

    model = load_model("models/slider_crank.py").build()
    info = export_fmu(model, tmp_path / "c.fmu", outputs=["*.f.*", "energy.total"], derivatives=False)
    assert info["outputs"] and all(n.split(".")[-2] == "f" or n == "energy.total" for n in info["outputs"])
    assert "energy.total" in info["outputs"] and "rod_joint.f.x" in info["outputs"]
    md = read_model_description(str(tmp_path / "c.fmu"))
    assert sorted(v.name for v in md.modelVariables if v.causality == "output") == sorted(info["outputs"])
    assert validate_fmu(str(tmp_path / "c.fmu")) == []
    with pytest.raises(ValueError, match="'nothing.here' matches no result column"):
        export_fmu(model, tmp_path / "d.fmu", outputs=["nothing.here"])


@pytest.mark.parametrize("fmi", VERSIONS)
def test_units_with_si_base_exponents(fmi, tmp_path, fmus):
    from fmpy import read_model_description

    from mbcomp.export.description import unit_exponents

    fmus("slider_crank", fmi, tmp_path / "c.fmu")
    md = read_model_description(str(tmp_path / "c.fmu"))
    unit = {v.name: v.unit for v in md.modelVariables}
    assert unit["crank.m"] == "kg" and unit["crank.I[2,2]"] == "kg.m2" and unit["world.g[2]"] == "m/s2"
    assert unit["crank_joint.phi"] == "rad" and unit["der(crank_joint.phi)"] == "rad/s"
    assert unit["v[1]"] is None  # an independent speed: which one changes with the partition
    assert unit["slider_joint.s"] == "m" and unit["der(slider_joint.s)"] == "m/s"
    defs = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert (defs["kg.m2"].kg, defs["kg.m2"].m) == (1, 2) and (defs["rad/s"].rad, defs["rad/s"].s) == (1, -1)
    # a newton metre second per radian is kg m^2 / (s rad): derived symbols reduce to base units
    assert unit_exponents("N m s/rad") == {"kg": 1, "m": 2, "s": -1, "rad": -1}


def test_the_showcase_through_its_dead_centres_with_fmpys_defaults(tmp_path):
    """The issue's acceptance run: ``mbcomp export models/slider_crank.py -o crank.fmu``, FMPy
    validates it and simulates it with the FMU's own default experiment (10 s, the model file's
    t_end; tolerance 1e-12) as Model Exchange and as Co-Simulation; both match ``mbcomp
    simulate models/slider_crank.py`` (its SIMULATION settings, rtol 1e-8) to 1e-6 rad in the
    crank angle (measured: 3.9e-7 and 3.5e-7, mostly the 1e-8 run's own error)."""
    from mbcomp.cli.main import main

    mod = load_model("models/slider_crank.py")
    path = tmp_path / "crank.fmu"
    assert main(["export", mod.__file__, "-o", str(path)]) == 0
    assert validate_fmu(str(path)) == []
    ref = mbcomp.simulate(mod.build(), **mod.SIMULATION)
    assert ref.time[-1] == 10.0
    for fmi_type in ("ModelExchange", "CoSimulation"):
        r = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, output=["crank_joint.phi"])
        assert r["time"][-1] == pytest.approx(10.0)
        assert max_diff(r, ref, "crank_joint.phi") < 1e-6, fmi_type
        # through both dead centres: the crank angle passes 0 and -pi (crank and rod in line)
        assert r["crank_joint.phi"].max() > 0.0 and r["crank_joint.phi"].min() < -np.pi


@pytest.mark.parametrize("fmi", VERSIONS)
def test_an_input_drives_the_fmu_from_fmpy(fmi, tmp_path):
    """A turntable (2 kg m^2, no gravity) driven by ``Torque(tau=Input("u"))``: FMPy feeds the
    FMU's input u = sin t. FMPy sets inputs at its communication points and the FMU holds them
    through a Co-Simulation step, so CS must equal mbcomp run with that zero-order hold; ME
    (CVODE with FMPy's input updates) stays near the exact w = (1 - cos t) / 2."""
    def turntable_u():
        return turntable(mbcomp.Input("u", unit="N m", description="motor torque"))

    path = tmp_path / "turntable.fmu"
    info = export_fmu(turntable_u(), path, fmi=fmi, derivatives=False)
    assert info["inputs"] == ["u"] and validate_fmu(str(path)) == []
    h = 0.01
    tt = np.linspace(0.0, 3.0, 301)
    signal = np.array(list(zip(tt, np.sin(tt))), dtype=[("time", np.float64), ("u", np.float64)])
    cs = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=3.0, input=signal, output=["j.w"],
                           output_interval=h)
    held = mbcomp.simulate(turntable_u(), t_end=3.0, n_out=301, rtol=1e-10, atol=1e-12, max_step=h,
                           inputs={"u": lambda t: np.sin(h * np.floor(t / h + 1e-9))})
    assert max_diff(cs, held, "j.w") < 1e-6
    me = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=3.0, input=signal, output=["j.w"],
                           output_interval=h)
    assert float(np.max(np.abs(me["j.w"] - (1 - np.cos(me["time"])) / 2))) < 1e-2


def test_a_law_that_cannot_be_traced_is_refused_naming_the_component(tmp_path):
    import math

    from mbcomp.library import Torque

    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=0.5))
    bob = m.add("bob", PointMass(m=2.0))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    motor = m.add("motor", Torque(tau=lambda t, phi, w: -math.sin(phi)))  # math.* on a traced value
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    m.connect(j.axis, motor.flange_b)
    with pytest.raises(ValueError, match="motor.*mbcomp.Input"):
        export_fmu(m, tmp_path / "x.fmu")


def test_a_driven_model_carries_its_drive_law_and_effort(tmp_path):
    """The seed's slotted disk driven at 2 rad/s (a PrescribedMotion whose law traces into the
    program): the FMU holds the drive, its sliders move as in mbcomp, and the drive's torque --
    the effort that keeps the disk at speed -- is an output equal to mbcomp's column."""
    model = load_model("models/textbook/ex5_5_slotted_disk.py").build(omega=2.0)
    path = tmp_path / "disk.fmu"
    info = export_fmu(model, path, derivatives=False)
    assert validate_fmu(str(path)) == [] and "drive.tau" in info["outputs"]
    ref = mbcomp.simulate(model, t_end=3.0, n_out=101, rtol=1e-11, atol=1e-13)
    r = run_me(path, 3.0, ["slot1.s", "disk_hinge.phi", "drive.tau"], fmi_type="CoSimulation")
    assert max_diff(r, ref, "slot1.s") < 1e-9
    np.testing.assert_allclose(r["disk_hinge.phi"], 2.0 * r["time"], atol=1e-12)  # theta0 = 0
    assert max_diff(r, ref, "drive.tau") < 1e-8 * (1 + float(np.max(np.abs(ref["drive.tau"]))))
    assert float(np.max(np.abs(ref["drive.tau"]))) > 0.1  # the drive works


@pytest.mark.parametrize("fmi", VERSIONS)
def test_co_simulation_projects_onto_the_constraints_after_every_step(fmi, tmp_path, fmus):
    """A model with a loop: the FMU's Co-Simulation projects [q, u] onto the constraint manifold
    after every accepted DOP853 step (the runtime's mbrt_project over the evaluation program it
    carries), so the loop stays closed to the projection's tolerance, as mbcomp's own
    projection keeps it -- not only to the Baumgarte drift of the right-hand side."""
    path = tmp_path / "four_bar.fmu"
    info = fmus("four_bar", fmi, path)
    assert info["projects"] and validate_fmu(str(path)) == []
    r = run_me(path, 1.0, ["residual.position", "residual.velocity", "crank_joint.phi"], fmi_type="CoSimulation")
    assert float(np.max(np.abs(r["residual.position"]))) < 1e-10
    assert float(np.max(np.abs(r["residual.velocity"]))) < 1e-8
    ref = reference("four_bar", 1.0, stabilization="projection")
    assert max_diff(r, ref, "crank_joint.phi") < 1e-8
    assert not fmus("pendulum", "3.0", tmp_path / "p.fmu")["projects"]  # an open tree: nothing to project


def test_state_nominals_come_from_the_models_scales(tmp_path, fmus):
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Model

    path = tmp_path / "c.fmu"
    fmus("slider_crank", "3.0", path)
    md = read_model_description(str(path))
    fmu = FMU3Model(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.modelExchange.modelIdentifier)
    fmu.instantiate()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    import ctypes

    values = (ctypes.c_double * 4)()  # [q, v]: v the one independent speed (the crank's)
    fmu.getNominalsOfContinuousStates(values, 4)
    nominal = dict(zip(["crank_joint.phi", "slider_joint.s", "pin.phi", "crank_joint.w"], list(values)))
    fmu.terminate()
    fmu.freeInstance()
    # angles 1 rad; the slider's position and speed the model's largest length (per second) or
    # more (the start's magnitude); the crank's start rate 6 rad/s
    assert nominal["crank_joint.phi"] == 1.0 and nominal["crank_joint.w"] == 6.0
    assert 0.1 < nominal["slider_joint.s"] < 1.0


@pytest.mark.parametrize("fmi", VERSIONS)
def test_model_exchange_states_are_dalemberts_with_events_that_project(fmi, tmp_path):
    """A model with a loop exports D'Alembert's states for Model Exchange: the coordinates and
    the independent speeds v (the speeds are outputs). When the positions drift from the loop
    (here: a four-bar 1e-4 m from flat, at a loose importer tolerance), CompletedIntegratorStep
    asks for Event Mode, where the FMU projects onto the constraints and chooses the partition
    again; FMPy restarts its integrator from the changed states. The loop stays closed and the
    motion is mbcomp's."""
    model = load_model("models/four_bar.py").build(gap=1e-4)
    path = tmp_path / "fb.fmu"
    info = export_fmu(model, path, fmi=fmi, derivatives=False)
    assert info["selects_states"] and info["states"][-1] == "v[1]" and "crank_joint.w" in info["outputs"]
    assert validate_fmu(str(path)) == []
    calls = []
    r = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=1.0, relative_tolerance=1e-8,
                          output=["crank_joint.phi", "crank_joint.w", "residual.position"], output_interval=0.005,
                          fmi_call_logger=calls.append)
    # projected in Event Mode (FMPy logs the flag as True in 3.0, 1 in 2.0)
    assert sum("valuesOfContinuousStatesChanged=True" in c or "valuesOfContinuousStatesChanged=1" in c
               for c in calls) >= 1
    assert float(np.max(np.abs(r["residual.position"]))) < 1e-6
    ref = mbcomp.simulate(model, t_end=1.0, n_out=201, rtol=1e-12, atol=1e-14, stabilization="projection",
                          method="DOP853")
    assert max_diff(r, ref, "crank_joint.phi") < 1e-3 and max_diff(r, ref, "crank_joint.w") < 1e-1
    tight = fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=1.0, relative_tolerance=1e-12,
                              output=["crank_joint.phi"], output_interval=0.005)
    assert max_diff(tight, ref, "crank_joint.phi") < 1e-7


@pytest.mark.parametrize("fmi", VERSIONS)
def test_start_values_are_parameters(fmi, tmp_path, fmus):
    """``start.<coordinate>``/``start.<speed>`` parameters set the start state: an open tree
    starts exactly there; a loop's start is projected onto its constraints at initialization."""
    path = tmp_path / "p.fmu"
    fmus("pendulum", fmi, path)
    r = run_me(path, 2.0, ["j.phi"], fmi_type="CoSimulation", start_values={"start.j.phi": 1.0, "start.j.w": -0.5})
    m = mbcomp.Model()
    w = m.add("world", World())
    j = m.add("j", Revolute(phi0=1.0, w0=-0.5))
    rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    bob = m.add("bob", PointMass(m=2.0))
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    assert max_diff(r, mbcomp.simulate(m, t_end=2.0, n_out=101, rtol=1e-11, atol=1e-13), "j.phi") < 1e-7
    crank = tmp_path / "crank.fmu"
    fmus("slider_crank", fmi, crank)
    for fmi_type in ("CoSimulation", "ModelExchange"):
        r = run_me(crank, 0.5, ["crank_joint.phi", "residual.position"], fmi_type=fmi_type,
                   start_values={"start.crank_joint.phi": 1.0})
        assert abs(r["residual.position"][0]) < 1e-10 and abs(r["crank_joint.phi"][0] - 1.0) < 0.3


@pytest.mark.parametrize("fmi", VERSIONS)
def test_outputs_carry_their_declared_units(fmi, tmp_path, fmus):
    from fmpy import read_model_description

    fmus("slider_crank", fmi, tmp_path / "c.fmu")
    md = read_model_description(str(tmp_path / "c.fmu"))
    unit = {v.name: v.unit for v in md.modelVariables if v.causality == "output"}
    assert unit["rod_joint.f.x"] == "N" and unit["rod_joint.tau.z"] == "N.m"  # named units (issue 33)
    assert unit["crank.r.x"] == "m" and unit["crank.w.z"] == "rad/s" and unit["energy.total"] == "J"
    assert unit["crank_joint.w"] == "rad/s" and unit["crank_joint.w.der"] == "rad/s2"
    assert unit["residual.position"] is None  # mixed metres and radians: no unit


def test_the_co_simulation_tolerance_is_a_parameter(tmp_path, fmus):
    """``solver.tolerance`` sets the FMU's DOP853 tolerance (and wins over the experiment's)."""
    path = tmp_path / "c.fmu"
    fmus("slider_crank", "3.0", path)
    ref = mbcomp.simulate(load_model("models/slider_crank.py").build(), t_end=2.0, n_out=101, rtol=1e-12, atol=1e-14)
    errs = []
    for tol in (1e-4, 1e-10):
        r = fmpy.simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=2.0, output=["crank_joint.phi"],
                              output_interval=0.02, start_values={"solver.tolerance": tol})
        errs.append(max_diff(r, ref, "crank_joint.phi"))
    assert errs[0] > 100 * errs[1] and errs[1] < 1e-7
