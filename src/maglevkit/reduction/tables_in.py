"""Characteristic maps from tabulated data: measured or FEM ``psi(s, I)`` and/or ``F(s, I)``.

A table gives, per electric circuit and on a rectangular, equidistant gap x current grid,
the flux linkage ``psi`` [Wb] and/or the force ``F`` [N] of the circuit's poles (all gaps
equal to ``s``, every circuit at ``I``: the maps' convention, :mod:`maglevkit.reduction.maps`).
:func:`maps_from_table` derives what the reduced model (paper eq. 8) needs:

* ``L~ = dpsi/dI`` and ``dL/ds = (dpsi/ds)/I`` at the grid points, from the tensor-product
  cubic interpolating spline of ``psi`` (not-a-knot; the same interpolant the current model
  puts through its maps).  On a grid row ``s = s_k`` that spline is the 1-D spline of the
  row, so the derivatives at the nodes are 1-D spline derivatives along one axis.
* ``I -> 0``: the spline is fitted to the currents as tabulated (not mirrored to ``-I``:
  ``psi`` is odd in ``I`` but not smooth at 0 where the iron's permeability rises,
  :data:`MIRROR_CURRENTS`); ``L~(s, 0)`` is its one-sided slope at 0 and
  ``dL/ds(s, 0) = d^2 psi/(ds dI)`` at 0 (the limit of ``(dpsi/ds)/I``).
* ``F`` from ``psi`` when no force is given: co-energy ``W'(s, I) = int_0^I psi di`` (the
  spline's exact antiderivative) and ``F = -dW'/ds`` (attraction-positive).  Exact for one
  circuit; with several circuits it is exact for their sum and per circuit when they do
  not couple or are alike (the table holds only the symmetric path ``I_1 = ... = I``).
* Several circuits: the symmetric path's slopes include the other circuits' coupling
  (``dpsi_j/dI = sum_k dpsi_j/dI_k``, all poles moving); the maps hold ``dpsi_j/dI_j`` and
  the own poles' ``dpsi_j/ds``.  The optional columns :data:`MUTUALS` carry the
  difference and are subtracted.  A total ``force_N`` beside per-circuit columns is
  checked against their sum (:data:`TOTAL_FORCE_TOLERANCE`) or, alone, split among the
  circuits by their co-energy forces.  ``maglevkit statics --csv`` writes all of these.
* ``psi`` from ``F`` is **not** possible: ``F`` fixes ``dpsi/ds = -dF/dI`` and so ``psi``
  only up to a function of the current (e.g. the leakage flux at a reference gap); a table
  without ``psi`` is refused.
* ``R_el`` and ``R_ec``: given values, or ``R_ec`` from a measured voltage step
  (:func:`eddy_resistance_from_step`, the paper's time-constant identification).

Consistency checks (:class:`TableReport`): co-energy reciprocity ``dF/dI = -dpsi/ds``
(attraction-positive ``F``) where both are given, in integral form over each gap cell with
a tolerance widened by the grid's own error (a derived ``F`` or ``dL/ds`` with a large grid
error is warned), monotonicity (``psi`` rising with ``I``
is required, since eq. 8 divides by ``L~``; ``psi`` and ``F`` falling with ``s`` and ``F``
rising with ``I`` are expected) and grid coverage.  Failures name the gap, the current and
the table row.  See docs/reduction.md, "Maps from tables".
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..errors import DataError, DataWarning, InputError, PlausibilityWarning
from ..models.inputs import per_name_values
from ..validation import real_number
from .maps import MAPS_FORMAT, CharacteristicMaps, check_grid, maps_dataset, pole_group_point

__all__ = ["GridTable", "TableReport", "TableRows", "csv_records", "eddy_resistance_from_step",
           "maps_from_table", "read_rows", "read_table", "RECIPROCITY_TOLERANCE"]

QUANTITIES = ("force_N", "flux_linkage_Wb")
"""The tabulated quantities (CSV column prefixes and netCDF variable names)."""

MUTUALS = ("mutual_inductance_H", "mutual_dpsi_dgap_Wb_per_m")
"""Optional per-circuit columns of a table with several circuits: the parts of the
symmetric-path slopes ``dpsi_j/dI`` and ``dpsi_j/ds`` that the *other* circuits make (their
currents, their poles).  ``L~_j = dpsi_j/dI - mutual_inductance_H_j`` and
``dpsi_j/ds_own = dpsi_j/ds - mutual_dpsi_dgap_Wb_per_m_j`` are then what the built maps
hold (``dpsi_j/dI_j`` with the other currents fixed, the circuit's own poles moving); a
table on a gap x current grid (every circuit at ``I``, all gaps at ``s``) cannot show them
otherwise.  ``maglevkit statics --csv`` writes them."""

TOTAL_FORCE_TOLERANCE = 1e-3
"""Largest relative difference, per row, between a table's total ``force_N`` and the sum of
its per-circuit ``force_N_<circuit>`` (relative to ``max(|total|, 1 % of the table's
largest)``).  The statics' own CSV (9 significant digits) agrees to ~1e-8; a test bed's
load cells to ~1e-3; a column of another magnet, a circuit left out or a unit slip by far
more.  Above it the table is refused naming the row."""

RECIPROCITY_TOLERANCE = 0.1
"""Default largest relative reciprocity residual per gap cell,
``|int F ds - (W'(s_k) - W'(s_k+1))| / scale`` (``W' = int_0^I psi di``,
``scale = max(|int F ds|, 1 % of its largest)``), before a table is refused, widened by the
grid's own error (:data:`GRID_ERROR_FACTOR`); above half of it a :class:`DataWarning` names
the worst cells.  Measured: our own statics written as a table meet it to 0.018 (U-magnet,
17 x 33 grid, 4-20 mm, 0-80 A; worst on the 4-5 mm cell at 2.5 A, where the iron's
initial-permeability knee lies below the grid's 2.5 A step); a force 30 % off (another
magnet) or a unit slip (x 1000) is refused, a force 7 % off is warned."""

STEP_SETTLE_TOLERANCE = 0.05
"""Largest relative difference between a voltage step's settled current change and
``dU/R_el`` (:func:`eddy_resistance_from_step`): a record ending after 3 time constants
still lacks 5 % of the step; a wrong step voltage or R_el is usually off by far more."""

STEP_FIT_RMS = 0.05
"""Largest rms of the step fit's ``log(remaining)`` residual: 5 % scatter of the remaining
step; eq. 8's response is one exponential (rms ~ 1e-12 for exact data)."""

RECIPROCITY_FLOOR = 0.01
"""The reciprocity residual's scale is at least this fraction of the map's largest force
(near 0 A the force vanishes and a relative error says nothing)."""

_GAP_PLAUSIBLE_M = (1e-4, 0.1)
"""Gaps outside this range [m] get a PlausibilityWarning (EMS gaps are ~ 4-20 mm): 4
typed for 4 mm is 4 m, 4e-6 a gap in km."""

MIRROR_CURRENTS = False
"""Whether the current axis is mirrored to ``-I`` (odd psi, even F) before the spline is
fitted.  Decided by measurement (docs/decisions.md): no.  ``psi`` is odd in ``I`` but not
smooth at 0 when the iron's permeability rises from its initial value (Roschke law:
``L = L0 + O(|I|)``), and the mirrored spline forces ``psi''(0) = 0``: on the U-magnet's
17 x 33 table it put ``L~(4 mm, 0 A)`` 28 % off; the one-sided not-a-knot spline does not."""

_MAX_LISTED = 5
"""Grid points named in one message (then "and N more")."""


# ---------------------------------------------------------------------------- the table
@dataclass(frozen=True)
class GridTable:
    """Tabulated ``F(s, I)`` and/or ``psi(s, I)`` per circuit on a rectangular grid.

    Attributes
    ----------
    gaps_m : ndarray (n_gaps,)
        Gap grid [m], increasing.
    currents_A : ndarray (n_currents,)
        Current grid [A], increasing, >= 0.
    circuits : tuple of str
        Circuit names (``_<circuit>`` column suffixes; ``("coil",)`` without suffix).
    force_N : ndarray (n_circuits, n_gaps, n_currents) or None
        Force of each circuit's poles [N], attraction positive.
    flux_linkage_Wb : ndarray (n_circuits, n_gaps, n_currents) or None
        Flux linkage of each circuit [Wb].
    rows : ndarray (n_gaps, n_currents) of int
        The file row (line number, header = 1) of each grid point; 0 if not from a CSV.
    source : str
        Where the data came from (file path or ``"<memory>"``).
    sha256 : str
        SHA-256 of the file's bytes (of the arrays for an in-memory table).
    total_force_N : ndarray (n_gaps, n_currents) or None
        Total force [N] of a table with several circuits (besides or instead of the
        per-circuit ``force_N``).
    mutual_inductance_H, mutual_dpsi_dgap_Wb_per_m : ndarray (n_circuits, n_gaps, n_currents) or None
        The other circuits' parts of ``dpsi_j/dI`` [H] and ``dpsi_j/ds`` [Wb/m] on the
        symmetric path (:data:`MUTUALS`).
    """

    gaps_m: np.ndarray
    currents_A: np.ndarray
    circuits: tuple[str, ...]
    force_N: np.ndarray | None
    flux_linkage_Wb: np.ndarray | None
    rows: np.ndarray
    source: str = "<memory>"
    sha256: str = ""
    total_force_N: np.ndarray | None = None
    mutual_inductance_H: np.ndarray | None = None
    mutual_dpsi_dgap_Wb_per_m: np.ndarray | None = None

    def where(self, k: int, m: int) -> str:
        """``gap ... m, current ... A (row r)`` of grid point ``(k, m)``."""
        row = int(self.rows[k, m])
        text = f"gap {self.gaps_m[k]:.6g} m, current {self.currents_A[m]:.6g} A"
        return text + (f" (row {row})" if row else "")

    def quantity(self, name: str) -> np.ndarray | None:
        return self.force_N if name == "force_N" else self.flux_linkage_Wb


_TOTAL = "<total>"
"""The circuit label of a table's total force in messages."""


def _listed(table: GridTable, points: Sequence[tuple[int, int]], circuit: str | None) -> str:
    head = ", ".join(table.where(k, m) for k, m in points[:_MAX_LISTED])
    more = f" and {len(points) - _MAX_LISTED} more" if len(points) > _MAX_LISTED else ""
    who = f"circuit {circuit!r}: " if circuit is not None and len(table.circuits) > 1 else ""
    if circuit == _TOTAL:
        who = "total force_N: "
    return f"{who}{head}{more}"


_COLUMN = re.compile(r"^(force_N|flux_linkage_Wb|mutual_inductance_H|mutual_dpsi_dgap_Wb_per_m)"
                     r"(?:_([A-Za-z0-9][A-Za-z0-9_.-]*))?$")
_ALLOWED = ("gap_m, current_A, force_N and/or flux_linkage_Wb (one column each per circuit "
            "with a _<circuit> suffix when there are several; then also a total force_N and "
            "the coupling columns mutual_inductance_H_<circuit>, "
            "mutual_dpsi_dgap_Wb_per_m_<circuit>)")
#: Columns ``maglevkit statics --csv`` writes besides the ones a table needs: derived from the
#: flux linkage, so not data of their own; a table that carries them is read without them
#: (a DataWarning names them), so that the statics' own file can be read back.
_DERIVED = re.compile(r"^(differential_inductance_H|dpsi_dgap_Wb_per_m)(?:_[A-Za-z0-9][A-Za-z0-9_.-]*)?$")


def _hint(name: str) -> str:
    low = name.lower()
    if low.startswith("gap") and low != "gap_m":
        return " (give the gap in metres as gap_m)"
    if low.startswith(("current", "i_")) and low != "current_a":
        return " (give the current in amperes as current_A)"
    if low.startswith(("force", "f_")):
        return " (give the force in newtons as force_N[_<circuit>])"
    if low.startswith(("flux", "psi")):
        return " (give the flux linkage in webers as flux_linkage_Wb[_<circuit>])"
    return ""


def _columns(header: list[str], source: str
             ) -> tuple[dict[str, int], dict[tuple[str, str], int], tuple[str, ...], int | None]:
    """Parse the header: (gap/current index, (quantity, circuit) -> index, circuits, index of
    a total ``force_N`` beside per-circuit columns or None)."""
    names = [h.strip() for h in header]
    seen: dict[str, int] = {}
    for i, n in enumerate(names):
        if n in seen:
            raise DataError(f"{source}: column {n!r} appears twice (columns {seen[n] + 1} and "
                            f"{i + 1})")
        seen[n] = i
    base: dict[str, int] = {n: seen[n] for n in ("gap_m", "current_A") if n in seen}
    missing = [n for n in ("gap_m", "current_A") if n not in seen]
    data: dict[tuple[str, str], int] = {}
    derived: list[str] = []
    for i, n in enumerate(names):
        if n in ("gap_m", "current_A"):
            continue
        if _DERIVED.match(n):
            derived.append(n)
            continue
        m = _COLUMN.match(n)
        if m is None:
            raise DataError(f"{source}: unknown column {n!r} (column {i + 1}){_hint(n)}; "
                            f"allowed: {_ALLOWED}")
        data[(m.group(1), m.group(2) or "")] = i
    if derived:
        warnings.warn(f"{source}: column(s) {derived} (derived quantities, as `maglevkit statics` "
                      "writes them) are not read; the table's data are force_N and/or "
                      "flux_linkage_Wb (and the mutual_* coupling columns)", DataWarning, stacklevel=3)
    if missing:
        raise DataError(f"{source}: the table lacks column(s) {missing}; columns: {_ALLOWED}")
    plain = [k for k in data if not k[1]]
    total = None
    if len(plain) < len(data) and plain:
        if plain == [("force_N", "")]:
            total = data.pop(("force_N", ""))     # the total force beside per-circuit columns
        else:
            raise DataError(f"{source}: columns with and without a _<circuit> suffix are mixed "
                            f"({[names[data[k]] for k in plain]} beside "
                            f"{[names[i] for k, i in data.items() if k[1]]}); with several "
                            "circuits every column carries its circuit's suffix (only a total "
                            "force_N may go without)")
    coupling = [names[i] for k, i in data.items() if k[0] in MUTUALS and not k[1]]
    if coupling:
        raise DataError(f"{source}: column(s) {coupling} without a _<circuit> suffix: the "
                        "mutual terms couple several circuits, one column per circuit "
                        "(mutual_inductance_H_<circuit>, mutual_dpsi_dgap_Wb_per_m_<circuit>)")
    if not any(k[0] in QUANTITIES for k in data) and total is None:
        raise DataError(f"{source}: the table has no force_N or flux_linkage_Wb column; "
                        f"columns: {_ALLOWED}")
    circuits = tuple(dict.fromkeys(c for _, c in data))
    for q in QUANTITIES + MUTUALS:
        have = [c for c in circuits if (q, c) in data]
        if have and len(have) != len(circuits):
            lack = [c for c in circuits if (q, c) not in data]
            raise DataError(f"{source}: {q} is given for circuit(s) {have} but not for {lack} "
                            f"(columns {[f'{q}_{c}' for c in lack]} missing; a column suffix "
                            "that names no circuit makes one of its own); give each quantity "
                            "for every circuit or for none")
    return base, data, circuits, total


def _key(value: float) -> float:
    """Grid coordinate as a key: 12 significant digits (0.1 + 0.2 and 0.3 are one gap)."""
    return float(f"{value:.12g}")


@dataclass(frozen=True)
class TableRows:
    """The rows of a CSV table, checked cell by cell (:func:`read_rows`).

    Attributes
    ----------
    gap_m, current_A : ndarray (n,)
        Per row [m], [A].
    columns : dict
        ``(quantity, circuit suffix)`` -> values per row.
    circuit_keys : tuple of str
        The column suffixes (``""`` without).
    circuits : tuple of str
        Circuit names (``"coil"`` without suffix).
    lines : ndarray (n,) of int
        Line number of each row (header = 1).
    source, sha256 : str
        File and SHA-256 of its bytes.
    total_force_N : ndarray (n,) or None
        A total ``force_N`` beside per-circuit columns (checked against the per-circuit
        forces' sum when those are given too, :data:`TOTAL_FORCE_TOLERANCE`).
    """

    gap_m: np.ndarray
    current_A: np.ndarray
    columns: dict[tuple[str, str], np.ndarray]
    circuit_keys: tuple[str, ...]
    circuits: tuple[str, ...]
    lines: np.ndarray
    source: str
    sha256: str
    total_force_N: np.ndarray | None = None


def read_rows(path: str | Path) -> TableRows:
    """The rows of a CSV table (format of :func:`read_table`), any points: columns and
    cells checked (numbers, finite, gap > 0, current >= 0, gap plausible), naming the row.
    """
    from ..errors import ParameterFileError

    if not isinstance(path, (str, Path)):
        raise InputError(f"a table needs a file path (str or Path), got {type(path).__name__}")
    p = Path(path)
    if not p.is_file():
        raise ParameterFileError(f"table file {str(p)!r} does not exist")
    raw = p.read_bytes()
    return _parse_csv(p, raw, hashlib.sha256(raw).hexdigest())


def read_table(path: str | Path) -> GridTable:
    """Read a table of ``F(s, I)`` and/or ``psi(s, I)`` from CSV or netCDF.

    CSV: a header row with ``gap_m`` [m], ``current_A`` [A] and ``force_N`` [N] and/or
    ``flux_linkage_Wb`` [Wb] (with several circuits one column per circuit with a
    ``_<circuit>`` suffix, e.g. ``force_N_front``, and optionally a total ``force_N`` and
    the coupling columns ``mutual_inductance_H_<circuit>`` [H],
    ``mutual_dpsi_dgap_Wb_per_m_<circuit>`` [Wb/m], :data:`MUTUALS`); then one row per
    grid point, in any order; lines starting with ``#`` are comments.  netCDF: variables ``force_N`` and/or
    ``flux_linkage_Wb`` with dimensions ``(gap, current)`` or ``(circuit, gap, current)``
    (e.g. a maglevkit maps file).

    Parameters
    ----------
    path : str or Path
        The table file (``.csv``, or ``.nc`` for netCDF).

    Raises
    ------
    DataError
        Unknown or missing columns (a quantity given for some circuits only), a cell that
        is not a finite number, a gap <= 0 or a negative current, a total force that is
        not the sum of the circuits' forces, duplicate grid points, a grid that is not
        rectangular (each naming the row or column).
    ParameterFileError
        The file does not exist or cannot be read.
    """
    from ..errors import ParameterFileError

    if not isinstance(path, (str, Path)):
        raise InputError(f"read_table needs a file path (str or Path), got {type(path).__name__}")
    p = Path(path)
    if not p.is_file():
        raise ParameterFileError(f"table file {str(p)!r} does not exist")
    raw = p.read_bytes()
    digest = hashlib.sha256(raw).hexdigest()
    if raw[:4] in (b"CDF\x01", b"CDF\x02", b"\x89HDF"):
        return _read_netcdf(p, digest)
    rows = _parse_csv(p, raw, digest)
    return _assemble(rows.gap_m, rows.current_A, rows.columns, rows.circuit_keys, rows.lines,
                     str(p), digest, checked=True, total=rows.total_force_N)


def csv_records(p: Path, raw: bytes) -> tuple[list[str] | None, list[tuple[int, list[str]]]]:
    """A CSV file's header and data rows, blank and ``#`` comment lines skipped.

    Parameters
    ----------
    p : Path
        The file (named in messages).
    raw : bytes
        Its content (UTF-8, a byte-order mark allowed).

    Returns
    -------
    header : list of str or None
        The first row that is not blank or a comment, as written (None: no such row).
    records : list of (int, list of str)
        The rows after it with their line numbers in the file.

    Raises
    ------
    DataError
        The content is not UTF-8 text.
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataError(f"{p}: not a UTF-8 text (CSV) file: {exc}") from None
    reader = csv.reader(text.splitlines())
    header: list[str] | None = None
    records: list[tuple[int, list[str]]] = []
    for line in reader:
        if not line or not "".join(line).strip() or line[0].lstrip().startswith("#"):
            continue
        if header is None:
            header = line
        else:
            records.append((reader.line_num, line))
    return header, records


def _parse_csv(p: Path, raw: bytes, digest: str) -> TableRows:
    header, records = csv_records(p, raw)
    if header is None:
        raise DataError(f"{p}: the table is empty (expected a header row: {_ALLOWED})")
    base, cols, circuits, total = _columns(header, str(p))
    if not records:
        raise DataError(f"{p}: the table has a header but no data rows")
    n = len(header)
    values = np.empty((len(records), n))
    for r, (row, cells) in enumerate(records):
        if len(cells) != n:
            raise DataError(f"{p}: row {row} has {len(cells)} cells, the header {n}")
        for i, cell in enumerate(cells):
            name = header[i].strip()
            try:
                v = float(cell)
            except ValueError:
                raise DataError(f"{p}: row {row}, column {name}: {cell.strip()!r} is not a "
                                "number") from None
            if not math.isfinite(v):
                raise DataError(f"{p}: row {row}, column {name}: {cell.strip()!r} is not a "
                                "finite number (every grid point needs a value)")
            values[r, i] = v
    lines = np.array([row for row, _ in records])
    gap, cur = values[:, base["gap_m"]], values[:, base["current_A"]]
    _check_axes(gap, cur, lines, str(p))
    columns = {k: values[:, i] for k, i in cols.items()}
    total_force = None if total is None else values[:, total]
    if total_force is not None and ("force_N", circuits[0]) in columns:
        _check_total_force(total_force, [columns[("force_N", c)] for c in circuits], circuits,
                           lines, str(p))
    return TableRows(gap_m=gap, current_A=cur, columns=columns,
                     circuit_keys=circuits, circuits=tuple(c or "coil" for c in circuits),
                     lines=lines, source=str(p), sha256=digest, total_force_N=total_force)


def _check_total_force(total: np.ndarray, forces: Sequence[np.ndarray], circuits: Sequence[str],
                       lines: np.ndarray, source: str) -> None:
    """A total ``force_N`` must equal the sum of the per-circuit forces
    (:data:`TOTAL_FORCE_TOLERANCE`), naming the first row where it does not."""
    summed = np.sum(forces, axis=0)
    scale = np.maximum(np.abs(total), RECIPROCITY_FLOOR * float(np.max(np.abs(total))))
    rel = np.abs(summed - total) / np.where(scale > 0.0, scale, 1.0)
    bad = np.nonzero(rel > TOTAL_FORCE_TOLERANCE)[0]
    if bad.size:
        r = int(bad[0])
        where = f"row {lines[r]}" if lines[r] else f"point {r}"
        parts = " + ".join(f"force_N_{c} {float(f[r]):.6g}" for c, f in zip(circuits, forces,
                                                                               strict=True))
        raise DataError(f"{source}: {where}: the total force_N = {float(total[r]):.6g} N is not "
                        f"the sum of the circuits' forces {parts} = {float(summed[r]):.6g} N "
                        f"(relative {float(rel[r]):.3g}, allowed {TOTAL_FORCE_TOLERANCE:g}; "
                        f"{bad.size} row(s) differ): a circuit left out, a column of another "
                        "magnet or another unit?  Give the total or agreeing per-circuit "
                        "forces")


def _check_axes(gap: np.ndarray, cur: np.ndarray, lines: np.ndarray, source: str) -> None:
    """Gaps > 0 (plausible), currents >= 0, naming the row."""
    def row(i: int) -> str:
        return f"row {lines[i]}" if lines[i] else f"point {i}"

    bad = np.nonzero(gap <= 0.0)[0]
    if bad.size:
        raise DataError(f"{source}: {row(bad[0])}: gap_m = {float(gap[bad[0]]):g} must be > 0 m")
    bad = np.nonzero(cur < 0.0)[0]
    if bad.size:
        raise DataError(f"{source}: {row(bad[0])}: current_A = {float(cur[bad[0]]):g} must be "
                        ">= 0 A (forces are even and flux linkages odd in the current: tabulate "
                        "I >= 0)")
    lo, hi = _GAP_PLAUSIBLE_M
    odd = np.nonzero((gap < lo) | (gap > hi))[0]
    if odd.size:
        warnings.warn(f"{source}: {row(odd[0])}: gap_m = {float(gap[odd[0]]):g} m lies outside "
                      f"{lo:g}-{hi:g} m (EMS air gaps are ~ 4-20 mm); is the gap in mm, not "
                      "m? (gap_m is in metres)", PlausibilityWarning, stacklevel=4)


def _assemble(gap: np.ndarray, cur: np.ndarray, cols: Mapping[tuple[str, str], np.ndarray],
              circuits: tuple[str, ...], lines: np.ndarray, source: str,
              digest: str, *, checked: bool = False, total: np.ndarray | None = None
              ) -> GridTable:
    """Scattered rows -> a rectangular grid (checks duplicates, coverage, equidistance)."""
    def row(i: int) -> str:
        return f"row {lines[i]}" if lines[i] else f"point {i}"

    if not checked:
        _check_axes(gap, cur, lines, source)
    gk = np.array([_key(v) for v in gap])
    ck = np.array([_key(v) for v in cur])
    seen: dict[tuple[float, float], int] = {}
    for i, pt in enumerate(zip(gk, ck, strict=True)):
        if pt in seen:
            raise DataError(f"{source}: {row(i)} repeats the grid point gap {pt[0]:g} m, current "
                            f"{pt[1]:g} A of {row(seen[pt])}; give every point once")
        seen[pt] = i
    gaps, currents = np.unique(gk), np.unique(ck)
    if len(seen) != gaps.size * currents.size:
        absent = [(g, c) for g in gaps for c in currents if (g, c) not in seen]
        listed = ", ".join(f"(gap {g:g} m, current {c:g} A)" for g, c in absent[:_MAX_LISTED])
        more = f" and {len(absent) - _MAX_LISTED} more" if len(absent) > _MAX_LISTED else ""
        raise DataError(f"{source}: the grid is not rectangular: {len(absent)} of the "
                        f"{gaps.size} x {currents.size} gap x current points are missing: "
                        f"{listed}{more}")
    for axis, what, unit, positive, col in ((gaps, "gap", "m", True, gk),
                                            (currents, "current", "A", False, ck)):
        try:
            check_grid(axis, what, unit, positive=positive)
        except InputError as exc:
            where = ""
            if axis.size > 2:
                step = np.diff(axis)
                k = int(np.argmax(np.abs(step - np.median(step))))
                first = int(np.nonzero(col == axis[k + 1])[0][0])
                where = (f"; the {what} step {axis[k]:g} -> {axis[k + 1]:g} {unit} (first at "
                         f"{row(first)}) differs from the usual {float(np.median(step)):g} {unit}")
            raise DataError(f"{source}: {exc}{where}; {what}s in the table: "
                            f"{', '.join(f'{v:g}' for v in axis)} {unit}") from None
    gi = {g: k for k, g in enumerate(gaps)}
    ci = {c: k for k, c in enumerate(currents)}
    index = (np.array([gi[g] for g in gk]), np.array([ci[c] for c in ck]))
    rows = np.zeros((gaps.size, currents.size), dtype=int)
    rows[index] = lines
    arrays: dict[str, np.ndarray | None] = {}
    for q in QUANTITIES + MUTUALS:
        if (q, circuits[0]) not in cols:
            arrays[q] = None
            continue
        a = np.empty((len(circuits), gaps.size, currents.size))
        for j, c in enumerate(circuits):
            a[j][index] = cols[(q, c)]
        arrays[q] = a
    names = tuple(c or "coil" for c in circuits)
    total_grid = None
    if total is not None:
        total_grid = np.empty((gaps.size, currents.size))
        total_grid[index] = total
    return GridTable(gaps_m=gaps, currents_A=currents, circuits=names, force_N=arrays["force_N"],
                     flux_linkage_Wb=arrays["flux_linkage_Wb"], rows=rows, source=source,
                     sha256=digest, total_force_N=total_grid,
                     mutual_inductance_H=arrays["mutual_inductance_H"],
                     mutual_dpsi_dgap_Wb_per_m=arrays["mutual_dpsi_dgap_Wb_per_m"])


def _read_netcdf(p: Path, digest: str) -> GridTable:
    from .._files import read_netcdf

    data = read_netcdf(p)
    have = [q for q in QUANTITIES if q in data.data_vars]
    if not have:
        raise DataError(f"{p}: no variable force_N or flux_linkage_Wb (dimensions (gap, "
                        f"current) or (circuit, gap, current)); variables: "
                        f"{sorted(str(v) for v in data.data_vars)}")
    for c in ("gap", "current"):
        if c not in data.coords:
            raise DataError(f"{p}: coordinate {c!r} missing (gap [m], current [A])")
    gaps = np.asarray(data["gap"].values, dtype=float)
    currents = np.asarray(data["current"].values, dtype=float)
    circuits = tuple(str(c) for c in data["circuit"].values) if "circuit" in data.dims \
        else ("",)
    cols: dict[tuple[str, str], np.ndarray] = {}
    total = None
    for q in have + [m for m in MUTUALS if m in data.data_vars]:
        v = data[q]
        dims = ("circuit", "gap", "current") if "circuit" in v.dims else ("gap", "current")
        if set(v.dims) != set(dims):
            raise DataError(f"{p}: variable {q} has dimensions {v.dims}; expected {dims}")
        arr = np.asarray(v.transpose(*dims).values, dtype=float)
        if arr.ndim == 2 and len(circuits) > 1 and q != "force_N":
            raise DataError(f"{p}: variable {q} has dimensions {v.dims} but the table has "
                            f"circuits {list(circuits)}; expected ('circuit', 'gap', 'current') "
                            "(only force_N may be the total over (gap, current))")
        arr = arr if arr.ndim == 3 else arr[None]
        bad = np.argwhere(~np.isfinite(arr))
        if bad.size:
            j, k, m = bad[0]
            raise DataError(f"{p}: {q} is not finite at gap {gaps[k]:g} m, current "
                            f"{currents[m]:g} A"
                            + (f" (circuit {circuits[j]!r})" if arr.shape[0] > 1 else ""))
        if arr.shape[0] != len(circuits):      # a total force (gap, current)
            total = arr[0].ravel()
            continue
        for j, c in enumerate(circuits):
            cols[(q, c)] = arr[j].ravel()
    gg, cc = np.meshgrid(gaps, currents, indexing="ij")
    if total is not None and ("force_N", circuits[0]) in cols:
        _check_total_force(total, [cols[("force_N", c)] for c in circuits], circuits,
                           np.zeros(gg.size, dtype=int), str(p))
    return _assemble(gg.ravel(), cc.ravel(), cols, circuits, np.zeros(gg.size, dtype=int),
                     str(p), digest, total=total)


# ---------------------------------------------------------------------------- derivatives
class _Axes:
    """Node derivatives and integrals of the tensor-product not-a-knot cubic spline.

    Along the current the spline is fitted to the tabulated currents; only with
    :data:`MIRROR_CURRENTS` (off) would a grid from 0 A be mirrored to ``-I`` first (odd
    for ``psi``, even for ``F``).
    """

    def __init__(self, gaps: np.ndarray, currents: np.ndarray) -> None:
        self.s, self.i = gaps, currents
        self.mirror = MIRROR_CURRENTS and currents[0] == 0.0
        self.ie = np.concatenate((-currents[:0:-1], currents)) if self.mirror else currents

    def _ext(self, y: np.ndarray, parity: int) -> np.ndarray:
        return np.concatenate((parity * y[:, :0:-1], y), axis=1) if self.mirror else y

    def d_current(self, y: np.ndarray, parity: int) -> np.ndarray:
        """``dy/dI`` at the nodes; ``parity`` -1 for odd data (psi), +1 for even (F)."""
        from scipy.interpolate import make_interp_spline

        spl = make_interp_spline(self.ie, self._ext(y, parity).T, k=3)
        return np.asarray(spl.derivative()(self.i)).T

    def integral_current(self, y: np.ndarray, parity: int) -> np.ndarray:
        """``int_0^I y di`` at the nodes (exact for the spline); needs a grid from 0 A."""
        from scipy.interpolate import make_interp_spline

        spl = make_interp_spline(self.ie, self._ext(y, parity).T, k=3).antiderivative()
        return np.asarray(spl(self.i) - spl(0.0)).T

    def d_gap(self, y: np.ndarray, order: int = 3) -> np.ndarray:
        """``dy/ds`` at the nodes (``order`` 2: of the quadratic spline, for error estimates)."""
        from scipy.interpolate import make_interp_spline

        return np.asarray(make_interp_spline(self.s, y, k=order).derivative()(self.s))

    def cell_integral_gap(self, y: np.ndarray, order: int = 3) -> np.ndarray:
        """``int_{s_k}^{s_k+1} y ds`` over each gap cell (exact for the spline of ``order``)."""
        from scipy.interpolate import make_interp_spline

        anti = np.asarray(make_interp_spline(self.s, y, k=order).antiderivative()(self.s))
        return np.diff(anti, axis=0)

    def gap_error(self, y: np.ndarray) -> np.ndarray:
        """Estimated grid error of :meth:`d_gap` at the nodes: ``|cubic - quadratic|`` slope.

        The quadratic spline's slope is one order less accurate, so the difference bounds
        the cubic's own error from above (measured on ``psi = (L + k/s) I``, 4-20 mm: true
        error 0.9-2x the estimate at 2 and 4 mm gap steps, largest at the grid's edge).
        Zero with fewer than four gaps (no cubic spline to compare).
        """
        if self.s.size < 4:
            return np.zeros_like(y)
        return np.abs(self.d_gap(y) - self.d_gap(y, 2))


# ---------------------------------------------------------------------------- report
@dataclass(frozen=True)
class TableReport:
    """What the consistency checks of :func:`maps_from_table` found.

    Attributes
    ----------
    reciprocity_max : dict
        Circuit -> largest relative reciprocity residual over the gap cells,
        ``|int F ds - (W'(s_k) - W'(s_k+1))| / scale`` (NaN when the force was derived
        from ``psi``: reciprocal by construction).
    reciprocity_worst : dict
        Circuit -> where it is largest (gap, current, row).
    force_from : str
        ``"table"`` or ``"co-energy of psi"``.
    messages : list of str
        The warnings issued (monotonicity, coverage, reciprocity).
    """

    reciprocity_max: dict[str, float]
    reciprocity_worst: dict[str, str]
    force_from: str
    messages: list[str] = field(default_factory=list)


def _warn(messages: list[str], text: str) -> None:
    messages.append(text)
    warnings.warn(text, DataWarning, stacklevel=3)


def _points(mask: np.ndarray) -> list[tuple[int, int]]:
    return [(int(k), int(m)) for k, m in np.argwhere(mask)]


def _monotonicity(table: GridTable, messages: list[str]) -> None:
    """psi strictly rising in I (required); psi, F falling in s and F rising in I (warned)."""
    psi = table.flux_linkage_Wb
    forces = [(c, None if table.force_N is None else table.force_N[j])
              for j, c in enumerate(table.circuits)]
    if table.total_force_N is not None:
        forces.append((_TOTAL, table.total_force_N))
    for j, (c, f) in enumerate(forces):
        if psi is not None and j < len(table.circuits):
            step = np.diff(psi[j], axis=1)
            bad = _points(np.pad(step <= 0.0, ((0, 0), (1, 0))))
            if bad:
                raise DataError(f"{table.source}: the flux linkage does not rise with the "
                                f"current at {_listed(table, bad, c)} (compared with the next "
                                "lower current): L~ = dpsi/dI <= 0 there, and eq. 8 divides "
                                "by L~; check the data (sign, units, column order)")
            # |psi| falls as the gap opens (less permeance); tolerance: 1e-9 of the row's
            # range for rounding in the file
            tol = 1e-9 * np.ptp(psi[j])
            bad = _points(np.pad(np.diff(psi[j], axis=0) > tol, ((1, 0), (0, 0))))
            if bad:
                _warn(messages, f"{table.source}: the flux linkage rises with the gap at "
                                f"{_listed(table, bad, c)} (compared with the next smaller "
                                "gap): dL/ds > 0 there, unusual for an attracting magnet")
        if f is not None:
            tol = 1e-9 * np.ptp(f)
            bad = _points(np.pad(np.diff(f, axis=0) > tol, ((1, 0), (0, 0))))
            if bad:
                _warn(messages, f"{table.source}: the force rises with the gap at "
                                f"{_listed(table, bad, c)} (compared with the next smaller gap)")
            bad = _points(np.pad(np.diff(f, axis=1) < -tol, ((0, 0), (1, 0))))
            if bad:
                _warn(messages, f"{table.source}: the force falls with the current at "
                                f"{_listed(table, bad, c)} (compared with the next lower "
                                "current)")
            bad = _points(f < -tol)
            if bad:
                _warn(messages, f"{table.source}: the force is negative (repelling) at "
                                f"{_listed(table, bad, c)}; force_N is attraction-positive")


def _coenergy_force(axes: _Axes, psi: np.ndarray) -> np.ndarray:
    """``F = -d/ds int_0^I psi di`` at the nodes (attraction-positive co-energy force)."""
    return -axes.d_gap(axes.integral_current(psi, -1))


GRID_ERROR_FACTOR = 2.0
"""The reciprocity tolerance grows by this multiple of the grid's own error estimate
(``|cubic - quadratic|`` cell integral of the force): measured on exact data
``psi = (L + k/s) I``, ``F = k I^2/(2 s^2)`` (4-20 mm, 0-80 A) the integral residual is
1.4x (2 mm gap step) to 3x (4 mm) that estimate, but below ``tolerance / 2`` where the
factor 2 does not cover it; a force 7 % off then stays warned on a 2 mm grid."""

GRID_ERROR_WARN = 0.05
"""A force or ``dL/ds`` derived from ``psi`` whose estimated grid error
(:meth:`_Axes.gap_error`, relative to ``max(|x|, 1 % of max |x|)``) exceeds this is warned:
half the default reciprocity tolerance, the accuracy a table's force is held to."""


def _relative(err: np.ndarray, ref: np.ndarray) -> np.ndarray:
    scale = np.maximum(np.abs(ref), RECIPROCITY_FLOOR * float(np.max(np.abs(ref))))
    return err / np.where(scale > 0.0, scale, 1.0)


def _reciprocity(table: GridTable, axes: _Axes, tolerance: float, messages: list[str]
                 ) -> tuple[np.ndarray, dict[str, float], dict[str, str]]:
    """Residual of co-energy reciprocity per gap cell; refuse above the scaled tolerance.

    ``dF/dI = -dpsi/ds`` integrated from ``I = 0`` (where ``F = 0``) and over a gap cell is
    ``int_{s_k}^{s_k+1} F ds = W'(s_k, I) - W'(s_k+1, I)`` with ``W' = int_0^I psi di``.  The
    co-energy at the nodes is exact for the spline of ``psi``; only the force's integral
    over the cell depends on the gap grid, and its error (:meth:`_Axes.cell_integral_gap`
    cubic against quadratic) widens the tolerance: ``tolerance + GRID_ERROR_FACTOR * est``
    (refused), half the tolerance plus the same (warned).  Residual and estimate are relative
    to ``max(|int F ds|, 1 % of its largest)``.  The node residual reported is that of the
    adjacent cell with the larger magnitude; the listed points name the cell's smaller gap.
    """
    assert table.force_N is not None and table.flux_linkage_Wb is not None
    res = np.empty_like(table.force_N)
    worst: dict[str, float] = {}
    where: dict[str, str] = {}
    for j, c in enumerate(table.circuits):
        f = table.force_N[j]
        wco = axes.integral_current(table.flux_linkage_Wb[j], -1)
        rhs = wco[:-1] - wco[1:]
        lhs = axes.cell_integral_gap(f)
        cell = _relative(lhs - rhs, lhs)
        est = (_relative(np.abs(lhs - axes.cell_integral_gap(f, 2)), lhs)
               if axes.s.size >= 3 else np.zeros_like(lhs))
        excess = np.abs(cell) - GRID_ERROR_FACTOR * est
        pad = np.zeros((1, cell.shape[1]))
        lo, hi = np.vstack((cell, pad)), np.vstack((pad, cell))
        res[j] = np.where(np.abs(lo) >= np.abs(hi), lo, hi)
        k, m = np.unravel_index(int(np.argmax(np.abs(cell))), cell.shape)
        worst[c], where[c] = float(abs(cell[k, m])), table.where(int(k), int(m))
        bad = _points(excess > tolerance)
        if bad:
            sel = np.abs(rhs) > RECIPROCITY_FLOOR * float(np.max(np.abs(rhs)))
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = float(np.median(lhs[sel] / rhs[sel])) if np.any(sel) else math.nan
            hint = ""
            if math.isfinite(ratio) and (abs(ratio) > 300 or abs(ratio) < 1 / 300):
                hint = (f"; the force is ~{ratio:.3g} x the co-energy force: a unit slip (gap "
                        "in mm as m, mWb as Wb, kN as N)?")
            raise DataError(f"{table.source}: force and flux linkage violate co-energy "
                            f"reciprocity dF/dI = -dpsi/ds (int F ds over a gap cell = the "
                            f"co-energy difference) by more than {tolerance:g} (relative) plus "
                            f"{GRID_ERROR_FACTOR:g}x the grid's own error on the gap cells "
                            f"starting at {_listed(table, bad, c)}; largest {worst[c]:.3g} at "
                            f"{where[c]}{hint}.  Force and flux linkage of one magnet satisfy "
                            "it; check the data, or drop the force columns to derive the force "
                            "from psi")
        if np.any(excess > tolerance / 2):
            loose = _points(excess > tolerance / 2)
            _warn(messages, f"{table.source}: co-energy reciprocity dF/dI = -dpsi/ds holds only "
                            f"to {worst[c]:.3g} (relative; worst on the gap cell starting at "
                            f"{where[c]}; above {tolerance / 2:g} plus {GRID_ERROR_FACTOR:g}x "
                            f"the grid's own error on the cells starting at "
                            f"{_listed(table, loose, c)})")
    return res, worst, where


def _derived_grid_error(table: GridTable, what: str, value: np.ndarray, err: np.ndarray,
                        messages: list[str]) -> None:
    """Warn when a quantity derived along the gap carries a large grid error estimate."""
    for j, c in enumerate(table.circuits):
        rel = _relative(err[j], value[j])
        k, m = np.unravel_index(int(np.argmax(rel)), rel.shape)
        if rel[k, m] > GRID_ERROR_WARN:
            _warn(messages, f"{table.source}: the {what} derived from psi along the gap carries "
                            f"an estimated grid error up to {rel[k, m]:.2g} (relative; at "
                            f"{table.where(int(k), int(m))}"
                            + (f", circuit {c!r}" if len(table.circuits) > 1 else "")
                            + f"; above {GRID_ERROR_WARN:g}): the gap grid is too coarse for "
                            "it; tabulate more gaps" + (" or give force_N columns"
                                                        if what == "force" else ""))


# ---------------------------------------------------------------------------- maps


def maps_from_table(data: str | Path | GridTable, *, resistance_ohm: Any = None,
                    eddy_resistance_ohm: Any = math.inf, magnet: Any = None,
                    pole_groups: Mapping[str, Sequence[str]] | None = None,
                    name: str | None = None,
                    reciprocity_tolerance: float = RECIPROCITY_TOLERANCE) -> CharacteristicMaps:
    """Characteristic maps from tabulated ``psi(s, I)`` and/or ``F(s, I)`` (module docstring).

    Parameters
    ----------
    data : path or GridTable
        A CSV or netCDF table (:func:`read_table`) or a table read already.
    resistance_ohm : float, sequence or mapping
        ``R_el`` per circuit [ohm] (one value for all).  Default: the magnet's, if
        ``magnet`` is given; otherwise required.
    eddy_resistance_ohm : float, sequence or mapping
        ``R_ec`` per circuit [ohm] (default ``inf``: no eddy currents), e.g. from a
        measured voltage step (:func:`eddy_resistance_from_step`).  Stored as both
        ``eddy_resistance_ohm`` and ``eddy_resistance_fit_ohm`` (the current model's
        default); no eddy network (``eddy_modes > 0`` is not available).
    magnet : Magnet, optional
        The magnet the table describes: its circuit names must match the table's; it gives
        the pole groups and gap names (so scenarios written for the magnet run on the maps)
        and the default ``R_el``.  The maps are *not* tied to its equivalent circuit
        (``magnet_hash`` is the table's hash).
    pole_groups : mapping, optional
        Circuit -> names of the gap inputs (poles) it drives.  Default: the magnet's, or
        one gap per circuit (``"gap"`` for one circuit, ``"gap_<circuit>"`` otherwise).
    name : str, optional
        The maps' ``magnet_name`` (default: the magnet's name or the file's stem).
    reciprocity_tolerance : float
        Largest relative residual of ``dF/dI = -dpsi/ds`` per gap cell, integral form
        (:data:`RECIPROCITY_TOLERANCE`), before the table is refused; warned above half of
        it; both plus :data:`GRID_ERROR_FACTOR` times the grid's own error estimate.

    Returns
    -------
    CharacteristicMaps
        With ``force_N``, ``inductance_H``, ``dL_ds_H_per_m``, ``flux_linkage_Wb``,
        ``apparent_inductance_H``, ``resistance_ohm``, ``eddy_resistance_ohm``,
        ``eddy_resistance_fit_ohm`` and, when force and flux linkage are both given,
        ``reciprocity_residual`` (``total_reciprocity_residual`` for a total force alone,
        which is split among the circuits by their co-energy forces).  With several
        circuits ``L~`` and ``dL/ds`` are the symmetric path's slopes less the
        :data:`MUTUALS` columns, where given.  The attribute ``table_report`` (JSON) holds the
        :class:`TableReport`; :func:`table_report` returns it.

    Raises
    ------
    DataError
        Bad table (:func:`read_table`), no flux linkage, a flux linkage that does not rise
        with the current, reciprocity violated beyond the tolerance, or a force to derive
        from a grid that does not start at 0 A.
    """
    table = data if isinstance(data, GridTable) else read_table(data)
    tol = real_number(reciprocity_tolerance, "reciprocity_tolerance", positive=True)
    table, groups, gap_names, r_default, default_name = _identity(table, magnet, pole_groups)
    circuits = table.circuits
    if resistance_ohm is None:
        if r_default is None:
            raise InputError("resistance_ohm (R_el per circuit [ohm]) is required: a table "
                             "holds no resistance (or give the magnet)")
        resistance_ohm = r_default
    r_el = per_name_values(resistance_ohm, circuits, "resistance_ohm", "ohm", positive=True)
    r_ec = per_name_values(eddy_resistance_ohm, circuits, "eddy_resistance_ohm", "ohm",
                           positive=True, allow_inf=True)
    psi = table.flux_linkage_Wb
    if psi is None:
        raise DataError(f"{table.source}: the table has no flux_linkage_Wb: the reduced model "
                        "needs L~ = dpsi/dI, and the force fixes the flux linkage only up to a "
                        "function of the current (dpsi/ds = -dF/dI; the flux at a reference gap, "
                        "e.g. the leakage, stays unknown); add flux_linkage_Wb columns")
    messages: list[str] = []
    g, c = table.gaps_m, table.currents_A
    if c[0] > 0.0:
        _warn(messages, f"{table.source}: the current grid starts at {c[0]:g} A, not 0 A: the "
                        "reduced model cannot run below it (the maps' range)")
    _monotonicity(table, messages)
    axes = _Axes(g, c)
    nc = len(circuits)
    ltilde = np.stack([axes.d_current(psi[j], -1) for j in range(nc)])
    dpsi_ds = np.stack([axes.d_gap(psi[j]) for j in range(nc)])
    # several circuits: the symmetric-path slopes less the other circuits' parts (MUTUALS)
    # are the maps' dpsi_j/dI_j and own-pole dpsi_j/ds
    if table.mutual_inductance_H is not None:
        ltilde = ltilde - table.mutual_inductance_H
    if table.mutual_dpsi_dgap_Wb_per_m is not None:
        dpsi_ds = dpsi_ds - table.mutual_dpsi_dgap_Wb_per_m
    _derived_grid_error(table, "dL/ds", dpsi_ds,
                        np.stack([axes.gap_error(psi[j]) for j in range(nc)]), messages)
    bad = [(j, _points(ltilde[j] <= 0.0)) for j in range(nc)]
    for j, pts in bad:
        if pts:
            less = (" less mutual_inductance_H" if table.mutual_inductance_H is not None
                    else "")
            raise DataError(f"{table.source}: the spline through the flux linkage has a "
                            f"slope L~{less} <= 0 at {_listed(table, pts, circuits[j])}; the "
                            "data are too coarse or too noisy near there")
    pos = c > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        dlds = np.where(pos, dpsi_ds / np.where(pos, c, 1.0), np.nan)
        lapp = np.where(pos, psi / np.where(pos, c, 1.0), np.nan)
    if not pos[0]:
        # I -> 0: the limit of (dpsi/ds)/I is d^2 psi/(ds dI) at 0 (the spline's slope in I)
        for j in range(nc):
            dlds[j, :, 0] = axes.d_current(dpsi_ds[j], -1)[:, 0]
            lapp[j, :, 0] = ltilde[j, :, 0]
    residual = None
    total_residual = None
    worst: dict[str, float] = {cc: math.nan for cc in circuits}
    where = {cc: "" for cc in circuits}
    if table.force_N is not None:
        force = table.force_N
        force_from = "table"
        if c[0] == 0.0:
            residual, worst, where = _reciprocity(table, axes, tol, messages)
        else:
            _warn(messages, f"{table.source}: reciprocity not checked: the co-energy needs "
                            "the flux linkage from 0 A")
    elif table.total_force_N is not None:
        if c[0] > 0.0:
            raise DataError(f"{table.source}: splitting the total force_N among the circuits "
                            "needs their co-energy from 0 A, but the currents start at "
                            f"{c[0]:g} A; add rows at 0 A or force_N_<circuit> columns")
        # exact for the sum: W'(s, I, ..., I) = int_0^I sum_j psi_j di on the symmetric path
        summed = replace(table, circuits=("total",), force_N=table.total_force_N[None],
                         flux_linkage_Wb=psi.sum(axis=0)[None],
                         source=f"{table.source} (the total force_N against the circuits' "
                                "summed flux linkage)")
        total_residual, worst_t, where_t = _reciprocity(summed, axes, tol, messages)
        worst, where = {**worst, **worst_t}, {**where, **where_t}
        coenergy = np.stack([_coenergy_force(axes, psi[j]) for j in range(nc)])
        sum_co = coenergy.sum(axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(sum_co != 0.0, coenergy / np.where(sum_co != 0.0, sum_co, 1.0),
                             1.0 / nc)
        force = table.total_force_N[None] * share
        force_from = "table total split by the circuits' co-energy shares"
    else:
        if c[0] > 0.0:
            raise DataError(f"{table.source}: deriving the force from the flux linkage needs "
                            f"the co-energy from 0 A, but the currents start at {c[0]:g} A; "
                            "add rows at 0 A or force_N columns")
        lo_g, hi_g = _GAP_PLAUSIBLE_M
        if g.min() < lo_g or g.max() > hi_g:
            raise DataError(f"{table.source}: gap_m runs from {g.min():g} to {g.max():g} m, "
                            f"outside {lo_g:g}-{hi_g:g} m (mm or km typed as m?); the force "
                            "derived from psi (F = -dW'/ds) scales with 1/gap unit, e.g. "
                            "1000x too small for gaps in mm; give gap_m in m (or force_N "
                            "columns)")
        force = np.stack([_coenergy_force(axes, psi[j]) for j in range(nc)])
        _derived_grid_error(table, "force", force, np.stack(
            [axes.gap_error(axes.integral_current(psi[j], -1)) for j in range(nc)]), messages)
        force_from = "co-energy of psi"
    report = TableReport(reciprocity_max=worst, reciprocity_worst=where, force_from=force_from,
                         messages=messages)
    ds = maps_dataset({"force_N": force, "inductance_H": ltilde, "dL_ds_H_per_m": dlds,
                       "flux_linkage_Wb": psi, "apparent_inductance_H": lapp},
                      circuits=circuits, gaps_m=g, currents_A=c, resistance_ohm=r_el)
    given = ("given (eddy_resistance_ohm of maps_from_table; inf: no eddy currents), "
             "e.g. from a measured voltage step")
    ds["eddy_resistance_ohm"] = ("circuit", r_ec, {"units": "ohm", "long_name":
                                                   "eddy-current resistance R_ec",
                                                   "description": given})
    ds["eddy_resistance_fit_ohm"] = ("circuit", r_ec.copy(), {
        "units": "ohm", "long_name": "eddy-current resistance R_ec from the step time constant",
        "description": given})
    if total_residual is not None:
        ds["total_reciprocity_residual"] = (("gap", "current"), total_residual[0], {
            "units": "1", "long_name": "co-energy reciprocity residual of the table's total "
                                       "force against the circuits' summed flux linkage",
            "description": "as reciprocity_residual, for the total force"})
    if residual is not None:
        ds["reciprocity_residual"] = (("circuit", "gap", "current"), residual, {
            "units": "1", "long_name": "co-energy reciprocity residual of the table",
            "description": "(int F ds - (W'(s_k) - W'(s_k+1))) / scale over each gap cell, "
                           "W' = int_0^I psi di of the spline, scale max(|int F ds|, 1 % of "
                           "its largest); at a node the adjacent cell's with the larger "
                           "magnitude"})
    ds.attrs.update({
        "format": MAPS_FORMAT,
        "magnet_name": name or default_name,
        "magnet_hash": table.sha256 or _array_hash(table),
        "magnet_hash_kind": "sha256 of the imported table (file bytes)",
        "magnet_parameter_hash": "",
        "magnet_parameters": "",
        "pole_groups": json.dumps(groups),
        "gap_names": ",".join(gap_names),
        "method": "imported table: L~ and dL/ds from the not-a-knot bicubic spline of psi "
                  + ("(odd-mirrored in I)" if MIRROR_CURRENTS else "(currents as tabulated)")
                  + _coupling_note(table)
                  + "; force " + {"table": "from the table",
                                  "co-energy of psi": "by co-energy, -d/ds int_0^I psi di"}.get(
                      force_from, "the table's total split by -d/ds int_0^I psi_j di"),
        "table_source": table.source,
        "table_sha256": table.sha256,
        "table_report": json.dumps(asdict(report)),
        "maglevkit_version": __version__,
        "conventions": "all gaps equal to s and every circuit at I (symmetric operation); "
                       "force is attraction-positive",
    })
    return CharacteristicMaps(ds)


def _coupling_note(table: GridTable) -> str:
    """How the maps' per-circuit slopes treat the other circuits (the ``method`` attribute)."""
    if len(table.circuits) == 1:
        return ""
    parts = [f"{q} columns subtracted" for q, a in (
        ("mutual_inductance_H", table.mutual_inductance_H),
        ("mutual_dpsi_dgap_Wb_per_m", table.mutual_dpsi_dgap_Wb_per_m)) if a is not None]
    if len(parts) == 2:
        return "; the other circuits' parts (" + ", ".join(parts) + ")"
    return ("; " + ", ".join(parts) + "; " if parts else "; ") + (
        "symmetric-path slopes otherwise (every circuit at I, all gaps at s: the other "
        "circuits' coupling included)")


def table_report(maps: CharacteristicMaps) -> TableReport:
    """The consistency report stored in maps from :func:`maps_from_table`."""
    raw = maps.dataset.attrs.get("table_report")
    if raw is None:
        raise InputError("these maps were not imported from a table (no table_report)")
    d = json.loads(raw)
    return TableReport(reciprocity_max={k: float(v) for k, v in d["reciprocity_max"].items()},
                       reciprocity_worst=d["reciprocity_worst"], force_from=d["force_from"],
                       messages=list(d["messages"]))


def _array_hash(table: GridTable) -> str:
    h = hashlib.sha256()
    for a in (table.gaps_m, table.currents_A, table.force_N, table.flux_linkage_Wb):
        if a is not None:
            h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def _identity(table: GridTable, magnet: Any, pole_groups: Mapping[str, Sequence[str]] | None
              ) -> tuple[GridTable, dict[str, tuple[str, ...]], tuple[str, ...], Any, str]:
    """(table, pole groups, gap names, default R_el, default name) of the imported maps; a
    one-circuit table takes the name of a one-circuit magnet's circuit."""
    circuits = table.circuits
    r_default = None
    default_name = Path(table.source).stem if table.source != "<memory>" else "table"
    if magnet is not None:
        from ..models.statics import as_network, circuit_pole_groups

        net = as_network(magnet)
        if len(circuits) == 1 and len(net.circuits) == 1:
            circuits = tuple(net.circuit_names)
            table = replace(table, circuits=circuits)
        if tuple(sorted(circuits)) != tuple(sorted(net.circuit_names)):
            unknown = [cc for cc in circuits if cc not in net.circuit_names]
            absent = [cc for cc in net.circuit_names if cc not in circuits]
            raise DataError(f"{table.source}: the table's circuits {list(circuits)} are not the "
                            f"magnet's {list(net.circuit_names)} (column suffixes _<circuit>)"
                            + (f"; suffix(es) {['_' + cc for cc in unknown]} name no circuit "
                               f"of {net.name!r}" if unknown else "")
                            + (f"; no columns for circuit(s) {absent}" if absent else ""))
        order = [net.circuit_names.index(cc) for cc in circuits]
        r_default = net.resistances[order]
        mid_g, mid_c = pole_group_point(table.gaps_m, table.currents_A)
        groups0 = pole_groups or circuit_pole_groups(net, gap_m=mid_g, current_A=mid_c)
        default_name = str(getattr(magnet, "name", net.name))
        gap_names = tuple(net.gap_names)
    else:
        groups0 = pole_groups or ({circuits[0]: ("gap",)} if len(circuits) == 1 else
                                  {cc: (f"gap_{cc}",) for cc in circuits})
        gap_names = tuple(gname for cc in circuits for gname in groups0.get(cc, ()))
    groups = {cc: tuple(str(x) for x in v) for cc, v in groups0.items()}
    if set(groups) != set(circuits) or any(not v for v in groups.values()):
        raise InputError(f"pole_groups must give every circuit {list(circuits)} at least one "
                         f"gap name, got {dict(groups)}")
    return table, groups, gap_names, r_default, default_name


# ---------------------------------------------------------------------------- R_ec from a step
@dataclass(frozen=True)
class StepIdentification:
    """``L~`` and ``R_ec`` from a measured voltage step (:func:`eddy_resistance_from_step`).

    Attributes
    ----------
    inductance_H : float
        ``L~ = tau R_el (1 - dI_0/dI_inf)`` [H].
    eddy_resistance_ohm : float
        ``R_ec = dU/dI_0 - R_el`` [ohm] (inf when no jump is seen).
    time_constant_s : float
        Fitted ``tau`` [s].
    current_jump_A : float
        ``dI_0`` [A], the jump the fit extrapolates to ``t = 0``.
    fit_rms : float
        RMS of the log-linear fit residual.
    """

    inductance_H: float
    eddy_resistance_ohm: float
    time_constant_s: float
    current_jump_A: float
    fit_rms: float


def eddy_resistance_from_step(time_s: Any, current_A: Any, *, voltage_step_V: float,
                              resistance_ohm: float) -> StepIdentification:
    """``R_ec`` and ``L~`` from a measured current response to a voltage step (paper IV-B).

    The magnet is held at a fixed gap at the current ``I(t < 0)`` (the first sample must be
    at ``t <= 0``); at ``t = 0`` the voltage steps by ``voltage_step_V``.  Eq. 8 at fixed
    gap is linear: ``dI(t) = dI_inf - (dI_inf - dI_0) exp(-t/tau)`` with ``dI_inf = dU/R_el``,
    ``dI_0 = dU/(R_el + R_ec)``; ``log(dI_inf - dI)`` is fitted by a straight line over
    the samples with ``2 % < remaining < 98 %`` (the procedure of
    :func:`~maglevkit.models.experiments.differential_inductance_from_step`).

    Parameters
    ----------
    time_s, current_A : array_like
        Sample times [s] (increasing, the first <= 0) and coil currents [A].
    voltage_step_V : float
        The voltage step ``dU`` [V] (either sign).
    resistance_ohm : float
        ``R_el`` [ohm].

    Raises
    ------
    DataError
        Bad samples; a settled current change of the wrong sign or off ``dU/R_el`` by more
        than :data:`STEP_SETTLE_TOLERANCE`; a fit rms above :data:`STEP_FIT_RMS`; a fitted
        jump fraction outside ``[0, 1)``.
    """
    from ..models.experiments import fit_step_response

    t = np.asarray(time_s, dtype=float)
    i = np.asarray(current_A, dtype=float)
    if t.ndim != 1 or t.shape != i.shape or t.size < 12:
        raise DataError(f"the voltage step needs matching 1-D time_s and current_A with at least "
                        f"12 samples, got shapes {t.shape} and {i.shape}")
    bad = np.nonzero(~(np.isfinite(t) & np.isfinite(i)))[0]
    if bad.size:
        raise DataError(f"the voltage step's sample {bad[0]} is not finite "
                        f"(t = {t[bad[0]]!r} s, I = {i[bad[0]]!r} A)")
    if np.any(np.diff(t) <= 0.0) or t[0] > 0.0:
        raise DataError("the voltage step's times must increase and start at t <= 0 (the "
                        "current before the step)")
    r = real_number(resistance_ohm, "resistance_ohm", "ohm", positive=True)
    du = real_number(voltage_step_V, "voltage_step_V", "V")
    if du == 0.0:
        raise DataError("voltage_step_V = 0: no step")
    before = i[t <= 0.0]
    di_inf = du / r
    sel = t > 0.0
    names = (f"voltage_step_V (--step-voltage) = {du:g} V and resistance_ohm (R_el) = "
             f"{r:g} ohm give dU/R_el = {di_inf:.4g} A")
    # the settled change: the mean of the last 3 samples (noise), against dU/R_el
    settled = float(np.mean(i[sel][-3:])) - float(before[-1])
    if settled * di_inf <= 0.0:
        raise DataError(f"the voltage step's current changes by {settled:.4g} A (last samples "
                        f"against the one before t = 0) but {names}: the step voltage's sign "
                        "(or the current's) is wrong, or the record is not the step")
    if abs(settled / di_inf - 1.0) > STEP_SETTLE_TOLERANCE:
        raise DataError(f"the voltage step's current settles at a change of {settled:.4g} A but "
                        f"{names} ({settled / di_inf - 1.0:+.1%}; allowed "
                        f"+-{STEP_SETTLE_TOLERANCE:.0%}): check the step voltage and R_el, or "
                        "record until the current has settled (> 3 time constants)")
    fit = fit_step_response(t[sel], (i[sel] - before[-1]) / di_inf)
    if fit.rms > STEP_FIT_RMS:
        raise DataError(f"the voltage step is not one exponential: the log-linear fit's rms is "
                        f"{fit.rms:.3g} (allowed {STEP_FIT_RMS:g}); eq. 8 at a fixed gap answers "
                        "a step with one exponential (noise, a moving gap or saturation?)")
    if not -STEP_SETTLE_TOLERANCE <= fit.jump_fraction < 1.0:
        raise DataError(f"the voltage step's fitted jump at t = 0 is {fit.jump_fraction:.3g} of "
                        f"the step (allowed [0, 1), down to -{STEP_SETTLE_TOLERANCE:g} read as 0 "
                        f"for noise): with {names} that is no eq. 8 response (R_ec = dU/dI_0 - "
                        "R_el needs 0 < dI_0 < dI_inf)")
    jump = fit.jump_fraction * di_inf
    r_ec = math.inf if fit.jump_fraction <= 0.0 else r / fit.jump_fraction - r
    return StepIdentification(
        inductance_H=fit.time_constant_s * r * (1.0 - max(fit.jump_fraction, 0.0)),
        eddy_resistance_ohm=r_ec, time_constant_s=fit.time_constant_s, current_jump_A=jump,
        fit_rms=fit.rms)
