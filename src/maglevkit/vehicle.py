"""Mechanical models the magnets are coupled to.

Only the simplest one so far: a rigid mass moving in heave under gravity, the magnet force
and an external force (the magnet's share of a vehicle, for gap-control studies).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import InputError, ParameterError

__all__ = ["HeaveMass", "HeaveState", "STANDARD_GRAVITY"]

STANDARD_GRAVITY = 9.80665
"""m/s^2"""


@dataclass(frozen=True)
class HeaveState:
    """Gap [m] and gap rate [m/s] of the heave mass (the gap grows downwards)."""

    gap_m: float
    gap_rate_m_per_s: float


@dataclass(frozen=True)
class HeaveMass:
    """Rigid mass under an attracting magnet: ``m s'' = m g + F_ext - F_mag``.

    The gap ``s`` grows when the mass moves away from the rail (downwards for a
    levitation magnet), so gravity opens the gap and the magnet force closes it.

    Parameters
    ----------
    mass_kg : float
        Carried mass [kg] (> 0).
    gravity : float
        Gravitational acceleration [m/s^2] (>= 0; 0 for a guidance magnet).
    """

    mass_kg: float
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mass_kg) and self.mass_kg > 0):
            raise ParameterError(f"mass_kg = {self.mass_kg!r} must be a finite number > 0")
        if not (math.isfinite(self.gravity) and self.gravity >= 0):
            raise ParameterError(f"gravity = {self.gravity!r} m/s^2 must be finite and >= 0")

    def acceleration(self, magnet_force_N: float, external_force_N: float = 0.0) -> float:
        """Gap acceleration [m/s^2]."""
        return self.gravity + (external_force_N - magnet_force_N) / self.mass_kg

    def step(self, state: HeaveState, dt: float, magnet_force_N: float,
             external_force_N: float = 0.0) -> HeaveState:
        """Advance by ``dt`` [s] with forces held constant (exact for constant acceleration)."""
        if not (math.isfinite(dt) and dt > 0):
            raise InputError(f"dt = {dt!r} s must be a finite number > 0")
        if not (math.isfinite(magnet_force_N) and math.isfinite(external_force_N)):
            raise InputError("forces must be finite")
        a = self.acceleration(magnet_force_N, external_force_N)
        return HeaveState(state.gap_m + state.gap_rate_m_per_s * dt + 0.5 * a * dt * dt,
                          state.gap_rate_m_per_s + a * dt)
