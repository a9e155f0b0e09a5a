"""Reduced circuits (paper eq. 8 on the characteristic maps): the current-based model of one
magnet, the bank of many magnets, its in-place stepper and the compiled cell-table kernel.

Above :mod:`maglevkit.reduction` (which builds the maps) and :mod:`maglevkit.models` (statics
and the detailed flux model).
"""

from .bank import (
    KERNEL_PARAMETERS,
    RUN_CHUNK,
    BankOutputs,
    BankRun,
    BankSimulation,
    BankState,
    MagnetBank,
    StepFlag,
)
from .current import (
    CurrentModel,
    CurrentModelLinearization,
    CurrentModelState,
    CurrentOutputs,
    ReducedSimulation,
)
from .stepper import BankStepper

__all__ = [
    "KERNEL_PARAMETERS",
    "RUN_CHUNK",
    "BankOutputs",
    "BankRun",
    "BankSimulation",
    "BankState",
    "BankStepper",
    "CurrentModel",
    "CurrentModelLinearization",
    "CurrentModelState",
    "CurrentOutputs",
    "MagnetBank",
    "ReducedSimulation",
    "StepFlag",
]
