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
from .validation import real_array, renamed_keywords

__all__ = ["simulate"]


@overload
def simulate(model: CurrentModel, times_s: Any, *, gaps_m: Any, voltages_V: Any,
             gap_rates_m_per_s: Any = None, dt_s: float | None = None,
             initial_currents_A: Any = None, initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> ReducedSimulation: ...


@overload
def simulate(model: MagnetBank, times_s: Any, *, gaps_m: Any, voltages_V: Any,
             gap_rates_m_per_s: Any = None, dt_s: float | None = None,
             initial_currents_A: Any = None, initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> BankSimulation: ...


@overload
def simulate(model: Any, times_s: Any, *, gaps_m: Any, voltages_V: Any,
             gap_rates_m_per_s: Any = None, dt_s: float | None = None,
             initial_currents_A: Any = None, initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> SimulationResult: ...


@renamed_keywords(t="times_s", gaps="gaps_m", voltages="voltages_V", gap_rates="gap_rates_m_per_s",
                  dt="dt_s", initial_currents="initial_currents_A")
def simulate(model: Any, times_s: Any, *, gaps_m: Any, voltages_V: Any,
             gap_rates_m_per_s: Any = None, dt_s: float | None = None,
             initial_currents_A: Any = None, initial_state: Any = None, gap_rate_tolerance: float = 0.02,
             **options: Any) -> SimulationResult | ReducedSimulation | BankSimulation:
    """Simulate a magnet model on a time grid.

    The old keyword names ``t``, ``gaps``, ``voltages``, ``gap_rates``, ``dt``, ``initial_currents`` still
    work as deprecated aliases (a ``DeprecationWarning`` names the new one).

    Parameters
    ----------
    model : FluxModel, CurrentModel, MagnetBank, Magnet or Network
        A :class:`~maglevkit.reduced.current.CurrentModel` or
        :class:`~maglevkit.reduced.bank.MagnetBank` runs its own ``simulate`` with the same
        inputs and conventions; anything else runs the flux model
        (:func:`~maglevkit.models.flux.simulate_flux`), where ``options`` (``saturation``,
        ``eddy_currents``, ``method``, ``rtol``, ``atol``, ...) build a
        :class:`~maglevkit.models.flux.FluxModel` (or change a given one).
    times_s : (t0, tf), [t0, tf] or array
        A time span [s] (with ``dt_s``) or an explicit increasing grid [s].
    gaps_m : float, sequence, mapping, Signal, callable or array
        Gaps [m]; they move linearly between samples.
    voltages_V : same forms
        Circuit voltages [V]; zero-order hold on each interval.
    gap_rates_m_per_s : same forms, optional
        Gap rates [m/s], checked against the gaps' secants within ``gap_rate_tolerance``.
    dt_s : float, optional
        Grid step [s] with a time span (default 1e-4 s).
    initial_currents_A : float, sequence or mapping, optional
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
        if initial_currents_A is not None:
            real_array(initial_currents_A if not isinstance(initial_currents_A, Mapping)
                       else list(initial_currents_A.values()), "initial_currents", "A")
        if options:
            raise InputError(f"options {sorted(options)} apply to the flux model; build the "
                             f"{type(model).__name__} with its own options instead")
        return model.simulate(times_s, gaps_m=gaps_m, voltages_V=voltages_V,
                              gap_rates_m_per_s=gap_rates_m_per_s, dt_s=dt_s,
                              initial_currents_A=initial_currents_A, initial_state=initial_state,
                              gap_rate_tolerance=gap_rate_tolerance)
    return simulate_flux(model, times_s, gaps_m=gaps_m, voltages_V=voltages_V,
                         gap_rates_m_per_s=gap_rates_m_per_s, dt_s=dt_s,
                         initial_currents_A=initial_currents_A, initial_state=initial_state,
                         gap_rate_tolerance=gap_rate_tolerance, **options)
