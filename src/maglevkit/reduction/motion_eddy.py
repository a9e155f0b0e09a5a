"""Eq. 8 with a shielded gap section: a reduced model whose motion-induced current passes
through eddy dynamics (our extension of the paper's Fig. 8; docs/reduction.md, "Gap motion").

In Fig. 8 the motion-induced voltage ``dL/ds I_L ds/dt`` sits in the same node as the
eddy resistor and the coil: whatever the gap does, the coil sees a fixed fraction
``1/(1 + R_el/R_ec)`` of the motion-induced current, with no phase.  In the detailed
network the iron's eddy currents shield the gap's flux change from the coil (the coil
current falls like ``1/f`` above ~100 Hz on the TR09 standard magnet), while a voltage
step still makes the coil current jump.  Both are kept by a ladder of three elements per
circuit, read from the coil terminals::

    U --R_el--+--L_u--+----------+
              |       |          |
             R_a     R_2    L(s, I_L), EMF dL/ds I_L ds/dt
              |       |          |
    ----------+-------+----------+

* ``R_a`` shunts the coil directly: the current jump of a voltage step (``dU/(R_el + R_a)``);
* ``L_u``: the flux linkage not behind the iron's eddy currents (leakage), constant;
* ``R_2``: the eddy currents that shield the gap section ``L(s, I_L)``, whose differential
  inductance is ``L~(s, I_L) - L_u`` and which carries the motion-induced voltage
  ``e = dL/ds I_L ds/dt`` -- all of it (``beta = 0``), or all but the share ``beta`` that
  sits in ``L_u``, outside the shield (a gap-dependent path that no eddy current holds:
  the split TR09 network's flank strips part-way along the coil, docs/reduction.md).

States per circuit: ``I_L`` (the gap section's current) and ``I_e = I_u - I_L`` (the
shielding eddy current through ``R_2``; ``I_u`` is the current through ``L_u``)::

    a = 1 + R_el/R_a,   V_A = (U - R_el (I_L + I_e))/a,   V_m = R_2 I_e
    (L~ - L_u) dI_L/dt = V_m - (1 - beta) e
    L_u dI_e/dt = V_A - V_m - beta e - L_u dI_L/dt
    I = (U - V_A)/R_el,   F = F(s, I_L + gamma I_e)

The force is read from eq. 8's force map at the *force current* ``I_L + gamma I_e``: the
share ``gamma`` of the shielding eddy current's MMF that acts on the gap (0: eq. 8's
``F(s, I_L)``).  In a steady state ``I_e = 0``, so the statics are unchanged.

``L_u -> 0`` gives eq. 8 with ``R_ec = R_a R_2/(R_a + R_2)``.  The parameters are fitted to
the detailed model's small-signal responses (gap -> coil current and voltage -> coil
current; gap -> force on request) at one operating point: the detailed DAE is linearised there
(:func:`detailed_frequency_response`) and the ladder's closed-form transfer functions
(:func:`ladder_frequency_response`) are fitted by least squares (:func:`fit_motion_eddy`);
``beta`` is not fitted but follows from the detailed model's exact instantaneous
gap -> current jump (at frozen flux linkages and eddy fluxes), as ``R_a`` starts from its
exact voltage -> current jump; ``gamma`` likewise from the detailed model's instantaneous
gap -> force jump, the held-flux stiffness (:func:`force_share`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, MaglevkitWarning, SolverError
from ..validation import renamed_keywords

__all__ = ["DetailedFrequencyResponse", "MotionEddyFit", "detailed_frequency_response",
           "fit_motion_eddy", "ladder_force_response", "ladder_frequency_response",
           "unshielded_share", "force_share", "ladder_voltage_currents",
           "step_force_residual", "MAX_STEP_FORCE_LOSS",
           "relative_rms_residual", "FIT_FREQUENCIES_HZ", "SHARE_VARIABLE",
           "FORCE_SHARE_VARIABLE", "HELD_FLUX_FORCE_SHARE_VARIABLE", "Ladder3Response",
           "ladder3_frequency_response", "ladder3_force_current", "MotionEddy3Fit",
           "fit_motion_eddy3", "MOTION_EDDY3_WEIGHTS"]

#: The maps' variable of the ladder's unshielded share ``beta`` of the motion term.
SHARE_VARIABLE = "motion_eddy_unshielded_share"
#: The maps' variable of the ladder's force share ``gamma`` of the eddy current (maps
#: without it are read with ``gamma = 0``, the force ``F(s, I_L)`` they were built for).
FORCE_SHARE_VARIABLE = "motion_eddy_force_share"
#: The maps' variable of the ``gamma`` derived from the detailed model's held-flux stiffness
#: (:func:`force_share`, kept where voltage steps lose at most :data:`MAX_STEP_FORCE_LOSS`).
#: ``build_maps`` stores it here and leaves :data:`FORCE_SHARE_VARIABLE` at 0: it costs the
#: closed loop (split TR09: 5.7 -> 20.7 % current error), so it is used only when asked
#: (:meth:`~maglevkit.reduction.maps.CharacteristicMaps.with_held_flux_force`).
HELD_FLUX_FORCE_SHARE_VARIABLE = "motion_eddy_held_flux_force_share"

#: Frequencies of the fit [Hz]: 0.1 Hz .. 1 kHz, 60 points evenly spaced in log f.
FIT_FREQUENCIES_HZ = np.geomspace(0.1, 1000.0, 60)


@dataclass(frozen=True)
class DetailedFrequencyResponse:
    """Small-signal responses of the detailed (flux-based) model of one circuit.

    At the steady state with every gap at ``gap_m`` and every current at ``current_A``
    (voltages ``R_el I``), linearised exactly (CasADi AD of the DAE).

    Attributes
    ----------
    frequencies_Hz : ndarray (n_f,)
    gap_to_current_A_per_m : ndarray (n_f,), complex
        Coil current per gap of the circuit's own poles moving together [A/m].
    gap_to_force_N_per_m : ndarray (n_f,), complex
        Circuit force (its poles' sum) per gap [N/m].
    voltage_to_current_A_per_V : ndarray (n_f,), complex
        Coil current per coil voltage [A/V] (the other circuits' voltages held).
    differential_inductance_H : float
        ``L~ = dpsi_j/dI_j`` of the statics there [H].
    dpsi_ds_Wb_per_m : float
        ``dpsi_j/ds`` over the circuit's own poles [Wb/m] (``dL/ds I``).
    gap_current_jump_A_per_m : float
        The instantaneous coil current change per gap [A/m] at frozen flux linkages and
        eddy fluxes (the gap -> current response as ``f -> oo``; 0 where every
        gap-dependent flux is held by eddy currents).
    dforce_dcurrent_N_per_A, dforce_dgap_N_per_m : float
        The statics' ``dF_j/dI_j`` [N/A] and ``dF_j/ds`` [N/m] (circuit force, own poles
        moving): with them the ladder's force is compared.  NaN: the fit leaves the force
        out.
    gap_force_jump_N_per_m : float
        The instantaneous circuit force change per gap [N/m] at frozen flux linkages and
        eddy fluxes (the gap -> force response as ``f -> oo``, the held-flux stiffness);
        NaN: not known (the ladder's force share ``gamma`` is then 0).
    voltage_to_force_N_per_V : ndarray (n_f,), complex, optional
        Circuit force per coil voltage [N/V] (None: not evaluated).
    """

    frequencies_Hz: np.ndarray
    gap_to_current_A_per_m: np.ndarray
    gap_to_force_N_per_m: np.ndarray
    voltage_to_current_A_per_V: np.ndarray
    differential_inductance_H: float
    dpsi_ds_Wb_per_m: float
    gap_current_jump_A_per_m: float = 0.0
    dforce_dcurrent_N_per_A: float = float("nan")
    dforce_dgap_N_per_m: float = float("nan")
    gap_force_jump_N_per_m: float = float("nan")
    voltage_to_force_N_per_V: np.ndarray | None = None


def detailed_frequency_response(net: Any, *, gap: float, current: float,
                                frequencies_Hz: Any = FIT_FREQUENCIES_HZ,
                                groups: dict[str, tuple[str, ...]] | None = None,
                                common_mode: bool = False
                                ) -> list[DetailedFrequencyResponse]:
    """Linearise the detailed DAE at a steady state and evaluate its frequency responses.

    The flux model (``models/flux.py``) is ``y' = K^+ h(x, I, U, s)``, ``0 = g(y, x, I, U, s)``
    (``g = [D x - y; Q h]``) with differential ``y`` and algebraic ``z = (x, I)``; ``g_z`` is
    regular (index 1), so ``dz = -g_z^-1 (g_y dy + g_w dw)`` and
    ``(p - A) dy = B dw`` with ``A = f_y - f_z g_z^-1 g_y``, ``B = f_w - f_z g_z^-1 g_w``
    for the inputs ``w = (s, U)``.  Evaluated at ``p = 2 pi i f``.

    Parameters
    ----------
    net : Network
    gap, current : float
        Operating point: every gap [m], every circuit current [A].
    frequencies_Hz : array_like
        Frequencies [Hz].
    groups : dict, optional
        Circuit -> its poles (gap inputs); default :func:`circuit_pole_groups` there.
    common_mode : bool
        False (default): each circuit's responses to its own poles moving and to its own
        voltage (the others held).  True: to every gap of the magnet moving together and
        to every circuit's voltage changing together (a heave of the whole magnet driven
        alike, which couples the circuits through their mutual fluxes and shared eddy
        elements); the force is still the circuit's own poles', and the statics' partials
        (``L~``, ``dpsi/ds``, ``dF/dI``, ``dF/ds``) stay the circuit's own -- the reduced
        model's per-circuit law -- so that a ladder fitted to them carries the coupling in
        its elements.  The instantaneous jumps follow the same inputs.

    Returns
    -------
    list of DetailedFrequencyResponse
        One per circuit.
    """
    import casadi as ca

    from ..circuit.assembly import assemble
    from ..models.flux import flux_dae
    from ..models.statics import circuit_pole_groups, solve_statics

    freqs = np.asarray(frequencies_Hz, dtype=float)
    d = flux_dae(net, "idas", 1e-9, 1e-11, 20000, 2, 3)
    eq = assemble(net)
    nc, ng = len(net.circuits), len(net.gap_names)
    y = ca.SX.sym("y", d.n_diff)
    U = ca.SX.sym("U", nc)
    hv = ca.vertcat(-eq.residual, U - net.resistances * eq.I)
    ydot = ca.mtimes(ca.DM(d.Kp), hv)
    alg = ca.vertcat(ca.mtimes(ca.DM(d.D), eq.x) - y, ca.mtimes(ca.DM(d.Q), hv))
    z = ca.vertcat(eq.x, eq.I)
    w = ca.vertcat(eq.s, U)
    jac = ca.Function("detailed_linearisation", [y, z, w],
                      [ca.jacobian(ydot, y), ca.jacobian(ydot, z), ca.jacobian(ydot, w),
                       ca.jacobian(alg, y), ca.jacobian(alg, z), ca.jacobian(alg, w),
                       ca.jacobian(eq.force, z), ca.jacobian(eq.force, w)])
    sol = solve_statics(net, gaps_m=np.full(ng, gap), currents_A=np.full(nc, current))
    x0 = np.asarray(sol.loop_flux_Wb, dtype=float).ravel()
    i0 = np.asarray(sol.currents_A, dtype=float).ravel()
    s0 = np.asarray(sol.gaps_m, dtype=float).ravel()
    fy, fz, fw, gy, gz, gw, force_z, force_w = (
        np.asarray(v, dtype=float) for v in jac(d.D @ x0, np.concatenate((x0, i0)),
                                                np.concatenate((s0, net.resistances * i0))))
    try:
        gzi_gy = np.linalg.solve(gz, gy)
        gzi_gw = np.linalg.solve(gz, gw)
    except np.linalg.LinAlgError:
        raise SolverError("the detailed DAE's algebraic Jacobian is singular at the "
                          "identification point", state={"gap_m": gap, "current_A": current}
                          ) from None
    a = fy - fz @ gzi_gy
    b = fw - fz @ gzi_gw
    cz, dz = -gzi_gy, -gzi_gw
    if groups is None:
        groups = circuit_pole_groups(net, gap_m=gap, current_A=current)
    gi = {g: k for k, g in enumerate(net.gap_names)}
    eye = np.eye(a.shape[0])
    nl = d.n_loops
    owns, wins = [], []
    for j, c in enumerate(net.circuit_names):
        own = [gi[g] for g in groups[c]]
        win = np.zeros((ng + nc, 2))
        if common_mode:
            win[:ng, 0] = 1.0        # every gap of the magnet moves together
            win[ng:, 1] = 1.0        # every circuit's voltage changes together
        else:
            win[own, 0] = 1.0        # the circuit's own poles move together
            win[ng + j, 1] = 1.0     # its voltage
        owns.append(own)
        wins.append(win)
    # one LU per frequency for every circuit's inputs (columns 2j, 2j + 1): the
    # factorisation of the ladder network's ~360 states is the identification's cost
    w_all = np.hstack(wins)
    bw_all = b @ w_all
    y_all = np.stack([np.linalg.solve(2j * np.pi * f * eye - a, bw_all) for f in freqs])
    out = []
    for j, (own, win) in enumerate(zip(owns, wins, strict=True)):
        res = np.empty((freqs.size, 4), dtype=complex)
        for k in range(freqs.size):
            yy = y_all[k][:, 2 * j:2 * j + 2]
            zz = cz @ yy + dz @ win
            force = (force_z @ zz + force_w @ win)[own].sum(axis=0)
            res[k] = (zz[nl + j, 0], force[0], zz[nl + j, 1], force[1])
        # statics: circuit force over own poles, its current and its poles' gaps
        df_di = np.asarray(sol.dforce_dcurrent_N_per_A)[own, j].sum()
        df_ds = np.asarray(sol.dforce_dgap_N_per_m)[np.ix_(own, own)].sum()
        # the instantaneous (frozen y) responses: coil current and circuit force
        z_jump = dz @ win
        f_jump = (force_z @ z_jump + force_w @ win)[own].sum(axis=0)
        out.append(DetailedFrequencyResponse(
            freqs, res[:, 0], res[:, 1], res[:, 2],
            float(sol.differential_inductance_H[j, j]),
            float(np.asarray(sol.dpsi_dgap_Wb_per_m)[j, own].sum()),
            float(z_jump[nl + j, 0]), float(df_di), float(df_ds), float(f_jump[0]),
            res[:, 3]))
    return out


@renamed_keywords(ltilde="differential_inductance_H", dpsi_ds="dpsi_ds_Wb_per_m",
                  r_el="resistance_ohm", r_a="jump_resistance_ohm",
                  l_u="unshielded_inductance_H", r_2="shielding_resistance_ohm")
def ladder_frequency_response(frequencies_Hz: Any, *, differential_inductance_H: float,
                              dpsi_ds_Wb_per_m: float, resistance_ohm: float,
                              jump_resistance_ohm: float, unshielded_inductance_H: float,
                              shielding_resistance_ohm: float, beta: float = 0.0
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form small-signal responses of the shielded-gap ladder (module docstring).

    Linearised at a steady state (``I_e = 0``, ``V_m = 0``), with ``k = dL/ds I_L =
    dpsi/ds`` and ``a = 1 + R_el/R_a``; unknowns ``I_u = I_L + I_e`` and ``I_L``::

        [p L_u + R_el/a + R_2,   -R_2            ] [I_u]   [U/a - beta k p s   ]
        [-R_2,          p (L~ - L_u) + R_2       ] [I_L] = [-(1 - beta) k p s  ]

        I = (1 - 1/a) U/R_el + I_u/a

    As ``p -> oo`` the gap -> current response tends to ``-beta k/(a L_u)``, the
    instantaneous jump (:func:`unshielded_share` inverts it).

    Parameters
    ----------
    frequencies_Hz : array_like
        Frequencies [Hz].
    differential_inductance_H : float
        ``L~`` [H].
    dpsi_ds_Wb_per_m : float
        ``k = dL/ds I_L`` [Wb/m].
    resistance_ohm : float
        ``R_el`` [ohm].
    jump_resistance_ohm : float
        The shunt ``R_a`` [ohm] (maps variable ``motion_eddy_jump_resistance_ohm``).
    unshielded_inductance_H : float
        The series ``L_u`` [H].
    shielding_resistance_ohm : float
        The gap section's eddy resistance ``R_2`` [ohm].
    beta : float
        The unshielded share of the motion term [-] (default 0).

    The old keyword names ``ltilde``, ``dpsi_ds``, ``r_el``, ``r_a``, ``l_u``, ``r_2``
    are deprecated aliases for one release (a ``DeprecationWarning`` names the new one).

    Returns
    -------
    gap_to_current_A_per_m, gap_to_inductor_current_A_per_m, voltage_to_current_A_per_V : ndarray
        Complex, per frequency: ``dI/ds``, ``dI_L/ds`` and ``dI/dU``.  The shielding eddy
        current follows as ``dI_e/ds = a dI/ds - dI_L/ds`` (at constant voltage
        ``dI_u = a dI``; :func:`ladder_force_response`).
    """
    ltilde, dpsi_ds, r_el = differential_inductance_H, dpsi_ds_Wb_per_m, resistance_ohm
    r_a, l_u, r_2 = jump_resistance_ohm, unshielded_inductance_H, shielding_resistance_ohm
    p = 2j * np.pi * np.asarray(frequencies_Hz, dtype=float)
    a = 1.0 + r_el / r_a
    m11 = p * l_u + r_el / a + r_2
    m22 = p * (ltilde - l_u) + r_2
    det = m11 * m22 - r_2 * r_2
    # gap input: rhs (-beta k p, -(1 - beta) k p)
    e1, e2 = -beta * dpsi_ds * p, -(1.0 - beta) * dpsi_ds * p
    iu_s = (m22 * e1 + r_2 * e2) / det
    il_s = (r_2 * e1 + m11 * e2) / det
    # voltage input: rhs (1/a, 0)
    iu_u = (m22 / a) / det
    return iu_s / a, il_s, (1.0 - 1.0 / a) / r_el + iu_u / a


@renamed_keywords(shield_resistance_ohm="jump_resistance_ohm")
def unshielded_share(jump_A_per_m: float, *, dpsi_ds_Wb_per_m: float, resistance_ohm: float,
                     jump_resistance_ohm: float, unshielded_inductance_H: float) -> float:
    """The ladder's ``beta`` that gives the detailed model's instantaneous gap -> current
    jump ``D``: ``beta = -D a L_u/k`` (:func:`ladder_frequency_response`).

    Parameters
    ----------
    jump_A_per_m : float
        ``D`` [A/m] (:attr:`DetailedFrequencyResponse.gap_current_jump_A_per_m`).
    dpsi_ds_Wb_per_m : float
        ``k = dL/ds I_L`` [Wb/m]; 0 (no current): ``beta = 0``.
    resistance_ohm : float
        ``R_el`` [ohm], >= 0.
    jump_resistance_ohm : float
        The shunt ``R_a`` [ohm], > 0 (``shield_resistance_ohm`` is its deprecated name).
    unshielded_inductance_H : float
        ``L_u`` [H].

    Returns
    -------
    float
        ``beta`` [-].

    Raises
    ------
    InputError
        A non-finite argument, ``R_a <= 0`` or ``R_el < 0``.
    """
    args = {"jump_A_per_m": jump_A_per_m, "dpsi_ds_Wb_per_m": dpsi_ds_Wb_per_m,
            "resistance_ohm": resistance_ohm, "jump_resistance_ohm": jump_resistance_ohm,
            "unshielded_inductance_H": unshielded_inductance_H}
    for name, value in args.items():
        if not math.isfinite(float(value)):
            raise InputError(f"unshielded_share: {name} = {value!r} must be finite")
    if not jump_resistance_ohm > 0.0:
        raise InputError(f"unshielded_share: jump_resistance_ohm = {jump_resistance_ohm!r} "
                         "must be > 0 (the ladder's R_a)")
    if resistance_ohm < 0.0:
        raise InputError(f"unshielded_share: resistance_ohm = {resistance_ohm!r} must be >= 0")
    if dpsi_ds_Wb_per_m == 0.0:
        return 0.0
    return float(-jump_A_per_m * (1.0 + resistance_ohm / jump_resistance_ohm)
                 * unshielded_inductance_H / dpsi_ds_Wb_per_m)


def force_share(force_jump_N_per_m: float, *, differential_inductance_H: float,
                dpsi_ds_Wb_per_m: float, dforce_dcurrent_N_per_A: float,
                dforce_dgap_N_per_m: float, unshielded_inductance_H: float,
                beta: float) -> float:
    """The ladder's force share ``gamma`` that gives the detailed model's instantaneous
    gap -> force jump ``J`` (the stiffness at frozen flux linkages and eddy fluxes).

    As ``p -> oo`` the ladder's states jump by ``dI_L/ds = -(1 - beta) k/(L~ - L_u)``
    and ``dI_u/ds = -beta k/L_u`` (``k = dpsi/ds``), so ``dI_e/ds = dI_u/ds - dI_L/ds``,
    and its force ``F(s, I_L + gamma I_e)`` by ``dF/ds + dF/dI (dI_L/ds + gamma dI_e/ds)``;
    equal to ``J``::

        gamma = ((J - dF/ds)/(dF/dI) - dI_L/ds) / dI_e/ds

    (docs/equations.md section 8).

    Parameters
    ----------
    force_jump_N_per_m : float
        ``J`` [N/m] (:attr:`DetailedFrequencyResponse.gap_force_jump_N_per_m`); NaN: not
        known, ``gamma = 0``.
    differential_inductance_H : float
        ``L~`` [H].
    dpsi_ds_Wb_per_m : float
        ``k`` [Wb/m]; 0 (no current): ``gamma = 0``.
    dforce_dcurrent_N_per_A, dforce_dgap_N_per_m : float
        The statics' ``dF/dI`` [N/A] and ``dF/ds`` [N/m] (NaN: ``gamma = 0``).
    unshielded_inductance_H : float
        ``L_u`` [H], ``0 < L_u < L~``.
    beta : float
        The unshielded share of the motion term [-].

    Returns
    -------
    float
        ``gamma`` [-].

    Raises
    ------
    InputError
        ``L_u`` not within ``(0, L~)``.
    """
    l_u, lt, k = unshielded_inductance_H, differential_inductance_H, dpsi_ds_Wb_per_m
    if not 0.0 < l_u < lt:
        raise InputError(f"force_share: unshielded_inductance_H = {l_u!r} must be within "
                         f"(0, differential_inductance_H = {lt!r})")
    known = (force_jump_N_per_m, dforce_dcurrent_N_per_A, dforce_dgap_N_per_m)
    if k == 0.0 or not all(math.isfinite(float(v)) for v in known) \
            or dforce_dcurrent_N_per_A == 0.0:
        return 0.0
    d_il = -(1.0 - beta) * k / (lt - l_u)
    d_ie = -beta * k / l_u - d_il
    if d_ie == 0.0:
        return 0.0
    return float(((force_jump_N_per_m - dforce_dgap_N_per_m) / dforce_dcurrent_N_per_A
                  - d_il) / d_ie)


#: Largest rise of the voltage -> force residual (RMS over the fit's frequencies, relative
#: to the detailed static ``dF/dU``, i.e. to a voltage step's force change) that the force
#: share ``gamma`` may cost; above it the ladder keeps ``gamma = 0`` (``F(s, I_L)``): the
#: U-magnet's ``gamma`` of -1.2 would take it from 1.0 to 8.3 %, the split TR09
#: network's -0.14 from 0.7 to 1.0 % (docs/equations.md section 8).
MAX_STEP_FORCE_LOSS = 0.01


def ladder_voltage_currents(frequencies_Hz: Any, *, differential_inductance_H: float,
                            resistance_ohm: float, jump_resistance_ohm: float,
                            unshielded_inductance_H: float, shielding_resistance_ohm: float
                            ) -> tuple[np.ndarray, np.ndarray]:
    """The ladder's voltage -> ``I_L`` and voltage -> ``I_e`` responses [A/V] (the system
    of :func:`ladder_frequency_response` with the voltage input ``(1/a, 0)``)."""
    p = 2j * np.pi * np.asarray(frequencies_Hz, dtype=float)
    l_u, r_2 = unshielded_inductance_H, shielding_resistance_ohm
    a = 1.0 + resistance_ohm / jump_resistance_ohm
    m11 = p * l_u + resistance_ohm / a + r_2
    m22 = p * (differential_inductance_H - l_u) + r_2
    det = m11 * m22 - r_2 * r_2
    iu, il = (m22 / a) / det, (r_2 / a) / det
    return il, iu - il


def step_force_residual(response: DetailedFrequencyResponse, voltage_to_force: np.ndarray
                        ) -> float:
    """RMS over frequencies of ``|model - detailed|`` of the voltage -> force response,
    relative to the detailed one at the lowest frequency (a voltage step's force change);
    NaN where the response has no voltage -> force."""
    gf = response.voltage_to_force_N_per_V
    if gf is None or not np.abs(gf[0]) > 0:
        return float("nan")
    return float(np.sqrt(np.mean(np.abs(voltage_to_force - gf) ** 2)) / np.abs(gf[0]))


def _response_force_share(response: DetailedFrequencyResponse, r_el: float, r_a: float,
                          l_u: float, r_2: float, beta: float) -> float:
    """:func:`force_share` with the facts of ``response``, kept where it costs voltage
    steps at most :data:`MAX_STEP_FORCE_LOSS` (:func:`step_force_residual`), else 0."""
    gamma = force_share(response.gap_force_jump_N_per_m,
                        differential_inductance_H=response.differential_inductance_H,
                        dpsi_ds_Wb_per_m=response.dpsi_ds_Wb_per_m,
                        dforce_dcurrent_N_per_A=response.dforce_dcurrent_N_per_A,
                        dforce_dgap_N_per_m=response.dforce_dgap_N_per_m,
                        unshielded_inductance_H=l_u, beta=beta)
    if gamma == 0.0 or response.voltage_to_force_N_per_V is None:
        return gamma
    il, ie = ladder_voltage_currents(response.frequencies_Hz,
                                     differential_inductance_H=response.differential_inductance_H,
                                     resistance_ohm=r_el, jump_resistance_ohm=r_a,
                                     unshielded_inductance_H=l_u, shielding_resistance_ohm=r_2)
    dfi = response.dforce_dcurrent_N_per_A
    loss = (step_force_residual(response, dfi * (il + gamma * ie))
            - step_force_residual(response, dfi * il))
    return gamma if loss <= MAX_STEP_FORCE_LOSS else 0.0


def _with_force(response: DetailedFrequencyResponse) -> bool:
    """Whether the fit compares the force: the statics' partials are known and the gap
    moves the force (not at I = 0, where the force does not depend on the gap)."""
    return bool(np.isfinite(response.dforce_dcurrent_N_per_A)
                and np.isfinite(response.dforce_dgap_N_per_m)
                and np.all(np.abs(response.gap_to_force_N_per_m) > 0))


def ladder_force_response(response: DetailedFrequencyResponse,
                          gap_to_inductor_current: np.ndarray,
                          gap_to_eddy_current: np.ndarray | float = 0.0,
                          gamma: float = 0.0) -> np.ndarray:
    """The ladder's gap -> circuit force ``dF/dI (dI_L + gamma dI_e) + dF/ds`` [N/m] (force
    ``F(s, I_L + gamma I_e)``; ``gamma = 0``: eq. 8's ``F(s, I_L)``) from its gap -> ``I_L``
    and gap -> ``I_e`` responses, with the statics' partials of ``response``."""
    return (response.dforce_dcurrent_N_per_A
            * (gap_to_inductor_current + gamma * np.asarray(gap_to_eddy_current))
            + response.dforce_dgap_N_per_m)


def relative_rms_residual(response: DetailedFrequencyResponse, gap_to_current: np.ndarray,
                          voltage_to_current: np.ndarray,
                          gap_to_force: np.ndarray | None = None) -> float:
    """RMS over frequencies and the responses of ``(model - detailed)/|detailed|`` (real
    and imaginary parts; the gap responses are left out where the detailed ones are 0,
    the force where ``gap_to_force`` is None or the response has no force partials)."""
    return float(np.sqrt(np.mean(_residuals(response, gap_to_current, voltage_to_current,
                                            gap_to_force) ** 2)))


def _residuals(response: DetailedFrequencyResponse, gap_to_current: np.ndarray,
               voltage_to_current: np.ndarray,
               gap_to_force: np.ndarray | None = None) -> np.ndarray:
    gs, gu = response.gap_to_current_A_per_m, response.voltage_to_current_A_per_V
    ns = np.abs(gs)
    # at I = 0 the gap does not move the current (dpsi/ds = 0): the voltage path only
    ws = 1.0 if np.all(ns > 0) else 0.0
    es = ws * (gap_to_current - gs) / np.where(ns > 0, ns, 1.0)
    eu = (voltage_to_current - gu) / np.abs(gu)
    parts = [es.real, es.imag, eu.real, eu.imag]
    if gap_to_force is not None and _with_force(response):
        gf = response.gap_to_force_N_per_m
        ef = (gap_to_force - gf) / np.abs(gf)
        parts += [ef.real, ef.imag]
    return np.concatenate(parts)


@dataclass(frozen=True)
class MotionEddyFit:
    """Fitted shielded-gap ladder of one circuit.

    Attributes
    ----------
    jump_resistance_ohm : float
        ``R_a`` [ohm].
    unshielded_inductance_H : float
        ``L_u`` [H].
    shielding_resistance_ohm : float
        ``R_2`` [ohm].
    unshielded_share : float
        ``beta`` [-] (from the detailed model's gap -> current jump,
        :func:`unshielded_share`).
    force_share : float
        ``gamma`` [-] (from the detailed model's gap -> force jump, :func:`force_share`;
        0 where the response has no force partials, or where it would cost voltage steps
        more than :data:`MAX_STEP_FORCE_LOSS`).
    rms_residual : float
        RMS of the residuals (each response relative to its modulus) over the fit's
        frequencies and the responses fitted.
    max_gap_error, max_voltage_error, max_force_error : float
        Largest ``|model/detailed - 1|`` of the gap -> current, voltage -> current and
        gap -> force responses over the fit's frequencies (NaN where not compared).
    """

    jump_resistance_ohm: float
    unshielded_inductance_H: float
    shielding_resistance_ohm: float
    unshielded_share: float
    force_share: float
    rms_residual: float
    max_gap_error: float
    max_voltage_error: float
    max_force_error: float


#: Largest ``L_u`` as a share of the maps' smallest ``L~`` (:func:`fit_motion_eddy`'s
#: bound in ``build_maps``): the gap section keeps at least a fifth of the smallest ``L~``
#: anywhere on the maps (``MotionEddyLadder`` refuses ``L~ <= L_u``).
MAX_UNSHIELDED_SHARE_OF_MIN_L = 0.8


@renamed_keywords(r_el="resistance_ohm", r_ec_jump="eddy_resistance_jump_ohm",
                  r_ec_fit="eddy_resistance_fit_ohm")
def fit_motion_eddy(response: DetailedFrequencyResponse, *, resistance_ohm: float,
                    eddy_resistance_jump_ohm: float, eddy_resistance_fit_ohm: float,
                    max_unshielded_inductance_H: float | None = None,
                    fit_force: bool = False) -> MotionEddyFit:
    """Least-squares fit of ``R_a``, ``L_u``, ``R_2`` to a detailed frequency response.

    Residuals: ``(model - detailed)/|detailed|`` of gap -> current, voltage -> current and,
    with ``fit_force`` (where the response carries the statics' force partials), gap ->
    force at every frequency (real and imaginary parts, equal weights).  ``beta`` follows ``R_a`` and
    ``L_u`` so that the ladder keeps the detailed model's instantaneous gap -> current jump
    (:func:`unshielded_share`), ``gamma`` so that it keeps the gap -> force jump
    (:func:`force_share`).  Parameters are fitted as ``log R_a``, ``log R_2`` and
    ``logit(L_u/L_max)`` (so ``0 < L_u < L_max``, ``L_max`` the smaller of ``L~`` and
    ``max_unshielded_inductance_H``), with scipy's trust-region least squares from
    several starts: ``R_a`` at the exact jump value ``eddy_resistance_jump_ohm`` (and 3x,
    1/3x), ``R_2`` such that ``R_a || R_2`` is the step fit's ``eddy_resistance_fit_ohm``
    (else 3 times it),
    ``L_u/L~`` 1 %, 5 % and 20 %.

    Parameters
    ----------
    response : DetailedFrequencyResponse
    resistance_ohm : float
        ``R_el`` [ohm].
    eddy_resistance_jump_ohm, eddy_resistance_fit_ohm : float
        Eq. 8's ``R_ec`` from the exact jump and from the step's time constant [ohm]
        (the maps variables ``eddy_resistance_ohm`` and ``eddy_resistance_fit_ohm``).
    max_unshielded_inductance_H : float, optional
        Upper bound of ``L_u`` [H] (``build_maps``: :data:`MAX_UNSHIELDED_SHARE_OF_MIN_L`
        times the maps' smallest ``L~``); default ``L~`` of the response.
    fit_force : bool
        Fit the gap -> force response too (default False, as ``build_maps``: on the split
        TR09 network it halves the force error under gap motion but makes voltage steps
        worse, 3.1 -> 5.3 % of the step; docs/decisions.md).  The force error is reported
        either way where the response has the force partials.
    """
    from scipy.optimize import least_squares

    r_el, r_ec_jump, r_ec_fit = resistance_ohm, eddy_resistance_jump_ohm, eddy_resistance_fit_ohm
    lt, k = response.differential_inductance_H, response.dpsi_ds_Wb_per_m
    l_max = lt if max_unshielded_inductance_H is None else min(lt, max_unshielded_inductance_H)
    f = response.frequencies_Hz
    gs, gu = response.gap_to_current_A_per_m, response.voltage_to_current_A_per_V
    jump = response.gap_current_jump_A_per_m

    def unpack(x: np.ndarray) -> tuple[float, float, float, float]:
        r_a, l_u = float(np.exp(x[0])), float(l_max / (1.0 + np.exp(-x[1])))
        return (r_a, l_u, float(np.exp(x[2])),
                unshielded_share(jump, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
                                 jump_resistance_ohm=r_a, unshielded_inductance_H=l_u))

    def model(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r_a, l_u, r_2, beta = unpack(x)
        ms, il, mu = ladder_frequency_response(
            f, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
            jump_resistance_ohm=r_a, unshielded_inductance_H=l_u, shielding_resistance_ohm=r_2,
            beta=beta)
        ie = (1.0 + r_el / r_a) * ms - il
        gamma = _response_force_share(response, r_el, r_a, l_u, r_2, beta)
        return ms, mu, ladder_force_response(response, il, ie, gamma)

    def resid(x: np.ndarray) -> np.ndarray:
        ms, mu, mf = model(x)
        return _residuals(response, ms, mu, mf if fit_force else None)

    r_a0 = r_ec_jump if np.isfinite(r_ec_jump) and r_ec_jump > 0 else 3.0 * r_ec_fit
    best = None
    for ra in (r_a0, 3.0 * r_a0, r_a0 / 3.0):
        g2 = 1.0 / r_ec_fit - 1.0 / ra
        r2 = 1.0 / g2 if g2 > 0 else 3.0 * r_ec_fit
        for frac in (0.01, 0.05, 0.2):       # of L_max
            x0 = np.array([np.log(ra), np.log(frac / (1.0 - frac)), np.log(r2)])
            sol = least_squares(resid, x0, xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000)
            if best is None or sol.cost < best.cost:
                best = sol
    assert best is not None
    if best.status <= 0:
        warnings.warn(f"the motion-eddy ladder fit did not converge (status {best.status}: "
                      f"{best.message}; {best.nfev} evaluations): its R_a, L_u, R_2 are those "
                      "where it stopped (see its relative rms residual)", MaglevkitWarning,
                      stacklevel=2)
    r_a, l_u, r_2, beta = unpack(best.x)
    ms, mu, mf = model(best.x)
    moving = bool(np.all(np.abs(gs) > 0))
    forced = _with_force(response)
    return MotionEddyFit(r_a, l_u, r_2, beta,
                         _response_force_share(response, r_el, r_a, l_u, r_2, beta),
                         relative_rms_residual(response, ms, mu, mf if fit_force else None),
                         float(np.max(np.abs(ms / gs - 1.0))) if moving else float("nan"),
                         float(np.max(np.abs(mu / gu - 1.0))),
                         float(np.max(np.abs(mf / response.gap_to_force_N_per_m - 1.0)))
                         if forced else float("nan"))


# --- the three-state ladder (two shielded sections; linearised only) -------------------------
#
# docs/equations.md section 8, "Three states: a second shielded section".  Read from the coil
# terminals: U --R_el--+--L_u--+--L_2--+------------+
#                      R_a     R_2     R_3    L(s, I_L)
# States per circuit: the currents I_u (through L_u), I_2 (through L_2) and I_L; the gap
# section's inductance is L~ - L_u - L_2, the motion voltage e = dL/ds I_L ds/dt is shared
# as beta e (in L_u), beta_2 e (in L_2) and (1 - beta - beta_2) e (gap section), and the
# force is read at I_F = I_L + c_1 (I_2 - I_L) + c_2 (I_u - I_2) (= I_L in a steady state).


@dataclass(frozen=True)
class Ladder3Response:
    """Small-signal responses of the three-state ladder (:func:`ladder3_frequency_response`).

    Attributes
    ----------
    gap_states : ndarray (n_f, 3), complex
        ``(dI_u, dI_2, dI_L)`` per gap [A/m].
    voltage_states : ndarray (n_f, 3), complex
        ``(dI_u, dI_2, dI_L)`` per coil voltage [A/V].
    gap_to_current_A_per_m, voltage_to_current_A_per_V : ndarray (n_f,), complex
        Coil current per gap [A/m] and per voltage [A/V].
    """

    gap_states: np.ndarray
    voltage_states: np.ndarray
    gap_to_current_A_per_m: np.ndarray
    voltage_to_current_A_per_V: np.ndarray


def ladder3_frequency_response(frequencies_Hz: Any, *, differential_inductance_H: float,
                               dpsi_ds_Wb_per_m: float, resistance_ohm: float,
                               jump_resistance_ohm: float, unshielded_inductance_H: float,
                               shielding_resistance_ohm: float, inner_inductance_H: float,
                               inner_shielding_resistance_ohm: float, beta: float = 0.0,
                               inner_beta: float = 0.0) -> Ladder3Response:
    """Closed-form small-signal responses of the three-state ladder (two shielded sections).

    Linearised at a steady state (every eddy current 0), ``k = dpsi/ds``, ``a = 1 +
    R_el/R_a``, ``L_3 = L~ - L_u - L_2``; unknowns ``(I_u, I_2, I_L)``::

        [p L_u + R_el/a + R_2,  -R_2,               0         ] [I_u]   [U/a - beta k p s      ]
        [-R_2,           p L_2 + R_2 + R_3,         -R_3      ] [I_2] = [-beta_2 k p s         ]
        [0,                     -R_3,          p L_3 + R_3    ] [I_L]   [-(1-beta-beta_2) k p s]

        I = (1 - 1/a) U/R_el + I_u/a

    ``L_2 = 0`` is the two-state ladder (:func:`ladder_frequency_response`) with ``R_2 || R_3``
    as its ``R_2``; ``R_3 -> oo`` the two-state ladder with ``R_2``.

    Parameters
    ----------
    frequencies_Hz : array_like
        Frequencies [Hz].
    differential_inductance_H : float
        ``L~`` [H].
    dpsi_ds_Wb_per_m : float
        ``k = dL/ds I_L`` [Wb/m].
    resistance_ohm, jump_resistance_ohm : float
        ``R_el`` (>= 0) and the shunt ``R_a`` (> 0) [ohm].
    unshielded_inductance_H, inner_inductance_H : float
        The series ``L_u`` (> 0) and ``L_2`` (>= 0) [H], ``L_u + L_2 < L~``.
    shielding_resistance_ohm, inner_shielding_resistance_ohm : float
        The shunts ``R_2`` and ``R_3`` [ohm], > 0.
    beta, inner_beta : float
        The shares of the motion term in ``L_u`` and in ``L_2`` [-] (default 0).

    Returns
    -------
    Ladder3Response

    Raises
    ------
    InputError
        A non-finite or out-of-range element (named, with its value).
    """
    lt, k, r_el = differential_inductance_H, dpsi_ds_Wb_per_m, resistance_ohm
    r_a, l_u, r_2 = jump_resistance_ohm, unshielded_inductance_H, shielding_resistance_ohm
    l_2, r_3 = inner_inductance_H, inner_shielding_resistance_ohm
    named = {"differential_inductance_H": lt, "dpsi_ds_Wb_per_m": k, "resistance_ohm": r_el,
             "jump_resistance_ohm": r_a, "unshielded_inductance_H": l_u,
             "shielding_resistance_ohm": r_2, "inner_inductance_H": l_2,
             "inner_shielding_resistance_ohm": r_3, "beta": beta, "inner_beta": inner_beta}
    for name, value in named.items():
        if not math.isfinite(float(value)):
            raise InputError(f"ladder3_frequency_response: {name} = {value!r} must be finite")
    for name in ("jump_resistance_ohm", "unshielded_inductance_H", "shielding_resistance_ohm",
                 "inner_shielding_resistance_ohm"):
        if not named[name] > 0.0:
            raise InputError(f"ladder3_frequency_response: {name} = {named[name]!r} must be > 0")
    if r_el < 0.0 or l_2 < 0.0:
        raise InputError(f"ladder3_frequency_response: resistance_ohm = {r_el!r} and "
                         f"inner_inductance_H = {l_2!r} must be >= 0")
    if not l_u + l_2 < lt:
        raise InputError(f"ladder3_frequency_response: unshielded_inductance_H + "
                         f"inner_inductance_H = {l_u + l_2!r} must be below "
                         f"differential_inductance_H = {lt!r} (the gap section's inductance)")
    p = 2j * np.pi * np.asarray(frequencies_Hz, dtype=float).ravel()
    a = 1.0 + r_el / r_a
    m = np.zeros((p.size, 3, 3), dtype=complex)
    m[:, 0, 0] = p * l_u + r_el / a + r_2
    m[:, 0, 1] = m[:, 1, 0] = -r_2
    m[:, 1, 1] = p * l_2 + r_2 + r_3
    m[:, 1, 2] = m[:, 2, 1] = -r_3
    m[:, 2, 2] = p * (lt - l_u - l_2) + r_3
    rhs = np.zeros((p.size, 3, 2), dtype=complex)
    rhs[:, :, 0] = -k * p[:, None] * np.array([beta, inner_beta, 1.0 - beta - inner_beta])
    rhs[:, 0, 1] = 1.0 / a
    x = np.linalg.solve(m, rhs)
    xs, xu = x[:, :, 0], x[:, :, 1]
    return Ladder3Response(xs, xu, xs[:, 0] / a, (1.0 - 1.0 / a) / r_el + xu[:, 0] / a)


def ladder3_force_current(i_u: Any, i_2: Any, i_l: Any, force_shares: Any) -> Any:
    """The three-state ladder's force current ``I_L + c_1 (I_2 - I_L) + c_2 (I_u - I_2)``
    [A] from its currents ``I_u``, ``I_2``, ``I_L`` [A] and ``force_shares = (c_1, c_2)``
    [-] (both 0: the force ``F(s, I_L)``; in a steady state it is ``I_L`` whatever they
    are).  Element-wise on floats, NumPy arrays and CasADi expressions (the law of
    ``CurrentModel(maps, motion_eddy=True, eddy_branches=2)`` too)."""
    c1, c2 = force_shares
    return i_l + c1 * (i_2 - i_l) + c2 * (i_u - i_2)


def _force3(states: np.ndarray, shares: Any) -> np.ndarray:
    return np.asarray(ladder3_force_current(states[..., 0], states[..., 1], states[..., 2],
                                            shares))


#: Weights of the gap -> current, voltage -> current, gap -> force and voltage -> force
#: residuals in ``build_maps``'s three-state fit: equal weights let the force responses
#: pull the voltage -> current response off (split TR09: up to 17 %, voltage steps 2.9 ->
#: 5.0 % current error); these keep it within 2 % and the gap responses within issue 26's
#: aims (docs/decisions.md, ladder3).
MOTION_EDDY3_WEIGHTS = (3.0, 10.0, 1.0, 1.0)


@dataclass(frozen=True)
class MotionEddy3Fit:
    """Fitted three-state ladder of one circuit (:func:`fit_motion_eddy3`).

    Attributes
    ----------
    jump_resistance_ohm, shielding_resistance_ohm, inner_shielding_resistance_ohm : float
        ``R_a``, ``R_2``, ``R_3`` [ohm].
    unshielded_inductance_H, inner_inductance_H : float
        ``L_u``, ``L_2`` [H].
    unshielded_share, inner_share : float
        ``beta`` (from the exact gap -> current jump, :func:`unshielded_share`) and
        ``beta_2`` (fitted) [-].
    force_shares : tuple of float
        ``(c_1, c_2)`` of :func:`ladder3_force_current` [-].
    rms_residual : float
        RMS relative residual over the four responses and the fit's frequencies, unweighted
        (each response relative to its modulus, real and imaginary parts; the fit's
        ``weights`` shape its objective, not this measure, which is the two-state fit's).
    response_residuals : tuple of 4 floats
        The same per response: gap -> current, voltage -> current, gap -> force, voltage ->
        force [-] (NaN: not known, a fit made by hand).
    series_bound_share : float
        ``(L_u + L_2)/L_max`` [-], ``L_max`` the bound of the series inductances; near 1 the
        bound holds the fit (NaN: not known).  ``build_maps``' bound is
        :data:`MAX_UNSHIELDED_SHARE_OF_MIN_L` times the maps' smallest ``L~``: on maps that
        reach deep saturation (the guidance magnet to 80 A) it sits far below the series
        inductances that the operating point asks for (docs/reduction.md, "Gap motion").
    """

    jump_resistance_ohm: float
    unshielded_inductance_H: float
    shielding_resistance_ohm: float
    inner_inductance_H: float
    inner_shielding_resistance_ohm: float
    unshielded_share: float
    inner_share: float
    force_shares: tuple[float, float]
    rms_residual: float
    response_residuals: tuple[float, float, float, float] = (math.nan,) * 4
    series_bound_share: float = math.nan

    def response(self, frequencies_Hz: Any, detailed: DetailedFrequencyResponse,
                 resistance_ohm: float) -> tuple[Ladder3Response, np.ndarray, np.ndarray]:
        """The ladder's responses at the operating point of ``detailed`` (its ``L~``, ``k``
        and force partials): states, gap -> force [N/m] and voltage -> force [N/V]."""
        r = ladder3_frequency_response(
            frequencies_Hz, differential_inductance_H=detailed.differential_inductance_H,
            dpsi_ds_Wb_per_m=detailed.dpsi_ds_Wb_per_m, resistance_ohm=resistance_ohm,
            jump_resistance_ohm=self.jump_resistance_ohm,
            unshielded_inductance_H=self.unshielded_inductance_H,
            shielding_resistance_ohm=self.shielding_resistance_ohm,
            inner_inductance_H=self.inner_inductance_H,
            inner_shielding_resistance_ohm=self.inner_shielding_resistance_ohm,
            beta=self.unshielded_share, inner_beta=self.inner_share)
        dfi = detailed.dforce_dcurrent_N_per_A
        return (r, dfi * _force3(r.gap_states, self.force_shares)
                + detailed.dforce_dgap_N_per_m,
                dfi * _force3(r.voltage_states, self.force_shares))


#: Starts of :func:`fit_motion_eddy3`: ``(R_a/R_ec, L_u/L_max, R_2/R_ec, L_2/L_max)`` with
#: ``R_ec`` the exact jump value (``R_3`` starts at ``2 R_ec``, ``beta_2`` at 0).  Four
#: spread ones: of the 36 of the grid R_a/R_ec in {1, 3}, L_u/L_max in {0.02, 0.05, 0.15},
#: L_2/L_max in {0.05, 0.2, 0.5}, R_2/R_ec in {2, 8}, 35 (split TR09) and 36 (U-magnet)
#: reach the same optimum (residual within 1e-6), these four on both (docs/decisions.md,
#: ladder3).
_FIT3_STARTS = ((1.0, 0.05, 0.2, 2.0), (3.0, 0.15, 0.5, 8.0), (1.0, 0.02, 0.5, 8.0),
                (3.0, 0.05, 0.05, 2.0))


def fit_motion_eddy3(response: DetailedFrequencyResponse, *, resistance_ohm: float,
                     eddy_resistance_jump_ohm: float,
                     max_series_inductance_H: float | None = None,
                     weights: Any = (1.0, 1.0, 1.0, 1.0)) -> MotionEddy3Fit:
    """Least-squares fit of the three-state ladder to all four detailed responses.

    Residuals ``(model - detailed)/|detailed|`` (real and imaginary parts, equal weights) of
    gap -> current, voltage -> current, gap -> force and voltage -> force at every frequency
    of ``response``.  Parameters: ``log R_a``, ``log R_2``, ``log R_3``, ``L_u`` and ``L_2``
    as shares of ``L_max`` (softmax, so ``L_u + L_2 < L_max``, ``L_max`` the smaller of
    ``L~`` and ``max_series_inductance_H``) and ``beta_2``; ``beta`` follows from the exact
    gap -> current jump (:func:`unshielded_share`); the force shares ``(c_1, c_2)`` enter
    linearly and are solved for at every iterate (linear least squares on the two force
    responses).  Four starts (``_FIT3_STARTS``): ``R_a`` at 1 or 3 times the exact jump
    ``R_ec``, ``R_2`` at 2 or 8 times it, ``R_3`` at 2 times it, ``L_u`` and ``L_2`` at 2 -
    15 % and 5 - 50 % of ``L_max``.

    Parameters
    ----------
    response : DetailedFrequencyResponse
        With the force partials and ``voltage_to_force_N_per_V``.
    resistance_ohm : float
        ``R_el`` [ohm].
    eddy_resistance_jump_ohm : float
        Eq. 8's ``R_ec`` from the exact jump [ohm] (the starts' scale), > 0.
    max_series_inductance_H : float, optional
        Bound of ``L_u + L_2`` [H] (e.g. 0.8 times the maps' smallest ``L~``); default ``L~``.
    weights : sequence of 4 floats
        Weights of the gap -> current, voltage -> current, gap -> force and voltage -> force
        residuals (default equal; :data:`MOTION_EDDY3_WEIGHTS` in ``build_maps``).

    Raises
    ------
    InputError
        The response has no force partials or voltage -> force, or ``R_ec`` is not > 0.
    """
    from scipy.optimize import least_squares

    if not _with_force(response) or response.voltage_to_force_N_per_V is None:
        raise InputError("fit_motion_eddy3: the response needs the force partials and "
                         "voltage_to_force_N_per_V (detailed_frequency_response gives both)")
    rj = float(eddy_resistance_jump_ohm)
    if not (math.isfinite(rj) and rj > 0.0):
        raise InputError(f"fit_motion_eddy3: eddy_resistance_jump_ohm = {rj!r} must be > 0")
    r_el = float(resistance_ohm)
    lt, k = response.differential_inductance_H, response.dpsi_ds_Wb_per_m
    l_max = lt if max_series_inductance_H is None else min(lt, max_series_inductance_H)
    f = response.frequencies_Hz
    dfi = response.dforce_dcurrent_N_per_A
    det = (response.gap_to_current_A_per_m, response.voltage_to_current_A_per_V,
           response.gap_to_force_N_per_m, response.voltage_to_force_N_per_V)
    w = [float(v) for v in weights]
    if len(w) != 4 or not all(math.isfinite(v) and v > 0 for v in w):
        raise InputError(f"fit_motion_eddy3: weights = {weights!r}; give four numbers > 0")
    scale = [np.abs(d) / wk for d, wk in zip(det, w, strict=True)]

    def unpack(x: np.ndarray) -> tuple[float, float, float, float, float, float, float]:
        e1, e2 = float(np.exp(x[1])), float(np.exp(x[3]))
        r_a, l_u, l_2 = float(np.exp(x[0])), l_max * e1 / (1 + e1 + e2), l_max * e2 / (1 + e1 + e2)
        beta = unshielded_share(response.gap_current_jump_A_per_m, dpsi_ds_Wb_per_m=k,
                                resistance_ohm=r_el, jump_resistance_ohm=r_a,
                                unshielded_inductance_H=l_u)
        return r_a, l_u, float(np.exp(x[2])), l_2, float(np.exp(x[4])), beta, float(x[5])

    def model(x: np.ndarray) -> tuple[list[np.ndarray], tuple[float, float]]:
        r_a, l_u, r_2, l_2, r_3, beta, beta_2 = unpack(x)
        r = ladder3_frequency_response(
            f, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
            jump_resistance_ohm=r_a, unshielded_inductance_H=l_u, shielding_resistance_ohm=r_2,
            inner_inductance_H=l_2, inner_shielding_resistance_ohm=r_3, beta=beta,
            inner_beta=beta_2)
        base_s = dfi * r.gap_states[:, 2] + response.dforce_dgap_N_per_m
        base_u = dfi * r.voltage_states[:, 2]
        cols_s = [dfi * _force3(r.gap_states, c) - base_s
                  + response.dforce_dgap_N_per_m for c in ((1, 0), (0, 1))]
        cols_u = [dfi * _force3(r.voltage_states, c) - base_u
                  for c in ((1, 0), (0, 1))]
        lhs = np.concatenate([np.stack(cols_s, 1) / scale[2][:, None],
                              np.stack(cols_u, 1) / scale[3][:, None]])
        rhs = np.concatenate([(det[2] - base_s) / scale[2], (det[3] - base_u) / scale[3]])
        c = np.linalg.lstsq(np.concatenate([lhs.real, lhs.imag]),
                            np.concatenate([rhs.real, rhs.imag]), rcond=None)[0]
        shares = (float(c[0]), float(c[1]))
        return [r.gap_to_current_A_per_m, r.voltage_to_current_A_per_V,
                dfi * _force3(r.gap_states, shares) + response.dforce_dgap_N_per_m,
                dfi * _force3(r.voltage_states, shares)], shares

    def resid(x: np.ndarray) -> np.ndarray:
        e = np.concatenate([(m - d) / s for m, d, s in zip(model(x)[0], det, scale,
                                                                strict=True)])
        return np.concatenate([e.real, e.imag])

    best = None
    for ra, s1, s2, r2 in _FIT3_STARTS:
        x0 = np.array([np.log(ra * rj), np.log(s1 / (1 - s1 - s2)), np.log(r2 * rj),
                       np.log(s2 / (1 - s1 - s2)), np.log(2.0 * rj), 0.0])
        sol = least_squares(resid, x0, xtol=1e-10, ftol=1e-10, max_nfev=3000)
        if best is None or sol.cost < best.cost:
            best = sol
    assert best is not None
    r_a, l_u, r_2, l_2, r_3, beta, beta_2 = unpack(best.x)
    fitted, shares = model(best.x)
    # unweighted: each response relative to its modulus (real and imaginary parts)
    parts = [np.concatenate([((m - d) / np.abs(d)).real, ((m - d) / np.abs(d)).imag])
             for m, d in zip(fitted, det, strict=True)]
    per = tuple(float(np.sqrt(np.mean(e ** 2))) for e in parts)
    return MotionEddy3Fit(r_a, l_u, r_2, l_2, r_3, beta, beta_2, shares,
                          float(np.sqrt(np.mean(np.concatenate(parts) ** 2))),
                          (per[0], per[1], per[2], per[3]), (l_u + l_2) / l_max)
