"""What the FMU-state tests drive an FMU with through FMPy alone (no mbcomp): open an instance,
step it, read values. Run as a script it is the "new process" of the serialization test:

    python fmu_state_child.py FMU FMI STATE_FILE T H N NAME...

instantiates the FMU's Co-Simulation, deserializes the bytes of STATE_FILE, sets them, takes N
steps of H from T and prints, per step, the values of NAME... as exact hexadecimal floats (one
line of JSON per step)."""
import ctypes
import json
import sys

import numpy as np

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

CLASSES = {("3.0", "cs"): FMU3Slave, ("3.0", "me"): FMU3Model, ("2.0", "cs"): FMU2Slave, ("2.0", "me"): FMU2Model}


class Instance:
    """One FMPy instance of ``path`` (FMI ``fmi``, ``kind`` "cs" or "me") with the parameter
    values ``params`` (by name), initialized at t = 0 with the relative tolerance ``tol``;
    ``get(names)`` reads Float64 values by name."""

    def __init__(self, path, fmi, kind, tol=1e-10, params=None, unzipped=None):
        md = read_model_description(str(path))
        self.fmi, self.kind = fmi, kind
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        iface = md.coSimulation if kind == "cs" else md.modelExchange
        self.fmu = CLASSES[fmi, kind](guid=md.guid, unzipDirectory=unzipped or extract(str(path)),
                                      modelIdentifier=iface.modelIdentifier)
        self.fmu.instantiate()
        self.nx = sum(v.derivative is not None for v in md.modelVariables)  # the continuous states
        for name, value in (params or {}).items():
            self.set(name, value)
        if fmi == "2.0":
            self.fmu.setupExperiment(tolerance=tol, startTime=0.0)
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(tolerance=tol, startTime=0.0)
        self.fmu.exitInitializationMode()
        if kind == "me":
            self.update()
            self.fmu.enterContinuousTimeMode()
        self.t = 0.0

    def get(self, names):
        vrs = [self.vr[n] for n in names]
        return list(self.fmu.getReal(vrs) if self.fmi == "2.0" else self.fmu.getFloat64(vrs))

    def set(self, name, value):
        (self.fmu.setReal if self.fmi == "2.0" else self.fmu.setFloat64)([self.vr[name]], [value])

    # Model Exchange: the continuous states, their derivatives, CompletedIntegratorStep
    def x(self):
        buf = (ctypes.c_double * self.nx)()
        self.fmu.getContinuousStates(buf, self.nx)
        return np.array(buf)

    def set_x(self, t, x):
        self.fmu.setTime(t)
        self.fmu.setContinuousStates((ctypes.c_double * self.nx)(*x), self.nx)

    def dx(self, t, x):
        """The derivatives at (t, x) (sets them)."""
        self.set_x(t, x)
        buf = (ctypes.c_double * self.nx)()
        (self.fmu.getDerivatives if self.fmi == "2.0" else self.fmu.getContinuousStateDerivatives)(buf, self.nx)
        return np.array(buf)

    def completed(self):
        """CompletedIntegratorStep: whether the FMU asks for Event Mode."""
        return bool(self.fmu.completedIntegratorStep()[0])

    def step(self, h):
        """One Co-Simulation step of h from the instance's time."""
        self.fmu.doStep(self.t, h)
        self.t += h

    def update(self):
        """Event Mode's update; whether the continuous states' values changed."""
        if self.fmi == "2.0":
            info = self.fmu.newDiscreteStates()
            return bool(info[3])
        return bool(self.fmu.updateDiscreteStates()[3])

    # the FMI 3.0 names, for either version (FMPy's 2.0 classes spell them FMUstate)
    def get_state(self, state=None):
        if self.fmi == "3.0":
            return self.fmu.getFMUState() if state is None else _overwrite3(self.fmu, state)
        return self.fmu.getFMUstate() if state is None else _overwrite2(self.fmu, state)

    def set_state(self, state):
        (self.fmu.setFMUState if self.fmi == "3.0" else self.fmu.setFMUstate)(state)

    def free_state(self, state):
        (self.fmu.freeFMUState if self.fmi == "3.0" else self.fmu.freeFMUstate)(state)

    def serialize(self, state):
        return (self.fmu.serializeFMUState if self.fmi == "3.0" else self.fmu.serializeFMUstate)(state)

    def deserialize(self, data):
        return (self.fmu.deserializeFMUState if self.fmi == "3.0" else self.fmu.deSerializeFMUstate)(data)


def _overwrite3(fmu, state):
    from ctypes import byref

    fmu.fmi3GetFMUState(fmu.component, byref(state))
    return state


def _overwrite2(fmu, state):
    from ctypes import byref

    fmu.fmi2GetFMUstate(fmu.component, byref(state))
    return state


def hexes(values):
    return [float(v).hex() for v in values]


def main(argv):
    path, fmi, state_file, t, h, n, *names = argv
    inst = Instance(path, fmi, "cs")
    with open(state_file, "rb") as f:
        state = inst.deserialize(f.read())
    inst.set_state(state)
    inst.free_state(state)
    inst.t = float.fromhex(t)
    for _ in range(int(n)):
        inst.step(float.fromhex(h))
        print(json.dumps(hexes(inst.get(names))))
    inst.fmu.terminate()
    inst.fmu.freeInstance()


if __name__ == "__main__":
    main(sys.argv[1:])
