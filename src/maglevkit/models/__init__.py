"""Magnet models: statics of the equivalent circuit and the flux-based DAE (the
current-based model and the bank are in :mod:`maglevkit.reduced`).

:func:`maglevkit.simulate` (one entry for every model) is in :mod:`maglevkit.simulation`,
above the reduced models; :func:`simulate_flux` is its flux-model branch.
"""

from .characteristics import (
    KNEE_EXPONENT,
    Coupling,
    coupling_ratios,
    force_exponent,
    nominal_point,
    saturation_knee,
)
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
    simulate_flux,
)
from .scenario import Scenario, bundled_scenarios, load_scenario, parse_scenario
from .signals import Constant, Ramp, Signal, Sine, Step, Tabulated, parse_signal
from .statics import StaticSolution, coenergy, magnetic_energy, pole_force_eq6, solve_statics

__all__ = [
    "DEFAULT_ATOL",
    "DEFAULT_RTOL",
    "Constant",
    "Coupling",
    "KNEE_EXPONENT",
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
    "coupling_ratios",
    "force_exponent",
    "nominal_point",
    "saturation_knee",
    "differential_inductance_from_step",
    "load_scenario",
    "magnetic_energy",
    "parse_scenario",
    "parse_signal",
    "pole_force_eq6",
    "simulate_flux",
    "solve_statics",
    "voltage_step_response",
]
