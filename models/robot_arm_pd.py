"""An imported robot driven by a PD law on its joints: a four-joint arm read from a URDF file.

The arm is ``models/data/robot_arm.urdf`` (written for mbcomp, primitive shapes only, so it runs
on a fresh install without any robot package): a column turning about the vertical
(``base_yaw``), then three hinges about the y axis (``shoulder``, ``elbow``, ``wrist``); at zero
it stands straight up along z. :func:`mbcomp.load_urdf` turns it into library components named
as the file's links and joints (``res["shoulder.phi"]``), with the file's joint damping
(``<dynamics damping>``) as ``<joint>_damping`` dampers.

Each joint is driven toward the target posture ``q*`` (``target``, rad) by a PD law, a
:class:`~mbcomp.library.RotationalSpringDamper` named ``<joint>_pd`` between the joint's
support and axis flanges: the torque on the joint is ``kp (q* - q) - kd dq/dt`` (N m).

* **Pure PD** (``gravity_compensation=False``): the arm sags below the target; it settles where
  the PD torque holds the weight, ``K (q* - q) = g(q)``, with ``g(q) = dV/dq`` the gravity
  torques (``V`` the potential energy of the links' weights).
* **PD + gravity compensation** (``gravity_compensation=True``): the weight of every moving link
  is held by an upward force ``-m g`` at its centre of mass (a
  :class:`~mbcomp.library.WorldForce` named ``<link>_gravity_comp`` on a
  :class:`~mbcomp.library.FixedTranslation` to the centre of mass): its generalized forces are
  exactly the torques ``tau = g(q)`` a controller applies to cancel gravity, so the arm settles
  at ``q*`` exactly.

Run::

    mbcomp simulate models/robot_arm_pd.py --animate arm.html
    mbcomp simulate models/robot_arm_pd.py -p gravity_compensation=true --plot arm.png
    mbcomp simulate models/robot_arm_pd.py -p target=0,1.2,-0.8,0.3 -p "kp=20,40,20,5"

Examples
--------
>>> import mbcomp
>>> arm = mbcomp.load_model("models/robot_arm_pd.py", gravity_compensation=True)
>>> mbcomp.assemble(arm).q_names
['base_yaw.phi', 'shoulder.phi', 'elbow.phi', 'wrist.phi']
"""
import pathlib

import numpy as np

import mbcomp
from mbcomp.library import FixedTranslation, RotationalSpringDamper, WorldForce

#: the robot description (primitive visual shapes; SI units)
URDF = pathlib.Path(__file__).resolve().parent / "data" / "robot_arm.urdf"
#: the driven joints, base to tip, and the links they move
JOINTS = ("base_yaw", "shoulder", "elbow", "wrist")
LINKS = ("column", "upper_arm", "forearm", "hand")

SIMULATION = dict(t_end=5.0, rtol=1e-8, atol=1e-10, n_out=20001)  # the PD laws' power sampled finely enough for the energy balance


def build(target=(0.5, 0.8, -0.6, 0.4), kp=(40.0, 80.0, 40.0, 10.0), kd=(8.0, 12.0, 3.0, 0.15),
          gravity_compensation=False, g=9.81):
    """The arm of :data:`URDF` with a PD law on each joint toward ``target``.

    Parameters
    ----------
    target : (4,) rad
        The posture ``q*`` of ``base_yaw, shoulder, elbow, wrist``.
    kp : (4,) N m/rad
        Proportional gains, one per joint (>= 0).
    kd : (4,) N m s/rad
        Derivative gains, one per joint (>= 0).
    gravity_compensation : bool
        Hold every moving link's weight by an upward force at its centre of mass (the joint
        torques ``g(q)``): the arm settles at ``target`` exactly; else it sags below it.
    g : m/s^2
        Gravity, along -z.

    Returns
    -------
    Model
    """
    for name, v in zip(("target", "kp", "kd"), (target, kp, kd)):
        if np.size(v) not in (1, len(JOINTS)):
            raise ValueError(f"robot_arm_pd: {name}={v!r} must give one value per joint {JOINTS} (or one for all) "
                             f"-> fix: e.g. -p {name}=" + ",".join(["1"] * len(JOINTS)))
    gains = [np.broadcast_to(np.asarray(v, dtype=float), (len(JOINTS),)) for v in (target, kp, kd)]
    model = mbcomp.load_urdf(URDF, gravity=(0.0, 0.0, -g))
    parts = model.components()
    for joint, q_star, k, d in zip(JOINTS, *gains):
        pd = model.add(f"{joint}_pd", RotationalSpringDamper(c=k, d=d, phi_rel0=q_star))
        model.connect(parts[joint].support, pd.flange_a)
        model.connect(parts[joint].axis, pd.flange_b)
    if gravity_compensation:
        for link in LINKS:
            body = parts[link]
            cm = model.add(f"{link}_cm", FixedTranslation(r=body.p.r_cm))
            hold = model.add(f"{link}_gravity_comp", WorldForce(f=(0.0, 0.0, body.p.m * g)))
            model.connect(body.frame_a, cm.frame_a)
            model.connect(cm.frame_b, hold.frame_b)
    return model
