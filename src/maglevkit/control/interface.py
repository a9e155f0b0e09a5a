"""The controller interface shared by every gap controller (cascade, MPC).

A controller is a sampled-data object: :meth:`Controller.reset` once at the start of a
run, then :meth:`Controller.update` once per sample with the latest :class:`Measurement`;
it returns the circuit voltages held until the next sample.  :func:`~maglevkit.control.
closed_loop` (and vehicle models, scenario sweeps) take any object with this interface.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import KW_ONLY, dataclass
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Controller", "Measurement"]


@dataclass(frozen=True)
class Measurement:
    """What a gap controller receives at one sample instant.

    Attributes
    ----------
    time_s : float
        Sample time [s].
    gap_m : float
        Measured gap [m].
    gap_rate_m_per_s : float
        Measured gap rate [m/s] (controllers that estimate it themselves ignore it).
    currents_A : ndarray (n_circuits,)
        Measured coil currents [A] (at the end of the previous hold interval, i.e. with
        the voltages last applied).
    gap_ref_m : float
        Gap reference [m] for this sample.
    absolute_velocity_m_per_s : float or None
        The magnet's absolute vertical velocity [m/s], positive downward (the direction
        that opens the gap), e.g. from an accelerometer; None (default): not measured
        (controllers that use it take the gap rate instead, exact on a rigid, even track).
    applied_voltages_V : ndarray (n_circuits,) or None
        The voltages the actuator actually applied over the last hold interval (their
        mean) [V], when the plant may limit the commanded ones (a two-quadrant chopper
        cannot drive a coil current below zero, a failed circuit gets none); None
        (default): as commanded.  Observers integrate these instead of the commands.
    """

    time_s: float
    gap_m: float
    gap_rate_m_per_s: float
    currents_A: np.ndarray
    gap_ref_m: float
    # the optional channels by keyword only: two merged branches each added a sixth
    # positional field, and a positional call silently filled the wrong one
    _: KW_ONLY
    absolute_velocity_m_per_s: float | None = None
    applied_voltages_V: np.ndarray | None = None


@runtime_checkable
class Controller(Protocol):
    """Sampled-data gap controller.

    Attributes
    ----------
    gap_ref_m : float
        Default gap reference [m] (used when the run gives none).
    voltage_limit_V : float
        Actuator limit ``|U| <= U_max`` [V]; :meth:`update` never returns more.
    """

    @property
    def gap_ref_m(self) -> float: ...

    @property
    def voltage_limit_V(self) -> float: ...

    def reset(self, measurement: Measurement, *, sample_time_s: float) -> None:
        """Start a run at ``measurement`` with the sample time ``sample_time_s`` [s].

        Parameters
        ----------
        measurement : Measurement
            The measurement at the first sample of the run.
        sample_time_s : float
            Sample (hold) time of the controller [s], finite and > 0.
        """
        ...

    def update(self, measurement: Measurement) -> np.ndarray:
        """Voltages [V] (n_circuits,) to hold from this sample to the next.

        Parameters
        ----------
        measurement : Measurement
            The measurement at this sample.

        Returns
        -------
        ndarray (n_circuits,)
            Circuit voltages [V], within ``+-voltage_limit_V``.
        """
        ...

    def diagnostics(self) -> Mapping[str, float | np.ndarray]:
        """Internal values after the last :meth:`update` (estimates, solver statistics),
        recorded by :func:`~maglevkit.control.closed_loop`; names carry units."""
        ...
