"""Magnet models: statics of the equivalent circuit, flux-based DAE, current-based ODE."""

from .statics import StaticSolution, coenergy, magnetic_energy, pole_force_eq6, solve_statics

__all__ = ["StaticSolution", "coenergy", "magnetic_energy", "pole_force_eq6", "solve_statics"]
