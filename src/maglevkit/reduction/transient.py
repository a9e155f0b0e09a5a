"""The paper's time-integration identification of ``L~`` and ``dL/ds`` (Sec. IV-B).

Both quantities come from simulations of the detailed flux-based model (``models/flux.py``):

* ``L~(s, I)``: time constant of a small voltage step at a fixed gap
  (:func:`~maglevkit.models.experiments.differential_inductance_from_step`).
* ``dL/ds(s, I)``: the virtual control law ``U = R_el I`` with a linearly increasing gap.
  In the detailed model Faraday's law reads ``psi' = U - R_el I``, so the law holds the
  flux linkages constant.  It is applied *exactly*: the resistive drop is substituted
  into the DAE (``h = [-r(x, s, I); 0]``), not sampled by a zero-order hold.  Eq. 8 then
  reduces to ``dI/dt = -dL/ds I s' / L~``, i.e.::

      d ln I / ds = -(dL/ds) / L~        =>   dL/ds = -L~ d ln I/ds

  ``ln I`` is fitted against the gap by a cubic polynomial over the ramp (least squares)
  and differentiated at the ramp start.  The ramp is slow compared with the eddy-current
  time constants, so the eddy currents (which lag the motion) bias the slope by only
  ``~ tau_ec / T`` (measured in ``docs/reduction.md``).

At ``I = 0`` the flux linkage is zero and stays zero, so the ramp carries no information.
The map needs the limit ``dL/ds(s, 0) = dL0/ds`` (the small-signal inductance's slope);
it is taken from the same experiment at the small current ``I_eps = 1e-4 A``
(``zero_current_A``).  The Roschke B-H law's permeability rises linearly with ``|B|`` from
its initial value, so ``L(s, I) = L0(s) + O(|I|)``: on the U-magnet ``dL/ds`` at 1e-3 A
differs from the limit by 6e-4 relative, at 1e-4 A by < 1e-5 (measured).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..circuit.assembly import assemble
from ..circuit.network import Network
from ..errors import InputError, SolverError
from ..models.experiments import differential_inductance_from_step
from ..models.flux import FluxModel
from ..models.statics import as_network, solve_statics
from ..validation import real_number, renamed_keywords, whole_number

__all__ = ["RampEstimate", "RampResponse", "dl_ds_from_ramp", "flux_held_ramp", "transient_point"]

#: Integrator tolerances of the identification experiments (tighter than simulation).
RTOL = 1e-9
ATOL = 1e-11


@dataclass(frozen=True)
class RampResponse:
    """Detailed-model response to a gap ramp under ``U = R_el I`` (constant flux linkage).

    Attributes
    ----------
    time_s : ndarray (n,)
        Sample times [s], from 0 to the ramp duration.
    gaps_m : ndarray (n, n_gaps)
        Gap of every gap input [m].
    currents_A : ndarray (n, n_circuits)
        Circuit currents [A].
    flux_linkage_Wb : ndarray (n, n_circuits)
        Constant up to the integrator's rounding (the law is exact).
    """

    time_s: np.ndarray
    gaps_m: np.ndarray
    currents_A: np.ndarray
    flux_linkage_Wb: np.ndarray


@dataclass(frozen=True)
class RampEstimate:
    """Result of :func:`dl_ds_from_ramp` (one circuit at one operating point).

    Attributes
    ----------
    dL_ds_H_per_m : float
        ``dL/ds = -L~ d ln I / ds`` [H/m].
    dlnI_ds_per_m : float
        Fitted slope of ``ln I`` over the gap at the ramp start [1/m].
    inductance_H : float
        The ``L~`` [H] used (from a voltage step unless given).
    current_A : float
        Current of the experiment [A] (``I_eps`` when the requested current is 0).
    fit_rms : float
        RMS residual of the cubic fit of ``ln I`` (relative current deviation).
    response : RampResponse
        The simulated ramp.
    """

    dL_ds_H_per_m: float
    dlnI_ds_per_m: float
    inductance_H: float
    current_A: float
    fit_rms: float
    response: RampResponse


class _HeldRamp:
    """Compiled DAE of the flux model with ``U = R_el I`` substituted (cached on the network).

    It reuses the flux model's structure (``D``, ``K``, ``Q`` of ``FluxDAE``) and only
    replaces the Faraday rows ``U - R I`` of ``h`` by zero.  Time is normalised to
    ``[0, 1]``; parameters are the duration ``T`` and the gap change ``Delta s`` per gap.
    """

    def __init__(self, net: Network, n_out: int) -> None:
        fm = FluxModel(net, rtol=RTOL, atol=ATOL, compiled="never")   # matrices only
        d = fm.dae
        eq = assemble(net)
        nc, ng = d.n_circuits, d.n_gaps
        y = ca.SX.sym("y", d.n_diff)
        T = ca.SX.sym("T")
        ds = ca.SX.sym("ds", ng)
        hv = ca.vertcat(-eq.residual, ca.SX.zeros(nc))
        ydot = ca.mtimes(ca.DM(d.Kp), hv)
        alg = ca.vertcat(ca.mtimes(ca.DM(d.D), eq.x) - y, ca.mtimes(ca.DM(d.Q), hv))
        dae = {"x": ca.vertcat(y, eq.s), "z": ca.vertcat(eq.x, eq.I), "p": ca.vertcat(T, ds),
               "ode": ca.vertcat(T * ydot, ds), "alg": alg}
        self.tau = np.linspace(0.0, 1.0, n_out)
        opts: dict[str, Any] = {"reltol": RTOL, "abstolv": list(ATOL * d.nominal), "max_num_steps": 100000,
                "disable_internal_warnings": True}
        self.integrator = ca.integrator("flux_held_ramp", "idas", dae, 0.0, self.tau[1:], opts)
        self.D = d.D
        self.n_diff, self.n_gaps, self.n_loops, self.n_circuits = d.n_diff, ng, d.n_loops, nc
        self.psi = ca.Function("psi", [eq.x], [eq.psi])


def _held(net: Network, n_out: int) -> _HeldRamp:
    key = ("reduction_held_ramp", n_out)
    obj = net.cache.get(key)
    if obj is None:
        obj = _HeldRamp(net, n_out)
        net.cache[key] = obj
    return obj  # type: ignore[no-any-return]


@renamed_keywords(gap="gap_m", current="current_A", gap_change="gap_change_m",
                  duration="duration_s")
def flux_held_ramp(model: Any, *, gap_m: Any, current_A: Any, gap_change_m: Any, duration_s: float,
                   samples: int = 201) -> RampResponse:
    """Simulate the detailed model under ``U = R_el I`` with linearly moving gaps.

    Starts at rest at the static operating point (``gap_m``, ``current_A``) and moves
    every gap linearly by ``gap_change_m`` (scalar or per gap) over ``duration_s``.

    Old keyword names (``gap``, ``current``, ``gap_change``, ``duration``) are deprecated
    aliases for one release.

    Parameters
    ----------
    model : Magnet, Network or FluxModel
        The detailed model (its network is used).
    gap_m : float, sequence or mapping
        Gap(s) [m] of one operating point at the start, > 0 (scalar: all gaps equal;
        keyword only, like all that follow).
    current_A : float, sequence or mapping
        Circuit current(s) [A] at the start (scalar: every circuit).
    gap_change_m : float or array_like (n_gaps,)
        Change of each gap over the ramp [m] (scalar: every gap); finite, and the gaps
        must stay > 0.
    duration_s : float
        Ramp time [s], finite and > 0.
    samples : int, default 201
        Output samples including the start (integer >= 10); one compiled integrator is
        cached on the network per value.

    Returns
    -------
    RampResponse

    Raises
    ------
    InputError
        ``duration_s`` or ``samples`` out of range, more than one operating point, bad
        gaps or currents, or a ``gap_change_m`` that is not finite or closes a gap.
    SolverError
        If the statics or the integration fail.
    """
    net = as_network(model)
    duration_s = real_number(duration_s, "duration", "s", positive=True)
    samples = whole_number(samples, "samples", minimum=10)
    sol = solve_statics(net, gaps_m=gap_m, currents_A=current_A)
    if sol.shape != ():
        raise InputError("flux_held_ramp takes one operating point")
    dsv = np.broadcast_to(np.asarray(gap_change_m, dtype=float), sol.gaps_m.shape).copy()
    if not np.all(np.isfinite(dsv)) or np.any(sol.gaps_m + dsv <= 0.0):
        raise InputError(f"gap_change = {gap_change_m!r} m must be finite and keep the gaps > 0")
    h = _held(net, samples)
    x0 = np.asarray(sol.loop_flux_Wb, dtype=float)
    xd0 = np.concatenate((h.D @ x0, sol.gaps_m))
    try:
        res = h.integrator(x0=xd0, z0=np.concatenate((x0, sol.currents_A)),
                           p=np.concatenate(((duration_s,), dsv)))
    except RuntimeError as exc:
        raise SolverError("flux-held gap ramp failed", state={"gap_m": sol.gaps_m,
                          "current_A": sol.currents_A}, reason=str(exc)[-300:]) from None
    xf = np.hstack((xd0[:, None], np.asarray(res["xf"])))
    zf = np.hstack((np.concatenate((x0, sol.currents_A))[:, None], np.asarray(res["zf"])))
    loops = zf[:h.n_loops]
    psi = np.asarray(h.psi(loops)).T
    return RampResponse(time_s=duration_s * h.tau, gaps_m=xf[h.n_diff:].T.copy(),
                        currents_A=zf[h.n_loops:].T.copy(), flux_linkage_Wb=psi)


@renamed_keywords(gap="gap_m", current="current_A", inductance="inductance_H",
                  duration="duration_s", zero_current="zero_current_A")
def dl_ds_from_ramp(model: Any, *, gap_m: float, current_A: float, circuit: int = 0,
                    poles: Any = None, inductance_H: float | None = None,
                    relative_gap_change: float = 0.02, duration_s: float | None = None,
                    zero_current_A: float = 1e-4, samples: int = 201) -> RampEstimate:
    """Identify ``dL/ds(s, I)`` of circuit ``circuit`` by the virtual control law (paper IV-B).

    Old keyword names (``gap``, ``current``, ``inductance``, ``duration``, ``zero_current``)
    are deprecated aliases for one release.

    Parameters
    ----------
    model : Magnet, Network or FluxModel
        The detailed model (its network is used).
    gap_m, current_A : float
        Operating point: every gap at ``gap_m`` [m] (> 0), every circuit at
        ``current_A`` [A] (finite, >= 0: the maps are even in the current).  Keyword
        only, like all that follow.
    circuit : int
        Index of the circuit, ``0 .. n_circuits - 1``.
    poles : sequence of int, optional
        Indices of the gap inputs that move (the circuit's own poles); default all.
    inductance_H : float, optional
        ``L~`` [H] to convert the slope; default: identified by a voltage step
        (:func:`~maglevkit.models.experiments.differential_inductance_from_step`), which
        keeps the method independent of the statics' sensitivities.
    relative_gap_change : float
        Ramp length as a fraction of the gap, in (0, 0.2] (default 0.02; the cubic fit
        removes the curvature).
    duration_s : float, optional
        Ramp time [s]; default ``50 L~/R_el`` (slow compared with the eddy currents).
    zero_current_A : float
        Current [A], > 0, used when ``current == 0`` (the limit ``I -> 0``, see module
        doc; default 1e-4 A).
    samples : int
        Output samples of the ramp (integer >= 10, default 201).

    Returns
    -------
    RampEstimate

    Raises
    ------
    InputError
        Any of the above out of range, or bad inputs of the experiments.
    SolverError
        If the current changes sign on the ramp, or an experiment fails.
    """
    net = as_network(model)
    nc = len(net.circuits)
    circuit = whole_number(circuit, "circuit", minimum=0)
    if circuit >= nc:
        raise InputError(f"circuit = {circuit!r} must be an index in 0..{nc - 1}")
    relative_gap_change = real_number(relative_gap_change, "relative_gap_change")
    if not 0.0 < relative_gap_change <= 0.2:
        raise InputError(f"relative_gap_change = {relative_gap_change!r} must lie in (0, 0.2]")
    current_A = real_number(current_A, "current", "A")
    if current_A < 0.0:
        raise InputError(f"current = {current_A!r} A must be a finite number >= 0 (maps are even "
                         "in the current)")
    zero_current_A = real_number(zero_current_A, "zero_current", "A", positive=True)
    ng = len(net.gap_names)
    if poles is None:
        idx = list(range(ng))
    else:
        if isinstance(poles, (str, bytes)) or not hasattr(poles, "__iter__"):
            raise InputError(f"poles = {poles!r}: expected a sequence of gap-input indices "
                             f"in 0..{ng - 1}")
        idx = [whole_number(k, "poles", minimum=0) for k in poles]
        if not idx or max(idx) >= ng or len(set(idx)) != len(idx):
            raise InputError(f"poles = {list(poles)!r}: expected at least one distinct "
                             f"gap-input index in 0..{ng - 1} (or None: all gaps)")
    i_exp = float(current_A) if current_A > 0.0 else float(zero_current_A)
    if inductance_H is None:
        inductance_H = differential_inductance_from_step(net, gap_m=gap_m, current_A=i_exp,
                                                       circuit=circuit).inductance_H
    r_el = float(net.resistances[circuit])
    if duration_s is None:
        duration_s = 50.0 * inductance_H / r_el
    change = np.zeros(ng)
    change[idx] = relative_gap_change * gap_m
    resp = flux_held_ramp(net, gap_m=gap_m, current_A=i_exp, gap_change_m=change, duration_s=duration_s,
                          samples=samples)
    cur = resp.currents_A[:, circuit]
    if np.any(cur <= 0.0):
        raise SolverError("the current changed sign on the flux-held ramp",
                          state={"gap_m": gap_m, "current_A": i_exp})
    u = (resp.gaps_m[:, idx[0]] - gap_m) / (relative_gap_change * gap_m)   # 0..1
    coef = np.polynomial.polynomial.polyfit(u, np.log(cur), 3)
    fit = np.polynomial.polynomial.polyval(u, coef) - np.log(cur)
    slope = float(coef[1]) / (relative_gap_change * gap_m)
    return RampEstimate(dL_ds_H_per_m=-inductance_H * slope, dlnI_ds_per_m=slope,
                        inductance_H=float(inductance_H), current_A=i_exp,
                        fit_rms=float(np.sqrt(np.mean(fit**2))), response=resp)


# Networks unpickled in a worker process lose their compiled functions (Network pickles
# without its cache); keep one instance per magnet so every task after the first in a
# process reuses the compiled integrators.
_WORKER_NETWORKS: dict[str, Network] = {}


def transient_point(key: str, net: Network, s: float, current: float,
                    poles: tuple[tuple[int, ...], ...]) -> dict[str, np.ndarray]:
    """Transient identification at one grid point for every circuit (one executor task).

    Returns per circuit: ``L~`` from a voltage step, ``dL/ds`` from the flux-held ramp of
    the circuit's own poles (``poles[j]``), and the step's slow-mode ``R_ec``.

    Parameters
    ----------
    key : str
        Identifies the network in this worker process (the first network given for a
        key is kept and reused, with its compiled functions).
    net : Network
        The detailed magnet's network.
    s : float
        Gap of every pole [m].
    current : float
        Current of every circuit [A], >= 0.
    poles : tuple of tuple of int
        Per circuit, the indices of its own gap inputs (moved by its ramp).

    Returns
    -------
    dict of str to ndarray (n_circuits,)
        ``"inductance_H"`` [H], ``"dL_ds_H_per_m"`` [H/m], ``"eddy_resistance_step_ohm"``
        [ohm].
    """
    net = _WORKER_NETWORKS.setdefault(key, net)
    nc = len(net.circuits)
    lt, dl, rec = np.empty(nc), np.empty(nc), np.empty(nc)
    for j in range(nc):
        step = differential_inductance_from_step(net, gap_m=s, current_A=current, circuit=j,
                                                 rtol=RTOL, atol=ATOL)
        if current > 0.0:
            l_ramp = step.inductance_H
        else:   # the ramp runs at I_eps; use L~ at the same current
            l_ramp = None
        ramp = dl_ds_from_ramp(net, gap_m=s, current_A=current, circuit=j, poles=poles[j],
                               inductance_H=l_ramp)
        lt[j], dl[j], rec[j] = step.inductance_H, ramp.dL_ds_H_per_m, step.eddy_resistance_ohm
    return {"inductance_H": lt, "dL_ds_H_per_m": dl, "eddy_resistance_step_ohm": rec}
