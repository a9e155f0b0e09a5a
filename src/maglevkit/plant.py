"""The simplest mechanical plant a magnet is coupled to, and gravity.

A rigid mass moving in heave under gravity, the magnet force and an external force (the
magnet's share of a vehicle, for gap-control studies).  It sits below both
:mod:`maglevkit.control` (which designs and runs controllers on it) and
:mod:`maglevkit.vehicle` (whose mechanics use the same gravity); ``maglevkit.vehicle``
re-exports its names.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .errors import ParameterError
from .validation import real_number, renamed_keywords

__all__ = ["HeaveMass", "HeaveState", "STANDARD_GRAVITY", "chopper_floor"]

STANDARD_GRAVITY = 9.80665
"""m/s^2"""


@dataclass(frozen=True)
class HeaveState:
    """Gap [m] and gap rate [m/s] of the heave mass (the gap grows downwards).

    Parameters
    ----------
    gap_m : float
        Air gap s [m] (not checked here; :func:`~maglevkit.control.closed_loop` stops
        when it would reach 0).
    gap_rate_m_per_s : float
        Gap rate ds/dt [m/s], > 0 when the gap opens.
    """

    gap_m: float
    gap_rate_m_per_s: float


@renamed_keywords(gravity="gravity_m_per_s2")
@dataclass(frozen=True)
class HeaveMass:
    """Rigid mass under an attracting magnet: ``m s'' = m g + F_ext - F_mag``.

    The gap ``s`` grows when the mass moves away from the rail (downwards for a
    levitation magnet), so gravity opens the gap and the magnet force closes it.

    Parameters
    ----------
    mass_kg : float
        Carried mass [kg] (> 0).
    gravity_m_per_s2 : float
        Gravitational acceleration [m/s^2] (>= 0; 0 for a guidance magnet).  The old
        name ``gravity`` is a deprecated alias (constructor keyword and attribute).
    """

    mass_kg: float
    gravity_m_per_s2: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        real_number(self.mass_kg, "mass_kg", "kg", positive=True, error=ParameterError)
        real_number(self.gravity_m_per_s2, "gravity_m_per_s2", "m/s^2", nonnegative=True,
                    error=ParameterError)

    def acceleration(self, magnet_force_N: float, external_force_N: float = 0.0) -> float:
        """Gap acceleration [m/s^2]: ``g + (F_ext - F_mag) / m``.

        Parameters
        ----------
        magnet_force_N : float
            Attractive magnet force [N] (closes the gap).
        external_force_N : float, default 0.0
            External force on the mass [N], positive opening the gap (like gravity).

        Returns
        -------
        float
            ``s''`` [m/s^2] (> 0: the gap opens faster).  The forces are not checked here
            (they are in :meth:`step`).
        """
        return self.gravity_m_per_s2 + (external_force_N - magnet_force_N) / self.mass_kg

    @renamed_keywords(dt="dt_s")
    def step(self, state: HeaveState, dt_s: float, magnet_force_N: float,
             external_force_N: float = 0.0) -> HeaveState:
        """Advance by ``dt`` [s] with forces held constant (exact for constant acceleration).

        The old keyword name ``dt`` still works as a deprecated alias (a ``DeprecationWarning`` names the
        new one).

        Parameters
        ----------
        state : HeaveState
            Gap [m] and gap rate [m/s] at the start of the step.
        dt_s : float
            Step [s], finite and > 0.
        magnet_force_N : float
            Attractive magnet force [N], held over the step.
        external_force_N : float, default 0.0
            External force [N], positive opening the gap, held over the step.

        Returns
        -------
        HeaveState
            Gap and gap rate at the end of the step.

        Raises
        ------
        InputError
            ``dt`` not finite and > 0, or a force that is not a finite real number.
        """
        dt = dt_s
        real_number(dt, "dt", "s", positive=True)
        real_number(magnet_force_N, "magnet_force_N", "N")
        real_number(external_force_N, "external_force_N", "N")
        a = self.acceleration(magnet_force_N, external_force_N)
        return HeaveState(state.gap_m + state.gap_rate_m_per_s * dt + 0.5 * a * dt * dt,
                          state.gap_rate_m_per_s + a * dt)


def chopper_floor(u: Any, inductor_current_A: Any, eddy_resistance_ohm: Any) -> Any:
    """The two-quadrant chopper's bound on a reduced circuit's commanded voltage.

    The chopper cannot reverse the coil current.  With eq. 8's circuit (Fig. 8 of the
    paper: coil resistance ``R_el`` in series, the eddy branch ``R_ec`` parallel to the
    inductance) the coil current is ``I = (U + R_ec I_L) / (R_el + R_ec)``, so ``I >= 0``
    is ``U >= -R_ec I_L``, and a command below that is raised to it.  The one place the
    vehicle loops (the NumPy loops and the compiled step) take this bound from; the
    plant's own freewheeling diodes inside the RK4 stages are
    :func:`~maglevkit.reduced.current.eq8_freewheel_voltage`, the same law in eq. 8's
    parameters.

    Parameters
    ----------
    u : ndarray or CasADi
        Commanded voltages [V].
    inductor_current_A : ndarray or CasADi
        Inductor currents ``I_L`` [A] (eq. 8's state).
    eddy_resistance_ohm : ndarray or CasADi
        ``R_ec`` [ohm] per circuit.

    Returns
    -------
    ndarray or CasADi
        ``u`` where ``u >= -R_ec I_L``, else ``-R_ec I_L``; chosen by a comparison (not
        ``max``), so that a NaN command stays NaN in NumPy and in CasADi alike and the
        bank names the same culprit on every path.
    """
    # A circuit without an eddy path (R_ec = inf, as a cross-section's network members may
    # have) at I_L = 0 gives the bound inf * 0 = NaN: no bound, the comparison keeps u
    # (CasADi's if_else alike); NumPy's warning about that product is not the user's.
    if isinstance(u, (ca.SX, ca.MX)) or isinstance(inductor_current_A, (ca.SX, ca.MX)) or \
            isinstance(eddy_resistance_ohm, (ca.SX, ca.MX)):
        low = -eddy_resistance_ohm * inductor_current_A
        return ca.if_else(u < low, low, u)
    with np.errstate(invalid="ignore"):
        low = -np.asarray(eddy_resistance_ohm) * inductor_current_A
    return np.where(u < low, low, u)
