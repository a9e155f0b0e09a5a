"""Characteristic maps of the simplified current-based model (paper Sec. IV-B).

For every electric circuit ``j`` and every point of a regular ``gap x current`` grid the
maps hold (all gaps equal to ``s``, every circuit carrying ``I`` -- symmetric operation):

* ``force_N``: ``F_j(s, I)``, the sum of the pole forces of the circuit's poles;
* ``inductance_H``: ``L~_j(s, I) = dL/dI I + L = dpsi_j/dI_j`` (other currents fixed);
* ``dL_ds_H_per_m``: ``dL_j/ds(s, I) = (sum_{k in j} dpsi_j/ds_k) / I`` (the circuit's own
  poles move together; at ``I = 0`` the limit ``d L~_j(s, 0)/ds``);
* ``flux_linkage_Wb`` and the apparent inductance ``L = psi/I``;
* ``resistance_ohm`` ``R_el`` and ``eddy_resistance_ohm`` ``R_ec`` per circuit;
* the identified eddy extensions of the current model: ``eddy_network_*`` (RL branches,
  :mod:`~maglevkit.reduction.eddy_network`) and ``motion_eddy_*`` (the shielded-gap ladder,
  :mod:`~maglevkit.reduction.motion_eddy`).

A pole ``k`` belongs to the circuit whose flux linkage depends most on its gap
(``argmax_j |dpsi_j/ds_k|`` at the grid centre), which recovers the half magnets of a
levitation magnet without any extra parameter.

Method ``"statics"`` computes ``L~`` and ``dL/ds`` from exact sensitivities of the static
network (implicit function theorem).  Method ``"transient"`` uses the paper's
time-integration procedure (:mod:`maglevkit.reduction.transient`: voltage-step time
constants and the virtual control law ``U = R_el I`` on a gap ramp), one executor task
per grid point; ``"both"`` keeps the statics maps and adds the transient ones and their
relative differences.  ``R_ec`` comes from the detailed DAE analytically
(:mod:`maglevkit.reduction.parameters`).  See ``docs/reduction.md``.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..circuit.network import Network
from ..errors import InputError, ParameterFileError, SolverError
from ..models.statics import as_network, circuit_pole_groups, solve_statics
from ..validation import real_array, renamed_keywords
from .eddy_network import EDDY_NETWORK_MODES, EddyNetworkFit, fit_eddy_network
from .motion_eddy import (
    FORCE_SHARE_VARIABLE,
    HELD_FLUX_FORCE_SHARE_VARIABLE,
    MAX_STEP_FORCE_LOSS,
    MAX_UNSHIELDED_SHARE_OF_MIN_L,
    MOTION_EDDY3_WEIGHTS,
    SHARE_VARIABLE,
    detailed_frequency_response,
    fit_motion_eddy,
    fit_motion_eddy3,
)
from .parameters import eddy_resistance
from .transient import transient_point

if TYPE_CHECKING:  # xarray is imported where it is used (0.45 s of start-up otherwise)
    import xarray as xr

__all__ = ["DEFAULT_EDDY_MODES_ATTRIBUTE", "CharacteristicMaps", "build_maps",
           "circuit_pole_groups", "default_eddy_modes", "law_hash", "load_maps", "model_hash",
           "network_hash"]

MAPS_FORMAT = "maglevkit-maps/1"
REQUIRED_VARIABLES = ("force_N", "inductance_H", "dL_ds_H_per_m", "resistance_ohm")
"""Variables :func:`load_maps` requires (the plots and the current-based model use them)."""


def _version() -> str:
    from .._version import __version__

    return __version__


def check_grid(values: Any, what: str, unit: str, *, positive: bool) -> np.ndarray:
    """A map grid axis as a float array: 1-D, at least 4 points, finite, strictly increasing
    (and > 0 with ``positive``); otherwise InputError naming ``what`` and ``unit``.

    Parameters
    ----------
    values : array_like
        The axis values [``unit``].
    what : str
        Its name in messages (``"gap"``, ``"current"``).
    unit : str
        Its unit in messages.
    positive : bool
        Require every value > 0.
    """
    arr = real_array(values, f"{what} grid", unit, finite=False)
    if arr.ndim != 1 or arr.size < 4:
        raise InputError(f"{what} grid must be 1-D with at least 4 points (cubic interpolation), "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what} grid must be finite [{unit}]")
    if np.any(np.diff(arr) <= 0.0):
        raise InputError(f"{what} grid must be strictly increasing")
    step = np.diff(arr)
    if np.max(np.abs(step - step.mean())) > 1e-9 * max(1.0, float(np.max(np.abs(arr)))):
        raise InputError(f"{what} grid must be equidistant (a regular grid, paper Sec. IV-B)")
    if positive and arr[0] <= 0.0:
        raise InputError(f"{what} grid must be > 0 {unit}, got {arr[0]!r}")
    if not positive and arr[0] < 0.0:
        raise InputError(f"{what} grid must be >= 0 {unit} (forces are even in the current)")
    return arr


def pole_group_point(gaps_m: np.ndarray, currents_A: np.ndarray) -> tuple[float, float]:
    """The operating point at which the maps assign the poles to circuits
    (:func:`circuit_pole_groups`): the middle gap of the grid and the larger of its middle
    current and half its largest current [m], [A]."""
    g, c = np.asarray(gaps_m, dtype=float), np.asarray(currents_A, dtype=float)
    return float(g[g.size // 2]), float(max(c[c.size // 2], c[-1] / 2))


def _statics_row(net: Network, s: float, currents: np.ndarray,
                 groups: dict[str, tuple[str, ...]]) -> dict[str, np.ndarray]:
    """Maps for one gap value over all currents (one executor task)."""
    gi = {g: k for k, g in enumerate(net.gap_names)}
    sol = solve_statics(net, gaps_m=np.full((currents.size, len(gi)), s),
                        currents_A=np.repeat(currents[:, None], len(net.circuits), axis=1))
    nc = len(net.circuits)
    force = np.empty((nc, currents.size))
    dpsi_ds = np.empty((nc, currents.size))
    for j, c in enumerate(net.circuit_names):
        idx = [gi[g] for g in groups[c]]
        force[j] = sol.pole_force_N[:, idx].sum(axis=-1)
        dpsi_ds[j] = sol.dpsi_dgap_Wb_per_m[:, j, idx].sum(axis=-1)
    psi = sol.flux_linkage_Wb.T
    ltilde = np.diagonal(sol.differential_inductance_H, axis1=-2, axis2=-1).T
    with np.errstate(divide="ignore", invalid="ignore"):
        dlds = np.where(currents > 0.0, dpsi_ds / np.where(currents > 0.0, currents, 1.0), np.nan)
        lapp = np.where(currents > 0.0, psi / np.where(currents > 0.0, currents, 1.0), np.nan)
    zero = np.nonzero(currents == 0.0)[0]
    if zero.size:
        # I -> 0: psi = L0(s) I + O(I^3) (odd B-H laws), so L -> L0 = L~(s, 0) and
        # dL/ds -> dL0/ds: central difference in s of the small-signal inductance
        # (h = 1e-6 s: truncation ~1e-12, rounding ~1e-10 relative).
        h = 1e-6 * s
        side = solve_statics(net, gaps_m=np.array([[s + h] * len(gi), [s - h] * len(gi)]),
                             currents_A=np.zeros((2, nc)))
        l0 = np.diagonal(side.differential_inductance_H, axis1=-2, axis2=-1)
        for j, c in enumerate(net.circuit_names):
            # moving only the circuit's own poles: sum of partial derivatives
            idx = [gi[g] for g in groups[c]]
            if len(idx) == len(gi):
                d = (l0[0, j] - l0[1, j]) / (2 * h)
            else:
                sp = np.full(len(gi), s)
                sm = sp.copy()
                sp[idx] += h
                sm[idx] -= h
                two = solve_statics(net, gaps_m=np.stack([sp, sm]), currents_A=np.zeros((2, nc)))
                lj = two.differential_inductance_H[:, j, j]
                d = (lj[0] - lj[1]) / (2 * h)
            dlds[j, zero] = d
            lapp[j, zero] = ltilde[j, zero]
    return {"force_N": force, "inductance_H": ltilde, "dL_ds_H_per_m": dlds,
            "flux_linkage_Wb": psi, "apparent_inductance_H": lapp}


@dataclass(frozen=True)
class CharacteristicMaps:
    """Characteristic maps of a magnet (an :class:`xarray.Dataset` with units).

    Use :func:`build_maps` to compute and :func:`load_maps` / :meth:`to_netcdf` to store.

    Parameters
    ----------
    dataset : xarray.Dataset
        The maps: data variables over the coordinates ``circuit``, ``gap`` [m] and
        ``current`` [A] (e.g. ``force_N`` [N], ``inductance_H`` [H], ``dL_ds_H_per_m``
        [H/m], ``flux_linkage_Wb`` [Wb]) and attributes such as ``magnet_hash`` and
        ``pole_groups``.  Kept as given (not copied, its contents not validated here:
        :func:`load_maps` checks files).

    Raises
    ------
    InputError
        ``dataset`` is not an :class:`xarray.Dataset`.
    """

    dataset: xr.Dataset

    def __post_init__(self) -> None:
        import xarray as xr

        if not isinstance(self.dataset, xr.Dataset):
            raise InputError("CharacteristicMaps wraps an xarray.Dataset of maps; use "
                             "build_maps or load_maps, got " + type(self.dataset).__name__)

    @property
    def circuits(self) -> tuple[str, ...]:
        return tuple(str(c) for c in self.dataset["circuit"].values)

    @property
    def gaps_m(self) -> np.ndarray:
        return np.asarray(self.dataset["gap"].values, dtype=float)

    @property
    def currents_A(self) -> np.ndarray:
        return np.asarray(self.dataset["current"].values, dtype=float)

    @property
    def magnet_hash(self) -> str:
        return str(self.dataset.attrs["magnet_hash"])

    @property
    def default_eddy_modes(self) -> int:
        """The reduced model's default ``eddy_modes`` on these maps [-].

        The magnet file's ``[reduced] eddy_modes`` when the maps were built
        (:attr:`maglevkit.magnets.base.Magnet.default_eddy_modes`, stored as the attribute
        :data:`DEFAULT_EDDY_MODES_ATTRIBUTE`); 0 (eq. 8 with one ``R_ec``) for maps without
        it: built from a bare network, imported from a table, or written by an earlier
        version.
        """
        return int(self.dataset.attrs.get(DEFAULT_EDDY_MODES_ATTRIBUTE, 0))

    @property
    def pole_groups(self) -> dict[str, tuple[str, ...]]:
        """Circuit name -> the gap inputs (poles) it drives."""
        raw = json.loads(self.dataset.attrs["pole_groups"])
        return {k: tuple(v) for k, v in raw.items()}

    def variable(self, name: str, circuit: str) -> np.ndarray:
        """A map (gap x current) of one circuit as a NumPy array.

        Parameters
        ----------
        name : str
            Name of a data variable of the dataset, e.g. ``"force_N"`` [N],
            ``"inductance_H"`` [H] or ``"dL_ds_H_per_m"`` [H/m].
        circuit : str
            One of :attr:`circuits`.

        Returns
        -------
        ndarray (n_gaps, n_currents)
            The map's values in its own unit (float64), on :attr:`gaps_m` x
            :attr:`currents_A`.

        Raises
        ------
        InputError
            Unknown circuit or map name (the message lists the known ones).
        """
        if circuit not in self.circuits:
            raise InputError(f"no circuit {circuit!r} in these maps; circuits: {list(self.circuits)}")
        if name not in self.dataset.data_vars:
            raise InputError(f"no map {name!r}; maps: {sorted(str(k) for k in self.dataset.data_vars)}")
        return np.asarray(self.dataset[name].sel(circuit=circuit).values, dtype=float)

    def to_netcdf(self, path: str | Path) -> Path:
        """Write the maps to a netCDF file (lossless: float64 throughout).

        Parameters
        ----------
        path : str or path-like
            File to write (netCDF4 engine); missing parent folders are created and an
            existing file is overwritten.

        Returns
        -------
        pathlib.Path
            ``path`` as a Path.
        """
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        self.dataset.to_netcdf(p, engine="netcdf4")
        return p

    def with_held_flux_force(self) -> CharacteristicMaps:
        """These maps with the shielded-gap ladder's force at ``F(s, I_L + gamma I_e)``.

        ``gamma`` is the share derived from the detailed model's held-flux stiffness
        (``motion_eddy_held_flux_force_share``, docs/equations.md section 8).  With it
        ``CurrentModel(maps, motion_eddy=True)`` (and the bank, FMU and MPC on these maps)
        follows the force under gap motion (split TR09, gap sine 10 +- 1 mm: force error
        3.2 / 6.2 / 8.5 % at 5 / 50 / 200 Hz instead of about 3 / 18 / 39 %), but a fast
        voltage change drives ``I_e`` before ``I_L``, so in a closed gap loop the force
        dips first (the closed-loop scenario's current / force error 5.7 / 1.6 -> 20.7 /
        13.1 %).  Use it for open-loop gap-disturbance studies, not for control loops.
        Where the derived share would cost voltage steps more than
        :data:`~maglevkit.reduction.motion_eddy.MAX_STEP_FORCE_LOSS`, ``build_maps`` stored
        0 as the held-flux share too (the U-magnet: -1.2 would take its step force residual
        from 1.0 to 8.3 %), and these maps then equal the default ones: a
        :class:`~maglevkit.errors.MaglevkitWarning` says so.

        Returns
        -------
        CharacteristicMaps
            A new object; the dataset is shallow-copied with ``motion_eddy_force_share``
            replaced.

        Raises
        ------
        InputError
            Maps without the derived share (built before it, imported from a table, or
            of a magnet without eddy currents).
        """
        ds = self.dataset
        if HELD_FLUX_FORCE_SHARE_VARIABLE not in ds:
            raise InputError(
                "with_held_flux_force: these maps have no "
                f"{HELD_FLUX_FORCE_SHARE_VARIABLE!r} (maps imported from a table or built by "
                "an older version); rebuild them with build_maps")
        gamma = np.asarray(ds[HELD_FLUX_FORCE_SHARE_VARIABLE].values, dtype=float)
        if not np.all(np.isfinite(gamma)):
            raise InputError("with_held_flux_force: these maps have no shielded-gap ladder "
                             f"({HELD_FLUX_FORCE_SHARE_VARIABLE} = {gamma.tolist()}: the magnet "
                             "has no eddy currents)")
        if np.all(gamma == 0.0):
            import warnings

            from ..errors import MaglevkitWarning

            warnings.warn("with_held_flux_force: build_maps kept no held-flux force share for "
                          "these maps (it would have cost the voltage steps' force more than "
                          f"{100 * MAX_STEP_FORCE_LOSS:g} points), so they equal the default "
                          "maps: the force stays F(s, I_L)", MaglevkitWarning, stacklevel=2)
        attrs = dict(ds[FORCE_SHARE_VARIABLE].attrs) if FORCE_SHARE_VARIABLE in ds else {}
        attrs["description"] = ("the held-flux gamma (with_held_flux_force): the force under "
                                "gap motion, at a cost in closed loop")
        return CharacteristicMaps(ds.assign({FORCE_SHARE_VARIABLE: ("circuit", gamma.copy(),
                                                                    attrs)}))

    def check_magnet(self, magnet: Any) -> None:
        """Raise if these maps were not built from ``magnet`` (same network and options).

        ``magnet`` may be a Magnet, a FluxModel or a Network: the identity is the hash of
        the equivalent circuit (:func:`model_hash`), so maps built from a Magnet are
        accepted for ``FluxModel(magnet)`` and vice versa, and refused for another magnet
        or other physics switches (saturation, eddy currents, ...).

        Parameters
        ----------
        magnet : Magnet, FluxModel or Network
            The detailed model the maps should belong to.

        Raises
        ------
        ParameterFileError
            The maps belong to another equivalent circuit (or are a file of an earlier
            version that stored another hash), or were imported from a table
            (:func:`~maglevkit.reduction.tables_in.maps_from_table`; the message says so).
        """
        h = model_hash(magnet)
        if h == self.magnet_hash:
            return
        source = self.dataset.attrs.get("table_source")
        if source is not None:
            # imported maps carry the table's hash: no magnet's network made them, so a
            # "rebuild" hint (the message below) would send the user away from their data
            raise ParameterFileError(
                f"these maps were imported from the table {source!r} (maglevkit maps import), "
                f"not built from magnet {getattr(magnet, 'name', 'this model')!r}: what runs "
                "the magnet's detailed model beside its maps (e.g. maglevkit compare) needs "
                "maps made by that model, `maglevkit maps build MAGNET`, which a table cannot "
                "give; imported maps run alone: `maglevkit export fmu MAPS_FILE`, "
                "mk.CurrentModel(maps), MagnetBank")
        # Files of earlier versions stored the parameter-file hash instead; they are refused
        # too: the physics behind the same parameters may have changed since.
        raise ParameterFileError(
            f"these maps belong to magnet {self.dataset.attrs.get('magnet_name')!r} "
            f"(hash {self.magnet_hash[:12]}...), not to {getattr(magnet, 'name', 'this model')!r} "
            f"(hash {h[:12]}...); rebuild them with `maglevkit maps build`"
        )


#: The maps attribute that carries the magnet file's ``[reduced] eddy_modes``
#: (:attr:`CharacteristicMaps.default_eddy_modes`).
DEFAULT_EDDY_MODES_ATTRIBUTE = "reduced_eddy_modes"


def default_eddy_modes(source: Any) -> int:
    """The reduced model's default ``eddy_modes`` of a magnet or of its maps [-].

    The one rule every entry point uses when its ``eddy_modes`` option is unset
    (``maglevkit compare``, ``demo``, ``export fmu``, :func:`maglevkit.export.export_fmu`,
    the vehicles): the magnet file's ``[reduced] eddy_modes`` (0: eq. 8 with one
    ``R_ec``; 1-3: the fitted RL eddy network, ``CurrentModel(maps, eddy_modes=m)``).

    Parameters
    ----------
    source : Magnet, CharacteristicMaps, FluxModel or Network
        A magnet (:attr:`~maglevkit.magnets.base.Magnet.default_eddy_modes`) or maps built
        from one (:attr:`CharacteristicMaps.default_eddy_modes`); a bare network or
        ``FluxModel`` has no file and gives 0.

    Returns
    -------
    int
        One of :data:`~maglevkit.magnets.base.REDUCED_EDDY_MODES`.

    Raises
    ------
    InputError
        ``source`` is none of these.
    """
    if isinstance(source, CharacteristicMaps):
        return source.default_eddy_modes
    value = getattr(source, "default_eddy_modes", None)
    if value is not None:
        return int(value)
    try:
        as_network(source)
    except (InputError, TypeError, AttributeError):
        raise InputError(f"default_eddy_modes: expected a Magnet, CharacteristicMaps, "
                         f"FluxModel or Network, got {type(source).__name__}") from None
    return 0


def network_hash(net: Network) -> str:
    """SHA-256 of a network's repr (it covers every element, material and parameter)."""
    import hashlib

    return hashlib.sha256(repr((net.branches, net.circuits)).encode()).hexdigest()


LAW_PACKAGES = ("materials.py", "circuit", "magnets", "models", "reduction")
"""The modules and subpackages whose code makes a map from a network (materials, elements'
laws, statics, DAE, reduction): :func:`law_hash` covers their source."""


@functools.cache
def law_hash(root: str | Path | None = None) -> str:
    """SHA-256 of the source that turns a network into maps (the laws, not the data).

    :func:`network_hash` covers a network's elements and parameters, not the code of their
    laws: cached maps built by an older maglevkit whose permeance or statics code has since
    changed would be taken for current.  Persistent caches (the vehicle maps cache) key on
    both.  Any edit to those files (a docstring too) changes it, which only costs a rebuild.

    Parameters
    ----------
    root : str or path-like, optional
        The package directory to hash (default: this installed ``maglevkit``); the files
        entries of :data:`LAW_PACKAGES` under it (a module, or a package's ``**/*.py`` in
        sorted order), with their relative paths.

    Returns
    -------
    str
        Hex digest.
    """
    import hashlib

    base = Path(root) if root is not None else Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for entry in LAW_PACKAGES:
        path = base / entry
        for f in [path] if path.is_file() else sorted(path.rglob("*.py")):
            h.update(f.relative_to(base).as_posix().encode() + b"\0")
            h.update(f.read_bytes())
    return h.hexdigest()


def model_hash(model: Any) -> str:
    """The identity of a detailed model for its maps: the hash of its equivalent circuit.

    The same for a Magnet, ``FluxModel(magnet)`` and ``magnet.network`` (a FluxModel keeps
    only the network), and different whenever an element, a material or a physics switch
    (saturation, fringing, leakage, eddy currents) changes the network.
    """
    return network_hash(as_network(model))


def load_maps(path: str | Path, *, magnet: Any = None) -> CharacteristicMaps:
    """Read maps from netCDF; with ``magnet``, check that they belong to it.

    Parameters
    ----------
    path : str or path-like
        A maps file written by :meth:`CharacteristicMaps.to_netcdf` (``maglevkit maps
        build``).  It is read into memory completely and closed.
    magnet : Magnet, FluxModel, Network or None, default None
        If given, :meth:`CharacteristicMaps.check_magnet` checks that the maps were built
        from this model.

    Returns
    -------
    CharacteristicMaps

    Raises
    ------
    InputError
        ``path`` is not a str or path-like.
    ParameterFileError
        The file does not exist, is not readable netCDF, is not a maglevkit maps file
        (``format`` attribute), lacks a required variable, coordinate or attribute
        (``magnet_hash``, ``pole_groups``), or belongs to another magnet.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"load_maps needs the path of a maps file (str or Path), got "
                         f"{type(path).__name__}")
    p = Path(path)
    if not p.is_file():
        raise ParameterFileError(f"maps file {str(p)!r} does not exist")
    from .._files import read_netcdf

    data = read_netcdf(p)
    if data.attrs.get("format") != MAPS_FORMAT:
        raise ParameterFileError(f"{p}: not a maglevkit maps file (format attribute "
                                 f"{data.attrs.get('format')!r}, expected {MAPS_FORMAT!r})")
    missing = [v for v in REQUIRED_VARIABLES if v not in data.data_vars]
    missing += [f"coordinate {c}" for c in ("circuit", "gap", "current") if c not in data.coords]
    # the attributes the maps read: the magnet's identity and the circuits' poles
    missing += [f"attribute {a}" for a in ("magnet_hash", "pole_groups") if a not in data.attrs]
    if missing:
        raise ParameterFileError(f"{p}: the maps file lacks {', '.join(missing)} (every maps "
                                 f"file has {', '.join(REQUIRED_VARIABLES)}); rebuild it with "
                                 "`maglevkit maps build`")
    maps = CharacteristicMaps(data)
    if magnet is not None:
        maps.check_magnet(magnet)
    return maps


def _run_tasks(fn: Callable[..., dict[str, np.ndarray]], args: Sequence[tuple],
               executor: Executor | None, progress: bool, label: str) -> list[dict[str, np.ndarray]]:
    from concurrent.futures import FIRST_COMPLETED, wait

    from .._interrupt import check_interrupt
    from .._progress import ProgressReporter

    results: list[dict[str, np.ndarray] | None] = [None] * len(args)
    reporter = ProgressReporter(len(args), label) if progress else None
    with reporter if reporter is not None else contextlib.nullcontext():
        if executor is None:
            for i, a in enumerate(args):
                check_interrupt()     # a deferred Ctrl-C (CLI): between points, not in CasADi
                results[i] = fn(*a)
                if reporter is not None:
                    reporter.advance()
        else:
            futures: dict[Future, int] = {executor.submit(fn, *a): i for i, a in enumerate(args)}
            waiting = set(futures)
            while waiting:
                # short waits: a deferred Ctrl-C is acted on within 0.2 s, not after the
                # next point (this process is not inside CasADi here)
                done, waiting = wait(waiting, timeout=0.2, return_when=FIRST_COMPLETED)
                check_interrupt()
                for fut in done:
                    results[futures[fut]] = fut.result()
                    if reporter is not None:
                        reporter.advance()
    return [r for r in results if r is not None]


AUTO_POOL_MIN_POINTS = 64
"""Smallest transient grid (points) for which ``executor="auto"`` starts a process pool.

Measured on this 2-core machine (U-magnet, fresh process each): 4 x 4 transient points
7.5 s in-process vs 10.1 s with a 2-process pool (each worker pays ~2.5 s for starting,
importing and compiling); 8 x 8: 29.0 s vs 27.5 s.  Statics maps never win from a pool:
U-magnet 17 x 33 0.59 vs 0.98 s, 50 x 50 1.17 vs 3.36 s; TR09 standard 12 x 41 11.6 vs
20.1 s (docs/reduction.md)."""


def _auto_executor(method: str, n_points: int) -> tuple[Executor | None, bool]:
    """The default executor (see :func:`build_maps`): a process pool for transient maps."""
    workers = min(os.cpu_count() or 1, n_points)
    if method == "statics" or workers < 2 or n_points < AUTO_POOL_MIN_POINTS:
        return None, False
    return ProcessPoolExecutor(max_workers=workers), True


def _as_executor(executor: Any, method: str = "statics",
                 n_points: int = 0) -> tuple[Executor | None, bool]:
    """Normalise the executor argument; returns (executor, whether we own it)."""
    if isinstance(executor, str) and executor == "auto":
        return _auto_executor(method, n_points)
    if executor is None or (isinstance(executor, str) and executor == "serial"):
        return None, False
    if isinstance(executor, str) and executor == "process":
        return ProcessPoolExecutor(max_workers=os.cpu_count() or 1), True
    if hasattr(executor, "get_executor") and not isinstance(executor, Executor):
        return executor.get_executor(), False   # a dask.distributed Client
    if isinstance(executor, Executor):
        return executor, False
    raise InputError("executor must be 'auto', None/'serial', 'process', a "
                     f"concurrent.futures.Executor or a dask.distributed Client, got {executor!r}")


METHODS = ("statics", "transient", "both")
_METHOD_TEXT = {
    "statics": "statics: exact sensitivities of the static network (implicit function theorem)",
    "transient": "transient: L~ from voltage-step time constants and dL/ds from the virtual "
                 "control law U = R_el I on a gap ramp (paper IV-B); force from statics",
    "both": "both: statics maps (exact sensitivities) plus the transient identification "
            "(paper IV-B) as *_transient variables with relative differences",
}


#: The R_ec fit's voltage step (the values the maps always used): a step of
#: ``dI_inf = 1e-3 max(|I|, 1 A)``, observed over 6 time constants with 50 samples each,
#: integrated at rtol 1e-9 / atol 1e-11 (the identification tolerances).
_FIT_RELATIVE_STEP = 1e-3
_FIT_N_TAU = 6.0
_FIT_SAMPLES_PER_TAU = 50
_FIT_RTOL, _FIT_ATOL = 1e-9, 1e-11


class StepRun:
    """One IDAS run of the flux DAE under constant voltages with an output grid.

    The flux model's ``simulate`` restarts IDAS at every output interval (its inputs may
    change there); a voltage step holds the voltages constant after ``t = 0``, so one run
    with output times suffices: 17x faster and without the restarts' accumulated error
    (docs/decisions.md, "Command-line conventions").  Same DAE as ``models/flux.py``
    (its ``D``, ``K``, ``Q``): differential states ``y`` (flux linkages, eddy fluxes),
    algebraic ``(x, I)``; the gaps and voltages are parameters, time is normalised to
    ``[0, 1]`` with the duration ``T`` as a parameter.  Compiled once per network.
    """

    def __init__(self, net: Network, n_out: int, tau: np.ndarray | None = None,
                 params: Any = None, topology: Network | None = None, *,
                 eddy_scale: Any = 1.0, resistance_scale: Any = 1.0) -> None:
        """``params``: CasADi symbols that ``net``'s elements contain (calibration
        factors, :mod:`maglevkit.calibration`), appended to the DAE's parameters (``dae``
        attribute; the IDAS ``integrator`` is not built then); ``topology``: a numeric
        network of the same topology and eddy elements for ``D``, ``K``, ``Q`` (default
        ``net``); ``eddy_scale``, ``resistance_scale``: factors (numbers or expressions of
        ``params``) on every eddy conductance and every ``R_el`` of ``topology``.

        Every ``G_ec`` times ``k`` scales the loop rows of ``M = K D`` (``C G C^T``), so
        ``K(k) = S K`` with ``S = diag(k 1_loops, 1_circuits)``: ``K(k) y' = h`` is
        ``K y' = S^-1 h``, i.e. the loop rows of ``h`` divided by ``k`` (exact, no new
        matrices)."""
        import casadi as ca

        from ..circuit.assembly import assemble
        from ..models.flux import flux_dae

        d = flux_dae(topology if topology is not None else net, "idas", _FIT_RTOL, _FIT_ATOL,
                     20000, 2, 3)
        eq = assemble(net)
        y = ca.SX.sym("y", d.n_diff)
        U = ca.SX.sym("U", d.n_circuits)
        T = ca.SX.sym("T")
        hv = ca.vertcat(-eq.residual / eddy_scale, U - resistance_scale
                        * net.resistances * eq.I)
        ydot = ca.mtimes(ca.DM(d.Kp), hv)
        alg = ca.vertcat(ca.mtimes(ca.DM(d.D), eq.x) - y, ca.mtimes(ca.DM(d.Q), hv))
        p = ca.vertcat(T, U, eq.s) if params is None else ca.vertcat(T, U, eq.s, params)
        dae = {"x": y, "z": ca.vertcat(eq.x, eq.I), "p": p, "ode": T * ydot, "alg": alg}
        self.tau = np.linspace(0.0, 1.0, n_out + 1)[1:] if tau is None else tau
        # absolute tolerances for every IDAS unknown (y, then z = (x, I)): the flux
        # model's nominal scales without its gap states
        nominal = np.concatenate((d.nominal[:d.n_diff], d.nominal[d.n_diff + d.n_gaps:]))
        if nominal.size != d.n_diff + d.n_loops + d.n_circuits:
            raise RuntimeError("internal: tolerance scales do not match the step DAE")
        opts: dict[str, Any] = {"reltol": _FIT_RTOL,
                                "abstolv": list(_FIT_ATOL * nominal),
                                "max_num_steps": 100000, "disable_internal_warnings": True}
        self.dae = dae
        self.D, self.n_loops = d.D, d.n_loops
        # the DAE's K y' = h (its ode is T pinv(K) h, exact as Q h = 0; calibration's Radau
        # steps solve the sparse K form)
        self.K, self.h = d.K, hv
        if params is not None:
            return
        self.integrator = ca.integrator("maglevkit_step_fit", "idas", dae, 0.0, self.tau, opts)


def _step_run(net: Network, n_out: int) -> StepRun:
    key = ("reduction_step_fit", n_out)
    run = net.cache.get(key)
    if run is None:
        run = StepRun(net, n_out)
        net.cache[key] = run
    return run  # type: ignore[no-any-return]


def _fitted_eddy_resistance(net: Network, gap: float, current: float) -> np.ndarray:
    """Per-circuit R_ec from the step-response time constant (inf without eddy currents).

    The procedure of :func:`~maglevkit.models.experiments.differential_inductance_from_step`
    (paper Sec. IV-B): circuit ``j`` at ``current`` [A] and every gap at ``gap`` [m] gets
    a voltage step ``dU = R_el dI_inf``; ``log(dI_inf - dI(t))`` is fitted by a straight
    line over the samples with ``2 % < remaining < 98 %``; its intercept gives the jump
    ``dI_0`` and ``R_ec = dU / dI_0 - R_el``.  The step is one IDAS run (:class:`StepRun`)
    instead of 300 restarted intervals: TR09 standard 4.1 -> 0.26 s per build; the value
    moved by +0.13 % (TR09) and +0.25 % (U-magnet) towards the converged (rtol 1e-12)
    value, which it now matches within 1e-4 (docs/decisions.md).
    """
    nc = len(net.circuits)
    if not net.has_eddy_currents:
        return np.full(nc, np.inf)
    sol = solve_statics(net, gaps_m=np.full(len(net.gap_names), gap), currents_A=np.full(nc, current))
    x0 = np.asarray(sol.loop_flux_Wb, dtype=float).ravel()
    i0 = np.asarray(sol.currents_A, dtype=float).ravel()
    s0 = np.asarray(sol.gaps_m, dtype=float).ravel()
    R = net.resistances
    run = _step_run(net, int(round(_FIT_N_TAU * _FIT_SAMPLES_PER_TAU)))
    out = np.empty(nc)
    for j in range(nc):
        # the window is sized with the statics' dpsi/dI (not used in the result)
        t_end = _FIT_N_TAU * max(float(sol.differential_inductance_H[j, j]), 1e-12) / R[j]
        di_inf = _FIT_RELATIVE_STEP * max(abs(float(i0[j])), 1.0)
        U = R * i0
        U[j] += R[j] * di_inf
        state = {"gap_m": gap, "current_A": current, "circuit": net.circuit_names[j]}
        try:
            res = run.integrator(x0=run.D @ x0, z0=np.concatenate((x0, i0)),
                                 p=np.concatenate(((t_end,), U, s0)))
        except RuntimeError as exc:
            raise SolverError("the voltage step of the R_ec fit failed", time_s=0.0, state=state,
                              reason=str(exc)[-300:]) from None
        remaining = di_inf - (np.asarray(res["zf"])[run.n_loops + j] - i0[j])
        t = t_end * run.tau
        sel = np.isfinite(remaining) & (remaining > 0.02 * di_inf) & (remaining < 0.98 * di_inf)
        if np.count_nonzero(sel) < 10:
            raise SolverError("too few samples to fit the step-response time constant",
                              state=state, reason=f"{np.count_nonzero(sel)} usable samples")
        A = np.vstack((np.ones(np.count_nonzero(sel)), t[sel])).T
        coef, *_ = np.linalg.lstsq(A, np.log(remaining[sel]), rcond=None)
        jump = di_inf - float(np.exp(coef[0]))
        if not (float(coef[1]) < 0.0 and jump > 0.0):
            raise SolverError("the R_ec fit's step response is not a decaying exponential "
                              "with a current jump", state=state,
                              reason=f"slope {float(coef[1])!r} 1/s, jump {jump!r} A")
        out[j] = R[j] * di_inf / jump - R[j]
    return out


#: The eddy network's identification (docs/reduction.md, "More eddy modes"): the same
#: small voltage step as the R_ec fit, observed over ``_FIT_N_TAU`` slow time constants
#: ``L~/R_el`` on a grid of ``_NET_LOG_SAMPLES`` geometric samples from 1e-5 of the
#: window (the fast eddy modes) plus ``_NET_LIN_SAMPLES`` equidistant ones (the slow part).
_NET_LOG_SAMPLES, _NET_LIN_SAMPLES = 200, 100


def _network_grid() -> np.ndarray:
    return np.unique(np.concatenate((np.geomspace(1e-5, 1.0, _NET_LOG_SAMPLES),
                                     np.linspace(0.0, 1.0, _NET_LIN_SAMPLES + 1)[1:])))


def _eddy_network_steps(net: Network, gap: float, current: float
                        ) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """The detailed model's small voltage steps at ``(gap, current)``, one per circuit.

    Returns per circuit the sample times [s] and ``dI_j/dU_j`` [A/V] there, and ``L~``
    (``dpsi_j/dI_j`` of the statics) per circuit.
    """
    nc = len(net.circuits)
    sol = solve_statics(net, gaps_m=np.full(len(net.gap_names), gap), currents_A=np.full(nc, current))
    x0 = np.asarray(sol.loop_flux_Wb, dtype=float).ravel()
    i0 = np.asarray(sol.currents_A, dtype=float).ravel()
    s0 = np.asarray(sol.gaps_m, dtype=float).ravel()
    R = net.resistances
    key = ("reduction_step_network", _NET_LOG_SAMPLES, _NET_LIN_SAMPLES)
    run = net.cache.get(key)
    if run is None:
        run = StepRun(net, 0, tau=_network_grid())
        net.cache[key] = run
    ltilde = np.array([float(sol.differential_inductance_H[j, j]) for j in range(nc)])
    times, responses = [], []
    for j in range(nc):
        t_end = _FIT_N_TAU * max(ltilde[j], 1e-12) / R[j]
        du = R[j] * _FIT_RELATIVE_STEP * max(abs(float(i0[j])), 1.0)
        U = R * i0
        U[j] += du
        try:
            res = run.integrator(x0=run.D @ x0, z0=np.concatenate((x0, i0)),
                                 p=np.concatenate(((t_end,), U, s0)))
        except RuntimeError as exc:
            raise SolverError("the voltage step of the eddy-network fit failed", time_s=0.0,
                              state={"gap_m": gap, "current_A": current,
                                     "circuit": net.circuit_names[j]},
                              reason=str(exc)[-300:]) from None
        times.append(t_end * run.tau)
        responses.append((np.asarray(res["zf"])[run.n_loops + j].ravel() - i0[j]) / du)
    return times, responses, ltilde


def _eddy_point(value: Any, g: np.ndarray, c: np.ndarray, ref_gap: float, ref_current: float
                ) -> tuple[float, float]:
    """The identification point of ``build_maps(eddy_reference=...)``, checked."""
    if value is None:
        return ref_gap, ref_current
    try:
        gap, current = value
    except (TypeError, ValueError):
        raise InputError(f"eddy_reference = {value!r}; give (gap_m, current_A) or None") from None
    ga, ca_ = real_array(gap, "eddy_reference gap"), real_array(current, "eddy_reference current")
    if ga.ndim or ca_.ndim:
        raise InputError(f"eddy_reference = {value!r}; give one gap [m] and one current [A]")
    gap, current = float(ga), float(ca_)
    if not (g[0] <= gap <= g[-1] and c[0] <= current <= c[-1]):
        raise InputError(f"eddy_reference = ({gap!r} m, {current!r} A) lies outside the maps' "
                         f"grid (gaps {g[0]:g}..{g[-1]:g} m, currents {c[0]:g}..{c[-1]:g} A)")
    return gap, current


def _fit_eddy_networks(net: Network, gap: float, current: float, r_ec_fit: np.ndarray
                       ) -> tuple[np.ndarray, list[list[EddyNetworkFit]]]:
    """``L~`` per circuit and, per circuit, the fitted networks for every entry of
    :data:`EDDY_NETWORK_MODES` (each fit starts from the one with a branch less)."""
    times, responses, ltilde = _eddy_network_steps(net, gap, current)
    fits = []
    for j in range(len(net.circuits)):
        if not np.all(np.isfinite(responses[j])):
            raise SolverError("the eddy-network fit's step response is not finite",
                              state={"gap_m": gap, "current_A": current,
                                     "circuit": net.circuit_names[j]})
        per: list[EddyNetworkFit] = []
        prev = None
        for m in EDDY_NETWORK_MODES:
            prev = fit_eddy_network(times[j], responses[j], ltilde=float(ltilde[j]),
                                    r_el=float(net.resistances[j]), modes=m,
                                    r_ec_guess=float(r_ec_fit[j]), start=prev)
            per.append(prev)
        fits.append(per)
    return ltilde, fits


def _store_eddy_network(ds: Any, net: Network, gap: float, current: float,
                        r_ec_fit: np.ndarray) -> None:
    """Add the ``eddy_network_*`` variables (docs/reduction.md, "More eddy modes")."""
    nc, mm = len(net.circuits), max(EDDY_NETWORK_MODES)
    r0 = np.full((nc, len(EDDY_NETWORK_MODES)), np.inf)
    rk = np.full((nc, len(EDDY_NETWORK_MODES), mm), np.nan)
    lk = np.full_like(rk, np.nan)
    rms = np.full(r0.shape, np.nan)
    ltilde = np.full(nc, np.nan)
    if net.has_eddy_currents:
        ltilde, fits = _fit_eddy_networks(net, gap, current, r_ec_fit)
        for j, per in enumerate(fits):
            for i, f in enumerate(per):
                r0[j, i] = f.r0_ohm
                rk[j, i, :f.resistance_ohm.size] = f.resistance_ohm
                lk[j, i, :f.inductance_H.size] = f.inductance_H
                rms[j, i] = f.rms_residual
    where = f"at the reference point s = {gap!r} m, I = {current!r} A"
    ds.coords["eddy_modes"] = ("eddy_modes", np.array(EDDY_NETWORK_MODES), {
        "long_name": "number m of RL branches of the eddy network"})
    ds.coords["eddy_branch"] = ("eddy_branch", np.arange(1, mm + 1), {
        "long_name": "RL branch k of the eddy network (fastest first)"})
    ds["eddy_network_r0_ohm"] = (("circuit", "eddy_modes"), r0, {
        "units": "ohm", "long_name": "resistor R_0 of the eddy network (its current jump)",
        "description": "Y_e(p) = 1/R_0 + sum_k 1/(R_k + p L_k) in parallel with L~ (Fig. 8 "
                       "extended), fitted to a small voltage step of the detailed model "
                       f"{where}; inf: no jump (or no eddy currents)"})
    ds["eddy_network_resistance_ohm"] = (("circuit", "eddy_modes", "eddy_branch"), rk, {
        "units": "ohm", "long_name": "resistance R_k of the eddy network's RL branches",
        "description": f"fitted {where}; NaN for k > m"})
    ds["eddy_network_inductance_H"] = (("circuit", "eddy_modes", "eddy_branch"), lk, {
        "units": "H", "long_name": "inductance L_k of the eddy network's RL branches",
        "description": f"fitted {where}; the current model scales it with "
                       "L~(s, I_L)/eddy_network_reference_inductance_H; NaN for k > m"})
    ds["eddy_network_reference_inductance_H"] = ("circuit", ltilde, {
        "units": "H", "long_name": "L~ at the eddy network's reference point",
        "description": f"dpsi_j/dI_j of the statics {where}"})
    ds["eddy_network_fit_rms"] = (("circuit", "eddy_modes"), rms, {
        "units": "1", "long_name": "RMS residual of the eddy network's step fit",
        "description": "RMS of (fitted - detailed) coil current over the fit's samples "
                       "(200 geometric from 1e-5 of the window, 100 equidistant; window 6 "
                       "L~/R_el), relative to the step's final value"})


def _store_motion_eddy(ds: Any, net: Network, gap: float, current: float,
                       r_ec_fit: np.ndarray, groups: dict[str, tuple[str, ...]],
                       min_inductance_H: np.ndarray) -> None:
    """Add the ``motion_eddy_*`` variables: the shielded-gap ladder of
    :mod:`maglevkit.reduction.motion_eddy` (docs/reduction.md, "Gap motion"), with ``L_u``
    below :data:`~maglevkit.reduction.motion_eddy.MAX_UNSHIELDED_SHARE_OF_MIN_L` times
    each circuit's smallest ``L~`` on the maps (``min_inductance_H`` [H])."""
    nc = len(net.circuits)
    r_a = np.full(nc, np.nan)
    l_u = np.full(nc, np.nan)
    r_2 = np.full(nc, np.nan)
    beta = np.full(nc, np.nan)
    gamma = np.full(nc, np.nan)
    rms = np.full(nc, np.nan)
    if net.has_eddy_currents:
        responses = detailed_frequency_response(net, gap=gap, current=current, groups=groups)
        r_jump = eddy_resistance(net, gap_m=gap, current_A=current)
        for j, resp in enumerate(responses):
            fit = fit_motion_eddy(resp, resistance_ohm=float(net.resistances[j]),
                                  eddy_resistance_jump_ohm=float(r_jump[j]),
                                  eddy_resistance_fit_ohm=float(r_ec_fit[j]),
                                  max_unshielded_inductance_H=MAX_UNSHIELDED_SHARE_OF_MIN_L
                                  * float(min_inductance_H[j]))
            r_a[j], l_u[j] = fit.jump_resistance_ohm, fit.unshielded_inductance_H
            r_2[j], beta[j] = fit.shielding_resistance_ohm, fit.unshielded_share
            gamma[j] = fit.force_share
            rms[j] = fit.rms_residual
    _store_motion_eddy3(ds, net, gap, current, groups, min_inductance_H,
                        responses if net.has_eddy_currents else None)
    where = (f"fitted to the detailed model's small-signal gap -> current and voltage -> "
             f"current responses (0.1 Hz - 1 kHz) at s = {gap!r} m, I = {current!r} A; NaN: "
             "no eddy currents")
    ds["motion_eddy_jump_resistance_ohm"] = ("circuit", r_a, {
        "units": "ohm", "long_name": "shunt R_a of the shielded-gap ladder (current jump)",
        "description": where})
    ds["motion_eddy_unshielded_inductance_H"] = ("circuit", l_u, {
        "units": "H", "long_name": "unshielded series inductance L_u of the shielded-gap "
                                   "ladder", "description": where})
    ds["motion_eddy_shielding_resistance_ohm"] = ("circuit", r_2, {
        "units": "ohm", "long_name": "shielding eddy resistance R_2 of the gap section",
        "description": where})
    ds[SHARE_VARIABLE] = ("circuit", beta, {
        "units": "1", "long_name": "share beta of the motion-induced voltage in L_u "
                                   "(outside the shield)",
        "description": "from the detailed model's instantaneous gap -> current jump at "
                       "frozen flux linkages and eddy fluxes, -D a L_u/(dL/ds I), at the "
                       "same point; absent (older maps): 0"})
    ds[HELD_FLUX_FORCE_SHARE_VARIABLE] = ("circuit", gamma, {
        "units": "1", "long_name": "gamma from the held-flux stiffness (used only on request)",
        "description": "from the detailed model's instantaneous gap -> force jump (the "
                       "stiffness at frozen flux linkages and eddy fluxes) at the same "
                       "point, 0 where it would cost voltage steps more than "
                       "MAX_STEP_FORCE_LOSS; CharacteristicMaps.with_held_flux_force() "
                       "copies it into motion_eddy_force_share"})
    ds[FORCE_SHARE_VARIABLE] = ("circuit", gamma * 0.0, {
        "units": "1", "long_name": "share gamma of the shielding eddy current in the ladder's "
                                   "force current I_L + gamma I_e (in use)",
        "description": "0: the force F(s, I_L), which keeps the closed loop (the held-flux "
                       "gamma follows the force under gap motion but costs the closed loop; "
                       "docs/reduction.md, Gap motion); absent (older maps): 0"})
    ds["motion_eddy_fit_rms"] = ("circuit", rms, {
        "units": "1", "long_name": "RMS relative residual of the shielded-gap ladder's fit",
        "description": "over both responses and 60 frequencies, each relative to the "
                       "detailed response's modulus"})

#: The maps' variables of the three-state ladder (``CurrentModel(maps, motion_eddy=True,
#: eddy_branches=2)``), per circuit, in the order of :class:`MotionEddy3Fit`'s fields.
MOTION_EDDY3_VARIABLES = (
    ("motion_eddy3_jump_resistance_ohm", "ohm", "shunt R_a"),
    ("motion_eddy3_unshielded_inductance_H", "H", "series L_u (unshielded)"),
    ("motion_eddy3_shielding_resistance_ohm", "ohm", "shunt R_2 (outer shield)"),
    ("motion_eddy3_inner_inductance_H", "H", "series L_2 (between the shields)"),
    ("motion_eddy3_inner_shielding_resistance_ohm", "ohm", "shunt R_3 (inner shield)"),
    ("motion_eddy3_unshielded_share", "1", "share beta of the motion voltage in L_u"),
    ("motion_eddy3_inner_share", "1", "share beta_2 of the motion voltage in L_2"),
    ("motion_eddy3_force_share_1", "1", "c_1 of the force current"),
    ("motion_eddy3_force_share_2", "1", "c_2 of the force current"),
    ("motion_eddy3_fit_rms", "1", "RMS relative residual of the fit (unweighted)"),
)


def _same_response(a: Any, b: Any) -> bool:
    """Whether two detailed responses agree to rounding (relative 1e-9 everywhere)."""
    pairs = [(a.gap_to_current_A_per_m, b.gap_to_current_A_per_m),
             (a.voltage_to_current_A_per_V, b.voltage_to_current_A_per_V),
             (a.gap_to_force_N_per_m, b.gap_to_force_N_per_m),
             (a.voltage_to_force_N_per_V, b.voltage_to_force_N_per_V),
             (np.array([a.differential_inductance_H, a.dpsi_ds_Wb_per_m,
                        a.gap_current_jump_A_per_m, a.dforce_dcurrent_N_per_A,
                        a.dforce_dgap_N_per_m]),
              np.array([b.differential_inductance_H, b.dpsi_ds_Wb_per_m,
                        b.gap_current_jump_A_per_m, b.dforce_dcurrent_N_per_A,
                        b.dforce_dgap_N_per_m]))]
    return all(x is not None and y is not None and np.shape(x) == np.shape(y)
               and bool(np.allclose(x, y, rtol=1e-9, atol=0.0)) for x, y in pairs)


def _store_motion_eddy3(ds: Any, net: Network, gap: float, current: float,
                        groups: dict[str, tuple[str, ...]], min_inductance_H: np.ndarray,
                        responses: Any) -> None:
    """Add the ``motion_eddy3_*`` variables: the three-state ladder
    (:func:`~maglevkit.reduction.motion_eddy.fit_motion_eddy3`, docs/equations.md section
    8), with ``L_u + L_2`` below ``MAX_UNSHIELDED_SHARE_OF_MIN_L`` times each circuit's
    smallest ``L~`` on the maps; NaN without eddy currents (or where the fit has no force
    response)."""
    nc = len(net.circuits)
    values = np.full((len(MOTION_EDDY3_VARIABLES), nc), np.nan)
    if responses is not None:
        r_jump = eddy_resistance(net, gap_m=gap, current_A=current)
        done: list[tuple[Any, float, float, int]] = []
        for j, resp in enumerate(responses):
            r_el = float(net.resistances[j])
            if not (np.isfinite(r_jump[j]) and r_jump[j] > 0):
                continue
            # symmetric circuits (the TR09 magnet's two halves) have the same responses to
            # rounding: one fit serves them
            twin = [k for other, rj, re, k in done if _same_response(other, resp)
                    and math.isclose(rj, float(r_jump[j]), rel_tol=1e-9) and re == r_el
                    and min_inductance_H[k] == min_inductance_H[j]]
            if twin:
                values[:, j] = values[:, twin[0]]
                continue
            done.append((resp, float(r_jump[j]), r_el, j))
            fit = fit_motion_eddy3(resp, resistance_ohm=r_el,
                                   eddy_resistance_jump_ohm=float(r_jump[j]),
                                   max_series_inductance_H=MAX_UNSHIELDED_SHARE_OF_MIN_L
                                   * float(min_inductance_H[j]),
                                   weights=MOTION_EDDY3_WEIGHTS)
            values[:, j] = (fit.jump_resistance_ohm, fit.unshielded_inductance_H,
                            fit.shielding_resistance_ohm, fit.inner_inductance_H,
                            fit.inner_shielding_resistance_ohm, fit.unshielded_share,
                            fit.inner_share, *fit.force_shares, fit.rms_residual)
    where = (f"fitted to the detailed model's small-signal gap and voltage -> current and "
             f"force responses (0.1 Hz - 1 kHz) at s = {gap!r} m, I = {current!r} A; NaN: "
             "no eddy currents; absent (older maps): eddy_branches=2 is refused")
    for (name, units, long_name), v in zip(MOTION_EDDY3_VARIABLES, values, strict=True):
        ds[name] = ("circuit", v, {"units": units, "long_name": "three-state ladder: "
                                   + long_name, "description": where})


MAP_UNITS = {"force_N": "N", "inductance_H": "H", "dL_ds_H_per_m": "H/m",
             "flux_linkage_Wb": "Wb", "apparent_inductance_H": "H",
             "inductance_transient_H": "H", "dL_ds_transient_H_per_m": "H/m",
             "inductance_relative_difference": "1", "dL_ds_relative_difference": "1",
             "eddy_resistance_step_ohm": "ohm"}
"""Units of the (circuit, gap, current) map variables."""
MAP_LONG_NAMES = {
    "force_N": "force of the circuit's poles F(s, I)",
    "inductance_H": "differential inductance L~ = dL/dI I + L",
    "dL_ds_H_per_m": "gap derivative of the inductance dL/ds",
    "flux_linkage_Wb": "flux linkage psi",
    "apparent_inductance_H": "inductance L = psi / I",
    "inductance_transient_H": "L~ from voltage-step time constants (paper IV-B)",
    "dL_ds_transient_H_per_m": "dL/ds from the virtual control law U = R_el I on a "
                               "gap ramp (paper IV-B)",
    "inductance_relative_difference": "L~ transient / statics - 1",
    "dL_ds_relative_difference": "dL/ds transient / statics - 1",
    "eddy_resistance_step_ohm": "R_ec implied by a single-exponential fit of the "
                                "voltage step (slow mode)"}
"""Long names of the (circuit, gap, current) map variables."""


def maps_dataset(data: dict[str, np.ndarray], *, circuits: Sequence[str], gaps_m: np.ndarray,
                 currents_A: np.ndarray, resistance_ohm: np.ndarray) -> xr.Dataset:
    """The maps' dataset layout: variables ``(circuit, gap, current)`` with units, the
    coordinates and ``resistance_ohm``; shared by :func:`build_maps` and the table import
    (:mod:`maglevkit.reduction.tables_in`).

    Parameters
    ----------
    data : dict
        Variable name (a key of :data:`MAP_UNITS`) -> array (circuit, gap, current).
    circuits : sequence of str
        Circuit names.
    gaps_m, currents_A : ndarray
        The grid [m], [A].
    resistance_ohm : ndarray
        ``R_el`` per circuit [ohm].
    """
    import xarray as xr

    dims = ("circuit", "gap", "current")
    ds = xr.Dataset(
        {k: (dims, v, {"units": MAP_UNITS[k], "long_name": MAP_LONG_NAMES[k]})
         for k, v in data.items()},
        coords={"circuit": list(circuits),
                "gap": ("gap", gaps_m, {"units": "m", "long_name": "substitute air gap s"}),
                "current": ("current", currents_A, {"units": "A",
                                                    "long_name": "circuit current I_L"})},
    )
    ds["resistance_ohm"] = ("circuit", np.asarray(resistance_ohm, dtype=float),
                            {"units": "ohm", "long_name": "ohmic resistance R_el"})
    return ds


@renamed_keywords(gaps="gaps_m", currents="currents_A")
def build_maps(model: Any, *, gaps_m: Any, currents_A: Any, executor: Any = "auto",
               progress: bool = True, method: str = "statics",
               eddy_reference: Any = None) -> CharacteristicMaps:
    """Compute the characteristic maps of a magnet on a regular gap x current grid.

    Parameters
    ----------
    model : Magnet or Network
        The detailed model.
    gaps_m : array_like
        Equidistant gap grid [m] (> 0, at least 4 points; deprecated alias ``gaps``).
        Stored as the maps' ``gap`` coordinate.
    currents_A : array_like
        Equidistant current grid [A] (>= 0, at least 4 points; deprecated alias
        ``currents``).  Stored as the maps' ``current`` coordinate.
    executor : "auto", None, "serial", "process", Executor or dask Client
        Where the tasks (statics: one per gap row; transient: one per grid point) run.
        ``"auto"`` (default): statics rows always in this process, transient points in
        a process pool of ``min(cpu_count, points)`` workers when the grid has at least
        :data:`AUTO_POOL_MIN_POINTS` (64) points and the machine at least 2 CPUs, else in
        this process.  Rule from measurements on 2 cores: a pool worker costs ~2.5 s to
        start, import and compile, more than statics maps of any practical grid take
        (U-magnet 50 x 50: 1.2 s in-process, 3.4 s with 2 processes) and more than it
        saves on small transient grids (4 x 4: 7.5 s vs 10.1 s; 8 x 8: 29.0 s vs 27.5 s).
        ``None``/``"serial"``: in this process; ``"process"``: a local process pool (also
        for the statics rows); any ``concurrent.futures.Executor``; or a
        ``dask.distributed.Client`` (its ``get_executor()``).  Results do not depend on it
        (bit-identical).
    progress : bool
        Report progress on stderr (default True): a rich progress bar on a terminal,
        otherwise plain lines with the ETA (every 10 % of the tasks, at most one per
        second and at least one per 10 s; :class:`maglevkit._progress.ProgressReporter`).
    method : {"statics", "transient", "both"}
        How ``L~`` and ``dL/ds`` are computed.  ``"statics"`` (default, fast): exact
        sensitivities of the static network.  ``"transient"``: the paper's time
        integrations of the detailed model (a voltage step and a flux-held gap ramp per
        grid point and circuit; ~0.3 s per point and circuit on the U-magnet, so use an
        executor).  ``"both"``: statics maps plus ``inductance_transient_H``,
        ``dL_ds_transient_H_per_m`` and their relative differences to the statics
        (``*_relative_difference`` = transient / statics - 1).  The transient methods
        also store ``eddy_resistance_step_ohm``, the ``R_ec`` a single-exponential fit of
        the step response implies (its slow mode; see docs/reduction.md).

    eddy_reference : (gap_m, current_A) or None
        Where the step-response identifications (``eddy_resistance_fit_ohm``, the eddy
        network ``eddy_network_*`` and the shielded-gap ladder ``motion_eddy_*``) run: a
        point inside the grid, e.g. the operating point of the scenarios the current model
        will run.  None (default): the maps' reference
        point, the grid centre gap and ``max(I_mid, I_max/2)`` (docs/reduction.md, "More
        eddy modes": the identification point matters).

    Returns
    -------
    CharacteristicMaps
    """
    if method not in METHODS:
        raise InputError(f"method = {method!r}; use one of {list(METHODS)}")
    net = as_network(model)
    g = check_grid(gaps_m, "gap", "m", positive=True)
    c = check_grid(currents_A, "current", "A", positive=False)
    ref_gap, ref_current = pole_group_point(g, c)
    eddy_gap, eddy_current = _eddy_point(eddy_reference, g, c, ref_gap, ref_current)
    groups = circuit_pole_groups(net, gap_m=ref_gap, current_A=ref_current)
    ex, owned = _as_executor(executor, method, g.size * c.size)
    done = False
    try:
        # "auto" runs the statics rows in this process even when it starts a pool for the
        # transient points (statics rows are cheaper than a worker's compile, see above)
        auto = isinstance(executor, str) and executor == "auto"
        rows = _run_tasks(_statics_row, [(net, float(s), c, groups) for s in g],
                          None if auto else ex, progress, "statics maps")
        if method != "statics":
            gi = {name: k for k, name in enumerate(net.gap_names)}
            poles = tuple(tuple(gi[p] for p in groups[name]) for name in net.circuit_names)
            key = network_hash(net)
            points = [(key, net, float(s), float(i), poles) for s in g for i in c]
            trans = _run_tasks(transient_point, points, ex, progress, "transient maps")
        done = True
    finally:
        if owned and ex is not None:
            if done:
                ex.shutdown()
            else:   # interrupted or failed: do not wait for (or run) the remaining points
                from .._interrupt import stop_pool

                stop_pool(ex)
    names = list(rows[0])
    data = {k: np.stack([r[k] for r in rows], axis=1) for k in names}  # (circuit, gap, current)
    if method != "statics":
        shape = (len(net.circuits), g.size, c.size)
        tdata = {k: np.stack([t[k] for t in trans], axis=1).reshape(shape) for k in trans[0]}
        if method == "transient":
            data["inductance_H"] = tdata["inductance_H"]
            data["dL_ds_H_per_m"] = tdata["dL_ds_H_per_m"]
        else:
            data["inductance_transient_H"] = tdata["inductance_H"]
            data["dL_ds_transient_H_per_m"] = tdata["dL_ds_H_per_m"]
            data["inductance_relative_difference"] = tdata["inductance_H"] / data["inductance_H"] - 1
            data["dL_ds_relative_difference"] = (tdata["dL_ds_H_per_m"] / data["dL_ds_H_per_m"]
                                                 - 1)
        data["eddy_resistance_step_ohm"] = tdata["eddy_resistance_step_ohm"]
    ds = maps_dataset(data, circuits=net.circuit_names, gaps_m=g, currents_A=c,
                      resistance_ohm=net.resistances)
    r_ec = eddy_resistance(net, gap_m=ref_gap, current_A=ref_current)
    # R_ec depends on the operating point only through the iron's differential
    # reluctances (and not at all when every loop carries an eddy element): its spread
    # over the grid corners is recorded, not hidden.
    corners = np.array([eddy_resistance(net, gap_m=float(sv), current_A=float(iv))
                        for sv in (g[0], g[-1]) for iv in (c[0], c[-1])])
    with np.errstate(invalid="ignore"):
        spread = np.where(np.isinf(r_ec), 0.0, np.ptp(corners, axis=0) / np.where(
            np.isinf(r_ec), 1.0, r_ec))
    ds["eddy_resistance_ohm"] = ("circuit", r_ec, {
        "units": "ohm", "long_name": "eddy-current resistance R_ec",
        "description": "1/Y_jj - R_el with Y = dI/dU at fixed flux linkages and eddy fluxes "
                       "(exact instantaneous current jump of the detailed model) at the "
                       f"reference point s = {ref_gap!r} m, I = {ref_current!r} A",
        "relative_spread_over_grid_corners": spread})
    ds["eddy_resistance_fit_ohm"] = ("circuit", _fitted_eddy_resistance(net, eddy_gap,
                                                                         eddy_current), {
        "units": "ohm", "long_name": "eddy-current resistance R_ec from the step time constant",
        "description": "R_ec that a single-exponential fit of a small voltage step of the "
                       "detailed model implies (paper Sec. IV-B procedure; matches the slow "
                       f"eddy mode) at s = {eddy_gap!r} m, I = {eddy_current!r} A; the "
                       "current-based model uses it by default (docs/decisions.md)"})
    _store_eddy_network(ds, net, eddy_gap, eddy_current,
                        np.asarray(ds["eddy_resistance_fit_ohm"].values, dtype=float))
    _store_motion_eddy(ds, net, eddy_gap, eddy_current,
                       np.asarray(ds["eddy_resistance_fit_ohm"].values, dtype=float), groups,
                       np.min(data["inductance_H"], axis=(1, 2)))
    magnet_name = getattr(model, "name", net.name)
    params = getattr(model, "parameters", None)
    # the magnet file's reduced-model default; 0 where no eddy network could be fitted
    modes = default_eddy_modes(model) if net.has_eddy_currents else 0
    ds.attrs.update({
        "format": MAPS_FORMAT,
        "magnet_name": str(magnet_name),
        "magnet_hash": network_hash(net),
        "magnet_hash_kind": "sha256 of the equivalent circuit (maglevkit.reduction.maps."
                            "model_hash)",
        "magnet_parameter_hash": str(getattr(model, "parameter_hash", "")),
        "magnet_parameters": json.dumps(params, sort_keys=True) if params is not None else "",
        "pole_groups": json.dumps(groups),
        DEFAULT_EDDY_MODES_ATTRIBUTE: int(modes),
        "gap_names": ",".join(net.gap_names),
        "method": _METHOD_TEXT[method],
        "maglevkit_version": _version(),
        "conventions": "all gaps equal to s and every circuit at I (symmetric operation); "
                       "force is attraction-positive",
    })
    return CharacteristicMaps(ds)
