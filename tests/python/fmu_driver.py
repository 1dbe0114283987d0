"""A hand-written co-simulation master on fmpy's FMU2Slave, shared by the
tests and, as a script, used to restore a serialized FMU state in a fresh
process:

    python fmu_driver.py UNZIPDIR STATE_FILE T0 H N   -> JSON list of outputs
"""

import json
import math
import sys
from ctypes import byref

from fmpy import calloc, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy


# fmpy's logging proxy (`addLoggerProxy`) keeps a process-wide pointer to
# the last callbacks it was given, and later instances that log through the
# proxy call it: a Recorder's callbacks must outlive it, or a later test's
# FMU logs into freed memory (a segfault in fmpy's logMessage). Every
# Recorder's callbacks are kept here for the life of the process.
_KEEP_ALIVE = []


class Recorder:
    """FMI callbacks that keep the FMU's log messages (status, category, text)."""

    def __init__(self):
        self.messages = []

        def log(env, name, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        self._log = fmi2CallbackLoggerTYPE(log)  # keep a reference
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self._log
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))
        _KEEP_ALIVE.append((self._log, self.callbacks))

    def has(self, status, *needles):
        return any(s >= status and all(n in m for n in needles) for s, _, m in self.messages)


def slave(unzipdir, name="inst", guid=None):
    md = read_model_description(unzipdir)
    fmu = FMU2Slave(
        guid=guid or md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=name,
    )
    return md, fmu


def outputs(md, fmu):
    """Every output, Real and Boolean, in model-description order."""
    values = []
    for v in md.modelVariables:
        if v.causality != "output":
            continue
        if v.type == "Real":
            values.append(fmu.getReal([v.valueReference])[0])
        elif v.type == "Boolean":
            values.append(float(fmu.getBoolean([v.valueReference])[0]))
    return values


def steps(fmu, t, h, n):
    for _ in range(n):
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
    return t


def restore_and_continue(unzipdir, state_file, t0, h, n):
    md, fmu = slave(unzipdir, "fresh")
    rec = Recorder()
    fmu.instantiate(callbacks=rec.callbacks)
    with open(state_file, "rb") as f:
        data = f.read()
    state = fmu.deSerializeFMUstate(data)
    fmu.setFMUstate(state)
    fmu.freeFMUstate(state)
    steps(fmu, t0, h, n)
    values = outputs(md, fmu)
    fmu.terminate()
    fmu.freeInstance()
    assert all(math.isfinite(x) for x in values)
    return values


if __name__ == "__main__":
    unzipdir, state_file, t0, h, n = sys.argv[1:6]
    print(json.dumps(restore_and_continue(unzipdir, state_file, float(t0), float(h), int(n))))
