"""Calibrate a magnet's uncertain network parameters to measured statics (issue 25, part 2).

The equivalent circuit's uncertain factors are applied as element wrappers (one law, used
both with numbers -- the calibrated network -- and with CasADi symbols -- the exact
parameter derivatives):

=========================  =======  ================================================
parameter                  nominal  effect
=========================  =======  ================================================
``leakage_factor``         1        scales every leakage permeance (gap-independent
                                    :class:`~maglevkit.circuit.LeakagePermeance` and the
                                    gap-dependent :class:`~maglevkit.circuit.GapLeakage`)
``fringing_factor``        1        scales the fringing permeance of the air gaps (the
                                    fringe-edge part of :class:`~maglevkit.circuit.AirGap`,
                                    :class:`~maglevkit.circuit.elements.FringePermeance`)
``gap_offset_m``           0        added to every gap: ``s_eff = s + delta`` [m]
                                    (coating, rail tolerance, gap sensor offset)
``iron_field_scale``       1        scales ``H(B)`` of every iron path (B-H curve
                                    stretched along H: permeability / k)
``iron_saturation_scale``  1        scales the B axis of every iron path:
                                    ``V_m = l H(B/k)`` (saturation flux density x k)
``eddy_conductance_scale`` 1        scales every eddy conductance ``G_ec`` (dynamics)
``resistance_scale``       1        scales every circuit's ``R_el`` (dynamics)
=========================  =======  ================================================

The last two do not enter the statics (static data cannot determine them: a zero
Jacobian column, named undetermined); measured voltage steps (:func:`read_steps`,
``calibrate(..., steps=)``) determine them, fitted together with the statics.

:func:`calibrate` fits a chosen subset by bounded least squares (SciPy ``least_squares``,
trust-region reflective) on the relative residuals ``(model - data)/|data|`` of the force
and/or flux linkage (and ``(I_model - I_data)/dI`` of the voltage steps' samples, ``dI``
the step's largest measured current change), with the exact Jacobian: the statics are a
CasADi ``rootfinder`` of
the network's loop law ``r(x; s, I, p) = 0``, whose parameter sensitivities CasADi
computes by the implicit function theorem, ``dx/dp = -(dr/dx)^-1 dr/dp``.  Reported:
residuals per point, values with 95 % confidence intervals from the Jacobian
(``cov = s^2 (J^T J)^-1``, ``s^2 = SSR/(m - n)``, Student t), the singular values of the
parameter-scaled Jacobian with the parameters the data cannot determine, and a held-out
check.  See docs/magnets.md, "Calibration".
"""

from __future__ import annotations

import hashlib
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ._interrupt import sigint_received
from .circuit.factors import DYNAMIC_PARAMETERS, PARAMETERS, with_factors
from .circuit.network import Network
from .errors import DataError, DataWarning, InputError, MaglevkitWarning, SolverError
from .parameter_files import toml_text

__all__ = ["PARAMETERS", "DEFAULT_PARAMETERS", "DYNAMIC_PARAMETERS", "STEP_COLUMNS",
           "STEP_GAP_PLAUSIBLE_M", "STEP_FINE_STEPS", "STEP_REST_TOLERANCE",
           "STEP_SPAN_MAX_TAU", "Calibration", "ParameterSetScore",
           "StaticPoints",
           "StepResponses", "VoltageStep", "calibrate", "calibrated_network",
           "parameter_sensitivities", "read_points", "read_steps", "select_parameters",
           "step_response_sensitivities", "step_substeps", "interval_substeps",
           "write_calibrated_toml", "load_calibrated_magnet"]


DEFAULT_PARAMETERS = ("leakage_factor", "fringing_factor", "gap_offset_m", "iron_field_scale",
                      "iron_saturation_scale")
"""Fitted to statics without ``parameters=``: the factors that act on the statics (with
voltage steps :data:`DYNAMIC_PARAMETERS` are added; steps alone fit only those)."""


# ---------------------------------------------------------------------------- the one law
def calibrated_network(model: Any, values: Mapping[str, Any]) -> Network:
    """The network of ``model`` with the calibration ``values`` applied
    (:func:`maglevkit.circuit.factors.with_factors`, the one law).

    Parameters
    ----------
    model : Magnet or Network
        The uncalibrated magnet or network.
    values : mapping
        Parameter names of :data:`PARAMETERS` to numbers (unit of the parameter) or CasADi
        symbols; missing ones stay nominal.  With nominal values the statics equal the
        original's.
    """
    from .models.statics import as_network

    return with_factors(as_network(model), values)


# ---------------------------------------------------------------------------- data
@dataclass(frozen=True)
class StaticPoints:
    """Measured statics: force and/or flux linkage per circuit at (gap, current) points.

    Attributes
    ----------
    gap_m, current_A : ndarray (n,)
        All gaps at ``gap_m`` [m], every circuit at ``current_A`` [A].
    force_N, flux_linkage_Wb : ndarray (n, n_circuits) or None
        Measured circuit force [N] (attraction positive) and flux linkage [Wb].
    circuits : tuple of str
    rows : ndarray (n,) of int
        File rows (line numbers).
    source, sha256 : str
        File and the SHA-256 of its bytes.
    """

    gap_m: np.ndarray
    current_A: np.ndarray
    force_N: np.ndarray | None
    flux_linkage_Wb: np.ndarray | None
    circuits: tuple[str, ...]
    rows: np.ndarray
    source: str = "<memory>"
    sha256: str = ""

    def subset(self, mask: np.ndarray) -> StaticPoints:
        return replace(self, gap_m=self.gap_m[mask], current_A=self.current_A[mask],
                       force_N=None if self.force_N is None else self.force_N[mask],
                       flux_linkage_Wb=None if self.flux_linkage_Wb is None
                       else self.flux_linkage_Wb[mask], rows=self.rows[mask])


def read_points(path: str | Path) -> StaticPoints:
    """Measured statics from a CSV in the table format of
    :func:`~maglevkit.reduction.tables_in.read_table` (columns ``gap_m``, ``current_A``,
    ``force_N`` and/or ``flux_linkage_Wb`` with ``_<circuit>`` suffixes), any points (no
    grid needed); the same checks of columns and cells, naming the row."""
    from .reduction.tables_in import read_rows

    rows = read_rows(path)
    n = rows.lines.size
    arrays: dict[str, np.ndarray | None] = {}
    for q in ("force_N", "flux_linkage_Wb"):
        if (q, rows.circuit_keys[0]) in rows.columns:
            arrays[q] = np.stack([rows.columns[(q, c)] for c in rows.circuit_keys], axis=1)
        else:
            arrays[q] = None
    if rows.total_force_N is not None and arrays["force_N"] is None:
        warnings.warn(f"{rows.source}: the total force_N is not fitted: calibrate fits "
                      "each circuit's force (force_N_<circuit> columns, which the table "
                      "lacks)", DataWarning, stacklevel=2)
    if np.any(rows.current_A <= 0.0):
        i = int(np.argmax(rows.current_A <= 0.0))
        raise DataError(f"{rows.source}: row {rows.lines[i]}: current_A = "
                        f"{rows.current_A[i]:g}; calibration points need I > 0 A (relative "
                        "residuals; F = psi = 0 at 0 A)")
    seen: dict[tuple[float, float], int] = {}
    for k, key in enumerate(zip(rows.gap_m.tolist(), rows.current_A.tolist(), strict=True)):
        if key in seen:
            warnings.warn(f"{rows.source}: row {rows.lines[k]} repeats the point gap "
                          f"{key[0]:g} m, current {key[1]:g} A of row {rows.lines[seen[key]]}; "
                          "both are fitted (a repeated measurement weighs the point twice; "
                          "delete the row if it is a copy)", DataWarning, stacklevel=2)
            break
        seen[key] = k
    return StaticPoints(gap_m=rows.gap_m, current_A=rows.current_A, force_N=arrays["force_N"],
                        flux_linkage_Wb=arrays["flux_linkage_Wb"], circuits=rows.circuits,
                        rows=rows.lines if n else np.zeros(0, dtype=int), source=rows.source,
                        sha256=rows.sha256)


STEP_COLUMNS = ("time_s", "current_A", "gap_m", "initial_current_A", "voltage_V")
"""Required columns of a voltage-step file (:func:`read_steps`); ``step`` and ``circuit``
are optional."""

STEP_GAP_PLAUSIBLE_M = (1e-4, 0.1)
"""Gaps outside this range [m] are refused in a step file as a unit slip (mm as m)."""


@dataclass(frozen=True)
class VoltageStep:
    """One measured voltage step: the coil current after ``U`` steps to ``voltage_V``.

    Attributes
    ----------
    label : str
        The ``step`` column's value (or its number in the file).
    time_s, current_A : ndarray (n,)
        Samples after the step, ``t > 0`` [s], and the stepped circuit's current [A].
    gap_m : float
        Every gap, held [m].
    initial_current_A : float
        Every circuit's current before the step, at rest [A].
    voltage_V : float
        The stepped circuit's voltage after ``t = 0`` [V] (the others hold
        ``R_el I_0``).
    circuit : str
        The stepped circuit ("" for a one-circuit magnet).
    rows : ndarray (n,) of int
        File rows of the samples.
    """

    label: str
    time_s: np.ndarray
    current_A: np.ndarray
    gap_m: float
    initial_current_A: float
    voltage_V: float
    circuit: str
    rows: np.ndarray

    @property
    def current_change_A(self) -> float:
        """Largest measured ``|I - I_0|`` [A]: the scale of the step's residuals."""
        return float(np.max(np.abs(self.current_A - self.initial_current_A)))


@dataclass(frozen=True)
class StepResponses:
    """Measured voltage steps (:func:`read_steps`).

    Attributes
    ----------
    steps : tuple of VoltageStep
    source, sha256 : str
        File and the SHA-256 of its bytes.
    """

    steps: tuple[VoltageStep, ...]
    source: str = "<memory>"
    sha256: str = ""


def read_steps(path: str | Path) -> StepResponses:
    """Measured voltage steps from a CSV file.

    Columns ``time_s`` [s], ``current_A`` [A] (the stepped circuit's coil current),
    ``gap_m`` [m], ``initial_current_A`` [A] (every circuit's current at rest before the
    step) and ``voltage_V`` [V] (the stepped circuit's voltage from ``t = 0`` on), optional
    ``step`` (a label) and ``circuit`` (the stepped circuit's name); lines starting with
    ``#`` are comments.  Consecutive rows with the same ``step``, ``gap_m``,
    ``initial_current_A``, ``voltage_V`` and ``circuit`` form one step; its times must
    increase; samples at ``t <= 0`` (before the step) are read and not fitted (the state
    before the step is the statics at ``initial_current_A``).

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Raises
    ------
    DataError
        A missing or unknown column, a cell that is not a finite number, times that do not
        increase within a step, fewer than 3 samples after ``t = 0``, a gap outside
        :data:`STEP_GAP_PLAUSIBLE_M` (mm as m), a negative current, or a current that does
        not change; each naming the row.
    """

    from .errors import ParameterFileError

    if not isinstance(path, (str, Path)):
        raise InputError(f"read_steps needs a file path (str or Path), got {type(path).__name__}")
    p = Path(path)
    if not p.is_file():
        raise ParameterFileError(f"voltage-step file {str(p)!r} does not exist")
    from .reduction.tables_in import csv_records

    raw = p.read_bytes()
    header, records = csv_records(p, raw)
    header = None if header is None else [h.strip() for h in header]
    allowed = (*STEP_COLUMNS, "step", "circuit")
    if header is None:
        raise DataError(f"{p}: the file is empty (expected a header row: "
                        f"{', '.join(STEP_COLUMNS)} [, step, circuit])")
    unknown = [h for h in header if h not in allowed]
    missing = [h for h in STEP_COLUMNS if h not in header]
    if unknown or missing or len(set(header)) != len(header):
        import difflib

        hints = [f"{u!r} -> {m[0]!r}?" for u in unknown
                 for m in [difflib.get_close_matches(u, missing or allowed, n=1, cutoff=0.6)]
                 if m]
        raise DataError(f"{p}: columns {header}: unknown {unknown}, missing {missing}"
                        + (f" (did you mean {', '.join(hints)})" if hints else "")
                        + f"; a voltage-step file has {', '.join(STEP_COLUMNS)} and "
                        "optionally step, circuit (each once)")
    if not records:
        raise DataError(f"{p}: the file has a header but no data rows")
    col = {h: k for k, h in enumerate(header)}
    steps: list[VoltageStep] = []
    group: list[tuple[int, list[float]]] = []
    key: tuple[Any, ...] | None = None
    first_row: dict[str, int] = {}

    def close() -> None:
        if not group:
            return
        rows = np.array([r for r, _ in group])
        vals = np.array([v for _, v in group])
        after = vals[:, 0] > 0.0
        label = str(key[0]) if key and key[0] else str(len(steps) + 1)
        if np.count_nonzero(after) < 3:
            raise DataError(f"{p}: the step starting at row {rows[0]} has "
                            f"{np.count_nonzero(after)} samples at time_s > 0; a step needs at "
                            "least 3 after t = 0 (gap_m, initial_current_A, voltage_V and "
                            "circuit are constant over a step's rows: a change starts a new "
                            "step)")
        if label in first_row:
            raise DataError(f"{p}: row {rows[0]}: step {label!r} again (its rows start at row "
                            f"{first_row[label]}) with another gap_m, initial_current_A, "
                            "voltage_V or circuit, or after another step; a step's rows are "
                            "consecutive and share those values")
        first_row[label] = int(rows[0])
        _check_rest(p, label, rows[~after], vals[~after], vals[after])
        step = VoltageStep(label=label, time_s=vals[after, 0], current_A=vals[after, 1],
                           gap_m=float(vals[0, 2]), initial_current_A=float(vals[0, 3]),
                           voltage_V=float(vals[0, 4]), circuit=str(key[4]) if key else "",
                           rows=rows[after])
        if not step.current_change_A > 1e-9 * max(1.0, abs(step.initial_current_A)):
            raise DataError(f"{p}: the step starting at row {rows[0]}: current_A stays at "
                            f"initial_current_A = {step.initial_current_A:g} A: no step")
        steps.append(step)

    for row, cells in records:
        if len(cells) != len(header):
            raise DataError(f"{p}: row {row} has {len(cells)} cells, the header {len(header)}")
        nums = []
        for name in STEP_COLUMNS:
            cell = cells[col[name]].strip()
            try:
                v = float(cell)
            except ValueError:
                raise DataError(f"{p}: row {row}, column {name}: {cell!r} is not a number"
                                ) from None
            if not math.isfinite(v):
                raise DataError(f"{p}: row {row}, column {name}: {cell!r} is not a finite "
                                "number")
            nums.append(v)
        lo, hi = STEP_GAP_PLAUSIBLE_M
        if not lo <= nums[2] <= hi:
            raise DataError(f"{p}: row {row}: gap_m = {nums[2]:g} lies outside {lo:g}-{hi:g} "
                            "m; is the gap in mm? (gap_m is in metres)")
        if nums[1] < 0.0 or nums[3] < 0.0:
            raise DataError(f"{p}: row {row}: current_A = {nums[1]:g}, initial_current_A = "
                            f"{nums[3]:g}: currents must be >= 0 A")
        new_key = (cells[col["step"]].strip() if "step" in col else "", *nums[2:5],
                   cells[col["circuit"]].strip() if "circuit" in col else "")
        if new_key != key:
            n_after = sum(1 for _, v in group if v[0] > 0.0)
            if group and key is not None and n_after < 3:
                changed = [f"{name} {a!r} -> {b!r}" for name, a, b in zip(
                    ("step", "gap_m", "initial_current_A", "voltage_V", "circuit"), key,
                    new_key, strict=True) if a != b]
                raise DataError(f"{p}: row {row}: {', '.join(changed)} after {n_after} "
                                f"samples at time_s > 0 of the step starting at row "
                                f"{group[0][0]}: a step needs at least 3 with the same "
                                "step, gap_m, initial_current_A, voltage_V and circuit (a "
                                "change starts a new step"
                                + ("; voltage_V is the voltage after the step, on the rows "
                                   "before it too" if n_after == 0 and key[3] != new_key[3]
                                   else "") + ")")
            close()
            group, key = [], new_key
        elif group and nums[0] <= group[-1][1][0]:
            raise DataError(f"{p}: row {row}: time_s = {nums[0]:g} s does not increase (row "
                            f"{group[-1][0]}: {group[-1][1][0]:g} s) within the step; start "
                            "another step with a new step label")
        group.append((row, nums))
    close()
    return StepResponses(steps=tuple(steps), source=str(p),
                         sha256=hashlib.sha256(raw).hexdigest())


STEP_REST_TOLERANCE = 0.02
"""Samples before the step (``time_s <= 0``) whose current differs from
``initial_current_A`` by more than this share of the step's current change (or 0.1 % of
``initial_current_A``, the larger) are warned about: the model starts from the statics at
``initial_current_A``, i.e. a magnet at rest."""


def _check_rest(path: Path, label: str, rows: np.ndarray, before: np.ndarray,
                after: np.ndarray) -> None:
    """Warn (naming the first row) when the samples before a step show a magnet that is
    not at rest at ``initial_current_A``."""
    if not rows.size:
        return
    i0 = float(before[0, 3])
    change = float(np.max(np.abs(after[:, 1] - i0)))
    tol = max(STEP_REST_TOLERANCE * change, 1e-3 * abs(i0))
    off = np.abs(before[:, 1] - i0) > tol
    if off.any():
        k = int(np.argmax(off))
        warnings.warn(f"{path}: row {int(rows[k])}: step {label!r} before the step (time_s = "
                      f"{before[k, 0]:g} s) has current_A = {before[k, 1]:g} A, not "
                      f"initial_current_A = {i0:g} A ({int(off.sum())} such rows): the model "
                      "starts from the magnet at rest at initial_current_A (the statics), "
                      "so the fit sees a step from the wrong state", DataWarning, stacklevel=4)


# ---------------------------------------------------------------------------- exact statics
class _ParametricStatics:
    """CasADi statics of a network with symbolic calibration parameters.

    ``evaluate(names, values, s, I, x0)`` returns the circuit forces, flux linkages, their
    exact Jacobians w.r.t. the named parameters and the loop fluxes (warm start).
    """

    def __init__(self, model: Any, names: Sequence[str],
                 pole_groups: Mapping[str, Sequence[str]]) -> None:
        import casadi as ca

        from .circuit.assembly import assemble
        from .models.statics import as_network

        base = as_network(model)
        self.names = tuple(names)
        p = ca.SX.sym("p", len(self.names))
        net = calibrated_network(base, {n: p[k] for k, n in enumerate(self.names)})
        eq = assemble(net)
        gi = {g: k for k, g in enumerate(net.gap_names)}
        groups = np.zeros((len(net.circuits), len(gi)))
        for j, c in enumerate(net.circuit_names):
            for g in pole_groups[c]:
                groups[j, gi[g]] = 1.0
        force = ca.mtimes(ca.DM(groups), eq.force)
        par = ca.vertcat(eq.s, eq.I, p)
        g_fun = ca.Function("calibration_residual", [eq.x, par], [eq.residual])
        rf = ca.rootfinder("calibration_statics", "newton", g_fun,
                           {"abstol": 1e-9, "abstolStep": 1e-14, "max_iter": 60,
                            "error_on_fail": True})
        X0 = ca.MX.sym("x0", eq.x.numel())
        SI = ca.MX.sym("s_I", eq.s.numel() + eq.I.numel())
        pp = ca.MX.sym("p", p.numel())
        P = ca.vertcat(SI, pp)
        xs = rf(X0, P)
        outs = ca.Function("calibration_outputs", [eq.x, par], [force, eq.psi])
        f_mx, psi_mx = outs(xs, P)
        inner = ca.Function("calibration_statics_inner", [X0, SI, pp],
                               [f_mx, psi_mx, ca.jacobian(f_mx, pp), ca.jacobian(psi_mx, pp),
                                xs])
        self.fun = lambda x0, par: inner(x0, par[:-p.numel()], par[-p.numel():])
        self.n_gaps, self.n_circuits = eq.s.numel(), eq.I.numel()
        self.network = base

    def evaluate(self, values: np.ndarray, gap: float, current: float, x0: np.ndarray
                 ) -> tuple[np.ndarray, ...]:
        par = np.concatenate((np.full(self.n_gaps, gap), np.full(self.n_circuits, current),
                              values))
        try:
            f, psi, jf, jpsi, xs = self.fun(x0, par)
        except RuntimeError as exc:
            if sigint_received():
                raise KeyboardInterrupt from None
            raise SolverError("the calibration statics did not converge",
                              state={"gap_m": gap, "current_A": current,
                                     **dict(zip(self.names, values, strict=True))},
                              reason=str(exc).splitlines()[-1][-200:]) from None
        if sigint_received():
            # a Ctrl-C inside CasADi's rootfinder is swallowed there: the fit went on and
            # wrote its file (exit 0); end it here, the CLI reports it (exit 130)
            raise KeyboardInterrupt
        return (np.asarray(f).ravel(), np.asarray(psi).ravel(), np.asarray(jf),
                np.asarray(jpsi), np.asarray(xs).ravel())


def _start(model: Any, values: Mapping[str, float], gap: np.ndarray, current: np.ndarray
           ) -> np.ndarray:
    """Loop fluxes of the (numeric) calibrated network at every point (solve_statics)."""
    from .models.statics import solve_statics

    net = calibrated_network(model, values)
    ng, nc = len(net.gap_names), len(net.circuits)
    if gap.size == 0:
        return np.zeros((0, net.n_loops))
    sol = solve_statics(net, gaps_m=np.repeat(gap[:, None], ng, axis=1),
                        currents_A=np.repeat(current[:, None], nc, axis=1))
    return np.asarray(sol.loop_flux_Wb, dtype=float).reshape(gap.size, -1)


def parameter_sensitivities(model: Any, values: Mapping[str, float], *, gap_m: float,
                            current_A: float) -> dict[str, np.ndarray]:
    """Circuit force and flux linkage at one point and their exact derivatives w.r.t. the
    calibration parameters ``values`` (names -> values).

    Returns
    -------
    dict
        ``force_N`` (n_c,), ``flux_linkage_Wb`` (n_c,), ``dforce_dp`` and ``dpsi_dp``
        (n_c, n_p) in the order of ``values``.
    """
    names = _names(values)
    groups = _groups(model)
    ps = _ParametricStatics(model, names, groups)
    v = np.array([float(values[n]) for n in names])
    x0 = _start(model, values, np.array([gap_m]), np.array([current_A]))[0]
    f, psi, jf, jpsi, _ = ps.evaluate(v, gap_m, current_A, x0)
    return {"force_N": f, "flux_linkage_Wb": psi, "dforce_dp": jf, "dpsi_dp": jpsi}


_STEP_SUBSTEPS = 40
"""Most Radau (order 5, 3 points) steps per output interval of the step response (plus 40
geometric ones from 1e-6 of the window to the first output, for the fast eddy modes);
:func:`step_substeps` takes fewer for many samples."""


_STEP_ABSTOL = 1e-10
"""Newton tolerance of the step response's rootfinders on the scaled DAE (relative to
each unknown's scale: every residual row is O(1) per relative change of the unknowns).
Measured (U-magnet, 10 mm, 20 A, +8 V, 12 samples, 10 Radau steps per interval), the
lumped network: derivatives against central differences 7.7e-9 / 1.1e-8 (with 1e-11:
8.9e-9 / 8.6e-9), the response against IDAS 1.9e-10 relative either way; unscaled with
1e-9 they were 3-6e-6 off for every difference step.  The eddy ladder
(``eddy_model = "ladder"``) cannot reach 1e-11: its collocation Newton stalls at the
rounding floor of its larger, stiffer system and fails; with 1e-10 (2 layers, 10 mm,
20 A, +30 V, 7 samples) derivatives 0.9e-9 ... 5.0e-9 and 3.8e-9 of the step's change
against IDAS (tests/test_calibration_ladder.py)."""


def _scaled_step_dae(run: Any, base: Network, *, gap_m: float, current_A: float,
                     u: np.ndarray, duration: float, names: Sequence[str]
                     ) -> tuple[dict[str, Any], np.ndarray, np.ndarray, dict[str, Any]]:
    """The step DAE of ``run`` in unknowns divided by their size at the nominal network's
    operating point (floored at 1e-3 of the largest of their kind) and algebraic rows
    divided by their largest entry of the scaled Jacobian there.

    The scales come from the nominal (uncalibrated) network, not the parameter values, so
    that the discrete scheme is the same function of the parameters (finite differences
    see the same scheme).  Returns the DAE dict, the scales of ``y`` and of ``z = (x, I)``,
    and the sparse form of its differential rows for :func:`_radau_step_function`
    (``K_y = K diag(y_scale)``, its rows' largest entries ``K_rows``, the scaled right side
    ``rhs`` of ``K y' = h`` and ``rhs_rows``, the largest entries of ``d rhs/dz``).
    """
    import casadi as ca

    dae = run.dae
    x_num = _start(base, {}, np.array([gap_m]), np.array([current_A]))[0]
    i_num = np.full(len(base.circuits), current_A)

    def floor(a: np.ndarray) -> np.ndarray:
        a = np.abs(a)
        return np.maximum(a, 1e-3 * max(float(a.max()), 1e-300))

    y_num = run.D @ x_num
    y_scale = floor(y_num)
    z_scale = np.concatenate((floor(x_num), floor(i_num)))
    ys = ca.SX.sym("y_scaled", dae["x"].numel())
    zs = ca.SX.sym("z_scaled", dae["z"].numel())
    ode, alg = ca.substitute([dae["ode"], dae["alg"]], [dae["x"], dae["z"]],
                             [ca.DM(y_scale) * ys, ca.DM(z_scale) * zs])
    # at the nominal factors (the statics x_num hold for the nominal network)
    nominal_p = np.concatenate(([duration], u, np.full(len(base.gap_names), gap_m),
                                [PARAMETERS[n].nominal for n in names]))
    jac = ca.Function("step_alg_jacobian", [zs, ys, dae["p"]], [ca.jacobian(alg, zs)])
    rows = np.max(np.abs(np.asarray(jac(np.concatenate((x_num, i_num)) / z_scale,
                                        y_num / y_scale, nominal_p))), axis=1)
    rows = np.where(rows > 0.0, rows, 1.0)
    # the sparse form K y' = h of the ode rows (_radau_step_function): K's columns times
    # y_scale, each row divided by its largest entry; a row of K that is zero (h_i = 0, an
    # algebraic row) by its largest entry of dh_i/dz_scaled at the nominal point
    rhs = ca.substitute(run.h, ca.vertcat(dae["x"], dae["z"]),
                        ca.vertcat(ca.DM(y_scale) * ys, ca.DM(z_scale) * zs))
    k_y = run.K * y_scale[None, :]
    k_rows = np.max(np.abs(k_y), axis=1)
    jac_h = ca.Function("step_rhs_jacobian", [zs, ys, dae["p"]], [ca.jacobian(rhs, zs)])
    h_rows = np.max(np.abs(np.asarray(jac_h(np.concatenate((x_num, i_num)) / z_scale,
                                            y_num / y_scale, nominal_p))), axis=1)
    sparse = {"K_y": k_y, "rhs": rhs, "K_rows": k_rows,
              "rhs_rows": np.where(h_rows > 0.0, h_rows, 1.0)}
    return ({"x": ys, "z": zs, "p": dae["p"], "ode": ode / ca.DM(y_scale),
             "alg": alg / ca.DM(rows)}, y_scale, z_scale, sparse)


_RADAU_DEGREE = 3
"""Collocation points per Radau IIA step (order 5)."""

_STEP_SCHEME = "radau"
"""How :class:`_ParametricStep` integrates: ``"radau"`` (:func:`_radau_steps`) or
``"casadi"`` (CasADi's ``collocation`` integrator on the explicit DAE, the scheme before
calsteps25; kept for the benchmark's before/after, ``benchmarks/bench_calibration_steps.py``)."""


def _radau_step_function(dae: Mapping[str, Any], sparse: Mapping[str, Any]) -> Any:
    """One Radau IIA step of the step DAE as a CasADi Newton rootfinder
    ``v = rf(v_guess, (y_0, h, p))``, ``v = (y_1, z_1, ..., y_3, z_3)`` the differential and
    algebraic states at the collocation points ``h tau_j`` (the last one the step's end).

    The collocation of CasADi's ``collocation`` integrator (a Lagrange polynomial through
    ``y_0`` and the ``y_j``, its derivative ``yp_j = sum_r C_rj y_r`` at each point), with the
    differential rows in the DAE's sparse form: the step DAE is ``K y' = h(y, z)`` (the
    flux model's ``K``), which :class:`~maglevkit.reduction.maps.StepRun` writes as
    ``y' = T pinv(K) h`` plus the algebraic rows ``Q h = 0`` (``Q`` spanning the left null
    space of ``K``).  ``pinv(K)`` and ``h`` are sparse (82 x 88 with 218 entries, 566 in
    ``dh/dz`` on the 6-layer ladder), their product is not (5765 of 7216): so the rows here
    are ``K (y_scale yp_j) - h T h_j = 0`` -- equivalent, since they hold exactly when both
    ``yp_j = h T pinv(K) h_j`` and ``Q h_j = 0`` do -- each divided by its largest entry of
    ``K diag(y_scale)`` (a zero row of ``K`` is ``h_i = 0``, divided by its largest entry of
    ``dh_i/dz`` at the nominal point), and the algebraic rows ``D x - y = 0`` as scaled by
    :func:`_scaled_step_dae`.  The same root as the explicit rows; the Newton's Jacobian
    (one SX function) and its factorisation stay sparse.
    """
    import casadi as ca

    tau = np.concatenate(([0.0], ca.collocation_points(_RADAU_DEGREE, "radau")))
    nd = _RADAU_DEGREE + 1
    # C[j, r]: derivative of the j-th Lagrange basis polynomial at tau_r
    C = np.zeros((nd, nd))
    for j in range(nd):
        basis = np.poly1d([1.0])
        for r in range(nd):
            if r != j:
                basis *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
        C[j] = basis.deriv()(tau)
    nx, nz = dae["x"].numel(), dae["z"].numel()
    f = ca.Function("step_dae_sparse", [dae["x"], dae["z"], dae["p"]],
                    [sparse["rhs"], dae["alg"][:nx]])
    k_y = ca.DM(sparse["K_y"])
    moving = [int(i) for i in np.flatnonzero(sparse["K_rows"] > 0.0)]
    held = [int(i) for i in np.flatnonzero(sparse["K_rows"] == 0.0)]
    y0 = ca.SX.sym("y0", nx)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", dae["p"].numel())
    v = ca.SX.sym("v", _RADAU_DEGREE * (nx + nz))
    ys = [y0] + [v[k * (nx + nz):k * (nx + nz) + nx] for k in range(_RADAU_DEGREE)]
    zs = [v[k * (nx + nz) + nx:(k + 1) * (nx + nz)] for k in range(_RADAU_DEGREE)]
    eq = []
    for j in range(1, nd):
        rhs, alg = f(ys[j], zs[j - 1], p)
        yp = C[0, j] * y0
        for r in range(1, nd):
            yp = yp + C[r, j] * ys[r]
        res = ca.mtimes(k_y, yp) - h * p[0] * rhs          # p[0]: the window T
        eq += [res[moving] / ca.DM(sparse["K_rows"][moving]),
               rhs[held] / ca.DM(sparse["rhs_rows"][held]), alg]
    g = ca.Function("radau_residual", [v, ca.vertcat(y0, h, p)], [ca.vertcat(*eq)])
    return ca.rootfinder("radau_step", "newton", g,
                         {"abstol": _STEP_ABSTOL, "abstolStep": 1e-14, "max_iter": 50,
                          "error_on_fail": True})


def _radau_steps(dae: Mapping[str, Any], sparse: Mapping[str, Any], y0: Any, z0: Any,
                 pars: Any, h: np.ndarray, keep: Sequence[int]) -> Any:
    """Fixed Radau IIA steps ``h`` (:func:`_radau_step_function`) from ``(y0, z0)``, unrolled
    in MX: the algebraic states at the ends of the steps ``keep``, one column each.  Each
    step's Newton starts from the previous step's collocation states (the first from
    ``(y0, z0)`` at every point), as CasADi's integrator does.  Differentiated by CasADi's
    AD, each rootfinder by the implicit function theorem at its root: values and exact
    derivatives from one run (the integrator's forward sensitivities integrated the
    nominal run a second time)."""
    import casadi as ca

    rf = _radau_step_function(dae, sparse)
    nx, nz = dae["x"].numel(), dae["z"].numel()
    last = (_RADAU_DEGREE - 1) * (nx + nz)
    guess = ca.repmat(ca.vertcat(y0, z0), _RADAU_DEGREE, 1)
    y, out, wanted = y0, [], set(keep)
    for k, hk in enumerate(h):
        guess = rf(guess, ca.vertcat(y, float(hk), pars))
        y = guess[last:last + nx]
        if k in wanted:
            out.append(guess[last + nx:])
    return ca.horzcat(*out)


class _ParametricStep:
    """One voltage step of the flux DAE with symbolic calibration parameters, built once:
    ``evaluate(values)`` gives the stepped circuit's current at the sample times and its
    exact Jacobian (see :func:`step_response_sensitivities`).

    The stepped circuit's voltage after the step is ``voltage_V`` (absolute) or the hold
    voltage ``k_R R_el I_0`` plus ``voltage_step_V``; the other circuits keep their hold
    voltage.
    """

    def __init__(self, model: Any, names: Sequence[str], *, gap_m: float, current_A: float,
                 times_s: np.ndarray, circuit: int, voltage_V: float | None = None,
                 voltage_step_V: float = 0.0, scheme: str | None = None) -> None:
        import casadi as ca

        from .circuit.assembly import assemble
        from .models.statics import as_network
        from .reduction.maps import StepRun

        self.names = tuple(names)
        base = as_network(model)
        t = np.asarray(times_s, dtype=float)
        nc, ng = len(base.circuits), len(base.gap_names)
        p = ca.SX.sym("p", len(self.names))
        sym = {n: p[k] for k, n in enumerate(self.names)}
        pnet = calibrated_network(base, sym)
        duration = float(t[-1])
        run = StepRun(pnet, 0, tau=t / duration, params=p, topology=base,
                      eddy_scale=sym.get("eddy_conductance_scale", 1.0),
                      resistance_scale=sym.get("resistance_scale", 1.0))
        eq = assemble(pnet)
        g_fun = ca.Function("step_statics_residual", [eq.x, ca.vertcat(eq.s, eq.I, p)],
                            [eq.residual])
        rf = ca.rootfinder("step_statics", "newton", g_fun,
                           {"abstol": 1e-10, "abstolStep": 1e-15, "max_iter": 60,
                            "error_on_fail": True})
        P = ca.MX.sym("p", len(self.names))
        X0 = ca.MX.sym("x0", eq.x.numel())
        s_vec = np.full(ng, float(gap_m))
        i_vec = np.full(nc, float(current_A))
        x0 = rf(X0, ca.vertcat(ca.DM(s_vec), ca.DM(i_vec), P))
        # voltages after the step: the hold voltage k_R R_el I_0 (the steady state before
        # the step), the stepped circuit's given or stepped from it
        k_r = (P[self.names.index("resistance_scale")] if "resistance_scale" in self.names
               else 1.0)
        u_nominal = base.resistances * i_vec
        u_nominal[circuit] = (float(voltage_V) if voltage_V is not None
                              else u_nominal[circuit] + float(voltage_step_V))
        u_sym = [k_r * float(base.resistances[j] * i_vec[j]) for j in range(nc)]
        u_sym[circuit] = (float(voltage_V) if voltage_V is not None
                          else u_sym[circuit] + float(voltage_step_V))
        pars = ca.vertcat(duration, *u_sym, ca.DM(s_vec), P)
        # The DAE in scaled unknowns and equations (_scaled_step_dae): the collocation's
        # Newton stops on an absolute residual, and unscaled its 1e-9 was ~1e-6 of the eddy
        # fluxes (~3e-3 Wb): the derivatives of that inexact root were off by 3-6e-6
        dae, y_scale, z_scale, sparse = _scaled_step_dae(run, base, gap_m=float(gap_m),
                                                 current_A=float(current_A), u=u_nominal,
                                                 duration=duration, names=self.names)
        # consistent algebraic states just after the step: the differential states (flux
        # linkages, eddy fluxes) are continuous, (x, I) jump (eddy currents), alg(y, z) = 0
        alg = ca.Function("step_alg", [dae["z"], ca.vertcat(dae["x"], dae["p"])],
                          [dae["alg"]])
        rz = ca.rootfinder("step_consistent", "newton", alg,
                           {"abstol": _STEP_ABSTOL, "abstolStep": 1e-15, "max_iter": 60,
                            "error_on_fail": True})
        y0 = ca.mtimes(ca.DM(run.D), x0) / ca.DM(y_scale)
        z0 = rz(ca.vertcat(x0, ca.DM(i_vec)) / ca.DM(z_scale), ca.vertcat(y0, pars))
        grid = np.concatenate(([0.0], t / duration))
        # the fast eddy modes start at t = 0: geometric steps there, then each output
        # interval in equal steps (interval_substeps: at most 1/STEP_FINE_STEPS of the
        # window each, so that a long interval of a thinned record is not one large step)
        fine = np.unique(np.concatenate([np.geomspace(1e-6, grid[1], 40)] + [
            np.linspace(a, b, n + 1) for a, b, n in zip(grid[:-1], grid[1:],
                                                        interval_substeps(grid),
                                                        strict=True)]))
        keep = [int(np.searchsorted(fine, v)) - 1 for v in grid[1:]]
        if (scheme or _STEP_SCHEME) == "casadi":
            colloc = ca.integrator("step_collocation", "collocation", dae, 0.0,
                                   list(fine[1:]),
                                   {"collocation_scheme": "radau", "interpolation_order": 3,
                                    "number_of_finite_elements": 1, "rootfinder": "newton",
                                    "rootfinder_options": {"abstol": _STEP_ABSTOL,
                                                           "abstolStep": 1e-14,
                                                           "max_iter": 50}})
            res = colloc(x0=y0, z0=z0, p=pars)
            zf = res["zf"][:, keep]
        else:
            zf = _radau_steps(dae, sparse, y0, z0, pars, np.diff(fine), keep)
        cur = zf[run.n_loops + circuit, :].T * float(z_scale[run.n_loops + circuit])
        self.fun = ca.Function("step_sensitivities", [X0, P], [cur, ca.jacobian(cur, P)])
        self.base = base
        self.gap_m, self.current_A = float(gap_m), float(current_A)

    def evaluate(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        guess = _start(self.base, dict(zip(self.names, values, strict=True)),
                       np.array([self.gap_m]), np.array([self.current_A]))[0]
        try:
            out, jac = self.fun(guess, values)
        except RuntimeError as exc:
            if sigint_received():
                raise KeyboardInterrupt from None
            raise SolverError("the voltage step with parameter sensitivities failed (a "
                              "stiff network, e.g. an eddy ladder, may need more Radau steps: "
                              "maglevkit.calibration.STEP_FINE_STEPS)",
                              state={"gap_m": self.gap_m, "current_A": self.current_A,
                                     **dict(zip(self.names, values, strict=True))},
                              reason=str(exc).splitlines()[-1][-200:]) from None
        if sigint_received():     # as in _ParametricStatics.evaluate
            raise KeyboardInterrupt
        return np.asarray(out).ravel(), np.asarray(jac).reshape(-1, len(self.names))


STEP_FINE_STEPS = 120
"""Radau steps over a step response's output intervals in total (at least 3 and at most
:data:`_STEP_SUBSTEPS` per interval; :func:`step_substeps`).  Measured (U-magnet, 10 mm,
20 A, +8 V, 12 samples to 0.2 s, against IDAS at rtol 1e-10): 40 / 10 / 5 / 3 steps per
interval 3.3e-8 / 3.3e-8 / 1.1e-7 / 1.6e-6 A off, 2.1 / 0.66 / 0.44 / 0.36 s per
evaluation with the Jacobian (CasADi's integrator, before calsteps25); the 40 geometric steps
after ``t = 0`` set the floor."""


def interval_substeps(grid: np.ndarray) -> np.ndarray:
    """Radau steps per output interval of a step response: the larger of
    :func:`step_substeps` (for the number of samples) and ``ceil(STEP_FINE_STEPS x
    dtau)``, at most 40, for each interval ``dtau`` of ``grid`` (``[0, t_1, ..., t_n] /
    t_n``).  With equally spaced samples this is :func:`step_substeps` for every interval
    (the same scheme as before the second term); with samples thinned geometrically
    (dense after the step, sparse later) the long late intervals get more steps: one
    interval of a quarter of the window in 5 Radau steps made the collocation's Newton
    fail on the U-magnet's 6-layer ladder at 20 -> 50 A (saturating iron).

    Parameters
    ----------
    grid : ndarray
        Increasing normalised times from 0 to 1 (the sample times over the window).
    """
    d = np.diff(np.asarray(grid, dtype=float))
    least = step_substeps(d.size)
    return np.clip(np.ceil(STEP_FINE_STEPS * d - 1e-9), least, _STEP_SUBSTEPS).astype(int)


def step_substeps(n_samples: int) -> int:
    """Radau steps per output interval for ``n_samples`` sample times:
    ``clip(ceil(STEP_FINE_STEPS / n_samples), 3, 40)`` (12 samples: 10; 117 FEM samples:
    3).

    Parameters
    ----------
    n_samples : int
        Number of sample times of the step response.
    """
    return int(min(_STEP_SUBSTEPS, max(3, math.ceil(STEP_FINE_STEPS / max(n_samples, 1)))))


def step_response_sensitivities(model: Any, values: Mapping[str, float], *, gap_m: float,
                                current_A: float, voltage_step_V: float, times_s: Any,
                                circuit: int = 0) -> dict[str, np.ndarray]:
    """A voltage step of the detailed (flux) model and its exact parameter derivatives.

    The magnet rests at the statics of ``(gap_m, current_A)`` (every circuit at
    ``current_A``, held by ``U = R_el I``); at ``t = 0`` circuit ``circuit``'s voltage
    steps by ``voltage_step_V``.  The flux DAE of the ``R_ec`` fit
    (:class:`~maglevkit.reduction.maps.StepRun`) with the calibration factors as symbolic
    parameters, integrated by Radau collocation (fixed steps, :func:`step_substeps` per
    output interval) so that CasADi's AD differentiates the discrete solution exactly; the
    initial state is the parametric statics and the algebraic states just after the step
    are solved consistently (rootfinders, implicit function theorem), so ``d I(t)/d p``
    includes the operating point's dependence.  (IDAS forward sensitivities failed in
    IDACalcIC / with error-test failures at t = 0 on this DAE.)  ``eddy_conductance_scale``
    and ``resistance_scale`` enter the DAE's rows (the hold voltage is ``k_R R_el I``).

    Parameters
    ----------
    model : Magnet or Network
        The uncalibrated magnet.
    values : mapping
        Calibration parameter names of :data:`PARAMETERS` -> values (unit of the
        parameter); the derivatives are taken w.r.t. these.
    gap_m : float
        Every gap [m].
    current_A : float
        The current every circuit holds before the step [A].
    voltage_step_V : float
        The stepped circuit's voltage change [V].
    times_s : array_like
        Increasing sample times > 0 [s].
    circuit : int
        Index of the stepped circuit.

    Returns
    -------
    dict
        ``current_A`` (n_t,) coil current of the stepped circuit [A] and ``dcurrent_dp``
        (n_t, n_p) in the order of ``values``.
    """
    from .models.statics import as_network

    names = _names(values)
    base = as_network(model)
    t = np.asarray(times_s, dtype=float)
    if t.ndim != 1 or t.size < 1 or t[0] <= 0.0 or np.any(np.diff(t) <= 0.0):
        raise InputError("times_s must be increasing sample times > 0 s")
    nc = len(base.circuits)
    if isinstance(circuit, bool) or not isinstance(circuit, int) or not 0 <= circuit < nc:
        raise InputError(f"circuit = {circuit!r} must be an index in 0..{nc - 1}")
    step = _ParametricStep(base, names, gap_m=float(gap_m), current_A=float(current_A),
                           times_s=t, circuit=circuit, voltage_step_V=float(voltage_step_V))
    cur, jac = step.evaluate(np.array([float(values[n]) for n in names]))
    return {"current_A": cur, "dcurrent_dp": jac}


def _names(values: Any) -> tuple[str, ...]:
    names = tuple(values)
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown or not names or len(set(names)) != len(names):
        raise InputError(f"calibration parameters {list(names)}: give distinct names from "
                         f"the documented set {list(PARAMETERS)} (unknown: {unknown})")
    return names


def _groups(model: Any) -> dict[str, tuple[str, ...]]:
    from .models.statics import as_network, circuit_pole_groups

    net = as_network(model)
    return circuit_pole_groups(net, gap_m=0.01, current_A=10.0)


# ---------------------------------------------------------------------------- the fit
NULL_RCOND = 1e-10
"""Singular values of the scaled Jacobian below this fraction of the largest span its
near-null directions (rounding of the exact parameter derivatives is ~1e-9 relative to the
residuals, squared in ``J^T J``: 1e-10 in ``J`` itself separates rank loss from it)."""

UNSEEN_SINGULAR_VALUE = 1e-9
"""The data see none of the fitted parameters when the parameter-scaled Jacobian's largest
singular value is at most this: a change of every parameter by its scale moves the relative
residuals by < 1e-9 (the derivatives' own rounding), e.g. ``resistance_scale`` and
``eddy_conductance_scale`` on statics, whose Jacobian columns are exactly zero.
:func:`calibrate` then refuses the fit (a file of start values tagged calibrated)."""

NULL_SHARE = 0.05
"""A parameter with more than this share (sum of its squared components) of the near-null
directions is named undetermined: the data fix it only together with the others there; a
share below 5 % moves it by less than 5 % of the null direction's length."""


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    parameters : tuple of str
        The fitted parameters.
    values : dict
        Fitted value per parameter (unit of :data:`PARAMETERS`).
    confidence_95 : dict
        Half-width of the 95 % confidence interval per parameter (inf: not determined).
    singular_values : ndarray
        Of the Jacobian with columns scaled by the parameters' scales, descending.
    undetermined : tuple of str
        Parameters the data cannot determine: a confidence half-width above the
        parameter's scale, or a share above :data:`NULL_SHARE` of the Jacobian's near-null
        directions (``null_shares``).
    residual_rms : float
        RMS of the relative fit residuals.
    points : list of dict
        Per fitted point: gap, current, row, circuit, quantity, data, model, relative error.
    holdout : list of dict
        The same for the held-out points (empty without).
    bounds_active : tuple of str
        Parameters that ended on a bound (their confidence interval is not meaningful).
    data_sha256 : str
        SHA-256 of the data file.
    nominal_points, nominal_holdout : list of dict
        As ``points`` and ``holdout`` for the nominal (uncalibrated) parameters.
    null_shares : dict
        Per parameter, its share (sum of squared components, in the scaled parameters) of
        the Jacobian's near-null directions; empty when the Jacobian has full rank.
    converged : bool
        Whether the least-squares solver met its tolerances (else it stopped at its
        evaluation limit; a warning says so).
    step_points, nominal_step_points : list of dict
        Per fitted voltage-step sample (calibrated and nominal parameters): step label,
        row, time, gap, initial current, voltage, circuit, data and model current, and the
        error relative to the step's current change (:attr:`VoltageStep.current_change_A`).
    step_holdout, nominal_step_holdout : list of dict
        The same for the held-out steps (``holdout_steps``; empty without).
    steps_sha256 : str
        SHA-256 of the voltage-step file ("" without).
    """

    parameters: tuple[str, ...]
    values: dict[str, float]
    confidence_95: dict[str, float]
    singular_values: np.ndarray
    undetermined: tuple[str, ...]
    residual_rms: float
    points: list[dict[str, Any]]
    holdout: list[dict[str, Any]]
    bounds_active: tuple[str, ...]
    data_sha256: str
    nominal_points: list[dict[str, Any]] = field(default_factory=list)
    nominal_holdout: list[dict[str, Any]] = field(default_factory=list)
    null_shares: dict[str, float] = field(default_factory=dict)
    converged: bool = True
    step_points: list[dict[str, Any]] = field(default_factory=list)
    nominal_step_points: list[dict[str, Any]] = field(default_factory=list)
    steps_sha256: str = ""
    step_holdout: list[dict[str, Any]] = field(default_factory=list)
    nominal_step_holdout: list[dict[str, Any]] = field(default_factory=list)

    def max_error(self, which: str = "holdout", quantity: str | None = None) -> float:
        """Largest ``|relative_error|`` of ``which`` (``"points"``, ``"holdout"``,
        ``"step_points"``, ``"step_holdout"`` or a ``nominal_`` one), of one ``quantity``
        or all (NaN: none).

        Parameters
        ----------
        which : str
            The list attribute.
        quantity : str, optional
            ``"force_N"``, ``"flux_linkage_Wb"`` or ``"current_A"`` (step samples).
        """
        rows = getattr(self, which)
        vals = [abs(r["relative_error"]) for r in rows if quantity in (None, r["quantity"])]
        return max(vals) if vals else math.nan


def _model_points(ps: _ParametricStatics, values: np.ndarray, data: StaticPoints,
                  x0: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int, str]]]:
    """Relative residuals, their Jacobian and (point, circuit, quantity) per residual."""
    res, jac, keys = [], [], []
    for k in range(data.gap_m.size):
        f, psi, jf, jpsi, xs = ps.evaluate(values, float(data.gap_m[k]),
                                           float(data.current_A[k]), x0[k])
        x0[k] = xs
        for q, model, dmodel, meas in (("force_N", f, jf, data.force_N),
                                       ("flux_linkage_Wb", psi, jpsi, data.flux_linkage_Wb)):
            if meas is None:
                continue
            for j in range(meas.shape[1]):
                scale = abs(float(meas[k, j]))
                res.append((model[j] - meas[k, j]) / scale)
                jac.append(dmodel[j] / scale)
                keys.append((k, j, q))
    return np.array(res), np.array(jac).reshape(len(res), values.size), keys


UNIT_SLIP_RATIO = 10.0
"""Data off the nominal model by more than this factor (median over a quantity's points)
are refused as a unit slip: the documented factors move the statics by tens of percent,
not by a factor 10 (kN for N, mWb for Wb are a factor 1000)."""


def _check_units(res: np.ndarray, keys: list[tuple[int, int, str]], data: StaticPoints
                 ) -> None:
    """Refuse data whose median ratio to the nominal model is beyond
    :data:`UNIT_SLIP_RATIO`, naming the quantity and its first row."""
    for q, unit in (("force_N", "N"), ("flux_linkage_Wb", "Wb")):
        idx = [n for n, key in enumerate(keys) if key[2] == q]
        if not idx:
            continue
        # res = model/data - 1: data/model = 1/(1 + res)
        ratio = float(np.median(1.0 / (1.0 + res[idx])))
        if not 1.0 / UNIT_SLIP_RATIO < ratio < UNIT_SLIP_RATIO:
            k = keys[idx[0]][0]
            raise DataError(f"{data.source}: {q} is {ratio:.3g} x the nominal magnet's "
                            f"(median over its {len(idx)} points, first at row "
                            f"{int(data.rows[k])}); the factors move the statics by tens of "
                            f"percent: a unit slip (the column is in {unit}; gaps in m, "
                            "currents in A) or another magnet")


def _report(res: np.ndarray, keys: list[tuple[int, int, str]], data: StaticPoints
            ) -> list[dict[str, Any]]:
    out = []
    for r, (k, j, q) in zip(res, keys, strict=True):
        meas = (data.force_N if q == "force_N" else data.flux_linkage_Wb)
        assert meas is not None
        out.append({"gap_m": float(data.gap_m[k]), "current_A": float(data.current_A[k]),
                    "row": int(data.rows[k]), "circuit": data.circuits[j], "quantity": q,
                    "data": float(meas[k, j]), "model": float(meas[k, j]) * (1.0 + float(r)),
                    "relative_error": float(r)})
    return out


def _step_circuit(step: VoltageStep, net: Network, source: str) -> int:
    if not step.circuit:
        if len(net.circuits) == 1:
            return 0
        raise DataError(f"{source}: step {step.label!r} (row {int(step.rows[0])}) names no "
                        f"circuit; the magnet has {list(net.circuit_names)}: add a circuit "
                        "column")
    if step.circuit not in net.circuit_names:
        raise DataError(f"{source}: step {step.label!r} (row {int(step.rows[0])}): circuit "
                        f"{step.circuit!r} is not one of the magnet's {list(net.circuit_names)}")
    return net.circuit_names.index(step.circuit)


def _step_residuals(models: Sequence[_ParametricStep], steps: StepResponses,
                    values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step residuals ``(I_model - I_data)/current_change_A`` and their Jacobian."""
    res, jac = [], []
    for model, step in zip(models, steps.steps, strict=True):
        cur, dcur = model.evaluate(values)
        scale = step.current_change_A
        res.append((cur - step.current_A) / scale)
        jac.append(dcur / scale)
    if not res:
        return np.zeros(0), np.zeros((0, values.size))
    return np.concatenate(res), np.vstack(jac)


def _step_report(res: np.ndarray, steps: StepResponses) -> list[dict[str, Any]]:
    out, k = [], 0
    for step in steps.steps:
        for n in range(step.time_s.size):
            r = float(res[k])
            out.append({"step": step.label, "row": int(step.rows[n]),
                        "time_s": float(step.time_s[n]), "gap_m": step.gap_m,
                        "initial_current_A": step.initial_current_A,
                        "voltage_V": step.voltage_V, "circuit": step.circuit,
                        "quantity": "current_A", "data": float(step.current_A[n]),
                        "model": float(step.current_A[n]) + r * step.current_change_A,
                        "relative_error": r})
            k += 1
    return out


def _check_step_units(res: np.ndarray, steps: StepResponses) -> None:
    """Refuse step currents whose median ratio to the nominal model's is beyond
    :data:`UNIT_SLIP_RATIO` (mA for A), naming the step and its first row."""
    k = 0
    for step in steps.steps:
        n = step.time_s.size
        model = step.current_A + res[k:k + n] * step.current_change_A
        k += n
        ok = np.abs(model) > 0.0
        ratio = float(np.median(step.current_A[ok] / model[ok])) if ok.any() else 1.0
        if not 1.0 / UNIT_SLIP_RATIO < ratio < UNIT_SLIP_RATIO:
            raise DataError(f"{steps.source}: step {step.label!r} (first row "
                            f"{int(step.rows[0])}): current_A is {ratio:.3g} x the nominal "
                            "magnet's response (median): a unit slip (currents in A, voltage "
                            "in V, times in s) or another magnet")


STEP_SPAN_MAX_TAU = 200.0
"""A step whose last sample lies beyond this many electrical time constants
``tau = L_d / R_el`` of the nominal magnet (differential inductance of the statics at the
step's gap and initial current) is refused as a unit slip (ms written as s: a record of a
few ``tau`` becomes thousands); the U-magnet's FEM records span 2.7-8.2 ``tau``."""


def _check_step_times(steps: StepResponses, net: Network) -> None:
    """Refuse a step whose samples span more than :data:`STEP_SPAN_MAX_TAU` time
    constants, naming the step and its last row."""
    from .models.statics import solve_statics

    for step in steps.steps:
        j = _step_circuit(step, net, steps.source)
        sol = solve_statics(net, gaps_m=np.full(len(net.gap_names), step.gap_m),
                            currents_A=np.full(len(net.circuits), step.initial_current_A))
        ind = np.asarray(sol.differential_inductance_H, dtype=float).reshape(
            len(net.circuits), len(net.circuits))[j, j]
        tau = float(ind) / float(net.resistances[j])
        span = float(step.time_s[-1])
        if tau > 0.0 and span > STEP_SPAN_MAX_TAU * tau:
            raise DataError(f"{steps.source}: step {step.label!r} (last row "
                            f"{int(step.rows[-1])}): time_s reaches {span:g} s, {span / tau:.0f} "
                            f"time constants L/R_el = {tau:.3g} s of the nominal magnet there "
                            f"(more than {STEP_SPAN_MAX_TAU:g}): is the time in ms? (time_s is "
                            "in seconds)")


def _holdout_labels(holdout_steps: str | Sequence[str]) -> list[str]:
    """The held-out step labels: a str is one label (it may contain commas)."""
    if isinstance(holdout_steps, str):
        return [holdout_steps]
    out: list[str] = []
    for h in holdout_steps:
        if not isinstance(h, str):
            raise InputError(f"holdout_steps: {h!r} is not a step label (str); give the "
                             "labels of the step file's step column (or the steps' numbers "
                             "'1', '2', ... without one)")
        if h not in out:
            out.append(h)
    return out


def calibrate(magnet: Any, data: str | Path | StaticPoints | None, *,
              parameters: Sequence[str] | None = None,
              holdout_gaps_m: Sequence[float] = (),
              initial: Mapping[str, float] | None = None,
              steps: str | Path | StepResponses | None = None,
              holdout_steps: str | Sequence[str] = (),
              require_determined: bool = True) -> Calibration:
    """Fit calibration parameters of ``magnet`` to measured statics and/or voltage steps
    (module docstring).

    Parameters
    ----------
    magnet : Magnet
        The magnet (its network) to calibrate.
    data : path or StaticPoints or None
        Measured force and/or flux linkage (:func:`read_points`), every circuit at the
        point's current, all gaps at its gap; None: voltage steps only.
    parameters : sequence of str, optional
        Names from :data:`PARAMETERS` (default :data:`DEFAULT_PARAMETERS` with static data,
        plus :data:`DYNAMIC_PARAMETERS` with steps).
    holdout_gaps_m : sequence of float
        Gaps [m] whose static points are left out of the fit and reported as the held-out
        check.
    initial : mapping, optional
        Start values (default: nominal).
    steps : path or StepResponses, optional
        Measured voltage steps (:func:`read_steps`), fitted with the statics: residuals
        ``(I_model - I_data)/current_change_A`` per sample, the model the flux DAE
        (:func:`step_response_sensitivities`) with exact parameter derivatives.
    holdout_steps : str or sequence of str
        Labels of voltage steps (:attr:`VoltageStep.label`) left out of the fit and
        reported as the held-out check of the dynamics (``step_holdout``); a str is one
        label (labels may contain commas).
    require_determined : bool, default True
        Refuse (``DataError``) a fit in which the data see none of the parameters;
        False returns it (:func:`select_parameters` scores every set by its held-out
        error, a set the data cannot determine too).

    Raises
    ------
    InputError
        An unknown held-out label (the message lists the steps' labels), every step held
        out without static data, or initial values outside the bounds.
    DataError
        Bad data (:func:`read_points`, :func:`read_steps`), a unit slip (statics or step
        currents off the nominal magnet by more than :data:`UNIT_SLIP_RATIO`, a step
        spanning more than :data:`STEP_SPAN_MAX_TAU` time constants: ms as s), fewer
        residuals than parameters, or data that determine none of the fitted parameters
        nor any combination of them (:data:`UNSEEN_SINGULAR_VALUE`; e.g.
        ``resistance_scale`` from statics alone: the message names them and the data that
        would); parameters undetermined beside others, or only in combination, are
        reported in :attr:`Calibration.undetermined`.

    Returns
    -------
    Calibration
    """
    from scipy.optimize import least_squares
    from scipy.stats import t as student_t

    from .models.statics import as_network

    if data is None and steps is None:
        raise InputError("calibrate needs static data, voltage steps (steps=) or both")
    step_data = (None if steps is None else steps if isinstance(steps, StepResponses)
                 else read_steps(steps))
    steps_sha = "" if step_data is None else step_data.sha256
    test_steps: StepResponses | None = None
    held_labels = _holdout_labels(holdout_steps)
    if held_labels:
        if step_data is None:
            raise InputError(f"holdout_steps {held_labels}: no voltage steps given "
                             "(steps=)")
        labels = [st.label for st in step_data.steps]
        unknown = [h for h in held_labels if h not in labels]
        if unknown:
            raise InputError(f"holdout_steps {unknown}: no step with that label; the steps: "
                             f"{labels}")
        held = set(held_labels)
        test_steps = replace(step_data, steps=tuple(st for st in step_data.steps
                                                    if st.label in held))
        step_data = replace(step_data, steps=tuple(st for st in step_data.steps
                                                   if st.label not in held))
        if not step_data.steps:
            if data is None:
                raise InputError(f"holdout_steps {held_labels} holds out every step and there "
                                 "are no static data: nothing left to fit")
            step_data = None
    if parameters is None:
        parameters = ((DEFAULT_PARAMETERS if data is not None else ())
                      + (DYNAMIC_PARAMETERS if step_data is not None else ()))
    names = _names(parameters)
    net = as_network(magnet)
    pts = None if data is None else data if isinstance(data, StaticPoints) else read_points(data)
    if pts is None:
        pts = StaticPoints(gap_m=np.zeros(0), current_A=np.zeros(0), force_N=None,
                           flux_linkage_Wb=None, circuits=tuple(net.circuit_names),
                           rows=np.zeros(0, dtype=int))
    if tuple(sorted(pts.circuits)) != tuple(sorted(net.circuit_names)):
        if len(pts.circuits) == 1 and len(net.circuits) == 1:
            pts = replace(pts, circuits=tuple(net.circuit_names))
        else:
            raise DataError(f"{pts.source}: the data's circuits {list(pts.circuits)} are not "
                            f"the magnet's {list(net.circuit_names)}")
    order = [pts.circuits.index(c) for c in net.circuit_names]
    pts = replace(pts, circuits=tuple(net.circuit_names),
                  force_N=None if pts.force_N is None else pts.force_N[:, order],
                  flux_linkage_Wb=None if pts.flux_linkage_Wb is None
                  else pts.flux_linkage_Wb[:, order])
    hold = np.zeros(pts.gap_m.size, dtype=bool)
    for g in holdout_gaps_m:
        hit = np.isclose(pts.gap_m, float(g), rtol=1e-9, atol=1e-12)
        if not hit.any():
            gaps = ", ".join(f"{x:.6g}" for x in sorted(set(pts.gap_m.tolist())))
            raise InputError(f"holdout gap {float(g):.6g} m: no data point at that gap "
                             f"(holdout_gaps_m, --holdout-gaps: in m); gaps in the data: "
                             f"{gaps} m")
        hold |= hit
    fit_pts, test_pts = pts.subset(~hold), pts.subset(hold)
    specs = [PARAMETERS[n] for n in names]
    n_steps = 0 if step_data is None else sum(st.time_s.size for st in step_data.steps)
    n_res = fit_pts.gap_m.size * len(net.circuits) * (
        (fit_pts.force_N is not None) + (fit_pts.flux_linkage_Wb is not None)) + n_steps
    if n_res <= len(names):
        raise DataError(f"{pts.source}: {n_res} fitted residuals for {len(names)} parameters; "
                        "the fit needs more data points than parameters")
    for checked in (step_data, test_steps):
        if checked is not None:
            _check_step_times(checked, net)
    groups = _groups(net)
    ps = _ParametricStatics(net, names, groups)
    step_models = [] if step_data is None else [
        _ParametricStep(net, names, gap_m=st.gap_m, current_A=st.initial_current_A,
                        times_s=st.time_s, circuit=_step_circuit(st, net, step_data.source),
                        voltage_V=st.voltage_V) for st in step_data.steps]
    start = dict(initial or {})
    p0 = np.array([float(start.get(n, s.nominal)) for n, s in zip(names, specs, strict=True)])
    lo = np.array([s.lower for s in specs])
    hi = np.array([s.upper for s in specs])
    if np.any(p0 < lo) or np.any(p0 > hi):
        raise InputError(f"initial values {dict(zip(names, p0, strict=True))} lie outside "
                         f"the bounds {dict(zip(names, zip(lo, hi, strict=True), strict=True))}")
    x0 = _start(net, dict(zip(names, p0, strict=True)), fit_pts.gap_m, fit_pts.current_A)
    nominal_res, _, nominal_keys = _model_points(ps, p0, fit_pts, x0.copy())
    _check_units(nominal_res, nominal_keys, fit_pts)
    nominal_step_res = np.zeros(0)
    if step_data is not None:
        nominal_step_res, _ = _step_residuals(step_models, step_data, p0)
        _check_step_units(nominal_step_res, step_data)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = p.tobytes()
        if key not in cache:
            r, jac, _ = _model_points(ps, p, fit_pts, x0)
            if step_data is not None:
                rs, js = _step_residuals(step_models, step_data, p)
                r = np.concatenate((r, rs))
                jac = np.vstack((jac.reshape(-1, p.size), js))
            cache.clear()
            cache[key] = (r, jac.reshape(-1, p.size))
        return cache[key]

    sol = least_squares(lambda p: evaluate(p)[0], p0, jac=lambda p: evaluate(p)[1],
                        bounds=(lo, hi), x_scale=np.array([s.scale for s in specs]),
                        method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
    if sol.status <= 0:
        warnings.warn(f"calibrate: the least-squares fit did not converge (status "
                      f"{sol.status}: {sol.message}; {sol.nfev} evaluations): the values and "
                      "intervals are those where it stopped", MaglevkitWarning, stacklevel=2)
    p = sol.x
    res, jac = evaluate(p)
    n_static, keys = len(nominal_keys), nominal_keys
    m, n = res.size, p.size
    scales = np.array([s.scale for s in specs])
    _, sv, vt = np.linalg.svd(jac * scales, full_matrices=False)
    dof = max(m - n, 1)
    s2 = float(res @ res) / dof
    tq = float(student_t.ppf(0.975, dof))
    # near-null directions (relative singular value below NULL_RCOND): a parameter with a
    # share of them above NULL_SHARE is undetermined (inf interval); the others get their
    # interval from the pseudo-inverse on the determined subspace.  A parameter the data do
    # not see at all (eddy conductances in statics) has a zero column: a singular value 0
    null = vt[sv <= NULL_RCOND * sv[0]]
    shares = np.sum(null**2, axis=0) if null.size else np.zeros(n)
    keep = sv > NULL_RCOND * sv[0]
    cov_scaled = s2 * (vt[keep].T / sv[keep] ** 2) @ vt[keep]
    half = tq * np.sqrt(np.maximum(np.diag(cov_scaled), 0.0)) * scales
    half = np.where(shares > NULL_SHARE, np.inf, half)
    undetermined = tuple(nm for nm, h, sc in zip(names, half, scales, strict=True)
                         if not h < sc)
    if require_determined and not sv[0] > UNSEEN_SINGULAR_VALUE:
        # every parameter undetermined and no direction either: the data see none of them
        # (undetermined parameters with a determined combination are reported instead)
        _refuse_undetermined(names, step_data is not None, fit_pts)
    active = tuple(nm for nm, v, a, b in zip(names, p, lo, hi, strict=True)
                   if v <= a + 1e-9 * max(1.0, abs(a)) or v >= b - 1e-9 * max(1.0, abs(b)))
    holdout: list[dict[str, Any]] = []
    nominal_hold: list[dict[str, Any]] = []
    if test_pts.gap_m.size:
        xt = _start(net, dict(zip(names, p, strict=True)), test_pts.gap_m, test_pts.current_A)
        hres, _, hkeys = _model_points(ps, p, test_pts, xt)
        holdout = _report(hres, hkeys, test_pts)
        xn = _start(net, dict(zip(names, p0, strict=True)), test_pts.gap_m, test_pts.current_A)
        nres, _, nkeys = _model_points(ps, p0, test_pts, xn)
        nominal_hold = _report(nres, nkeys, test_pts)
    step_hold: list[dict[str, Any]] = []
    nominal_step_hold: list[dict[str, Any]] = []
    if test_steps is not None:
        test_models = [_ParametricStep(net, names, gap_m=st.gap_m,
                                       current_A=st.initial_current_A, times_s=st.time_s,
                                       circuit=_step_circuit(st, net, test_steps.source),
                                       voltage_V=st.voltage_V) for st in test_steps.steps]
        step_hold = _step_report(_step_residuals(test_models, test_steps, p)[0], test_steps)
        nominal_step_hold = _step_report(_step_residuals(test_models, test_steps, p0)[0],
                                         test_steps)
    step_rep = [] if step_data is None else _step_report(res[n_static:], step_data)
    nominal_step_rep = ([] if step_data is None
                        else _step_report(nominal_step_res, step_data))
    return Calibration(
        parameters=names, values={nm: float(v) for nm, v in zip(names, p, strict=True)},
        confidence_95={nm: float(h) for nm, h in zip(names, half, strict=True)},
        singular_values=sv, undetermined=undetermined,
        residual_rms=float(np.sqrt(np.mean(res**2))),
        points=_report(res[:n_static], keys, fit_pts),
        holdout=holdout, bounds_active=active, data_sha256=pts.sha256,
        nominal_points=_report(nominal_res, nominal_keys, fit_pts),
        nominal_holdout=nominal_hold,
        null_shares=({nm: float(v) for nm, v in zip(names, shares, strict=True)}
                     if null.size else {}),
        converged=sol.status > 0, step_points=step_rep,
        nominal_step_points=nominal_step_rep, step_holdout=step_hold,
        nominal_step_holdout=nominal_step_hold,
        steps_sha256=steps_sha)


def _refuse_undetermined(names: Sequence[str], with_steps: bool, pts: StaticPoints) -> None:
    """Raise: the data determine none of the fitted parameters (a "calibrated" file would
    hold the start values, tagged calibrated).  Names what data would determine them."""
    dynamic = [n for n in names if n in DYNAMIC_PARAMETERS]
    static = [n for n in names if n not in DYNAMIC_PARAMETERS]
    needs = []
    if dynamic:
        one = len(dynamic) == 1
        needs.append(f"{', '.join(dynamic)} {'does' if one else 'do'} not enter the statics: "
                     f"measured voltage steps determine {'it' if one else 'them'} (steps=, "
                     "maglevkit calibrate --steps)"
                     + ("" if not with_steps else "; these steps do not (check their "
                        "circuits and current change)"))
    if static:
        gaps, currents = np.unique(pts.gap_m).size, np.unique(pts.current_A).size
        needs.append(f"{', '.join(static)}: force and/or flux linkage at more gaps and "
                     "currents, where they act, would determine them (the fitted data: "
                     f"{gaps} gap(s), {currents} current(s), held-out gaps left out)")
    raise DataError(f"calibrate: the data cannot determine any of the fitted parameters "
                    f"{list(names)} (they do not change the modelled data: a zero Jacobian), "
                    f"so a calibrated file would hold their start values; "
                    + "; ".join(needs))


@dataclass(frozen=True)
class ParameterSetScore:
    """Leave-one-gap-out cross-validation of one parameter set (:func:`select_parameters`).

    Attributes
    ----------
    parameters : tuple of str
        The set.
    worst : float
        Largest ``|relative error|`` at a left-out gap's points over all folds [1].
    rms : float
        RMS of the left-out points' relative errors over all folds [1].
    per_gap : dict
        Left-out gap [m] -> largest ``|relative error|`` at its points [1].
    """

    parameters: tuple[str, ...]
    worst: float
    rms: float
    per_gap: dict[float, float]


def select_parameters(magnet: Any, data: str | Path | StaticPoints, *,
                      candidates: Sequence[str] = DEFAULT_PARAMETERS,
                      holdout_gaps_m: Sequence[float] = (),
                      sets: Sequence[Sequence[str]] | None = None
                      ) -> list[ParameterSetScore]:
    """Rank parameter sets by leave-one-gap-out cross-validation on the fitted gaps only.

    Every set (default: every non-empty subset of ``candidates``) is fitted once per
    fitted gap with that gap left out, and scored by the largest relative error at the
    left-out gaps' points; the gaps of ``holdout_gaps_m`` are left out of every fold, so
    that the choice never sees them.  Returns the scores, best (smallest ``worst``) first:
    ``select_parameters(...)[0].parameters`` is the set to fit, chosen without the held-out
    data (docs/magnets.md, "Calibration").

    Parameters
    ----------
    magnet : Magnet or Network
        The magnet to calibrate.
    data : path or StaticPoints
        Measured statics (:func:`read_points`).
    candidates : sequence of str
        Names of :data:`PARAMETERS` whose subsets are scored.
    holdout_gaps_m : sequence of float
        Gaps [m] never used (the later held-out check).
    sets : sequence of sequences of str, optional
        Score these sets instead of all subsets of ``candidates``.

    Raises
    ------
    InputError
        Unknown names, or fewer than 3 fitted gaps (a fold needs a gap to leave out and
        at least two to fit).
    """
    import itertools

    pts = data if isinstance(data, StaticPoints) else read_points(data)
    held = [float(g) for g in holdout_gaps_m]
    gaps = sorted({float(g) for g in pts.gap_m.tolist()
                   if not any(math.isclose(g, h, rel_tol=1e-9, abs_tol=1e-12) for h in held)})
    if len(gaps) < 3:
        raise InputError(f"select_parameters needs at least 3 fitted gaps, the data have "
                         f"{gaps} m outside holdout_gaps_m")
    if sets is None:
        names = _names(candidates)
        sets = [c for k in range(1, len(names) + 1) for c in itertools.combinations(names, k)]
    out = []
    for subset in sets:
        names = _names(subset)
        errs: list[float] = []
        per_gap: dict[float, float] = {}
        for g in gaps:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MaglevkitWarning)
                res = calibrate(magnet, pts, parameters=names, holdout_gaps_m=[g, *held],
                                require_determined=False)
            e = [abs(r["relative_error"]) for r in res.holdout
                 if math.isclose(r["gap_m"], g, rel_tol=1e-9, abs_tol=1e-12)]
            per_gap[g] = max(e)
            errs += e
        out.append(ParameterSetScore(parameters=names, worst=max(per_gap.values()),
                                     rms=float(np.sqrt(np.mean(np.square(errs)))),
                                     per_gap=per_gap))
    return sorted(out, key=lambda sc: (sc.worst, sc.rms))


# ---------------------------------------------------------------------------- TOML out/in
def write_calibrated_toml(magnet: Any, result: Calibration, path: str | Path, *,
                          data_source: str = "", steps_source: str = "") -> Path:
    """Write the magnet's parameter file with a ``[calibration]`` table: the fitted values
    (each tagged ``calibrated`` in ``[calibration.provenance]``, with the data file's
    SHA-256), their 95 % half-widths and the parameters the data did not determine.

    :func:`~maglevkit.load_magnet` applies the values when it loads the file.

    Parameters
    ----------
    magnet : Magnet
        The uncalibrated magnet (loaded from a parameter file) the fit was made on.
    result : Calibration
        The fit (:func:`calibrate`).
    path : str or path
        The file to write.
    data_source : str
        The fitted data file (its name goes into the provenance tags).
    steps_source : str
        The fitted voltage-step file, if any (its name and SHA-256 go into the tags).
    """
    params = getattr(magnet, "parameters", None)
    if not isinstance(params, Mapping):
        raise InputError("write_calibrated_toml needs a Magnet loaded from a parameter file")
    doc = {k: v for k, v in params.items() if k != "calibration"}
    parts = []
    if result.data_sha256 or not result.steps_sha256:
        parts.append(f"{Path(data_source).name or 'data'} (sha256 {result.data_sha256})")
    if result.steps_sha256:
        parts.append(f"voltage steps {Path(steps_source).name or 'steps'} (sha256 "
                     f"{result.steps_sha256})")
    tag = "calibrated: least squares on " + " and ".join(parts)
    doc["calibration"] = {
        **{k: v for k, v in result.values.items()},
        "data_sha256": result.data_sha256,
        "residual_rms": result.residual_rms,
        "undetermined": list(result.undetermined),
        "confidence_95": dict(result.confidence_95),
        "provenance": {k: tag for k in result.values},
    }
    p = Path(path)
    header = (f"# {getattr(magnet, 'name', 'magnet')}: calibrated with maglevkit "
              "(maglevkit.calibration); maglevkit.load_magnet and every command taking MAGNET "
              "apply the [calibration] factors\n")
    p.write_text(header + toml_text(doc))
    return p


def load_calibrated_magnet(path: str | Path, **options: Any) -> Any:
    """A magnet from a file of :func:`write_calibrated_toml`, refusing a file without a
    ``[calibration]`` table.

    :func:`~maglevkit.load_magnet` (and every command taking ``MAGNET``) reads the table
    itself and applies the factors; this only insists that the file is calibrated.

    Parameters
    ----------
    path : str or path
        The calibrated parameter file.
    **options
        Physics switches of :func:`~maglevkit.load_magnet`.
    """
    from .magnets import load_magnet

    mag = load_magnet(path, **options)
    if "calibration" not in mag.parameters:
        raise DataError(f"{path}: no [calibration] table (write it with "
                        "write_calibrated_toml)")
    return mag


def data_hash(path: str | Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
