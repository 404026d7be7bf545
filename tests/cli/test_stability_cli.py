"""``mbcomp stability``: steady states, linearization, sweeps and errors, checked against analytic results.

* bead on a spinning ring (seed Example 7.1, models/textbook/ex7_1_bead_on_ring.py): steady
  states ``alpha = 0``, ``+-acos(g / (r omega^2))`` (and ``+-pi``); roots
  ``lambda^2 = omega^2 cos(2 alpha) - (g/r) cos(alpha)``: ``+-sqrt(omega^2 - g/r)`` at the
  bottom, ``+-i omega sin(alpha)`` off it;
* rolling disk (models/rolling_disk.py): upright rolling changes from unstable to marginally
  stable at ``spin = sqrt(g / (3 r))``; the lean equation ``J phi'' + K phi = 0`` with
  ``K = (I_a + m r^2) I_a W^2 / I_d - m g r``, ``J = I_d + m r^2`` (derived in the model file);
* the benchmark bicycle (models/bicycle.py): weave and capsize speeds of Meijaard et al. (2007).
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small LU solves; threads only cost on a shared machine

import json  # noqa: E402
import re  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mbcomp.cli import main  # noqa: E402

BEAD = "models/textbook/ex7_1_bead_on_ring.py"
DISK = "models/rolling_disk.py"
G = 9.81
R_BEAD = 0.5  # the bead model's default ring radius


def blocks(text):
    """``{value: (classification, first eigenvalue line)}`` from the --steady output."""
    out = {}
    for blk in text.split("\nsteady state ")[1:]:
        val = float(re.match(r"\d+: bead_hinge\.phi = (\S+)", blk).group(1))
        cls = re.search(r"^classification: (.+)$", blk, re.M).group(1)
        eig = blk.split("dominant states:\n")[1].splitlines()[0].split("(")[0].split()
        out[val] = (cls, complex(float(eig[0]), float(eig[1].rstrip("j"))))
    return out


def test_bead_steady_states_and_their_stability(tmp_path, capsys):
    omega = 6.0
    out, png = tmp_path / "bead.json", tmp_path / "bead.png"
    code = main(["stability", BEAD, "-p", f"omega={omega}", "--steady", "bead_hinge.w=0, bead_hinge.phi=-3.2:3.2",
                 "--out", str(out), "--plot", str(png)])
    text = capsys.readouterr().out
    assert code == 0
    assert "how: least squares" in text and "5 distinct solutions" in text
    found = blocks(text)
    a = np.arccos(G / (R_BEAD * omega ** 2))  # 0.99440721...
    want = {0.0: "unstable", a: "marginally stable", -a: "marginally stable", np.pi: "unstable", -np.pi: "unstable"}
    assert len(found) == 5
    for v, cls in want.items():
        (got,) = [x for x in found if abs(x - v) < 1e-9]
        assert found[got][0] == cls, (v, found[got])
    # the printed roots (6 digits): +sqrt(omega^2 - g/r) at the bottom, +i omega sin(a) off it
    assert abs(found[0.0][1].real - np.sqrt(omega ** 2 - G / R_BEAD)) < 1e-5
    (off,) = [x for x in found if abs(x - a) < 1e-9]
    assert abs(abs(found[off][1].imag) - omega * np.sin(a)) < 1e-5 and found[off][1].real == 0
    data = json.load(open(out))
    lam = {round(s["values"]["bead_hinge.phi"], 9):
           np.array(s["linearization"]["eigenvalues"]) for s in data["steady_states"]}
    np.testing.assert_allclose(sorted(lam[round(a, 9)][:, 1]), [-omega * np.sin(a), omega * np.sin(a)], rtol=1e-9)
    np.testing.assert_allclose(sorted(lam[0.0][:, 0]), [-np.sqrt(omega ** 2 - G / R_BEAD), np.sqrt(omega ** 2 - G / R_BEAD)],
                               rtol=1e-9)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_start_state_linearization_writes_json(tmp_path, capsys):
    out = tmp_path / "lin.json"
    assert main(["stability", BEAD, "-p", "alpha0=0", "-p", "omega=3", "--out", str(out)]) == 0
    assert "classification: marginally stable" in capsys.readouterr().out
    lam = np.array(json.load(open(out))["eigenvalues"])
    np.testing.assert_allclose(sorted(lam[:, 1]), np.array([-1, 1]) * np.sqrt(G / R_BEAD - 9.0), rtol=1e-9)
    np.testing.assert_allclose(lam[:, 0], 0.0, atol=1e-9)


def test_disk_sweep_finds_the_critical_spin(tmp_path, capsys):
    """r = 0.5 m, m = 0.7 kg (not build()'s defaults): the change at sqrt(g / (3 r)) = 2.5573 rad/s."""
    r, m = 0.5, 0.7
    out, png = tmp_path / "x.json", tmp_path / "x.png"
    code = main(["stability", DISK, "-p", f"r={r}", "-p", f"m={m}", "--sweep", "spin=1:5:9", "--out", str(out),
                 "--plot", str(png)])
    text = capsys.readouterr().out
    assert code == 0
    data = json.load(open(out))
    Wc = np.sqrt(G / (3 * r))
    (ch,) = data["changes"]
    # At Wc the state matrix has a triple zero root (a Jordan block: heading rate, lean, lean
    # rate), whose eigenvalues LAPACK resolves only to ~eps^(1/3) |A| = 1.5e-5; the located value
    # is therefore fixed to ~1e-9 relative by the rounding of A's entries. Two evaluations of A
    # that differ by one ulp in one entry (the jets' Kane sum and the recursive algorithms;
    # both within 3e-15 of the exact 15.696) land 4e-15 and 1.2e-9 from Wc.
    assert abs(ch["value"] / Wc - 1) < 1e-8, (ch["value"], Wc)
    assert (ch["from"], ch["to"]) == ("unstable", "marginally stable")
    # ch["kind"] is not checked: stability.sweep judges it at the located value, where the real
    # pair has just met at zero and may already be a tiny imaginary pair (here "oscillatory";
    # the crossing is a divergence: the unstable side's root is real)
    printed = re.search(r"stability changes at spin = (\S+) \(unstable -> marginally stable, \w+, "
                        r"Brent's method on the signed square of the colliding roots\)", text).group(1)
    assert float(printed) == ch["value"]
    Ia, Id = m * r * r / 2, m * r * r / 4
    for W, cls, re_, im in zip(data["values"], data["classifications"], data["eigenvalues_real"],
                               data["eigenvalues_imag"]):
        K, J = (Ia + m * r * r) * Ia * W ** 2 / Id - m * G * r, Id + m * r * r
        assert cls == ("marginally stable" if K > 0 else "unstable")
        assert abs(max(re_) - np.sqrt(max(-K / J, 0))) < 1e-8
        assert abs(max(np.abs(im)) - np.sqrt(max(K / J, 0))) < 1e-8
    assert data["marginally_stable_ranges"] == [[ch["value"], 5.0]] and data["stable_ranges"] == []
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_sweep_of_a_component_parameter_reaches_the_linearization(tmp_path, capsys):
    """``disk.m`` at run time with the inertia fixed (build()'s, m = 2 kg, r = 0.3 m):
    ``K = (I_a + m r^2) I_a W^2 / I_d - m g r``, ``J = I_d + m r^2`` now depend on ``m``."""
    out = tmp_path / "m.json"
    W, r = 6.0, 0.3
    assert main(["stability", DISK, "-p", f"spin={W}", "--sweep", "disk.m=1:4:3", "--out", str(out)]) == 0
    assert "no stability change for disk.m in [1, 4]" in capsys.readouterr().out
    data = json.load(open(out))
    Ia, Id = 2.0 * r * r / 2, 2.0 * r * r / 4
    for m, im in zip(data["values"], data["eigenvalues_imag"]):
        K, J = (Ia + m * r * r) * Ia * W ** 2 / Id - m * G * r, Id + m * r * r
        assert abs(max(im) - np.sqrt(K / J)) < 1e-8, (m, im)


def test_sweep_with_steady_follows_the_branch_it_starts_on(tmp_path, capsys):
    """Searched over -3..3 the bead has the steady states 0 and +-acos(g / (r omega^2)); the
    sweep starts on the one nearest the start value (alpha0 = -1) and follows it:
    ``-acos(g / (r omega^2))``, roots ``+-i omega sin(alpha)``."""
    out = tmp_path / "s.json"
    assert main(["stability", BEAD, "-p", "alpha0=-1", "--steady", "bead_hinge.w=0, bead_hinge.phi=-3:3",
                 "--sweep", "omega=5:8:4", "--out", str(out)]) == 0
    assert "no stability change for omega" in capsys.readouterr().out
    data = json.load(open(out))
    assert data["classifications"] == ["marginally stable"] * 4
    for omega, st, im in zip(data["values"], data["steady"], data["eigenvalues_imag"]):
        a = -np.arccos(G / (R_BEAD * omega ** 2))
        assert abs(st["bead_hinge.phi"] - a) < 1e-9
        assert abs(max(im) - omega * np.sin(-a)) < 1e-8


def test_bicycle_sweep_finds_weave_and_capsize_speeds(capsys):
    """Meijaard et al. (2007): weave speed 4.29238253634111, capsize speed 6.02426201538837 m/s
    (measured here: 4.292382536341105, 6.02426201538836; 7-13 s CPU)."""
    assert main(["stability", "models/bicycle.py", "--sweep", "v=0:10:11"]) == 0
    text = capsys.readouterr().out
    found = [float(x) for x in re.findall(r"stability changes at v = (\S+) ", text)]
    assert len(found) == 2
    assert abs(found[0] / 4.29238253634111 - 1) < 1e-9 and abs(found[1] / 6.02426201538837 - 1) < 1e-9
    assert "(unstable -> asymptotically stable, oscillatory" in text
    assert "(asymptotically stable -> unstable, divergence" in text
    assert f"stable ranges (asymptotically stable): [{found[0]!r}, {found[1]!r}]" in text


@pytest.mark.parametrize("argv, words", [
    (["-p", "omega=6", "--steady", "bead_hinge.phi=3:1"], ["bead_hinge.phi", "lo < hi"]),
    (["-p", "omega=6", "--steady", "bead_hinge.phi"], ["--steady", "bead_hinge.phi", "name=lo:hi"]),
    (["-p", "omega=6", "--steady", "bead_hinge.foo=-1:1"], ["bead_hinge.foo", "fix: use one of bead_hinge.phi"]),
    (["--steady", "bead_hinge.w=0"], ["no unknowns", "name=lo:hi"]),
    (["--sweep", "omega=1:5"], ["omega=1:5", "name=start:stop:count"]),
    (["--sweep", "omega=5:1:3"], ["start < stop"]),
    (["--sweep", "omegaa=1:5:3"], ["omegaa", "takes no parameter", "fix"]),
    (["--sweep", "bead.mass=1:2:2"], ["bead.mass", "no such parameter", "fix"]),
    (["--steady", "bead_hinge.w=0, bead_hinge.foo=-1:1", "--sweep", "omega=5:6:2"], ["bead_hinge.foo", "use one of"]),
    (["-p", "omegaa=6"], ["omegaa", "build() takes no parameter"]),
    (["-p", "bead.mass=2"], ["bead.mass", "no such parameter"]),
    ([], ["not a steady state", "bead_hinge.w", "--steady"]),  # the start angle 0.5 rad is not steady
])
def test_errors_are_one_clear_line_and_exit_2(argv, words, capsys):
    code = main(["stability", BEAD] + argv)
    cap = capsys.readouterr()
    assert code == 2, cap
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mbcomp: ") and "Traceback" not in cap.err
    for w in words:
        assert w in lines[0], (w, lines[0])


def test_no_steady_state_found_exits_1(capsys):
    code = main(["stability", BEAD, "-p", "omega=6", "--steady", "bead_hinge.w=0, bead_hinge.phi=0.3:0.6"])
    assert code == 1
    assert "no steady state found with bead_hinge.phi in [0.3, 0.6]" in capsys.readouterr().out
