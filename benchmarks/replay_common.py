"""A vehicle run's magnet replayed through its detailed model: shared by
``measure_vehicle_eddy_modes`` (a TR09 levitation circuit pair) and
``measure_cross_guidance_network`` (a guidance magnet of the cross-section).

The scripts record the voltages, gaps and gap rates the magnet bank received at every
step, feed one magnet's circuits through ``FluxModel.step`` (every pole at its circuit's
gap) and compare the coil currents' component at the excitation frequency.  The scripts
put this folder on ``sys.path`` to import it (as they do ``fem_common``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

import maglevkit as mk


def replay_detailed(magnet: Any, pole_groups: dict[str, Sequence[str]],
                    calls: Sequence[tuple[np.ndarray, ...]], idx: Sequence[int], *,
                    initial_gaps_m: np.ndarray, initial_currents_A: np.ndarray,
                    first_row_A: np.ndarray | None = None, dt_s: float = 1e-3) -> np.ndarray:
    """The detailed model's coil currents [A] of the circuits ``idx`` of the bank under the
    recorded inputs.

    Parameters
    ----------
    magnet : Magnet
        The detailed model's magnet (its circuits are the bank's ``idx``, in order).
    pole_groups : dict
        Circuit name -> its poles (the maps' ``pole_groups``): every pole gets its
        circuit's gap and gap rate.
    calls : sequence of (voltages [V], gaps [m], gap rates [m/s])
        The bank's inputs at every step, over all its circuits.
    idx : sequence of int
        The magnet's circuits among the bank's.
    initial_gaps_m, initial_currents_A : ndarray
        Per circuit: the start of the replay (the steady state there).
    first_row_A : ndarray, optional
        Row 0 of the result (default ``initial_currents_A``).
    dt_s : float
        The recorded step [s].

    Returns
    -------
    ndarray
        ``(len(calls) + 1, len(idx))``: row 0 the start, row ``k + 1`` after step ``k``.
    """
    flux = mk.FluxModel(magnet)
    gap_names = list(flux.gap_names)

    def poles(vals: np.ndarray) -> np.ndarray:
        out = np.full(len(gap_names), np.nan)
        for c, val in zip(flux.circuit_names, vals, strict=True):
            for p in pole_groups[c]:
                out[gap_names.index(p)] = val
        assert not np.isnan(out).any()
        return out

    st = flux.initial_state(gaps_m=poles(initial_gaps_m), currents_A=initial_currents_A)
    ref = np.empty((len(calls) + 1, len(idx)))
    ref[0] = initial_currents_A if first_row_A is None else first_row_A
    for k, (u, g, r) in enumerate(calls):
        st, out = flux.step(st, dt_s, u[idx], poles(g[idx]), poles(r[idx]))
        ref[k + 1] = out.currents_A
    return ref


def fundamental_errors(t_s: np.ndarray, currents_A: np.ndarray, reference_A: np.ndarray,
                       gap_m: np.ndarray, f_hz: float, *, from_s: float = 0.1
                       ) -> dict[str, float]:
    """The vehicle's coil currents against the replayed reference after ``from_s`` [s].

    ``currents_A`` and ``reference_A`` are ``(time, circuits)``; ``gap_m`` the excited gap
    over time.  Returns the RMS current error and the reference's RMS variation [A], and
    gain [A/m] and phase [deg] of the first circuit's component at ``f_hz`` per metre of
    gap (the vehicle's, the reference's, and the phase error).
    """
    sel = t_s >= from_s
    ph = np.exp(-2j * np.pi * f_hz * t_s[sel])
    g = gap_m[sel]
    gain = 2 * np.mean((g - g.mean()) * ph)

    def fund(x: np.ndarray) -> complex:
        return complex(2 * np.mean((x - x.mean()) * ph) / gain)

    veh, ref = currents_A[sel], reference_A[sel]
    zv, zr = fund(veh[:, 0]), fund(ref[:, 0])
    return {"rms_error_A": float(np.sqrt(np.mean((veh - ref) ** 2))),
            "rms_variation_A": float(np.sqrt(np.mean((ref - ref.mean(axis=0)) ** 2))),
            "gain_A_per_m": abs(zv), "gain_reference_A_per_m": abs(zr),
            "phase_deg": math.degrees(np.angle(zv)),
            "phase_reference_deg": math.degrees(np.angle(zr)),
            "phase_error_deg": math.degrees(np.angle(zv / zr))}
