"""Exudyn peers of ``bench/peers.py``: the planar N-link pendulum and the slider-crank, each
integrated by Exudyn's own C++ solvers (what an Exudyn user runs).

* ``pendulum(N, phi0, w0)``: ``ObjectKinematicTree`` (minimal coordinates: the relative hinge
  angles, as mbcomp's), N ``RevoluteZ`` joints, joint k+1 at ``(0, -L, 0)`` in link k, each
  link a rod of mass ``m`` with its centre at ``(0, -L/2, 0)`` and central inertia
  ``diag(m L^2/12, 0, m L^2/12)``, gravity ``(0, -g, 0)``: ``models/n_link_pendulum.py``.
  Solved by Exudyn's explicit adaptive solvers (``DOPRI5``, ``DVERK6``) with
  ``relativeTolerance = absoluteTolerance = tol``.
* ``slider_crank(phi0, w0)``: ``models/slider_crank.py`` in Exudyn's redundant coordinates
  (``ObjectRigidBody2D`` crank and rod, a ``MassPoint2D`` slider, ``RevoluteJoint2D`` pins, a
  ``CoordinateConstraint`` holding the slider on the x axis; gravity as
  ``LoadMassProportional``): an index-3 DAE, which Exudyn's explicit solvers do not take, so
  it runs on its implicit generalized-alpha solver (no error control: the step count is the
  setting, ``h = t_end / steps``). The start is consistent (positions and velocities from the
  loop's closure, computed here).

``run(tol_or_steps) -> (cpu_s, y_end)``: CPU seconds of ``SolveDynamic`` alone (the system
is built and assembled before, untimed, like the other peers' models) and the state at the
end ``[q, u]`` (the pendulum's relative angles and rates; the slider-crank's crank angle,
slider position, crank rate, slider speed). Exudyn writes no dense output on a grid, so its
error is measured at ``t_end`` only.
"""
import math
import time

import numpy as np

__all__ = ["available", "pendulum", "slider_crank"]


def available():
    try:
        import exudyn  # noqa: F401
    except ImportError as exc:
        return f"exudyn not installed ({exc}); pip install exudyn"
    return None


def _settings(t_end, steps):
    import exudyn as exu

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = t_end
    ti.numberOfSteps = int(steps)
    ti.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 1e30
    s.show.computationTime = False
    s.show.statistics = False
    return s


class Pendulum:
    """The N-link pendulum as an Exudyn kinematic tree."""

    def __init__(self, N, phi0, w0, L=0.5, m=1.0, g=9.81, t_end=10.0):
        self.args = (int(N), np.asarray(phi0, float), np.asarray(w0, float), L, m, g)
        self.t_end = t_end

    def _system(self):
        import exudyn as exu
        from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

        N, phi0, w0, L, m, g = self.args
        It = m * L * L / 12.0
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * N, initialCoordinates=list(phi0),
                                           initialCoordinates_t=list(w0), numberOfODE2Coordinates=N))
        mbs.AddObject(ObjectKinematicTree(
            nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * N, linkParents=list(range(-1, N - 1)),
            jointTransformations=exu.Matrix3DList([np.eye(3)] * N),
            jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] + [[0.0, -L, 0.0]] * (N - 1)),
            linkInertiasCOM=exu.Matrix3DList([np.diag([It, 0.0, It])] * N),
            linkCOMs=exu.Vector3DList([[0.0, -L / 2, 0.0]] * N), linkMasses=[m] * N, gravity=[0.0, -g, 0.0]))
        mbs.Assemble()
        return SC, mbs

    def run(self, tol, solver="DOPRI5"):
        import exudyn as exu

        SC, mbs = self._system()
        s = _settings(self.t_end, 100)
        s.timeIntegration.automaticStepSize = True
        s.timeIntegration.relativeTolerance = tol
        s.timeIntegration.absoluteTolerance = tol
        c0 = time.process_time()
        ok = mbs.SolveDynamic(s, solverType=getattr(exu.DynamicSolverType, solver))
        cpu_s = time.process_time() - c0
        if not ok:
            raise RuntimeError(f"Exudyn {solver} failed at tol {tol:g}")
        return cpu_s, np.concatenate((mbs.systemData.GetODE2Coordinates(), mbs.systemData.GetODE2Coordinates_t()))


def slider_crank_start(phi0, w0, a=0.2, b=0.6):
    """Consistent start of the loop: crank angle ``phi0`` (rad), rate ``w0`` (rad/s), crank
    ``a``, rod ``b`` (m) -> rod angle (absolute, rad), its rate, slider position, speed."""
    P = a * np.array([math.cos(phi0), math.sin(phi0)])
    vP = w0 * np.array([-P[1], P[0]])
    xs = P[0] + math.sqrt(b * b - P[1] ** 2)
    th = math.atan2(-P[1], xs - P[0])
    wr = -vP[1] / (b * math.cos(th))
    vs = vP[0] - b * wr * math.sin(th)
    return th, wr, xs, vs


class SliderCrank:
    """``models/slider_crank.py`` (defaults) in Exudyn's redundant 2-D coordinates."""

    def __init__(self, phi0=0.3, w0=6.0, a=0.2, b=0.6, m_crank=1.0, m_rod=2.0, m_slider=0.5, g=9.81, t_end=10.0):
        self.p = dict(phi0=phi0, w0=w0, a=a, b=b, mc=m_crank, mr=m_rod, ms=m_slider, g=g)
        self.t_end = t_end

    def _system(self):
        import exudyn as exu
        from exudyn.itemInterface import (CoordinateConstraint, LoadMassProportional, MarkerBodyMass,
                                          MarkerBodyPosition, MarkerNodeCoordinate, MassPoint2D, NodePoint2D,
                                          NodePointGround, NodeRigidBody2D, ObjectGround, ObjectRigidBody2D,
                                          RevoluteJoint2D)

        p = self.p
        a, b, phi, w = p["a"], p["b"], p["phi0"], p["w0"]
        th, wr, xs, vs = self.start = slider_crank_start(phi, w, a, b)
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        e = lambda t: np.array([math.cos(t), math.sin(t)])  # noqa: E731
        perp = lambda t: np.array([-math.sin(t), math.cos(t)])  # noqa: E731
        rc, vc = a / 2 * e(phi), w * a / 2 * perp(phi)
        P, vP = a * e(phi), w * a * perp(phi)
        rr, vr = P + b / 2 * e(th), vP + wr * b / 2 * perp(th)
        bodies = []
        for (r, v, ang, rate, m, L) in ((rc, vc, phi, w, p["mc"], a), (rr, vr, th, wr, p["mr"], b)):
            n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[r[0], r[1], ang], initialVelocities=[v[0], v[1], rate]))
            bodies.append(mbs.AddObject(ObjectRigidBody2D(physicsMass=m, physicsInertia=m * L * L / 12.0, nodeNumber=n)))
        ns = mbs.AddNode(NodePoint2D(referenceCoordinates=[xs, 0.0], initialVelocities=[vs, 0.0]))
        slider = mbs.AddObject(MassPoint2D(physicsMass=p["ms"], nodeNumber=ns))
        crank, rod = bodies
        mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
        pins = [(mg, mbs.AddMarker(MarkerBodyPosition(bodyNumber=crank, localPosition=[-a / 2, 0.0, 0.0]))),
                (mbs.AddMarker(MarkerBodyPosition(bodyNumber=crank, localPosition=[a / 2, 0.0, 0.0])),
                 mbs.AddMarker(MarkerBodyPosition(bodyNumber=rod, localPosition=[-b / 2, 0.0, 0.0]))),
                (mbs.AddMarker(MarkerBodyPosition(bodyNumber=rod, localPosition=[b / 2, 0.0, 0.0])),
                 mbs.AddMarker(MarkerBodyPosition(bodyNumber=slider, localPosition=[0.0, 0.0, 0.0])))]
        for m0, m1 in pins:
            mbs.AddObject(RevoluteJoint2D(markerNumbers=[m0, m1]))
        ng = mbs.AddNode(NodePointGround())
        mng = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
        msy = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ns, coordinate=1))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mng, msy]))
        for body in (crank, rod, slider):
            mk = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
            mbs.AddLoad(LoadMassProportional(markerNumber=mk, loadVector=[0.0, -p["g"], 0.0]))
        mbs.Assemble()
        self.nodes = (mbs.GetObject(crank)["nodeNumber"], ns)
        return SC, mbs

    def run(self, steps, solver="GeneralizedAlpha"):
        """``(cpu_s, [crank angle, slider position, crank rate, slider speed])`` at t_end."""
        import exudyn as exu

        SC, mbs = self._system()
        s = _settings(self.t_end, steps)
        s.timeIntegration.automaticStepSize = False
        # Newton to 1e-10 (the default 1e-8 would be the error floor); spectral radius left at
        # Exudyn's default 0.9 (1.0, no numerical damping, makes its Newton fail on this loop)
        s.timeIntegration.newton.relativeTolerance = 1e-10
        c0 = time.process_time()
        ok = mbs.SolveDynamic(s, solverType=getattr(exu.DynamicSolverType, solver))
        cpu_s = time.process_time() - c0
        if not ok:
            raise RuntimeError(f"Exudyn {solver} failed with {steps} steps")
        nc, ns = self.nodes
        qc = mbs.GetNodeOutput(nc, exu.OutputVariableType.Coordinates)
        vc = mbs.GetNodeOutput(nc, exu.OutputVariableType.Coordinates_t)
        qs = mbs.GetNodeOutput(ns, exu.OutputVariableType.Coordinates)
        vsl = mbs.GetNodeOutput(ns, exu.OutputVariableType.Coordinates_t)
        # node coordinates are displacements from the reference configuration (the start)
        return cpu_s, np.array([self.p["phi0"] + qc[2], self.start[2] + qs[0], vc[2], vsl[0]])


def pendulum(N, phi0, w0, **kw):
    return Pendulum(N, phi0, w0, **kw)


def slider_crank(**kw):
    return SliderCrank(**kw)
