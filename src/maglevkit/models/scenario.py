"""Scenario files: input signals and run settings for a transient simulation (TOML).

Example (``maglevkit/data/scenarios/step.toml``)::

    [scenario]
    duration = 0.3            # s
    dt = 1e-4                 # s, output step and zero-order hold of the voltages
    initial_current = 10.0    # A (optional; default: steady state of the first voltage)

    [voltages]                # per circuit name, or "all"
    all = {type = "step", initial = 20.0, final = 60.0, time = 0.02}

    [gaps]                    # per gap name, or "all" (m)
    all = {type = "sine", offset = 0.010, amplitude = 0.001, frequency = 10.0}

    [model]                   # optional physics switches
    saturation = true
    eddy_currents = true

    [solver]                  # optional
    method = "idas"
    rtol = 1e-6
    atol = 1e-8

Signals are numbers or tables (see :mod:`maglevkit.models.signals`).  Unknown or missing
keys raise :class:`~maglevkit.errors.ParameterFileError`.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import InputError, ParameterFileError
from ..validation import renamed_keywords
from .inputs import check_span
from .signals import Signal, parse_signal

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Scenario", "load_scenario", "parse_scenario", "bundled_scenarios"]

_TABLES = {"scenario", "voltages", "gaps", "model", "solver"}


@renamed_keywords(voltages="voltages_V", gaps="gaps_m")
@dataclass(frozen=True)
class Scenario:
    """A parsed scenario.

    The old field names ``voltages`` and ``gaps`` are deprecated aliases for one release
    (constructor keywords and read-only attributes); the file's tables keep their names
    ``[voltages]`` and ``[gaps]``.

    Attributes
    ----------
    duration_s, dt_s : float
        Simulated time and output/hold step [s].
    initial_current_A : float or None
        Initial current of every circuit [A] (None: steady state of the first voltage).
    voltages_V, gaps_m : dict of str to Signal
        Signals per circuit [V] / gap name [m] (key ``"all"``: every input).
    model_options, solver_options : dict
        FluxModel switches (``saturation``, ``eddy_currents``) and solver settings
        (``method`` ``"idas"`` or ``"radau"``, ``rtol``, ``atol``).
    source : str
        File path or bundled name (for messages).
    """

    duration_s: float
    dt_s: float
    voltages_V: Mapping[str, Signal]
    gaps_m: Mapping[str, Signal]
    initial_current_A: float | None = None
    model_options: Mapping[str, Any] = field(default_factory=dict)
    solver_options: Mapping[str, Any] = field(default_factory=dict)
    source: str = ""

    def inputs_for(self, names: tuple[str, ...], which: str) -> dict[str, Signal]:
        """Signals for the given input names (``which`` is ``"voltages"`` or ``"gaps"``).

        Parameters
        ----------
        names : tuple of str
            The model's circuit names (voltages, signals in [V]) or gap names (gaps,
            signals in [m]).
        which : {"voltages", "gaps"}
            Which table to read.

        Returns
        -------
        dict of str to Signal
            One signal per name, the named entry or else the ``"all"`` entry.

        Raises
        ------
        InputError
            ``which`` neither ``"voltages"`` nor ``"gaps"``.
        ParameterFileError
            A name in the table that the model does not have, or a name without a signal
            (and no ``"all"``).
        """
        if not isinstance(which, str) or which not in ("voltages", "gaps"):
            raise InputError(f"inputs_for: which = {which!r}; allowed: 'voltages' or 'gaps'")
        table = self.voltages_V if which == "voltages" else self.gaps_m
        unit = "circuit" if which == "voltages" else "gap"
        unknown = sorted(set(table) - set(names) - {"all"})
        if unknown:
            raise ParameterFileError(f"{self.source}: [{which}] names {unknown} are not "
                                     f"{unit}s of this magnet; its {unit}s are {list(names)} "
                                     "(or use 'all')")
        out = {}
        for nm in names:
            sig = table.get(nm, table.get("all"))
            if sig is None:
                raise ParameterFileError(f"{self.source}: [{which}] has no signal for {unit} "
                                         f"{nm!r}; give {list(names)} or 'all'")
            out[nm] = sig
        return out


def _number(tab: Mapping[str, Any], key: str, where: str, *, positive: bool = True,
            required: bool = True) -> float | None:
    if key not in tab:
        if required:
            raise ParameterFileError(f"[{where}]: missing required key {key!r}")
        return None
    v = tab[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ParameterFileError(f"[{where}] {key} = {v!r}: expected a number")
    if not math.isfinite(v):
        raise ParameterFileError(f"[{where}] {key} = {v!r}: must be finite")
    if positive and not v > 0:
        raise ParameterFileError(f"[{where}] {key} = {v!r}: must be > 0")
    return float(v)


def _check_keys(tab: Any, allowed: set[str], where: str) -> Mapping[str, Any]:
    if not isinstance(tab, Mapping):
        raise ParameterFileError(f"[{where}] must be a table")
    unknown = sorted(set(tab) - allowed)
    if unknown:
        raise ParameterFileError(f"[{where}]: unknown key(s) {unknown}; allowed keys are: "
                                 f"{', '.join(sorted(allowed))}")
    return tab


def parse_scenario(data: Mapping[str, Any], source: str = "scenario") -> Scenario:
    """Validate a parsed scenario dictionary (see the module docstring).

    Parameters
    ----------
    data : mapping
        The parsed TOML: tables ``scenario`` (``duration`` [s], ``dt`` [s], optional
        ``initial_current`` [A]), ``voltages`` and ``gaps`` (signals per name or
        ``"all"``), optional ``model`` and ``solver``.
    source : str, default "scenario"
        Label for error messages and :attr:`Scenario.source`.

    Returns
    -------
    Scenario

    Raises
    ------
    ParameterFileError
        Unknown or missing tables or keys; a duration or step that is not a finite number
        > 0, or a duration that is not a whole number of steps; bad signals; model
        switches that are not true/false; an unknown solver method or tolerances <= 0.
    """
    unknown = sorted(set(data) - _TABLES)
    if unknown:
        raise ParameterFileError(f"{source}: unknown table(s) {unknown}; allowed: "
                                 f"{', '.join(sorted(_TABLES))}")
    for req in ("scenario", "voltages", "gaps"):
        if req not in data:
            raise ParameterFileError(f"{source}: missing the [{req}] table")
    sc = _check_keys(data["scenario"], {"duration", "dt", "initial_current"}, "scenario")
    duration = _number(sc, "duration", "scenario")
    dt = _number(sc, "dt", "scenario")
    i0 = _number(sc, "initial_current", "scenario", positive=False, required=False)
    assert duration is not None and dt is not None
    try:
        check_span(0.0, duration, dt)   # the same rule as simulate((0, duration), dt_s=dt)
    except InputError as exc:
        raise ParameterFileError(f"{source}: [scenario] {exc}") from None
    sigs: dict[str, dict[str, Signal]] = {}
    for which in ("voltages", "gaps"):
        tab = data[which]
        if not isinstance(tab, Mapping) or not tab:
            raise ParameterFileError(f"{source}: [{which}] must be a table of signals per name "
                                     "(or 'all')")
        sigs[which] = {str(k): parse_signal(v, f"[{which}] {k}") for k, v in tab.items()}
    model = dict(_check_keys(data.get("model", {}), {"saturation", "eddy_currents"}, "model"))
    for k, v in model.items():
        if not isinstance(v, bool):
            raise ParameterFileError(f"[model] {k} = {v!r}: expected true or false")
    solver = dict(_check_keys(data.get("solver", {}), {"method", "rtol", "atol"}, "solver"))
    if "method" in solver and solver["method"] not in ("idas", "radau"):
        raise ParameterFileError(f"[solver] method = {solver['method']!r}: use 'idas' or 'radau'")
    for k in ("rtol", "atol"):
        if k in solver:
            solver[k] = _number(solver, k, "solver")
    return Scenario(duration, dt, sigs["voltages"], sigs["gaps"], i0, model, solver, source)


def load_scenario(source: str | Path) -> Scenario:
    """Load a scenario TOML file, or a bundled scenario by name (e.g. ``"step"``).

    Parameters
    ----------
    source : str or Path
        Path of a ``.toml`` file, or the name of a bundled scenario
        (:func:`bundled_scenarios`).

    Returns
    -------
    Scenario

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    InputError
        ``source`` is not a name or a path.
    """
    if not isinstance(source, (str, os.PathLike)) or not str(source):
        raise InputError(f"load_scenario: source = {source!r}: expected a bundled scenario "
                         f"name ({', '.join(bundled_scenarios())}) or the path of a .toml file")
    path = Path(source)
    if path.suffix != ".toml" and not path.exists():
        names = bundled_scenarios()
        if str(source) not in names:
            raise ParameterFileError(f"no scenario file {str(source)!r} and no bundled scenario "
                                     f"of that name; bundled: {', '.join(names)}")
        text = (resources.files("maglevkit") / "data" / "scenarios" / f"{source}.toml").read_text()
    else:
        if not path.is_file():
            raise ParameterFileError(f"scenario file {str(path)!r} does not exist")
        text = path.read_text()
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterFileError(f"{source}: not valid TOML: {exc}") from None
    return parse_scenario(data, str(source))


def bundled_scenarios() -> list[str]:
    """Names of the scenario files shipped with maglevkit."""
    files = resources.files("maglevkit") / "data" / "scenarios"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))
