"""Magnets: parametric topologies built from TOML parameter files.

A parameter file has a ``[magnet]`` table whose ``kind`` selects the builder, the
builder's own tables, optional ``[materials.NAME]`` tabulated B-H curves, and an
optional ``[provenance]`` table that tags values (``"magnet.turns" = "[E] estimate"``),
and an optional ``[operating]`` table with the nominal operating point
(``nominal_gap`` [m], ``nominal_current`` [A]) that figures and maps normalise by.
All values are SI (m, ohm, A, ...).  Unknown and missing keys are errors.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ..circuit.network import Network
from ..errors import MaterialError, ParameterError, ParameterFileError
from ..materials import Material, TabulatedBH, get_material, normalise_name

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "Magnet",
    "ModelOptions",
    "load_magnet",
    "build_magnet",
    "bundled_magnets",
    "register_kind",
    "Schema",
    "take",
    "resolve_material",
]


@dataclass(frozen=True)
class ModelOptions:
    """Physics switches for building a magnet (for comparisons like the paper's Figs. 6-7).

    Attributes
    ----------
    saturation : bool
        Nonlinear iron (False: constant initial permeability).
    fringing : bool
        Fringing permeances at the pole edges.
    leakage : bool
        Leakage permeances.
    eddy_currents : bool
        Eddy-current elements (used by the dynamic model).
    """

    saturation: bool = True
    fringing: bool = True
    leakage: bool = True
    eddy_currents: bool = True


@dataclass(frozen=True)
class Magnet:
    """A magnet: its equivalent magnetic circuit plus the parameters it was built from.

    Attributes
    ----------
    name : str
        Display name.
    kind : str
        Builder kind (e.g. ``"u_magnet"``).
    network : Network
        The equivalent magnetic circuit with its electric circuits.
    parameters : dict
        The parsed parameter file (SI units).
    provenance : dict
        ``"table.key" -> tag/source`` for the values that have one.
    options : ModelOptions
        The physics switches used.
    source : str
        File path or bundled name it came from.
    """

    name: str
    kind: str
    network: Network
    parameters: Mapping[str, Any]
    provenance: Mapping[str, str] = field(default_factory=dict)
    options: ModelOptions = field(default_factory=ModelOptions)
    source: str = ""

    @property
    def gap_names(self) -> tuple[str, ...]:
        return self.network.gap_names

    @property
    def circuit_names(self) -> tuple[str, ...]:
        return self.network.circuit_names

    @property
    def nominal_gap(self) -> float | None:
        """Nominal gap [m] from the file's ``[operating]`` table (None if not given)."""
        op = self.parameters.get("operating")
        return None if op is None else float(op["nominal_gap"])

    @property
    def nominal_current(self) -> float | None:
        """Nominal circuit current [A] from the file's ``[operating]`` table (None if not given)."""
        op = self.parameters.get("operating")
        return None if op is None else float(op["nominal_current"])

    @property
    def parameter_hash(self) -> str:
        """SHA-256 of the parameters and physics options (identifies a magnet for maps)."""
        blob = json.dumps({"parameters": self.parameters, "options": self.options.__dict__},
                          sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()

    def with_options(self, **changes: bool) -> Magnet:
        """Rebuild this magnet with some physics switches changed."""
        opts = {**self.options.__dict__, **changes}
        return build_magnet(self.parameters, options=ModelOptions(**opts), source=self.source,
                            provenance=self.provenance)


# ----------------------------------------------------------------- schema helpers
@dataclass(frozen=True)
class Schema:
    """One key of a parameter table: type, whether required, unit and a check.

    ``check`` is one of ``"positive"``, ``"nonnegative"``, ``"any"``.
    """

    kind: type
    required: bool = True
    unit: str = ""
    check: str = "positive"
    default: Any = None


def take(table: Any, schema: Mapping[str, Schema], where: str) -> dict[str, Any]:
    """Validate a TOML table against a schema; unknown, missing or bad keys raise."""
    if not isinstance(table, Mapping):
        raise ParameterFileError(f"[{where}] must be a table")
    unknown = sorted(set(table) - set(schema))
    if unknown:
        raise ParameterFileError(
            f"[{where}]: unknown key(s) {unknown}; allowed keys are: {', '.join(schema)}"
        )
    out: dict[str, Any] = {}
    for key, sc in schema.items():
        if key not in table:
            if sc.required:
                unit = f" [{sc.unit}]" if sc.unit else ""
                raise ParameterFileError(f"[{where}]: missing required key {key!r}{unit}")
            out[key] = sc.default
            continue
        v = table[key]
        if sc.kind is float:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: expected a number [{sc.unit}]")
            v = float(v)
            if not math.isfinite(v):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: must be finite")
            if sc.check == "positive" and v <= 0.0:
                raise ParameterFileError(f"[{where}] {key} = {v!r} {sc.unit}: must be > 0")
            if sc.check == "nonnegative" and v < 0.0:
                raise ParameterFileError(f"[{where}] {key} = {v!r} {sc.unit}: must be >= 0")
        elif sc.kind is int:
            if isinstance(v, bool) or not isinstance(v, int):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: expected a whole number")
            if sc.check == "positive" and v <= 0:
                raise ParameterFileError(f"[{where}] {key} = {v!r}: must be > 0")
        elif sc.kind is bool:
            if not isinstance(v, bool):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: expected true or false")
        elif sc.kind is str:
            if not isinstance(v, str):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: expected a string")
        elif sc.kind is list:
            if not isinstance(v, list):
                raise ParameterFileError(f"[{where}] {key} = {v!r}: expected a list")
        out[key] = v
    return out


OPERATING_SCHEMA = {
    "nominal_gap": Schema(float, unit="m"),
    "nominal_current": Schema(float, unit="A"),
}


def resolve_material(name: str, custom: Mapping[str, Material], where: str) -> Material:
    """A material by name: a ``[materials.NAME]`` table of the file, or a built-in record."""
    key = normalise_name(name)
    if key in custom:
        return custom[key]
    try:
        return get_material(name)
    except MaterialError as exc:
        names = sorted(m.name for m in custom.values())
        extra = f" or one of this file's [materials] tables {names}" if custom else ""
        raise ParameterFileError(f"[{where}] material: {exc}{extra}") from None


def _parse_materials(raw: Any) -> dict[str, Material]:
    if raw is None:
        return {}
    if not isinstance(raw, Mapping):
        raise ParameterFileError("[materials] must hold tables like [materials.my_steel]")
    out: dict[str, Material] = {}
    for name, tab in raw.items():
        where = f"materials.{name}"
        t = take(tab, {"H": Schema(list, unit="A/m"), "B": Schema(list, unit="T"),
                       "resistivity": Schema(float, required=False, unit="ohm m")}, where)
        try:
            out[normalise_name(name)] = TabulatedBH(tuple(t["H"]), tuple(t["B"]), name=name,
                                                    resistivity=t["resistivity"])
        except MaterialError as exc:
            raise ParameterFileError(f"[{where}]: {exc}") from None
    return out


# ----------------------------------------------------------------- registry and loading
Builder = Callable[[Mapping[str, Any], Mapping[str, Material], ModelOptions], tuple[str, Network]]
_BUILDERS: dict[str, tuple[Builder, tuple[str, ...]]] = {}


def register_kind(kind: str, builder: Builder, tables: tuple[str, ...]) -> None:
    """Register a builder for ``[magnet] kind = KIND``; ``tables`` are its allowed top-level tables."""
    _BUILDERS[kind] = (builder, tables)


def build_magnet(parameters: Mapping[str, Any], *, options: ModelOptions | None = None,
                 source: str = "", provenance: Mapping[str, str] | None = None) -> Magnet:
    """Build a :class:`Magnet` from a parsed parameter dictionary."""
    options = options or ModelOptions()
    if not isinstance(parameters, Mapping) or "magnet" not in parameters:
        raise ParameterFileError(f"{source or 'parameters'}: missing the [magnet] table")
    mag = parameters["magnet"]
    if not isinstance(mag, Mapping) or "kind" not in mag:
        raise ParameterFileError(f"{source or 'parameters'}: [magnet] needs a 'kind' key; "
                                 f"known kinds: {', '.join(sorted(_BUILDERS))}")
    kind = mag["kind"]
    if kind not in _BUILDERS:
        raise ParameterFileError(f"[magnet] kind = {kind!r} is unknown; known kinds: "
                                 f"{', '.join(sorted(_BUILDERS))}")
    builder, tables = _BUILDERS[kind]
    allowed = {"magnet", "materials", "provenance", "operating", *tables}
    unknown = sorted(set(parameters) - allowed)
    if unknown:
        raise ParameterFileError(f"unknown table(s) {unknown}; a {kind!r} file may have: "
                                 f"{', '.join(sorted(allowed))}")
    materials = _parse_materials(parameters.get("materials"))
    prov = dict(provenance or {})
    raw_prov = parameters.get("provenance", {})
    if not isinstance(raw_prov, Mapping):
        raise ParameterFileError("[provenance] must map 'table.key' to a tag string")
    if "operating" in parameters:
        take(parameters["operating"], OPERATING_SCHEMA, "operating")
    try:
        name, network = builder(parameters, materials, options)
    except (ParameterError, MaterialError) as exc:
        raise ParameterFileError(f"{source or 'parameters'}: {exc}") from None
    # After the builder, so that a missing or misspelt value is reported as such rather
    # than as a provenance entry that names nothing.
    for key, tag in raw_prov.items():
        table, _, sub = str(key).partition(".")
        if table not in parameters or not isinstance(parameters[table], Mapping) \
                or sub not in parameters[table]:
            raise ParameterFileError(f"[provenance] {key!r} names no value of this file")
        prov[str(key)] = str(tag)
    # The physics switches hold for every kind, whether or not its builder reads them.
    network = network.with_options(saturation=options.saturation,
                                   eddy_currents=options.eddy_currents)
    return Magnet(name=name, kind=kind, network=network, parameters=_plain(parameters),
                  provenance=prov, options=options, source=source)


def _plain(obj: Any) -> Any:
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_plain(v) for v in obj]
    return obj


def bundled_magnets() -> list[str]:
    """Names of the parameter files shipped with maglevkit."""
    files = resources.files("maglevkit") / "data"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def load_magnet(source: str | Path, *, saturation: bool = True, fringing: bool = True,
                leakage: bool = True, eddy_currents: bool = True) -> Magnet:
    """Load a magnet from a TOML file path or a bundled name (e.g. ``"u-magnet"``).

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    """
    options = ModelOptions(saturation=saturation, fringing=fringing, leakage=leakage,
                           eddy_currents=eddy_currents)
    path = Path(source)
    if path.suffix != ".toml" and not path.exists():
        names = bundled_magnets()
        if str(source) not in names:
            raise ParameterFileError(f"no magnet file {str(source)!r} and no bundled magnet of that "
                                     f"name; bundled magnets: {', '.join(names)}")
        text = (resources.files("maglevkit") / "data" / f"{source}.toml").read_text()
        label = str(source)
    else:
        if not path.is_file():
            raise ParameterFileError(f"magnet file {str(path)!r} does not exist")
        text = path.read_text()
        label = str(path)
    try:
        params = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterFileError(f"{label}: not valid TOML: {exc}") from None
    return build_magnet(params, options=options, source=label)
