"""FMU states (issue 33 item 2): get, set, free, serialize, deserialize, FMI 3.0 and 2.0, Model
Exchange and Co-Simulation, driven through FMPy.

The bar: a Co-Simulation rollback (save at t, step on, restore, step again) gives bit for bit
the values of never having stepped on (OpenModelica #12260's hang is the failure to avoid); a
serialized state restored in a new process continues bit for bit; a Model Exchange restore puts
back the states and D'Alembert's partition, so an integrator continues exactly as without the
detour; a truncated, corrupted or foreign buffer is refused with a message saying which, and the
instance goes on unharmed. The C runs once under AddressSanitizer and UBSan in a harness.
"""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from mbcomp.codegen import c_compiler

from conftest import load_model
from pendulum_model import pendulum

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")
from fmpy import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from fmu_state_child import Instance, hexes  # noqa: E402
import sanitized  # noqa: E402
from mbcomp.export import export_fmu  # noqa: E402

VERSIONS = ["3.0", "2.0"]
CHILD = pathlib.Path(__file__).with_name("fmu_state_child.py")
#: what a Co-Simulation comparison reads: states and an output of the evaluation program
READ = {"pendulum": ["j.phi", "j.w", "bob.r.x", "energy.total"],
        "slider_crank": ["crank_joint.phi", "slider_joint.s", "crank_joint.w", "rod_joint.f.x", "residual.position"]}


MODELS = {"pendulum": pendulum, "pendulum_2m": lambda: pendulum(-2.0),
          "slider_crank": lambda: load_model("models/slider_crank.py").build(),
          # 1e-4 m from flat: D'Alembert's partition changes back and forth (crank <-> coupler)
          "four_bar_flat": lambda: load_model("models/four_bar.py").build(gap=1e-4)}


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    """``fmu(name, fmi)``: the path of the FMU (both kinds) of ``MODELS[name]``, built once per
    module and test process."""
    root, built = tmp_path_factory.mktemp("state_fmus"), {}

    def get(name, fmi):
        if (name, fmi) not in built:
            path = root / f"{name}_{fmi[0]}.fmu"
            export_fmu(MODELS[name](), path, fmi=fmi)
            built[name, fmi] = path
        return built[name, fmi]
    return get


def trajectory(inst, n, h, names):
    """The values of ``names`` after each of ``n`` Co-Simulation steps of ``h``, as exact hex."""
    out = []
    for _ in range(n):
        inst.step(h)
        out.append(hexes(inst.get(names)))
    return out


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name", ["pendulum", "slider_crank"])
def test_co_simulation_rollback_is_bit_identical(name, fmi, fmu):
    """Save at t, DoStep(h) twice, restore, DoStep(h): exactly the first DoStep(h)'s values, and
    the run on from there is, bit for bit, an instance's that never stepped past t. An earlier
    state object overwritten by GetFMUState holds the later state."""
    names, h = READ[name], 0.05
    a, ref = Instance(fmu(name, fmi), fmi, "cs"), Instance(fmu(name, fmi), fmi, "cs")
    trajectory(a, 4, h, names)
    at_save, t_save = hexes(a.get(names)), a.t
    state = a.get_state()
    first = trajectory(a, 1, h, names)
    trajectory(a, 2, h, names)
    assert trajectory(a, 1, h, names) != first  # the instance did move on
    a.set_state(state)
    a.t = t_save
    assert hexes(a.get(names)) == at_save
    if fmi == "3.0":
        assert a.get(["time"]) == [t_save]
    again = trajectory(a, 12, h, names)
    assert again[:1] == first
    trajectory(ref, 4, h, names)
    assert again == trajectory(ref, 12, h, names)  # as never having stepped past t
    # GetFMUState into the existing state object: it now holds the later state
    later, t_later = hexes(a.get(names)), a.t
    assert a.get_state(state).value == state.value
    trajectory(a, 3, h, names)
    a.set_state(state)
    a.t = t_later
    assert hexes(a.get(names)) == later
    a.free_state(state)
    assert state.value is None  # FreeFMUState sets the pointer NULL
    a.free_state(state)  # a NULL state: nothing to free, no error


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name", ["pendulum", "slider_crank"])
def test_a_serialized_state_continues_bit_identically_in_a_new_process(name, fmi, fmu, tmp_path):
    """Serialize mid-run (the pendulum with a tuned rod length: the parameters are part of the
    state), deserialize in a new Python process that instantiated the FMU with its defaults:
    its steps are the uninterrupted run's, bit for bit, with the tuned parameter."""
    names, h, path = READ[name] + (["rod.r[2]"] if name == "pendulum" else []), 0.05, fmu(name, fmi)
    a = Instance(path, fmi, "cs", params={"rod.r[2]": -2.0} if name == "pendulum" else None)
    trajectory(a, 5, h, names)
    state = a.get_state()
    data = a.serialize(state)
    a.free_state(state)
    (tmp_path / "state.bin").write_bytes(data)
    t_save = a.t
    on = trajectory(a, 10, h, names)
    res = subprocess.run([sys.executable, str(CHILD), str(path), fmi, str(tmp_path / "state.bin"), t_save.hex(),
                          h.hex(), "10", *names], capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": str(CHILD.parent)})
    assert res.returncode == 0, res.stderr[-2000:]
    child = [json.loads(line) for line in res.stdout.splitlines() if line.startswith("[")]
    assert child == on
    if name == "pendulum":
        assert float.fromhex(child[-1][-1]) == -2.0  # the tuned rod, not the default 1 m


def _rk4_run(inst, n, h):
    """``n`` classical Runge-Kutta steps of ``h`` over the Model Exchange instance (an importer's
    fixed-step integrator: it reads the states, sets them, calls CompletedIntegratorStep and
    Event Mode when asked); per step the states x, which speed is independent (the output of
    the speed equal to v), and whether an event changed the states."""
    out = []
    for _ in range(n):
        y = inst.x()
        k1 = inst.dx(inst.t, y)
        k2 = inst.dx(inst.t + h / 2, y + h / 2 * k1)
        k3 = inst.dx(inst.t + h / 2, y + h / 2 * k2)
        k4 = inst.dx(inst.t + h, y + h * k3)
        inst.t += h
        inst.set_x(inst.t, y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
        event = inst.completed()
        if event:
            inst.fmu.enterEventMode()
            event = inst.update()
            inst.fmu.enterContinuousTimeMode()
        x = inst.x()
        speeds = inst.get(["crank_joint.w", "coupler_joint.w" if "coupler_joint.w" in inst.vr else "rod_joint.w"])
        out.append((hexes(x), speeds.index(x[-1]) if x[-1] in speeds else -1, event))
    return out


@pytest.mark.parametrize("fmi", VERSIONS)
@pytest.mark.parametrize("name", ["slider_crank", "four_bar_flat"])
def test_model_exchange_restores_the_states_and_the_partition(name, fmi, fmu):
    """D'Alembert's states x = [q, v] and the partition that says which speed v is: an
    importer's RK4 saves the FMU state, integrates on (the four-bar near flat changes its
    partition from the coupler's speed to the crank's on the way, the slider-crank projects in
    Event Mode), restores, integrates again: the same bits, step for step; so does a fresh
    instance given the serialized state. Setting x and the time alone, without the state,
    leaves the later partition in place: another v, other derivatives."""
    path = fmu(name, fmi)
    a = Instance(path, fmi, "me", tol=1e-10)
    h = 2e-3
    _rk4_run(a, 250 if name == "slider_crank" else 50, h)  # the slider-crank's first event: step 296
    t_save, x_save = a.t, a.x()
    state = a.get_state()
    data = a.serialize(state)
    dx_save = a.dx(t_save, x_save)
    on = _rk4_run(a, 100, h)
    if name == "four_bar_flat":
        assert len({w for _, w, _ in on}) == 2  # the partition changed on the way
    else:
        assert any(e for _, _, e in on)  # Event Mode projected the states
    a.set_state(state)
    a.t = t_save
    assert _rk4_run(a, 100, h) == on
    fresh = Instance(path, fmi, "me", tol=1e-10)
    restored = fresh.deserialize(data)
    fresh.set_state(restored)
    fresh.t = t_save
    assert _rk4_run(fresh, 100, h) == on
    fresh.free_state(restored)
    if name == "four_bar_flat":  # x alone is not the state: the later partition reads it as another speed
        a.set_x(t_save, x_save)
        assert not np.array_equal(a.dx(t_save, x_save), dx_save)
        a.set_state(state)
        assert np.array_equal(a.dx(t_save, x_save), dx_save)
    a.free_state(state)


def _fnv(data):
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def _resealed(data):
    """``data`` with its checksum (the last 8 bytes) made right again."""
    return data[:-8] + _fnv(data[:-8]).to_bytes(8, "little")


@pytest.mark.parametrize("fmi", VERSIONS)
def test_bad_buffers_are_refused_with_what_is_wrong(fmi, fmu, capfd):
    """Truncated, corrupted (header, values, a crafted mode), random, another FMU's (another
    model; the same model with another parameter set), the other kind's: fmiError and a message
    naming the problem; no crash, and the instance steps and rolls back as before."""
    a = Instance(fmu("slider_crank", fmi), fmi, "cs")
    trajectory(a, 2, 0.05, READ["slider_crank"])
    state = a.get_state()
    data = a.serialize(state)
    other = Instance(fmu("pendulum", fmi), fmi, "cs")
    twin = Instance(fmu("pendulum_2m", fmi), fmi, "cs")  # the same sizes, another token
    me = Instance(fmu("slider_crank", fmi), fmi, "me")
    flip = bytearray(data)
    flip[40] ^= 0x01  # inside the token
    payload = bytearray(data)
    payload[len(data) // 2] ^= 0x80
    mode = bytearray(data)
    mode[168:176] = (99).to_bytes(8, "little")  # the mode, the first value after the header
    fmt = bytearray(data)
    fmt[8] = 3
    cases = [
        (data[:-1], "truncated"), (data[:100], "truncated"), (data[:0], "truncated"),
        (bytes(flip), "checksum"), (bytes(payload), "checksum"), (b"X" + data[1:], "not an mbcomp FMU state"),
        (bytes(fmt), "format 3"), (_resealed(bytes(mode)), "mode or a flag is out of range"),
        (bytes(np.random.default_rng(1).integers(0, 256, len(data), dtype=np.uint8)), "not an mbcomp FMU state"),
        (other.serialize(other.get_state()), "another FMU"),
    ]
    for buf, message in cases:
        capfd.readouterr()
        with pytest.raises(Exception, match="status 3"):
            a.deserialize(buf)
        out = capfd.readouterr()
        assert message in out.out + out.err, (message, out.out[-300:])
    with pytest.raises(Exception, match="status 3"):  # the same sizes, another token
        other.deserialize(twin.serialize(twin.get_state()))
    assert "the state was saved by another FMU" in capfd.readouterr().out
    with pytest.raises(Exception, match="status 3"):
        me.deserialize(data)
    assert "a Co-Simulation state cannot be set in a Model Exchange instance" in capfd.readouterr().out
    with pytest.raises(Exception, match="status 3"):  # NULL: no state
        a.set_state(type(state)())
    # unharmed: the instance rolls back as before
    t0, names = a.t, READ["slider_crank"]
    first = trajectory(a, 2, 0.05, names)
    a.set_state(state)
    a.t = t0
    assert trajectory(a, 2, 0.05, names) == first
    a.free_state(state)


@pytest.mark.parametrize("fmi", VERSIONS)
def test_the_model_description_declares_the_capabilities(fmi, fmu):
    path = fmu("slider_crank", fmi)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    for iface in (md.modelExchange, md.coSimulation):
        assert iface.canGetAndSetFMUstate and iface.canSerializeFMUstate
    xml = zipfile.ZipFile(path).read("modelDescription.xml").decode()
    spelled = "FMUState" if fmi == "3.0" else "FMUstate"  # as each version's schema has it
    assert xml.count(f'canGetAndSet{spelled}="true"') == 2 and xml.count(f'canSerialize{spelled}="true"') == 2


SAN_FLAGS = sanitized.SAN_FLAGS

#: the harness: the FMU's own C (its model file includes fmu_core.c, fmu_state.c, fmi3.c) driven
#: through the FMI 3.0 functions: Co-Simulation rollback and serialization, a Model Exchange
#: state, and refusals of every kind of bad buffer; exit 0 only if all hold
HARNESS = r"""
#include "MODEL_C"
static int errors;
static void logger(void *env, fmi3Status s, fmi3String cat, fmi3String msg)
{ (void)env; (void)cat; if (s >= fmi3Error) { errors++; fprintf(stderr, "[FMU] %s\n", msg); } }
#define CHECK(x) do { if (!(x)) { fprintf(stderr, "FAILED: %s (line %d)\n", #x, __LINE__); return 1; } } while (0)
static fmi3Instance cs_instance(void)
{
    fmi3Instance c = fmi3InstantiateCoSimulation("h", GUID, NULL, 0, 0, 0, 0, NULL, 0, NULL, logger, NULL);
    if (!c || fmi3EnterInitializationMode(c, 1, 1e-10, 0.0, 0, 0.0) || fmi3ExitInitializationMode(c)) return NULL;
    return c;
}
int main(void)
{
    fmi3Instance a = cs_instance(), b = cs_instance(), m;
    fmi3FMUState s = NULL, s2 = NULL, s3 = NULL;
    fmi3ValueReference vr[NX];
    double first[NX], again[NX], x[NXS + 1], dx1[NXS + 1], dx2[NXS + 1], t = 0.0;
    size_t n = 0, i;
    unsigned char *buf, *bad;
    fmi3Boolean e1, e2, e3; fmi3Float64 last;
    for (i = 0; i < NXS; i++) vr[i] = VR_X + (fmi3ValueReference)i;
    CHECK(a && b);
    for (i = 0; i < 3; i++, t += 0.05) CHECK(fmi3DoStep(a, t, 0.05, 1, &e1, &e2, &e3, &last) == fmi3OK);
    CHECK(fmi3GetFMUState(a, &s) == fmi3OK && s);
    CHECK(fmi3DoStep(a, t, 0.05, 0, &e1, &e2, &e3, &last) == fmi3OK);
    CHECK(fmi3GetFloat64(a, vr, NXS, first, NXS) == fmi3OK);
    CHECK(fmi3DoStep(a, t + 0.05, 0.05, 0, &e1, &e2, &e3, &last) == fmi3OK);
    CHECK(fmi3SetFMUState(a, s) == fmi3OK);
    CHECK(fmi3DoStep(a, t, 0.05, 0, &e1, &e2, &e3, &last) == fmi3OK);
    CHECK(fmi3GetFloat64(a, vr, NXS, again, NXS) == fmi3OK);
    CHECK(memcmp(first, again, sizeof(double) * NXS) == 0);
    CHECK(fmi3SerializedFMUStateSize(a, s, &n) == fmi3OK && n > MB_HEAD_BYTES);
    buf = (unsigned char *)malloc(n); bad = (unsigned char *)malloc(n);
    CHECK(buf && bad);
    CHECK(fmi3SerializeFMUState(a, s, buf, n - 1) == fmi3Error);
    CHECK(fmi3SerializeFMUState(a, s, buf, n) == fmi3OK);
    CHECK(fmi3DeserializeFMUState(b, buf, n, &s2) == fmi3OK && s2);
    CHECK(fmi3SetFMUState(b, s2) == fmi3OK);
    CHECK(fmi3DoStep(b, t, 0.05, 0, &e1, &e2, &e3, &last) == fmi3OK);
    CHECK(fmi3GetFloat64(b, vr, NXS, again, NXS) == fmi3OK);
    CHECK(memcmp(first, again, sizeof(double) * NXS) == 0);
    errors = 0;
    for (i = 0; i < n; i++) {  /* every truncation (in a block of its size: ASan sees a read past it); every byte flipped */
        unsigned char *cut = (unsigned char *)malloc(i ? i : 1);
        CHECK(cut != NULL);
        memcpy(cut, buf, i);
        CHECK(fmi3DeserializeFMUState(b, cut, i, &s3) == fmi3Error && s3 == NULL);
        free(cut);
        memcpy(bad, buf, n); bad[i] ^= 0x5a;
        CHECK(fmi3DeserializeFMUState(b, bad, n, &s3) == fmi3Error && s3 == NULL);
    }
    for (i = 0; i < n; i++) bad[i] = (unsigned char)(i * 37u + 11u);
    CHECK(fmi3DeserializeFMUState(b, bad, n, &s3) == fmi3Error && s3 == NULL);
    CHECK(errors == (int)(2 * n + 1));
    CHECK(fmi3SetFMUState(b, NULL) == fmi3Error && fmi3FreeFMUState(b, &s3) == fmi3OK);
    m = fmi3InstantiateModelExchange("m", GUID, NULL, 0, 0, NULL, logger);
    CHECK(m && fmi3EnterInitializationMode(m, 1, 1e-10, 0.0, 0, 0.0) == fmi3OK && fmi3ExitInitializationMode(m) == fmi3OK);
    CHECK(fmi3EnterContinuousTimeMode(m) == fmi3OK);
    CHECK(fmi3SetFMUState(m, s) == fmi3Error);  /* a Co-Simulation state */
    CHECK(fmi3DeserializeFMUState(m, buf, n, &s3) == fmi3Error);
    CHECK(fmi3GetFMUState(m, &s3) == fmi3OK && fmi3GetContinuousStates(m, x, NXS) == fmi3OK);
    CHECK(fmi3GetContinuousStateDerivatives(m, dx1, NXS) == fmi3OK);
    for (i = 0; i < NXS; i++) x[i] += 1e-3;
    CHECK(fmi3SetTime(m, 0.5) == fmi3OK && fmi3SetContinuousStates(m, x, NXS) == fmi3OK);
    CHECK(fmi3SetFMUState(m, s3) == fmi3OK && fmi3GetContinuousStateDerivatives(m, dx2, NXS) == fmi3OK);
    CHECK(memcmp(dx1, dx2, sizeof(double) * NXS) == 0);
    CHECK(fmi3FreeFMUState(m, &s3) == fmi3OK && s3 == NULL);
    fmi3FreeFMUState(a, &s); fmi3FreeFMUState(b, &s2);
    CHECK(s == NULL && s2 == NULL);
    fmi3FreeInstance(a); fmi3FreeInstance(b); fmi3FreeInstance(m);
    free(buf); free(bad);
    printf("ok %zu bytes\n", n);
    return 0;
}
"""


@pytest.mark.parametrize("name", ["pendulum", "slider_crank"])
def test_the_state_code_is_clean_under_asan_and_ubsan(name, fmu, tmp_path):
    """The FMU's C (an open tree; the slider-crank: state selection and projection compiled in) in a harness
    built with AddressSanitizer and UBSan: rollback and serialization bit-identical, every
    truncation and every single-byte corruption of a serialized state refused (no read past a
    buffer, no undefined behaviour), the Model Exchange state restored, nothing leaked."""
    if not sanitized.usable(tmp_path):
        pytest.skip("this compiler cannot build a sanitized program")
    src = tmp_path / "src"
    with zipfile.ZipFile(fmu(name, "3.0")) as z:
        z.extractall(src)
    model_c = [p for p in (src / "sources").glob("*.c")
               if p.name not in ("fmu_core.c", "fmu_state.c", "fmu_rules.c", "fmu_derivatives.c", "fmu_events.c", "fmi3.c",
                                 "fmu_user_events.c")
               and not p.name.startswith("mbrt_")]
    assert len(model_c) == 1
    (src / "sources" / "harness.c").write_text(HARNESS.replace("MODEL_C", model_c[0].name))
    exe = tmp_path / "harness"
    res = subprocess.run([c_compiler(), *SAN_FLAGS, "-std=c99", "-Wall", "-Wextra", str(src / "sources" / "harness.c"),
                          *sanitized.runtime_objects(src / "sources"), "-o", str(exe), "-lm"],
                         capture_output=True, text=True, cwd=src / "sources")
    assert res.returncode == 0, res.stderr[-3000:]
    assert "fmu_state.c" not in res.stderr  # no warning in the state code
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=600,
                         env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
    assert run.returncode == 0, (run.stdout[-1000:], run.stderr[-3000:])
    assert run.stdout.startswith("ok ") and "runtime error" not in run.stderr and "Sanitizer" not in run.stderr
    print(run.stdout.strip(), "(ASan + UBSan)")
    shutil.rmtree(src)
