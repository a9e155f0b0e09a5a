"""Equivalent magnetic circuit: elements, network topology and symbolic assembly."""

from .assembly import NetworkEquations, assemble
from .elements import (
    AirGap,
    EddyCurrent,
    Element,
    FringePermeance,
    GapLayerPermeance,
    GapLeakage,
    IronPath,
    LeakagePermeance,
    LinearElement,
    carter_coefficient,
)
from .network import Branch, Circuit, Coil, Network

__all__ = [
    "AirGap",
    "Branch",
    "Circuit",
    "Coil",
    "EddyCurrent",
    "Element",
    "FringePermeance",
    "GapLayerPermeance",
    "GapLeakage",
    "IronPath",
    "LeakagePermeance",
    "LinearElement",
    "Network",
    "NetworkEquations",
    "assemble",
    "carter_coefficient",
]
