"""Magnet models: statics of the equivalent circuit and the flux-based DAE (the
current-based model and the bank are in :mod:`maglevkit.reduced`)."""

from .experiments import (
    InductanceEstimate,
    differential_inductance_from_step,
    voltage_step_response,
)
from .flux import (
    DEFAULT_ATOL,
    DEFAULT_RTOL,
    EnergyBalance,
    FluxModel,
    FluxOutputs,
    FluxState,
    SimulationResult,
    simulate,
)
from .scenario import Scenario, bundled_scenarios, load_scenario, parse_scenario
from .signals import Constant, Ramp, Signal, Sine, Step, Tabulated, parse_signal
from .statics import StaticSolution, coenergy, magnetic_energy, pole_force_eq6, solve_statics

__all__ = [
    "DEFAULT_ATOL",
    "DEFAULT_RTOL",
    "Constant",
    "EnergyBalance",
    "FluxModel",
    "FluxOutputs",
    "FluxState",
    "InductanceEstimate",
    "Ramp",
    "Scenario",
    "Signal",
    "SimulationResult",
    "Sine",
    "StaticSolution",
    "Step",
    "Tabulated",
    "bundled_scenarios",
    "coenergy",
    "differential_inductance_from_step",
    "load_scenario",
    "magnetic_energy",
    "parse_scenario",
    "parse_signal",
    "pole_force_eq6",
    "simulate",
    "solve_statics",
    "voltage_step_response",
]
