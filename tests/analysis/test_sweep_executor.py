"""``executor=`` on the sweeps: ``mbcomp.sweep`` (stability) and the work-precision study give the
serial results on a process pool."""
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import mbcomp
from mbcomp.analysis.workprecision import default_combos, work_precision
from mbcomp.library import FixedTranslation, PointMass, PrescribedMotion, Revolute, World

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


class Spin:
    """A picklable drive law: the spin angle omega * t (rad)."""

    def __init__(self, omega):
        self.omega = omega

    def __call__(self, t):
        return self.omega * t


def bead(omega):
    """The bead on a ring spun at omega (rad/s): unstable at the bottom above omega^2 = g / r."""
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    spin = m.add("spin", Revolute(n=(0, 1, 0)))
    drive = m.add("drive", PrescribedMotion(s=Spin(omega)))
    hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
    rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0)))
    b = m.add("bead", PointMass(m=0.1))
    m.connect(w.frame_b, spin.frame_a)
    m.connect(drive.flange_b, spin.axis)
    m.connect(spin.frame_b, hinge.frame_a)
    m.connect(hinge.frame_b, rod.frame_a)
    m.connect(rod.frame_b, b.frame_a)
    return m


@pytest.fixture(scope="module")
def pool():
    with ProcessPoolExecutor(max_workers=2) as ex:
        yield ex


def test_sweep_on_a_process_pool_equals_serial(pool):
    grid = np.linspace(2.0, 6.0, 5)
    serial = mbcomp.sweep(bead, "omega", grid)
    far = mbcomp.sweep(bead, "omega", grid, executor=pool)
    assert np.array_equal(serial.eigenvalues, far.eigenvalues)
    assert serial.classifications == far.classifications
    assert serial.changes == far.changes and len(far.changes) == 1
    assert far.changes[0]["value"] == pytest.approx(np.sqrt(9.81 / 0.5), rel=1e-12)


def test_sweep_refuses_what_cannot_pickle(pool):
    with pytest.raises(TypeError, match="define the function .* at module level, or use executor='dask'"):
        mbcomp.sweep(lambda w: bead(w), "omega", [3.0, 5.0], executor=pool)


def test_work_precision_on_a_process_pool_equals_serial(pool):
    model = str(ROOT / "models/slider_crank.py")
    combos = [c for c in default_combos() if c.label in ("ODE i1 Baumgarte / DOP853", "D'Alembert / Radau",
                                                         "DAE i3 / radau5")]
    ref = (0.2, {"crank_joint.phi": 0.95}, "given")
    kw = dict(tols=[1e-4, 1e-6], t_end=0.2, reference=ref)
    lines_serial, lines_far = [], []
    serial = work_precision(model, combos, log=lines_serial.append, **kw)
    far = work_precision(model, combos, log=lines_far.append, executor=pool, **kw)
    keys = ["combo", "setting", "value", "status", "nfev", "steps", "error", "message"]
    assert [[r[k] for k in keys] for r in far] == [[r[k] for k in keys] for r in serial]
    assert len(far) == 6 and {r["status"] for r in far} == {"success"}
    assert [ln.split(" cpu ")[0] for ln in lines_far] == [ln.split(" cpu ")[0] for ln in lines_serial]
