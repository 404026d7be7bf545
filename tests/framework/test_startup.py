"""Starting mbcomp is cheap: a heavy package is imported by the feature that needs it, not by
``import mbcomp`` or on the way to every simulation.

sympy (symbolic equations, drive laws to differentiate), ``scipy.integrate`` (scipy's
steppers), ``scipy.optimize`` (steady states, sweeps), networkx (``Topology.graph``),
matplotlib (plots) and tqdm (a progress bar, after two seconds) together cost over a second
to import. Each check runs in a fresh interpreter (this process has imported everything
already) and reads ``sys.modules``; nothing here measures time.
"""
import json
import pathlib
import subprocess
import sys
import textwrap

ROOT = pathlib.Path(__file__).resolve().parents[2]

#: packages the default path (load a model, assemble it, ``mbcomp simulate -q``) must not import
HEAVY = ("sympy", "networkx", "matplotlib", "tqdm", "scipy.integrate", "scipy.optimize", "scipy.stats")


def loaded_after(code):
    """The packages of ``HEAVY`` imported by running ``code`` in a fresh interpreter, and what
    ``code`` printed before (its last line is the loaded list as JSON)."""
    probe = textwrap.dedent(code) + textwrap.dedent(f"""
        import json, sys
        print(json.dumps(sorted(name for name in {HEAVY!r} if name in sys.modules)))
        """)
    out = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    *before, last = out.strip().splitlines()
    return set(json.loads(last)), before


def test_building_and_assembling_a_model_imports_no_heavy_package():
    loaded, _ = loaded_after("""
        import mbcomp
        import mbcomp.codegen, mbcomp.library, mbcomp.simulation, mbcomp.solvers
        system = mbcomp.assemble(mbcomp.load_model("models/slider_crank.py"))
        assert system.topology.cut == ["rod_joint"], system.topology.cut
        """)
    assert not loaded, f"imported on the way to a simulation: {sorted(loaded)}"


def test_cli_simulate_imports_no_heavy_package():
    """``mbcomp simulate MODEL -q``: with a C compiler the run is the C engine's and needs no
    scipy integrator either; without one, scipy's DOP853 steps it (``scipy.integrate``)."""
    loaded, out = loaded_after("""
        from mbcomp.cli.main import main
        from mbcomp.codegen import c_compiler
        code = main(["simulate", "models/slider_crank.py", "--t-end", "0.2", "-q"])
        assert code == 0, code
        print(c_compiler() is not None)
        """)
    assert any(line.startswith("status: success") for line in out), out
    expected = set() if out[-1] == "True" else {"scipy.integrate"}
    assert loaded == expected, f"imported by `mbcomp simulate -q`: {sorted(loaded)}"


def test_the_features_that_need_them_still_import_them():
    """A drive law given as a string is differentiated by sympy, ``METHODS`` lists scipy's
    classes, ``Topology.graph`` is a networkx graph -- each imports its package when used."""
    loaded, out = loaded_after("""
        import sys
        import mbcomp
        from mbcomp.library import PrescribedMotion
        from mbcomp.simulation import driver
        d = PrescribedMotion(s="0.5*t**2")
        print("sympy" in sys.modules, d.motion(2.0, d.p))
        print("scipy.integrate" in sys.modules, driver.METHODS["RK45"].__module__, driver.METHODS is driver.METHODS)
        topo = mbcomp.assemble(mbcomp.load_model("models/slider_crank.py")).topology
        print("networkx" in sys.modules, type(topo.graph).__name__, sorted(k for *_, k in topo.graph.edges(keys=True)))
        """)
    assert out[0] == "False (2.0, 2.0, 1.0)"
    assert out[1] == "False scipy.integrate._ivp.rk True"
    assert out[2].startswith("False MultiGraph ['crank_joint', 'crank_tip', ")
    assert {"sympy", "scipy.integrate", "networkx"} <= loaded


def test_subpackages_are_attributes_after_a_plain_import():
    """``import mbcomp`` then ``mbcomp.codegen.compile_system`` works although nothing on the
    light default path imported mbcomp.codegen; an unknown name is still an AttributeError."""
    out = subprocess.run([sys.executable, "-c", textwrap.dedent("""
        import mbcomp
        print(callable(mbcomp.codegen.compile_system), callable(mbcomp.solvers.STEPPERS.get))
        try:
            mbcomp.no_such_thing
        except AttributeError as exc:
            print("AttributeError", exc)
        """)], cwd=ROOT, capture_output=True, text=True, check=True).stdout.splitlines()
    assert out[0] == "True True"
    assert out[1].startswith("AttributeError") and "no_such_thing" in out[1]
