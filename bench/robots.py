"""Real robots (issue 34 item 5): build time and per-call cost of mbcomp against Pinocchio and
MuJoCo on the same URDF and MJCF files, as ratios in one run.

Robots: URDFs of ``example-robot-data`` (the UR5, the Panda, the Kinova arm, TALOS's left arm
with a fixed base; Solo-12, A1, the simple humanoid, Unitree's G1 and the full TALOS with a
floating base), and -- where ``mbcomp.io.mjcf.load_mjcf`` exists -- dm-control's suite MJCFs
(cheetah, walker, humanoid). Each is read by mbcomp (:func:`mbcomp.load_urdf` /
``load_mjcf``), by Pinocchio (``buildModelFromUrdf``, with ``JointModelFreeFlyer`` where
floating; ``buildModelFromMJCF``) and by MuJoCo:

* an MJCF: ``MjModel.from_xml_path`` of the file itself;
* a URDF: MuJoCo reads URDF, but cannot resolve ``package://`` mesh paths (every file here
  fails on them) nor decode Collada meshes (``.dae``: Kinova) nor STLs with no face (the
  simple humanoid's); so MuJoCo reads a copy with ``package://`` resolved to the package's
  directory (``mujoco input``: ``meshes``) or, where that fails, without ``<visual>`` and
  ``<collision>`` (``no geometry``: dynamics unchanged, the file's ``<inertial>`` is used).
  A floating base is added as a free joint on the root body through ``MjSpec``
  (``fusestatic`` off, else MuJoCo fuses the root link into the world).

Measured (CPU seconds, this process plus waited-for children, ``bench/peers/cpu_clock.py``;
per call: median of 5 batches of ~0.05 s each, from Python as a user calls each):

* **build**: mbcomp ``load + assemble`` (the numeric system), and the whole build up to the
  first compiled calls -- ``load_urdf`` + ``assemble`` + ``compile_system(backend="c")`` (the
  evaluation program of ``M`` and ``f``) + the first right-hand side call (its program) --
  in a fresh process with an empty compile cache (``cold``: the compiler runs) and again in a
  fresh process with that cache (``warm``: what a second run pays); Pinocchio: parsing the URDF
  into its model; MuJoCo: loading (and compiling) the file, meshes included where it reads them
  (its asset cache disabled, so that repeated builds decode them again as a first build does);
* **M + bias**: mbcomp's compiled evaluation (``system.evaluate(t, q, u)``: ``M`` and ``f``,
  the evaluation program, which also gives every body's state; ``prog``: that program alone,
  one ``ctypes`` call without the ``Evaluation`` object around it), ``pin.crba`` + ``pin.rnea``
  (zero acceleration), MuJoCo's ``mj_fwdPosition`` + ``mj_fwdVelocity`` + ``mj_fullM``;
* **forward dynamics**: mbcomp's right-hand side ``f(t, y) -> dy/dt`` as the integrators call
  it (the thin C extension, ``codegen/thin.py``), ``pin.aba`` (with the joints' damping torque),
  ``mj_forward`` (constraints and actuation disabled: the robots' unconstrained dynamics).

Before timing, each peer's numbers are cross-checked at a random state with mbcomp's: the
largest relative difference of ``M`` (``err M``) and of the accelerations (``err a``), mapped
by joint name (a floating base: Pinocchio's velocities are in base axes, ``u = T v``;
MuJoCo's free joint has mbcomp's speeds). Pinocchio on an MJCF builds composite joints and its
own armature model: timed, not compared (``-``).

Measured (2026-11-29, 2-core VM shared with other jobs, pin 4.1.0, MuJoCo 4.0.0; mimic joints
free and no meshes on mbcomp's side, armature on both sides of the MJCFs): every cross-check
within 4.5e-13 (M within 1.1e-15); **forward dynamics** mbcomp / Pinocchio 0.39-0.63 on the
URDFs (0.18-0.51 on the MJCFs), mbcomp / MuJoCo 0.42-0.80 (0.21-0.54); **M + bias** through
``system.evaluate`` 1.0-3.1 times Pinocchio's ``crba + rnea`` and 1.4-2.7 times MuJoCo's (a
floor of ~2.5 us is the ``Evaluation`` object: the program alone is 1.6-7.0 us, 0.7-1.4 times
Pinocchio); **build**: ``load_urdf + assemble`` 39-70 ms, the whole build to compiled calls
0.28-3.5 s cold and 0.056-0.54 s warm (the printing of the C, hashed to find the cached
library, is most of it), 210-590 times Pinocchio's parse (0.2-2 ms) and 1.4-630 times MuJoCo's
(0.3 ms without meshes to 0.25 s with the G1's).

Writes bench/robots.csv (one row per robot) and bench/robots.png (per-call ratios); both
git-ignored like every bench output.

Run: python bench/robots.py [--robots ur5,panda,...] [--skip mujoco,pinocchio] [--no-cold]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import csv  # noqa: E402
import json  # noqa: E402
import pathlib  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
import xml.etree.ElementTree as ET  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from peers.cpu_clock import cpu  # noqa: E402

URDFS = [("ur5", "ur_description/urdf/ur5_robot.urdf", False), ("panda", "panda_description/urdf/panda.urdf", False),
         ("kinova", "kinova_description/robots/kinova.urdf", False),
         ("talos_arm", "talos_data/robots/talos_left_arm.urdf", False),
         ("solo12", "solo_description/robots/solo12.urdf", True), ("a1", "a1_description/urdf/a1.urdf", True),
         ("simple_humanoid", "simple_humanoid_description/urdf/simple_humanoid.urdf", True),
         ("g1", "g1_description/urdf/g1_29dof_rev_1_0.urdf", True),
         ("talos_full", "talos_data/robots/talos_full_v2.urdf", True)]
MJCFS = [("cheetah", "cheetah.xml"), ("walker", "walker.xml"), ("humanoid", "humanoid.xml")]


def robots_dir():
    """example-robot-data's ``robots`` directory, or None when the package is absent."""
    from importlib.metadata import PackageNotFoundError, files
    try:
        found = [f for f in (files("example-robot-data") or []) if str(f).endswith("ur5_robot.urdf")]
    except PackageNotFoundError:
        return None
    return str(found[0].locate()).split("/ur_description/")[0] if found else None


def suite_dir():
    try:
        import dm_control
    except ImportError:
        return None
    return os.path.join(os.path.dirname(dm_control.__file__), "suite")


def mjcf_loader():
    """``mbcomp.io.mjcf.load_mjcf``, or None with the reason."""
    try:
        from mbcomp.io.mjcf import load_mjcf
    except ImportError as exc:
        return None, f"no MJCF import in this mbcomp ({exc})"
    return load_mjcf, ""


def load(path, floating, armature=True):
    """mbcomp's model of the file (the import's notes silenced: ``mbcomp info`` lists them);
    ``armature=False``: an MJCF's armature left out. A URDF's mimic joints move freely, as in
    the peers' models (Pinocchio's default, MuJoCo's URDF reader): mbcomp's default holds them
    by a flange constraint, which changes the accelerations (Panda's and Talos's fingers). No
    visual shapes: the build is the dynamics model's, as ``pin.buildModelFromUrdf``'s (reading
    the meshes is ``bench/robot_visuals.py``'s)."""
    import mbcomp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        if path.endswith(".xml"):
            return mjcf_loader()[0](path, armature=armature)
        return mbcomp.load_urdf(path, floating=floating, mimic=False, visuals=False)


# ------------------------------------------------------------------------------------------
# builds: mbcomp in fresh processes (cold and warm compile cache), Pinocchio, MuJoCo
# ------------------------------------------------------------------------------------------
def child_build(path, floating):
    """In a fresh process: CPU seconds of load + assemble, and of the whole build to the first
    compiled evaluation and right-hand side call (printed as JSON)."""
    import mbcomp
    from mbcomp.codegen import compile_system
    from mbcomp.formulations import LagrangeIndex1

    c0 = cpu()
    system = mbcomp.assemble(load(path, floating))
    numeric = cpu() - c0
    cs = compile_system(system, "c", lazy=False, verify=False)
    q, u = start_state(system)
    cs.evaluate(0.0, q, u).M
    LagrangeIndex1(cs).fun(0.0, np.r_[q, u])
    print(json.dumps({"numeric": numeric, "compiled": cpu() - c0, "backend": cs.stats["backend"]}))


def mbcomp_builds(path, floating, cold=True):
    """``{numeric, cold, warm}`` CPU seconds, each build in a fresh Python process (warm and
    numeric: medians of three)."""
    cache = tempfile.mkdtemp(prefix="mbcomp_robots_")
    out = {}
    for label in (("cold", "warm") if cold else ("warm0", "warm")):
        got = [_child(path, floating, cache) for _ in range(1 if label != "warm" else 3)]
        out[label] = float(np.median([g["compiled"] for g in got]))
        out["numeric"] = float(np.median([g["numeric"] for g in got]))
    return out


def _child(path, floating, cache):
    r = subprocess.run([sys.executable, str(HERE / "robots.py"), "--child", path, str(int(floating))],
                       capture_output=True, text=True, env={**os.environ, "MBCOMP_CACHE": cache})
    if r.returncode:
        raise RuntimeError(f"{path}: the build process failed: {r.stderr.strip()[-400:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def batch_seconds(f, target=0.2):
    """CPU seconds of one ``f()``, repeated to ``target`` s when one call is short."""
    c0 = cpu()
    f()
    s = cpu() - c0
    if s >= target:
        return s
    n = max(1, int(target / max(s, 1e-6)))
    c0 = cpu()
    for _ in range(n):
        f()
    return (cpu() - c0) / n


def pinocchio_model(path, floating):
    import pinocchio as pin

    if path.endswith(".xml"):
        return pin.buildModelFromMJCF(path)
    return pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)


def mujoco_variant(path, root_dir, geometry=True, floating=False):
    """A copy of the URDF that MuJoCo can read: ``package://`` paths resolved (or the
    geometry removed), MuJoCo's compiler options in a ``<mujoco>`` element."""
    root = ET.parse(path).getroot()
    for el in root.iter():
        for k, v in el.attrib.items():
            if v.startswith("package://"):
                el.set(k, os.path.join(root_dir, v.split("/robots/", 1)[1]))
    if not geometry:
        for link in root.findall("link"):
            for g in link.findall("visual") + link.findall("collision"):
                link.remove(g)
    mj = ET.SubElement(root, "mujoco")
    ET.SubElement(mj, "compiler", {"discardvisual": "true", "strippath": "false",
                                   "fusestatic": "false" if floating else "true"})
    out = os.path.join(tempfile.mkdtemp(prefix="mbcomp_robots_mj_"), os.path.basename(path))
    ET.ElementTree(root).write(out)
    return out


def mujoco_model(path, floating, root_dir):
    """``(MjModel, build seconds, what MuJoCo read)`` of the file, or ``(None, None, why not)``."""
    import mujoco

    mujoco.mj_setCacheCapacity(mujoco.mj_getCache(), 0)  # no asset cache: every build decodes its meshes
    if path.endswith(".xml"):
        return mujoco.MjModel.from_xml_path(path), batch_seconds(lambda: mujoco.MjModel.from_xml_path(path)), "file"

    def make(p):
        if not floating:
            return mujoco.MjModel.from_xml_path(p)
        spec = mujoco.MjSpec.from_file(p)
        spec.worldbody.first_body().add_freejoint(name="root_joint")
        return spec.compile()

    why = []
    for geometry, label in ((True, "meshes"), (False, "no geometry")):
        p = mujoco_variant(path, root_dir, geometry, floating)
        try:
            m = make(p)
        except Exception as exc:  # MuJoCo raises ValueError with its compiler's message
            why.append(str(exc).splitlines()[0][:90])
            continue
        return m, batch_seconds(lambda: make(p)), label
    return None, None, "; ".join(why)


# ------------------------------------------------------------------------------------------
# states: one random state in mbcomp's coordinates, mapped to Pinocchio's and MuJoCo's
# ------------------------------------------------------------------------------------------
def start_state(system, seed=34):
    """A random ``(q, u)`` of the system: angles in (-1, 1) rad, unit quaternions, speeds ~ N(0, 1)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.0, 1.0, system.nq)
    for k, n in enumerate(system.q_names):
        if n.endswith(".Q.w"):
            Q = rng.standard_normal(4)
            q[k:k + 4] = Q / np.linalg.norm(Q)
    return q, rng.standard_normal(system.nu)


def _joint_of(names):
    return [n.split(".")[0] for n in names]


def pinocchio_state(system, model, q, u):
    """Pinocchio's ``(q, v)`` of mbcomp's ``(q, u)``, ``T`` with ``u = T v`` and ``dT/dt v``
    (URDF robots: revolute, prismatic, continuous and free-flyer joints), or None when a joint
    does not map."""
    import pinocchio as pin

    qj, uj = _joint_of(system.q_names), _joint_of(system.u_names)
    qp, v, T = pin.neutral(model), np.zeros(model.nv), np.zeros((system.nu, model.nv))
    Tdv = np.zeros(system.nu)
    for i in range(1, model.njoints):
        iq, nq, iv = model.idx_qs[i], model.nqs[i], model.idx_vs[i]
        name = model.names[i].replace("-", "_")
        if name not in qj:  # held fixed by the import (it moves no mass)
            qp[iq:iq + nq] = (0.0,) if nq == 1 else (1.0, 0.0)
            continue
        j, k = qj.index(name), uj.index(name)
        if nq == 7:
            Q = q[j + 3:j + 7]
            qp[iq:iq + 7] = np.r_[q[j:j + 3], Q[1:], Q[0]]
            R = pin.Quaternion(*Q).toRotationMatrix()
            T[k:k + 3, iv:iv + 3], T[k + 3:k + 6, iv + 3:iv + 6] = R, np.eye(3)
            v[iv:iv + 3], v[iv + 3:iv + 6] = R.T @ u[k:k + 3], u[k + 3:k + 6]
            Tdv[k:k + 3] = R @ np.cross(v[iv + 3:iv + 6], v[iv:iv + 3])  # d(R v_lin)/dt at fixed v_lin
        elif nq in (1, 2):
            qp[iq:iq + nq] = q[j] if nq == 1 else (np.cos(q[j]), np.sin(q[j]))
            T[k, iv], v[iv] = 1.0, u[k]
        else:
            return None
    return qp, v, T, Tdv


def mujoco_state(system, m, names, q, u):
    """MuJoCo's ``(qpos, qvel)`` of mbcomp's ``(q, u)`` and the permutation ``P`` of speeds
    (``u = P qvel``), with ``names`` mbcomp's joint of each MuJoCo joint; None when a joint does
    not map. Hinge and slide coordinates are MuJoCo's ``qpos`` (``ref`` included), free and ball
    joints' quaternions (w x y z) and speeds too (a free joint's linear velocity in world axes,
    angular velocities in body axes)."""
    qj, uj = _joint_of(system.q_names), _joint_of(system.u_names)
    qpos, qvel, P = np.zeros(m.nq), np.zeros(m.nv), np.zeros((system.nu, m.nv))
    size = {0: (7, 6), 1: (4, 3), 2: (1, 1), 3: (1, 1)}
    for i, name in enumerate(names):
        kind = int(m.jnt_type[i])
        if name not in qj or kind not in size:
            return None
        j, k, a, d = qj.index(name), uj.index(name), m.jnt_qposadr[i], m.jnt_dofadr[i]
        nq, nv = size[kind]
        qpos[a:a + nq], qvel[d:d + nv] = q[j:j + nq], u[k:k + nv]
        P[k:k + nv, d:d + nv] = np.eye(nv)
    return (qpos, qvel, P) if P.sum() == system.nu else None


def relative(a, b):
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


# ------------------------------------------------------------------------------------------
# one robot: cross-checks, then per-call costs
# ------------------------------------------------------------------------------------------
def per_call(f, target=0.05, repeats=5):
    """Median CPU seconds per ``f()`` over ``repeats`` batches of about ``target`` s."""
    n = 1
    while True:
        c0 = time.process_time()
        for _ in range(n):
            f()
        s = time.process_time() - c0
        if s >= target / 4:
            break
        n *= 4
    n = max(1, int(n * target / max(s, 1e-9)))
    times = []
    for _ in range(repeats):
        c0 = time.process_time()
        for _ in range(n):
            f()
        times.append((time.process_time() - c0) / n)
    return float(np.median(times))


class Mbcomp:
    """mbcomp's compiled system of one robot: ``M + f`` by the evaluation program, ``dy/dt`` by
    the thin right-hand side."""

    def __init__(self, path, floating):
        import mbcomp
        from mbcomp.codegen import compile_system
        from mbcomp.formulations import LagrangeIndex1

        self.model = load(path, floating)
        self.system = compile_system(mbcomp.assemble(self.model), "c", lazy=False, verify=False)
        self.q, self.u = start_state(self.system)
        self.y = np.r_[self.q, self.u]
        slow = LagrangeIndex1(self.system).fun
        slow(0.0, self.y)
        self.rhs = self.system.evaluator.lagrange_thin(0.0, 0.0) or slow
        self.rhs_kind = "thin C" if self.rhs is not slow else "LagrangeIndex1.fun"
        ev = self.system.evaluate(0.0, self.q, self.u)
        self.M, self.f = np.array(ev.M), np.array(ev.f)
        self.ud = np.asarray(self.rhs(0.0, self.y))[self.system.nq:]

    def mass_and_bias(self):
        ev = self.system.evaluate(0.0, self.q, self.u)
        return ev.M, ev.f

    def program(self):
        """The evaluation program alone (one ``ctypes`` call: ``M``, ``f`` and the bodies' states
        as one flat vector), without the :class:`Evaluation` built around it."""
        return self.system.evaluator.bound.run(0.0, self.q, self.u)

    def forward(self):
        return self.rhs(0.0, self.y)


def pinocchio_row(mb, path, floating, row):
    """Pinocchio's build, cross-check and per-call costs into ``row``."""
    import pinocchio as pin

    model = pinocchio_model(path, floating)
    row["pin build"] = batch_seconds(lambda: pinocchio_model(path, floating))
    data = model.createData()
    state = None if path.endswith(".xml") else pinocchio_state(mb.system, model, mb.q, mb.u)
    if state is None:  # an MJCF (composite joints, Pinocchio's own armature): timed at its own state
        qp, v = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)), np.ones(model.nv)
    else:
        qp, v, T, Tdv = state
        Mp = pin.crba(model, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        row["err M pin"] = relative(T.T @ mb.M @ T, Mp)
        a = pin.aba(model, data, qp, v, -model.damping * v)
        row["err a pin"] = relative(mb.ud, T @ a + Tdv)
    tau, zero = -model.damping * v, np.zeros(model.nv)
    row["pin M+b"] = per_call(lambda: (pin.crba(model, data, qp), pin.rnea(model, data, qp, v, zero)))
    row["pin fd"] = per_call(lambda: pin.aba(model, data, qp, v, tau))


def mujoco_check(system, m, names, d, row, q, u, M_mb, ud):
    """``err M mj`` and ``err a mj`` of mbcomp's ``M`` and ``du/dt`` at ``(q, u)`` against MuJoCo's."""
    import mujoco

    state = mujoco_state(system, m, names, q, u)
    if state is None:
        return
    d.qpos[:], d.qvel[:], P = state
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    row["err M mj"] = relative(P.T @ M_mb @ P, M)
    row["err a mj"] = relative(ud, P @ d.qacc)


def mujoco_row(mb, path, floating, root_dir, row):
    """MuJoCo's build, cross-check and per-call costs into ``row``."""
    import mujoco

    m, seconds, how = mujoco_model(path, floating, root_dir)
    row["mujoco input"] = how
    if m is None:
        return
    row["mj build"], row["mj nv"] = seconds, m.nv
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    m.opt.density = m.opt.viscosity = 0.0  # fluid forces and tendons: not imported by mbcomp (noted)
    m.tendon_stiffness[:] = m.tendon_damping[:] = 0.0
    names = getattr(mb.model, "mjcf_joints", None) or [m.joint(i).name.replace("-", "_") for i in range(m.njnt)]
    d = mujoco.MjData(m)
    mujoco_check(mb.system, m, names, d, row, mb.q, mb.u, mb.M, mb.ud)  # armature too (ReflectedInertia)
    d.qpos[:], d.qvel[:] = m.qpos0, 0.0
    M = np.zeros((m.nv, m.nv))

    def mass_and_bias():
        mujoco.mj_fwdPosition(m, d)
        mujoco.mj_fwdVelocity(m, d)
        mujoco.mj_fullM(m, d, M)
    row["mj M+b"] = per_call(mass_and_bias)
    row["mj fd"] = per_call(lambda: mujoco.mj_forward(m, d))


def measure(label, path, floating, root_dir, args):
    mb = Mbcomp(path, floating)
    row = {"robot": label, "floating": floating, "nq": mb.system.nq, "dof": mb.system.nu, "rhs": mb.rhs_kind}
    row.update({f"mb {k}": v for k, v in mbcomp_builds(path, floating, cold=not args.no_cold).items()})
    row["mb M+b"] = per_call(mb.mass_and_bias)
    row["mb M+b prog"] = per_call(mb.program)
    row["mb fd"] = per_call(mb.forward)
    if "pinocchio" not in args.skip:
        pinocchio_row(mb, path, floating, row)
    if "mujoco" not in args.skip:
        mujoco_row(mb, path, floating, root_dir, row)
    return row


# ------------------------------------------------------------------------------------------
# tables, CSV, chart
# ------------------------------------------------------------------------------------------
def _cell(row, key, scale=1.0, fmt="{:.3g}", width=9):
    v = row.get(key)
    return f"{'-':>{width}}" if v is None else f"{fmt.format(v * scale):>{width}}"


def _ratio(row, a, b, width=7):
    if row.get(a) is None or row.get(b) is None:
        return f"{'-':>{width}}"
    return f"{row[a] / row[b]:{width}.2f}"


def print_tables(rows):
    print("\nbuild, CPU seconds (mbcomp: fresh processes; cold: empty compile cache, warm: filled)")
    print(f"{'robot':<16}{'dof':>4}{'mb load+asm':>12}{'mb cold':>9}{'mb warm':>9}{'pin':>9}{'mujoco':>9}"
          f"{'warm/pin':>9}{'warm/mj':>8}  mujoco input")
    for r in rows:
        print(f"{r['robot']:<16}{r['dof']:>4}{_cell(r, 'mb numeric', width=12)}{_cell(r, 'mb cold')}"
              f"{_cell(r, 'mb warm')}{_cell(r, 'pin build')}{_cell(r, 'mj build')}"
              f"{_ratio(r, 'mb warm', 'pin build', 9)}"
              f"{_ratio(r, 'mb warm', 'mj build', 8)}  {r.get('mujoco input', '-')}")
    print("\nper call from Python, microseconds (CPU, median of 5 batches); ratios mbcomp / peer")
    print("(prog: mbcomp's evaluation program alone, one ctypes call, without the Evaluation object)")
    print(f"{'':<20}{'--- M + bias ---':^52}{'--- forward dynamics ---':^44}")
    print(f"{'robot':<16}{'dof':>4}{'prog':>8}" + f"{'mbcomp':>8}{'pin':>8}{'mujoco':>8}{'/pin':>10}{'/mj':>10}" * 2)
    for r in rows:
        cells = _cell(r, "mb M+b prog", 1e6, "{:.2f}", 8)
        for k in ("M+b", "fd"):
            cells += (_cell(r, f"mb {k}", 1e6, "{:.2f}", 8) + _cell(r, f"pin {k}", 1e6, "{:.2f}", 8)
                      + _cell(r, f"mj {k}", 1e6, "{:.2f}", 8) + _ratio(r, f"mb {k}", f"pin {k}", 10)
                      + _ratio(r, f"mb {k}", f"mj {k}", 10))
        print(f"{r['robot']:<16}{r['dof']:>4}{cells}")
    print("\ncross-check at a random state, max |difference| / max |peer| (- : not compared)")
    print(f"{'robot':<16}{'err M pin':>11}{'err a pin':>11}{'err M mj':>11}{'err a mj':>11}")
    for r in rows:
        print(f"{r['robot']:<16}" + "".join(_cell(r, k, fmt="{:.1e}", width=11)
                                           for k in ("err M pin", "err a pin", "err M mj", "err a mj")))


def write_outputs(rows):
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(HERE / "robots.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    x = np.arange(len(rows))
    for ax, (key, title) in zip(axes, (("M+b", "M + bias, per call"), ("fd", "forward dynamics, per call"),
                                       ("build", "build (mbcomp warm)"))):
        for k, (peer, name) in enumerate((("pin", "Pinocchio"), ("mj", "MuJoCo"))):
            mine = "mb warm" if key == "build" else f"mb {key}"
            theirs = f"{peer} build" if key == "build" else f"{peer} {key}"
            ratio = [r[mine] / r[theirs] if r.get(theirs) else np.nan for r in rows]
            ax.bar(x + (k - 0.5) * 0.38, ratio, 0.38, label=f"mbcomp / {name}")
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_yscale("log")
        ax.set_xticks(x, [f"{r['robot']} ({r['dof']})" for r in rows], rotation=60, ha="right", fontsize=8)
        ax.set_title(title)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("time ratio (< 1: mbcomp faster)")
    fig.tight_layout()
    fig.savefig(HERE / "robots.png", dpi=110)
    print(f"\nwrote {HERE / 'robots.csv'} and {HERE / 'robots.png'}")


def robot_list(args):
    """``[(label, path, floating)]`` of the robots asked for and found; prints every skip."""
    out = []
    root = robots_dir()
    if root is None:
        print("URDF robots skipped: example-robot-data is not installed (pip install mbcomp[robots])")
    else:
        out += [(label, os.path.join(root, rel), fl) for label, rel, fl in URDFS]
    load_mjcf, why = mjcf_loader()
    suite = suite_dir()
    if load_mjcf is None or suite is None:
        print(f"MJCF robots skipped: {why or 'dm-control is not installed'}")
    else:
        out += [(f"{label} (mjcf)", os.path.join(suite, f), True) for label, f in MJCFS]
    if args.robots:
        wanted = args.robots.split(",")
        out = [r for r in out if r[0].split(" (")[0] in wanted or r[0] in wanted]
    return out, root


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", help="comma-separated labels (default: all), e.g. ur5,a1,cheetah")
    ap.add_argument("--skip", default="", help="peers to leave out: pinocchio,mujoco")
    ap.add_argument("--no-cold", action="store_true", help="no cold-cache build (the compiler's minutes)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child_build(args.child[0], bool(int(args.child[1])))
    robots, root = robot_list(args)
    os.chdir(tempfile.mkdtemp(prefix="mbcomp_robots_cwd_"))  # MuJoCo writes MUJOCO_LOG.TXT where it runs
    rows = []
    for label, path, floating in robots:
        print(f"{label}: {os.path.basename(path)}{' (floating base)' if floating else ''} ...", flush=True)
        rows.append(measure(label, path, floating, root, args))
    if rows:
        print_tables(rows)
        write_outputs(rows)


if __name__ == "__main__":
    main()
