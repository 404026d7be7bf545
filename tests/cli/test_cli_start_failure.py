"""``mbcomp simulate`` on a model whose law raises at the start: one line naming the
component, the law and the time, exit status 1, no traceback."""
import textwrap

from mbcomp.cli import main

MODEL = textwrap.dedent('''
    import mbcomp
    from mbcomp.library import FixedTranslation, PointMass, Revolute, Torque, World


    def stiction(t, phi, w):
        return -0.1 * w / abs(w)  # undefined at rest: the pendulum starts at rest


    def build():
        m = mbcomp.Model()
        w = m.add("world", World())
        j = m.add("hinge", Revolute(phi0=0.5))
        rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
        bob = m.add("bob", PointMass(m=1.0))
        motor = m.add("friction", Torque(tau=stiction))
        m.connect(w.frame_b, j.frame_a)
        m.connect(j.frame_b, rod.frame_a)
        m.connect(rod.frame_b, bob.frame_a)
        m.connect(j.axis, motor.flange_b)
        return m
''')


def test_a_law_raising_at_the_start_is_one_clear_line(tmp_path, capsys):
    path = tmp_path / "stiction.py"
    path.write_text(MODEL)
    out = tmp_path / "run.csv"
    rc = main(["simulate", str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 1
    assert err.startswith("mbcomp: Torque 'friction': stiction raised ZeroDivisionError at t=0:")
    assert "stiction.py:7 in stiction" in err and "Traceback" not in err
    assert not out.exists()  # nothing was integrated, so nothing was written
