"""One :func:`simulate` for every magnet model: flux model, reduced model, bank of circuits.

It sits above the models it runs (the flux model in :mod:`maglevkit.models.flux`, the reduced
:class:`~maglevkit.reduced.current.CurrentModel` and :class:`~maglevkit.reduced.bank.MagnetBank`)
so none of them has to import another to serve as the common entry point.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, overload

from .errors import InputError
from .models.flux import SimulationResult, simulate_flux
from .reduced.bank import BankSimulation, MagnetBank
from .reduced.current import CurrentModel, ReducedSimulation
from .reduction.maps import CharacteristicMaps
from .validation import real_array

__all__ = ["simulate"]


@overload
def simulate(model: CurrentModel, t: Any, *, gaps: Any, voltages: Any, gap_rates: Any = None,
             dt: float | None = None, initial_currents: Any = None,
             initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> ReducedSimulation: ...


@overload
def simulate(model: MagnetBank, t: Any, *, gaps: Any, voltages: Any, gap_rates: Any = None,
             dt: float | None = None, initial_currents: Any = None,
             initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> BankSimulation: ...


@overload
def simulate(model: Any, t: Any, *, gaps: Any, voltages: Any, gap_rates: Any = None,
             dt: float | None = None, initial_currents: Any = None,
             initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> SimulationResult: ...


def simulate(model: Any, t: Any, *, gaps: Any, voltages: Any, gap_rates: Any = None,
             dt: float | None = None, initial_currents: Any = None,
             initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> SimulationResult | ReducedSimulation | BankSimulation:
    """Simulate a magnet model on a time grid.

    Parameters
    ----------
    model : FluxModel, CurrentModel, MagnetBank, Magnet or Network
        A :class:`~maglevkit.reduced.current.CurrentModel` or
        :class:`~maglevkit.reduced.bank.MagnetBank` runs its own ``simulate`` with the same
        inputs and conventions; anything else runs the flux model
        (:func:`~maglevkit.models.flux.simulate_flux`), where ``options`` (``saturation``,
        ``eddy_currents``, ``method``, ``rtol``, ``atol``, ...) build a
        :class:`~maglevkit.models.flux.FluxModel` (or change a given one).
    t : (t0, tf), [t0, tf] or array
        A time span [s] (with ``dt``) or an explicit increasing grid [s].
    gaps : float, sequence, mapping, Signal, callable or array
        Gaps [m]; they move linearly between samples.
    voltages : same forms
        Circuit voltages [V]; zero-order hold on each interval.
    gap_rates : same forms, optional
        Gap rates [m/s], checked against the gaps' secants within ``gap_rate_tolerance``.
    dt : float, optional
        Grid step [s] with a time span (default 1e-4 s).
    initial_currents : float, sequence or mapping, optional
        Start at the static operating point with these currents [A].
    initial_state : optional
        Start from this state of the same model instead.
    gap_rate_tolerance : float
        Allowed relative disagreement of given gap rates with the gaps (default 0.02).

    Returns
    -------
    SimulationResult, ReducedSimulation or BankSimulation
        By model (see :func:`~maglevkit.models.flux.simulate_flux` for the conventions).

    Raises
    ------
    InputError
        Invalid inputs, or ``options`` given with a reduced model (they are flux-model
        options; the reduced models take theirs when they are built).
    SolverError
        The integrator failed.
    """
    if isinstance(model, CharacteristicMaps):
        raise InputError("simulate: model is characteristic maps, which describe a magnet but "
                         "do not run; build CurrentModel(maps) first (or MagnetBank for "
                         "several) and simulate that")
    if isinstance(model, (CurrentModel, MagnetBank)):
        if initial_currents is not None:
            real_array(initial_currents if not isinstance(initial_currents, Mapping)
                       else list(initial_currents.values()), "initial_currents", "A")
        if options:
            raise InputError(f"options {sorted(options)} apply to the flux model; build the "
                             f"{type(model).__name__} with its own options instead")
        return model.simulate(t, gaps=gaps, voltages=voltages, gap_rates=gap_rates, dt=dt,
                              initial_currents=initial_currents, initial_state=initial_state,
                              gap_rate_tolerance=gap_rate_tolerance)
    return simulate_flux(model, t, gaps=gaps, voltages=voltages, gap_rates=gap_rates, dt=dt,
                         initial_currents=initial_currents, initial_state=initial_state,
                         gap_rate_tolerance=gap_rate_tolerance, **options)
