"""3-D chains and trees (issue 32 item 3): one forward-dynamics call of mbcomp's generated C
program against Pinocchio's ABA, as ratios in one run, with the program's operation count.

Two mechanisms, each built with identical parameters in mbcomp and in Pinocchio:

* ``ball chain``: ``models/chain_3d.py`` (N uniform cylinders, mass ``M`` kg, length ``L`` m,
  radius ``A`` m, hanging along -y from spherical joints; ``JointModelSpherical``);
* ``floating tree``: a free-flying box (``FreeMotion`` from the world; ``JointModelFreeFlyer``)
  with ``LIMBS`` limbs of spherical joints and the same cylinders, ``(N - 1) / LIMBS`` links
  each, attached at the box's corners ``LIMB_AT``.

N counts the bodies (N = 10, 40, 100 by default). States: a generic state (every quaternion
and rate different) is drawn for Pinocchio and mapped to mbcomp's coordinates (quaternions
``(w, x, y, z)`` against Pinocchio's ``(x, y, z, w)``; the free joint's linear speed is the
world-frame ``dr/dt`` in mbcomp, the base-frame one in Pinocchio, whose ``dv/dt`` maps as
``R (a + w x v)``). Before anything is timed, mbcomp's ``du/dt`` (numeric, compiled, and the
bare program) must agree with a reference to ``max(AGREE, 10 eps cond(M))`` (max abs
difference over max abs ``du/dt``): Pinocchio's ``crba`` and ``nonLinearEffects`` solved densely
by numpy. Not ``pinocchio.aba`` itself: on the ball chain it loses digits as N grows (measured,
2026-11-28, pin 4.1.0, this generic state: 1e-11 at N = 10, 9e-6 at N = 40, 2e3 -- no digit --
at N = 100, while mbcomp and the dense solve agree to 3.5e-9; its error is printed, ``err pin``).
Pinocchio's own inverse dynamics says the same: ``rnea(q, v, aba(q, v, 0))`` misses zero by
3.9e-16 / 1.1e-10 / 62 of ``max |nonLinearEffects|`` at N = 10 / 40 / 100, ``rnea`` of the
dense solve's accelerations by 1.6e-15 / 2.2e-15 / 5.7e-15 (pin 4.1.0, 2026-11-28; cond M
7.8e5 / 4.2e7 / 5.8e8: the dense solve is where the digits are).

Timed per call (CPU time, medians of 5 batches):

* ``mbcomp C``: the generated C function ``mbcomp_fun`` (``[dq/dt, du/dt]``, the program the
  C engine steps) called in a C loop (a small C timing loop compiled once, no Python per call);
* ``pin C++``: ``pinocchio::aba`` (LOCAL convention, Pinocchio's default) in a C++ loop over
  the same model built in C++ from Pinocchio's own model's numbers (compiled once, -O3, ~45 s,
  cached; needs Eigen's headers -- ``apt-get install libeigen3-dev`` -- else this column is
  skipped with the reason);
* ``mbcomp fun``: :meth:`LagrangeIndex1.fun` on the compiled system (what scipy's integrators
  call; the Python wrapper's cost included); ``pin py``: ``pinocchio.aba`` called from Python.

Ratios: ``C / C++`` (the algorithms) and ``fun / py`` (what a Python caller sees). With
``--straight`` the same ``fun`` printed without loops over repeated blocks
(``codegen/block_loops.py``; straight-line code, as before them) is timed too, and its
``dy/dt`` compared with the printed program's (``diff``: 0, the same operations in the same
order).

Measured (2026-11-28, 2-core VM, pin 4.1.0; C / C++ at N = 10 / 40 / 100): with dense 6 x 6
products in the ABA (11,002 / 47,752 / 121,252 operations) the ball chain 0.78 / 0.86 / 1.85,
the floating tree 0.82 / 0.92 / 1.83; with the spatial algebra's structure
(``docs/design/generated-programs.md``, 8,023 / 34,633 / 87,853 operations) 0.61 / 0.66 / 0.96
and 0.62 / 0.66 / 0.99-1.04. At N = 100 the straight-line program (~1 MB of machine code) no
longer fits the L2 cache: its cost per operation is 1.45 times that at N = 40. With the
repeated blocks printed as loops (``--straight``, three runs, medians, C / C++ at N = 10 / 40 /
100): the ball chain 0.49 / 0.48 / 0.48 (straight-line in the same runs 0.61 / 0.63 / 0.99),
the floating tree 0.59 / 0.54 / 0.51 (0.61 / 0.63 / 1.05); the same dy/dt bit for bit.

Run: python bench/chain3d.py [--Ns 10,40,100] [--mechanisms chain,tree] [--straight]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import ctypes  # noqa: E402
import hashlib  # noqa: E402
import pathlib  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import mbcomp  # noqa: E402
from mbcomp.codegen import block_loops, compile_system  # noqa: E402
from mbcomp.codegen.compiler import Bound, Code  # noqa: E402
from mbcomp.codegen.toolchain import cache_directory, cached_library  # noqa: E402
from mbcomp.codegen.tracer import trace  # noqa: E402
from mbcomp.formulations import LagrangeIndex1  # noqa: E402
from mbcomp.initialization import initialize  # noqa: E402
from peers.cpu_clock import cpu  # noqa: E402

CHAIN = mbcomp.load_model_file(HERE.parent / "models" / "chain_3d.py")
L, M, A, G = 0.5, 1.0, 0.02, 9.81          # link length (m), mass (kg), radius (m), gravity (m/s^2)
BASE_M, BASE_SIZE = 5.0, (0.4, 0.2, 0.3)  # the tree's box: mass (kg), edges (m)
LIMBS = 3
LIMB_AT = ((0.2, -0.1, 0.15), (-0.2, -0.1, 0.15), (0.0, -0.1, -0.15))
AGREE = 1e-10
T0 = 0.0

# ------------------------------------------------------------------------------------------
# the mechanisms, in mbcomp and in Pinocchio
# ------------------------------------------------------------------------------------------


def cylinder():
    return CHAIN.cylinder_inertia(M, L, A)


def box_inertia():
    a, b, c = BASE_SIZE
    return BASE_M / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def limb_sizes(N):
    n = N - 1
    if n % LIMBS:
        raise ValueError(f"floating tree: N - 1 = {n} bodies do not split into {LIMBS} limbs -> give N = 1 + {LIMBS} k")
    return [n // LIMBS] * LIMBS


def tree_model(N):
    """The floating tree in mbcomp: components ``base`` (box on ``free``) and per limb ``l``
    joints ``j<l>_<k>``, links ``b<l>_<k>``, offsets."""
    from mbcomp.library import FixedTranslation, FreeMotion, RigidBody, Spherical, World

    mdl = mbcomp.Model()
    world = mdl.add("world", World(g=(0.0, -G, 0.0)))
    free = mdl.add("free", FreeMotion())
    base = mdl.add("base", RigidBody(m=BASE_M, r_cm=(0.0, 0.0, 0.0), I=box_inertia()))
    mdl.connect(world.frame_b, free.frame_a)
    mdl.connect(free.frame_b, base.frame_a)
    for li, n in enumerate(limb_sizes(N)):
        at = mdl.add(f"at{li}", FixedTranslation(r=LIMB_AT[li]))
        mdl.connect(free.frame_b, at.frame_a)
        prev = at.frame_b
        for k in range(n):
            joint = mdl.add(f"j{li}_{k}", Spherical())
            link = mdl.add(f"b{li}_{k}", RigidBody(m=M, r_cm=(0.0, -L / 2, 0.0), I=cylinder()))
            mdl.connect(prev, joint.frame_a)
            mdl.connect(joint.frame_b, link.frame_a)
            if k < n - 1:
                tip = mdl.add(f"t{li}_{k}", FixedTranslation(r=(0.0, -L, 0.0)))
                mdl.connect(joint.frame_b, tip.frame_a)
                prev = tip.frame_b
    return mdl


def pinocchio_model(kind, N):
    """The same mechanism in Pinocchio and the mbcomp joint name of each Pinocchio joint."""
    import pinocchio as pin

    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, -G, 0.0]), np.zeros(3))
    link = pin.Inertia(M, np.array([0.0, -L / 2, 0.0]), cylinder())
    down = np.array([0.0, -L, 0.0])
    names = []
    if kind == "chain":
        parent = 0
        for k in range(1, N + 1):
            parent = model.addJoint(parent, pin.JointModelSpherical(), pin.SE3(np.eye(3), down if k > 1 else np.zeros(3)),
                                    f"joint{k}")
            model.appendBodyToJoint(parent, link, pin.SE3.Identity())
            names.append(f"joint{k}")
        return model, names
    base = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "free")
    model.appendBodyToJoint(base, pin.Inertia(BASE_M, np.zeros(3), box_inertia()), pin.SE3.Identity())
    names.append("free")
    for li, n in enumerate(limb_sizes(N)):
        parent = base
        for k in range(n):
            at = np.array(LIMB_AT[li]) if k == 0 else down
            parent = model.addJoint(parent, pin.JointModelSpherical(), pin.SE3(np.eye(3), at), f"j{li}_{k}")
            model.appendBodyToJoint(parent, link, pin.SE3.Identity())
            names.append(f"j{li}_{k}")
    return model, names


def mbcomp_model(kind, N):
    return CHAIN.build(N=N, L=L, m=M, a=A, g=G) if kind == "chain" else tree_model(N)


class StateMap:
    """Pinocchio's ``(q, v, ddq)`` <-> mbcomp's ``y = [q, u]`` and ``du/dt`` (by joint name)."""

    def __init__(self, model, names, system):
        qn, un = system.q_names, system.u_names
        self.nq, self.nu = system.nq, system.nu
        self.joints = []
        for j, name in enumerate(names, start=1):
            jm = model.joints[j]
            qi = qn.index(f"{name}.Q.w") if jm.nq == 4 else qn.index(f"{name}.r.x")
            ui = un.index(f"{name}.w.x") if jm.nv == 3 else un.index(f"{name}.v.x")
            self.joints.append((jm.nq, jm.idx_q, jm.idx_v, qi, ui))

    def y(self, q, v):
        from mbcomp.kinematics import quat_to_matrix

        y = np.zeros(self.nq + self.nu)
        for nq, iq, iv, qi, ui in self.joints:
            if nq == 4:
                y[qi:qi + 4] = np.roll(q[iq:iq + 4], 1)
                y[self.nq + ui:self.nq + ui + 3] = v[iv:iv + 3]
            else:
                Q = np.roll(q[iq + 3:iq + 7], 1)
                y[qi:qi + 3], y[qi + 3:qi + 7] = q[iq:iq + 3], Q
                y[self.nq + ui:self.nq + ui + 3] = quat_to_matrix(Q) @ v[iv:iv + 3]
                y[self.nq + ui + 3:self.nq + ui + 6] = v[iv + 3:iv + 6]
        return y

    def ud(self, q, v, a):
        from mbcomp.kinematics import cross, quat_to_matrix

        out = np.zeros(self.nu)
        for nq, iq, iv, qi, ui in self.joints:
            if nq == 4:
                out[ui:ui + 3] = a[iv:iv + 3]
            else:
                R = quat_to_matrix(np.roll(q[iq + 3:iq + 7], 1))
                out[ui:ui + 3] = R @ (a[iv:iv + 3] + cross(v[iv + 3:iv + 6], v[iv:iv + 3]))
                out[ui + 3:ui + 6] = a[iv + 3:iv + 6]
        return out


def generic_state(model, seed=3):
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    np.random.seed(seed)  # randomConfiguration draws from numpy's global generator
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    return q, 0.8 * rng.standard_normal(model.nv)


# ------------------------------------------------------------------------------------------
# timing loops: the generated C function in C, pinocchio::aba in C++
# ------------------------------------------------------------------------------------------
C_LOOP = r"""
#include <time.h>
typedef int (*prog_t)(const double *, const double *, double, const double *, const double *, const double *,
                      double *, double *);
/* CPU seconds per call of a generated program over n calls (-1 when a call returned nonzero) */
double mbcomp_bench_loop(void *f, const double *q, const double *u, const double *d, const double *h,
                         const double *p, double *w, double *out, long n) {
  prog_t g = (prog_t)f;
  struct timespec a, b;
  int bad = 0;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  for (long i = 0; i < n; i++) bad |= g(q, u, 0.0, d, h, p, w, out);
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  if (bad) return -1.0;
  return ((double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec)) / (double)n;
}
"""

CPP_LOOP = r"""
#include "pinocchio/multibody.hpp"
#include "pinocchio/algorithm/aba.hpp"
#include <ctime>
#include <string>
using namespace pinocchio;
struct Built { Model model; Data data; };
/* joint kinds: 0 spherical, 1 free flyer; placements R (row-major), p; bodies m, c, I (row-major) */
extern "C" void *pin_build(long n, const long *kind, const long *parent, const double *R, const double *p,
                           const double *m, const double *c, const double *I, const double *g) {
  Built *b = new Built();
  b->model.gravity.linear(Eigen::Vector3d(g[0], g[1], g[2]));
  for (long k = 0; k < n; k++) {
    SE3 X(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R + 9 * k),
          Eigen::Map<const Eigen::Vector3d>(p + 3 * k));
    std::string name = "j" + std::to_string(k);
    JointIndex id = kind[k] == 0 ? b->model.addJoint(parent[k], JointModelSpherical(), X, name)
                                 : b->model.addJoint(parent[k], JointModelFreeFlyer(), X, name);
    Inertia Y(m[k], Eigen::Map<const Eigen::Vector3d>(c + 3 * k),
              Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(I + 9 * k));
    b->model.appendBodyToJoint(id, Y, SE3::Identity());
  }
  b->data = Data(b->model);
  return b;
}
extern "C" void pin_free(void *h) { delete (Built *)h; }
/* CPU seconds per pinocchio::aba over n calls; the accelerations into a */
extern "C" double pin_aba_loop(void *h, const double *q, const double *v, double *a, long n) {
  Built *b = (Built *)h;
  Eigen::VectorXd Q = Eigen::Map<const Eigen::VectorXd>(q, b->model.nq);
  Eigen::VectorXd V = Eigen::Map<const Eigen::VectorXd>(v, b->model.nv);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(b->model.nv);
  timespec t0, t1;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
  for (long i = 0; i < n; i++) aba(b->model, b->data, Q, V, tau);
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
  Eigen::Map<Eigen::VectorXd>(a, b->model.nv) = b->data.ddq;
  return ((double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec)) / (double)n;
}
"""
CPP_FLAGS = ["-O3", "-DNDEBUG", "-shared", "-fPIC", "-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
             "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION"]


def c_loop():
    lib = cached_library([("bench_loop", C_LOOP, ["-O2"])], "mbcomp_bench_loop", None, "timing loop")
    lib.mbcomp_bench_loop.restype = ctypes.c_double
    lib.mbcomp_bench_loop.argtypes = [ctypes.c_void_p] * 8 + [ctypes.c_long]
    return lib.mbcomp_bench_loop


def cpp_loop():
    """The C++ timing loop over ``pinocchio::aba`` (built once, cached): the library, or why not."""
    import pinocchio

    prefix = pathlib.Path(pinocchio.__file__).resolve()
    while prefix.name != "cmeel.prefix" and prefix != prefix.parent:
        prefix = prefix.parent
    cxx = shutil.which(os.environ.get("CXX", "g++"))
    eigen = next((p for p in ("/usr/include/eigen3", str(prefix / "include" / "eigen3"))
                  if os.path.isdir(os.path.join(p, "Eigen"))), None)
    if prefix.name != "cmeel.prefix" or cxx is None or eigen is None:
        return None, "no C++ compiler, Pinocchio headers (cmeel prefix) or Eigen headers (apt-get install libeigen3-dev)"
    args = CPP_FLAGS + [f"-I{prefix / 'include'}", f"-I{eigen}"]
    key = hashlib.sha256("\0".join([CPP_LOOP, cxx, pinocchio.__version__] + args).encode()).hexdigest()[:16]
    so = os.path.join(cache_directory(None), f"bench_pin_aba_{key}.so")
    if not os.path.exists(so):
        src = so[:-3] + ".cpp"
        pathlib.Path(src).write_text(CPP_LOOP)
        print(f"compiling the Pinocchio C++ timing loop (once, ~45 s): {so}", flush=True)
        r = subprocess.run([cxx, *args, src, "-o", so + ".tmp", f"-L{prefix / 'lib'}", "-lpinocchio_default",
                            f"-Wl,-rpath,{prefix / 'lib'}"], capture_output=True, text=True)
        if r.returncode:
            return None, f"the C++ loop did not compile: {r.stderr.strip().splitlines()[-1][:120]}"
        os.replace(so + ".tmp", so)
    lib = ctypes.CDLL(so)
    lib.pin_build.restype = ctypes.c_void_p
    lib.pin_build.argtypes = [ctypes.c_long] + [ctypes.c_void_p] * 8
    lib.pin_free.argtypes = [ctypes.c_void_p]
    lib.pin_aba_loop.restype = ctypes.c_double
    lib.pin_aba_loop.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_long]
    return lib, ""


class CppModel:
    """Pinocchio's model rebuilt in C++ from its numbers (joint kinds, parents, placements,
    inertias), timed by :data:`CPP_LOOP`."""

    def __init__(self, lib, model):
        kinds, rows = [], {k: [] for k in ("parent", "R", "p", "m", "c", "I")}
        for j in range(1, model.njoints):
            kinds.append(0 if model.joints[j].nq == 4 else 1)
            X, Y = model.jointPlacements[j], model.inertias[j]
            for k, v in (("parent", model.parents[j]), ("R", X.rotation.ravel()), ("p", X.translation),
                         ("m", Y.mass), ("c", Y.lever), ("I", Y.inertia.ravel())):
                rows[k].append(v)
        self.arrays = [np.ascontiguousarray(kinds, np.int64), np.ascontiguousarray(rows["parent"], np.int64)]
        self.arrays += [np.ascontiguousarray(np.array(rows[k], float).ravel()) for k in ("R", "p", "m", "c", "I")]
        self.arrays.append(np.ascontiguousarray(model.gravity.linear, float))
        self.lib, self.nv = lib, model.nv
        self.h = lib.pin_build(len(kinds), *[a.ctypes.data for a in self.arrays])

    def aba(self, q, v, n):
        q, v = np.ascontiguousarray(q, float), np.ascontiguousarray(v, float)
        a = np.zeros(self.nv)
        return self.lib.pin_aba_loop(self.h, q.ctypes.data, v.ctypes.data, a.ctypes.data, n), a

    def close(self):
        self.lib.pin_free(self.h)


def median_loop(run, target=0.05, repeats=5):
    """Median seconds per call of ``run(n) -> seconds per call`` over ``repeats`` batches of
    about ``target`` s."""
    n = 16
    while run(n) * n < target / 4 and n < 1 << 22:
        n *= 4
    n = max(1, int(target / max(run(n), 1e-9)))
    return float(np.median([run(n) for _ in range(repeats)]))


def per_call(f, target=0.05, repeats=5):
    def run(n):
        c0 = time.process_time()
        for _ in range(n):
            f()
        return (time.process_time() - c0) / n
    return median_loop(run, target, repeats)


# ------------------------------------------------------------------------------------------
# one mechanism at one N
# ------------------------------------------------------------------------------------------
def measure(kind, N, loop, cpp, straight=False):
    import pinocchio as pin

    model, names = pinocchio_model(kind, N)
    data = model.createData()
    system = mbcomp.assemble(mbcomp_model(kind, N))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the hanging chain's start is ill-conditioned; not used
        initialize(system, T0)
    smap = StateMap(model, names, system)
    q, v = generic_state(model)
    y = smap.y(q, v)
    tau = np.zeros(model.nv)
    M = pin.crba(model, model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    ref = smap.ud(q, v, np.linalg.solve(M, -pin.nonLinearEffects(model, model.createData(), q, v)))
    scale = np.max(np.abs(ref))
    row = dict(kind=kind, N=N, cond=np.linalg.cond(M))
    tol = max(AGREE, 10.0 * np.finfo(float).eps * row["cond"])
    row["err pin aba"] = np.max(np.abs(smap.ud(q, v, pin.aba(model, data, q, v, tau)) - ref)) / scale
    c0 = cpu()
    code = Code(trace(system, 3_000_000, program="fun"), "c")
    row["build"] = cpu() - c0
    bound = Bound(code, system)
    row["ops"] = code.n_ops_fun
    cs = compile_system(system, "c", lazy=True, verify=False)
    fun = LagrangeIndex1(cs).fun
    nq = system.nq
    for label, dy in (("numeric", LagrangeIndex1(system).fun(T0, y)), ("compiled", fun(T0, y)),
                      ("program", bound.run_fun(T0, y, 0.0, 0.0))):
        err = np.max(np.abs(np.asarray(dy)[nq:] - ref)) / scale
        row[f"err {label}"] = err
        if not err <= tol:
            raise AssertionError(f"{kind} N = {N}: mbcomp's {label} du/dt differs from Pinocchio's dense solve by "
                                 f"{err:.1e} (relative) > {tol:.1e}")
    bound.yin[:y.size] = y
    _, _, pd, ph, pp, pw, _, _, py = bound.ptrs
    pq, pu = bound.fun_args
    f = ctypes.cast(code.dll.mbcomp_fun, ctypes.c_void_p).value

    def c_run(n):
        s = loop(f, pq, pu, pd, ph, pp, pw, py, n)
        if s < 0:
            raise RuntimeError(f"{kind} N = {N}: the program's guard failed at the timed state")
        return s
    row["mbcomp C"] = median_loop(c_run)
    if straight:
        time_straight(system, y, bound, loop, row)
    row["mbcomp fun"] = per_call(lambda: fun(T0, y))
    row["pin py"] = per_call(lambda: pin.aba(model, data, q, v, tau))
    if cpp is not None:
        cm = CppModel(cpp, model)
        _, a = cm.aba(q, v, 1)
        err = np.max(np.abs(smap.ud(q, v, a) - ref)) / scale
        if not err <= max(tol, 2.0 * row["err pin aba"]):  # compiled apart: rounding may move
            raise AssertionError(f"{kind} N = {N}: the C++ model's aba differs from Pinocchio's dense solve by "
                                 f"{err:.1e}, Pinocchio's own aba by {row['err pin aba']:.1e}: not the same model?")
        row["pin C++"] = median_loop(lambda n: cm.aba(q, v, n)[0])
        cm.close()
    return row


def time_straight(system, y, bound, loop, row):
    """The same ``fun`` printed without loops over repeated blocks (straight-line, as before
    issue 32's loops) timed into ``row["straight C"]``, with its largest relative difference
    from the printed program's ``dy/dt`` (``row["rolled vs straight"]``: 0, the same
    operations in the same order)."""
    was, block_loops.BLOCK_MIN = block_loops.BLOCK_MIN, 0
    try:
        code0 = Code(trace(system, 3_000_000, program="fun"), "c")
    finally:
        block_loops.BLOCK_MIN = was
    bound0 = Bound(code0, system)
    dy0 = bound0.run_fun(T0, y, 0.0, 0.0)
    dy = bound.run_fun(T0, y, 0.0, 0.0)
    row["rolled vs straight"] = np.max(np.abs(np.asarray(dy) - dy0)) / np.max(np.abs(dy0))
    bound0.yin[:y.size] = y
    _, _, pd, ph, pp, pw, _, _, py = bound0.ptrs
    pq, pu = bound0.fun_args
    f0 = ctypes.cast(code0.dll.mbcomp_fun, ctypes.c_void_p).value
    row["straight C"] = median_loop(lambda n: loop(f0, pq, pu, pd, ph, pp, pw, py, n))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--Ns", default="10,40,100")
    ap.add_argument("--mechanisms", default="chain,tree")
    ap.add_argument("--straight", action="store_true",
                    help="also time the same program printed without loops (straight-line, as before issue 32's loops)")
    args = ap.parse_args(argv)
    loop = c_loop()
    cpp, why = cpp_loop()
    if cpp is None:
        print(f"pin C++ column skipped: {why}")
    head = (f"{'mechanism':<14}{'N':>5}{'ops':>9}{'mbcomp C':>10}{'pin C++':>9}{'C/C++':>7}"
            f"{'mbcomp fun':>12}{'pin py':>8}{'fun/py':>7}{'cond M':>9}{'err mb':>9}{'err pin':>9}"
            + (f"{'straight C':>11}{'/C++':>6}{'diff':>9}" if args.straight else ""))
    print("one forward-dynamics call, microseconds (CPU, median of 5 batches); err: max |du/dt - reference| / "
          "max |reference|,\nreference: Pinocchio's crba + nonLinearEffects solved densely (numpy); err mb: mbcomp's "
          "compiled fun, err pin: pinocchio.aba")
    print(head)
    for kind in args.mechanisms.split(","):
        for N in (int(n) for n in args.Ns.split(",")):
            r = measure(kind, N, loop, cpp, args.straight)
            us = {k: r[k] * 1e6 for k in ("mbcomp C", "pin C++", "mbcomp fun", "pin py") if k in r}
            cpp_s = f"{us['pin C++']:9.2f}{us['mbcomp C'] / us['pin C++']:7.2f}" if "pin C++" in us else f"{'-':>9}{'-':>7}"
            name = {"chain": "ball chain", "tree": "floating tree"}[kind]
            print(f"{name:<14}{N:>5}{r['ops']:>9}{us['mbcomp C']:10.2f}{cpp_s}{us['mbcomp fun']:12.2f}"
                  f"{us['pin py']:8.2f}{us['mbcomp fun'] / us['pin py']:7.2f}{r['cond']:9.1e}{r['err compiled']:9.1e}"
                  f"{r['err pin aba']:9.1e}" + _straight_cells(r), flush=True)


def _straight_cells(r):
    """The straight-line program's columns: its time, its ratio to Pinocchio's C++ and the
    largest relative difference of its dy/dt from the printed program's."""
    if "straight C" not in r:
        return ""
    ratio = f"{r['straight C'] / r['pin C++']:6.2f}" if "pin C++" in r else f"{'-':>6}"
    return f"{r['straight C'] * 1e6:11.2f}{ratio}{r['rolled vs straight']:9.1e}"


if __name__ == "__main__":
    main()
