"""Magnet models: statics of the equivalent circuit, flux-based DAE, current-based ODE."""

from .bank import BankOutputs, BankSimulation, BankState, MagnetBank
from .current import CurrentModel, CurrentModelState, CurrentOutputs, ReducedSimulation
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
from .stepper import BankStepper

__all__ = [
    "BankOutputs",
    "BankSimulation",
    "BankState",
    "BankStepper",
    "DEFAULT_ATOL",
    "DEFAULT_RTOL",
    "Constant",
    "CurrentModel",
    "CurrentModelState",
    "CurrentOutputs",
    "EnergyBalance",
    "FluxModel",
    "FluxOutputs",
    "FluxState",
    "InductanceEstimate",
    "MagnetBank",
    "Ramp",
    "ReducedSimulation",
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
