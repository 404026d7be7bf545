"""The bad-input list of issue 18: what mbcomp says to each mistake a new user made.

Each case builds a small model with one mistake, runs it through the public API and prints
what came back: the exception type and its message, or the result's status and message (or
"accepted silently" when nothing was said). Run it on two checkouts to compare versions:

    python bench/bad_inputs.py                 # this checkout
    PYTHONPATH=/tmp/old/src python bench/bad_inputs.py --markdown   # another one

Only public API is used, so the script runs unchanged against older versions.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import warnings

import numpy as np

import mbcomp
from mbcomp.library import (FixedTranslation, PointMass, PrescribedMotion, Prismatic, Revolute, RigidBody,
                            Spherical, Torque, World)


def pendulum(law=None, world=True):
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0))) if world else None
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    bob = m.add("bob", PointMass(m=1.0))
    if w is not None:
        m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, rod.frame_a)
    m.connect(rod.frame_b, bob.frame_a)
    if law is not None:
        motor = m.add("motor", Torque(tau=law))
        m.connect(j.axis, motor.flange_b)
    return m


def law_tuple():
    return mbcomp.simulate(pendulum(lambda t, phi, w: (1.0, 2.0)), t_end=0.1)


def law_none():
    return mbcomp.simulate(pendulum(lambda t, phi, w: None), t_end=0.1)


def law_signature():
    return mbcomp.simulate(pendulum(lambda t: 1.0), t_end=0.1)


def massless_point():
    m = mbcomp.Model()
    w = m.add("world", World())
    s = m.add("s", Spherical())
    b = m.add("b", PointMass(m=1.0))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    return mbcomp.simulate(m, t_end=0.1)


def mass_ratio():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j1 = m.add("j1", Prismatic(n=(1, 0, 0)))
    heavy = m.add("heavy", RigidBody(m=10.0, I=np.eye(3)))
    j2 = m.add("j2", Revolute(n=(0, 0, 1), phi0=0.5))
    rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    light = m.add("light", PointMass(m=1e-9))
    m.connect(w.frame_b, j1.frame_a)
    m.connect(j1.frame_b, heavy.frame_a)
    m.connect(heavy.frame_a, j2.frame_a)
    m.connect(j2.frame_b, rod.frame_a)
    m.connect(rod.frame_b, light.frame_a)
    return mbcomp.simulate(m, t_end=0.1)


def self_connected():
    m = pendulum()
    j = m.add("j2", Revolute())
    m.connect(j.frame_a, j.frame_b)
    return mbcomp.simulate(m, t_end=0.1)


def drive_on_spherical():
    m = mbcomp.Model()
    w = m.add("world", World())
    s = m.add("ball", Spherical())
    b = m.add("b", RigidBody(m=1.0, I=np.eye(3)))
    d = m.add("d", PrescribedMotion(s="t"))
    m.connect(w.frame_b, s.frame_a)
    m.connect(s.frame_b, b.frame_a)
    m.connect(s.axis, d.flange_b)
    return mbcomp.simulate(m, t_end=0.1)


def simulate_a_path():
    return mbcomp.simulate("models/slider_crank.py", t_end=0.1)


def build_returns_none():
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as fh:
        fh.write("import mbcomp\ndef build():\n    m = mbcomp.Model()\n")
    try:
        return mbcomp.simulate(mbcomp.load_model(fh.name), t_end=0.1)
    finally:
        os.unlink(fh.name)


def unconnected_body():
    m = pendulum()
    m.add("lost", PointMass(m=1.0))
    return mbcomp.simulate(m, t_end=0.1)


def no_world():
    m = mbcomp.Model()
    try:
        m.add("ball", RigidBody(m=1.0, I=np.eye(3)), free=True)
    except TypeError:  # a version before Model.add(free=): a body joined to nothing floated
        m.add("ball", RigidBody(m=1.0, I=np.eye(3)))
    return mbcomp.simulate(m, t_end=0.1)


def negative_rtol():
    return mbcomp.simulate(pendulum(), t_end=0.1, rtol=-1e-6)


def n_out_zero():
    return mbcomp.simulate(pendulum(), t_end=0.1, n_out=0)


def dt_out_too_long():
    res = mbcomp.simulate(pendulum(), t_end=1.0, dt_out=5.0)
    return res, f"output times {res.time.tolist()}"


def negative_gain():
    return mbcomp.simulate(pendulum(), t_end=0.1, alpha=-10.0)


def loop_left_open():
    m = mbcomp.load_model_file("models/slider_crank.py").build()
    res = mbcomp.simulate(m, t_end=10.0, rtol=1e-6, atol=1e-8, stabilization="none")
    return res, f"residual.position at t_end {res['residual.position'][-1]:.2g}"


def open_rigid_offset():
    m = mbcomp.Model()
    w = m.add("world", World(g=(0, -9.81, 0)))
    j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    bob = m.add("bob", RigidBody(m=1.0, r_cm=(1.0, 0, 0), I=np.eye(3) * 0.01))
    tip = m.add("tip", FixedTranslation(r=(1.2, 0, 0)))    # a marker at the tip; its frame_b left open
    m.connect(w.frame_b, j.frame_a)
    m.connect(j.frame_b, bob.frame_a)
    m.connect(j.frame_b, tip.frame_a)
    return mbcomp.simulate(m, t_end=0.1)


CASES = [
    ("a law returning a tuple", law_tuple),
    ("a law returning None", law_none),
    ("a law with the wrong signature", law_signature),
    ("a point mass on a spherical joint (3 massless rotations)", massless_point),
    ("a mass ratio of 1e10", mass_ratio),
    ("a joint connected to itself", self_connected),
    ("PrescribedMotion on a Spherical", drive_on_spherical),
    ("simulate('model.py')", simulate_a_path),
    ("build() returning None", build_returns_none),
    ("a body never connected", unconnected_body),
    ("no World", no_world),
    ("rtol=-1e-6", negative_rtol),
    ("n_out=0", n_out_zero),
    ("dt_out longer than the run", dt_out_too_long),
    ("alpha=-10 (Baumgarte)", negative_gain),
    ("a loop left open (stabilization='none', rtol 1e-6)", loop_left_open),
    ("an open FixedTranslation.frame_b", open_rigid_offset),
]


def outcome(fn):
    """``(kind, text)`` of one case: an exception, a result with its status, warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = fn()
        except Exception as exc:  # noqa: BLE001 - the point is what each mistake raises
            return type(exc).__name__, str(exc)
    extra = ""
    if isinstance(out, tuple):
        out, extra = out
    msg = out.message if out.message not in ("", "reached t_end") else ""
    said = [str(w.message) for w in caught if issubclass(w.category, (RuntimeWarning, UserWarning))
            and str(w.message).removeprefix("mbcomp: ") not in msg]
    text = "; ".join(x for x in [msg] + said + [extra] if x)
    return f"status {out.status}", text or "accepted silently"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--markdown", action="store_true", help="one markdown table row per case")
    args = ap.parse_args(argv)
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    for name, fn in CASES:
        kind, text = outcome(fn)
        text = " ".join(text.split())
        if args.markdown:
            print(f"| {name} | {kind}: {text.replace('|', '/')} |")
        else:
            print(f"{name}\n    {kind}: {text}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
