"""The units of a system's result columns, declared where the columns are made.

One table for the results (:attr:`mbcomp.simulation.result.Result.units`, CSV headers on
request) and the FMU's output variables (:mod:`mbcomp.export.description`):

* coordinates and speeds: the joints' declared units (``coordinates``, ``speeds``); a speed's
  rate ``<speed>.der`` per second;
* reactions ``<joint>.f.*`` (N) and ``<joint>.tau.*`` (N m); a drive's effort ``tau`` (N m) or
  ``f`` (N) by its joint's axis kind, and its ``power`` (W); a joint's own outputs by its
  ``output_units`` (a rod's ``f_rod`` in N, a cut sensor's ``force.*`` in N);
* bodies: ``r`` (m), ``v`` (m/s), ``w`` (rad/s), ``Q`` (1), momenta (kg m/s, kg m^2/s);
* force and flange elements: ``power`` (W), ``potential`` (J), and the outputs a component
  declares in its ``output_units`` (``{"f": "N", "length": "m"}``);
* the system: ``energy.*`` (J), ``momentum.*`` (kg m/s), ``angular_momentum.*`` (kg m^2/s).

Mixed columns (residuals, multipliers, outputs whose unit nobody declares) have none.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> units = column_units(mbcomp.assemble(m))
>>> units["j.phi"], units["j.w.der"], units["j.tau.z"], units["bob.v.x"], units["energy.total"]
('rad', 'rad/s^2', 'N m', 'm/s', 'J')
"""
from __future__ import annotations

from ..modeling.units import per_second, unit_exponents

__all__ = ["column_units"]

_XYZ = "xyz"


def column_units(system):
    """``{column name: unit text}`` of the result columns of ``system`` whose unit is declared
    (texts as mbcomp writes units: ``"rad"``, ``"N m"``, ``"m/s"``; each one the FMU can read,
    :func:`mbcomp.modeling.units.unit_exponents`). A name may be listed for a column a run
    does not make (a drive's power when the drive is on no 1-D joint)."""
    topo, out = system.topology, {}

    def put(name, text):
        if text and unit_exponents(text) is not None:
            out[name] = text

    for name, u in zip(system.q_names, topo.q_units):
        put(name, u)
    for name, u in zip(system.u_names, topo.u_units):
        put(name, u)
        put(f"{name}.der", per_second(u))
    for e in topo.edges:
        if e.kind == "joint" and e.dof == 1 and e.q.stop == e.q.start and e.comp.coordinates:
            (cn, cu), (sn, su) = e.comp.coordinates[0], e.comp.speeds[0]
            put(f"{e.name}.{cn}", cu)
            put(f"{e.name}.{sn}", su)
        for ax in _XYZ:
            put(f"{e.name}.f.{ax}", "N")
            put(f"{e.name}.tau.{ax}", "N m")
        if e.drive:
            rotational = e.comp.axis_kind == "rotational"
            put(f"{e.drive}.tau" if rotational else f"{e.drive}.f", "N m" if rotational else "N")
            put(f"{e.drive}.power", "W")
        if e.kind == "joint":
            for key, text in getattr(e.comp, "output_units", {}).items():
                put(f"{e.name}.{key}", text)
    for path, _comp, _node in topo.bodies:
        for ax in _XYZ:
            for suffix, text in (("r", "m"), ("v", "m/s"), ("w", "rad/s"), ("momentum", "kg m/s"),
                                 ("angular_momentum", "kg m^2/s")):
                put(f"{path}.{suffix}.{ax}", text)
        for c in "wxyz":
            put(f"{path}.Q.{c}", "1")
    elements = [(path, comp) for path, comp, _ports in topo.forces] + list(topo.flange_elements) + list(topo.flange_constraints)
    for path, comp in elements:
        put(f"{path}.power", "W")
        put(f"{path}.power_nc", "W")
        put(f"{path}.potential", "J")
        for key, text in getattr(comp, "output_units", {}).items():
            put(f"{path}.{key}", text)
    for k in ("kinetic", "potential", "total", "work", "dissipated", "balance"):
        put(f"energy.{k}", "J")
    for ax in _XYZ:
        put(f"momentum.{ax}", "kg m/s")
        put(f"angular_momentum.{ax}", "kg m^2/s")
    return out
