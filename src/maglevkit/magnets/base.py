"""Magnets: parametric topologies built from TOML parameter files.

A parameter file has a ``[magnet]`` table whose ``kind`` selects the builder, the
builder's own tables, optional ``[materials.NAME]`` tabulated B-H curves (``H``/``B`` lists or
``csv = "file.csv"``, optional ``interpolation``, ``resistivity``), a
``[provenance]`` table that tags every value (``"magnet.turns" = "[E] estimate"``; tags
start with ``[P]``, ``[R]`` or ``[E]``), an optional ``[operating]`` table with the
nominal operating point (``nominal_gap`` [m], ``nominal_current`` [A]) that figures and
maps normalise by, and an optional ``[reduced]`` table with the reduced model's default
on this magnet's maps (``eddy_modes``: :data:`REDUCED_EDDY_MODES`,
:attr:`Magnet.default_eddy_modes`).  All values are SI (m, ohm, A, ...).  Unknown and missing keys,
wrong types, negative or fractional counts (turns included) are errors; a missing
``[provenance]`` table, values without a tag and malformed tags are a
:class:`~maglevkit.errors.ProvenanceWarning`.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..circuit.factors import PARAMETERS, with_factors
from ..circuit.ladder import EDDY_MODELS, LADDER_COEFFICIENTS
from ..circuit.network import Network
from ..errors import (
    InputError,
    MaterialError,
    ParameterError,
    ParameterFileError,
    PlausibilityWarning,
    ProvenanceWarning,
)
from ..materials import Material, TabulatedBH, get_material, normalise_name, read_bh_csv
from ..parameter_files import bundled_files, read_parameter_file
from ..validation import Plausible, check_plausible, external_stacklevel, flag, renamed_keywords

__all__ = [
    "MAGNET_PLAUSIBLE",
    "MAX_CURRENT_DENSITY_A_PER_M2",
    "OPTION_NAMES",
    "REDUCED_EDDY_MODES",
    "REDUCED_SCHEMA",
    "Magnet",
    "ModelOptions",
    "PlausibleRange",
    "load_magnet",
    "build_magnet",
    "bundled_magnets",
    "read_calibration",
    "CALIBRATION_KEYS",
    "resistivity",
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
    eddy_model : str
        ``"lumped"``: one eddy element per iron part (a resistor for the coil at
        ``t = 0+``); ``"ladder"``: ``eddy_layers`` nested flux tubes across each part's
        section, each with its own eddy element (diffusion into solid iron,
        :mod:`maglevkit.circuit.ladder`); ``"ladder_split"``: the ladder with the
        U-magnet's rail split under and between the poles.  A kind refuses the models
        its builder does not have (:func:`eddy_models_of_kind`: the ladder on every kind
        of :data:`LADDER_KINDS`, the split ladder on the U-magnet only), with or without
        ``eddy_currents``.  A magnet file may name its own (``[magnet] eddy_model``,
        ``eddy_layers``): :func:`load_magnet` and :func:`build_magnet` without these
        options take the file's values (a built :class:`Magnet`'s options hold the
        values used).
    eddy_layers : int
        Tubes per iron part of the ladder (1 ... 8; ignored by ``"lumped"``).

    Raises
    ------
    InputError
        A switch that is not True or False (``"no"`` would be truthy), an unknown
        ``eddy_model``, ``eddy_layers`` not a whole number in 1 ... 8.
    """

    saturation: bool = True
    fringing: bool = True
    leakage: bool = True
    eddy_currents: bool = True
    eddy_model: str = "lumped"
    eddy_layers: int = 6

    def __post_init__(self) -> None:
        # "no" or 0 would be truthy/falsy by accident: every switch must be a real bool
        for name in SWITCH_NAMES:
            object.__setattr__(self, name, flag(getattr(self, name), name))
        if self.eddy_model not in EDDY_MODELS:
            raise InputError(f"eddy_model = {self.eddy_model!r}; allowed are "
                             f"{', '.join(repr(m) for m in EDDY_MODELS)}")
        n = self.eddy_layers
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) \
                or int(n) not in LADDER_COEFFICIENTS:
            raise InputError(f"eddy_layers = {n!r}; allowed are the whole numbers "
                             f"{min(LADDER_COEFFICIENTS)} ... {max(LADDER_COEFFICIENTS)}")
        object.__setattr__(self, "eddy_layers", int(n))


#: Options a magnet file may set in its ``[magnet]`` table (an option given to
#: :func:`load_magnet` or :func:`build_magnet` wins).
FILE_OPTION_NAMES = ("eddy_model", "eddy_layers")
#: The True/False physics switches of :class:`ModelOptions`.
SWITCH_NAMES = ("saturation", "fringing", "leakage", "eddy_currents")
#: All options of :class:`ModelOptions` (keyword names of ``load_magnet`` and
#: ``Magnet.with_options``).
OPTION_NAMES = (*SWITCH_NAMES, "eddy_model", "eddy_layers")
#: Magnet kinds whose builder has the ``"ladder"`` eddy model.
LADDER_KINDS = ("u_magnet", "levitation_magnet", "guidance_magnet")
#: Magnet kinds whose builder has the ``"ladder_split"`` eddy model (the U-magnet's rail).
LADDER_SPLIT_KINDS = ("u_magnet",)


def eddy_models_of_kind(kind: str) -> tuple[str, ...]:
    """The ``eddy_model`` values the builder of magnet kind ``kind`` takes."""
    return tuple(m for m in EDDY_MODELS if m == "lumped"
                 or (m == "ladder" and kind in LADDER_KINDS)
                 or (m == "ladder_split" and kind in LADDER_SPLIT_KINDS))
#: Magnet kinds whose ``[magnet]`` table has the ``end_effects`` key (true: the terms of the
#: finite extent across the 2-D cut; ``Magnet.with_options(end_effects=...)`` sets it).
#: The guidance magnet's network has no such term (false builds the same network).
END_EFFECTS_KINDS = ("u_magnet", "levitation_magnet", "guidance_magnet")

#: Winding current density [A/m^2], averaged over the coil's cross-section, above which a
#: current is reported as implausible (:class:`PlausibleRange`): at 100 A/mm^2 even a
#: winding that were solid copper heats adiabatically at ~50 K/s (rho J^2 / c_v with
#: rho = 1.7e-8 ohm m, c_v = 3.45e6 J/(m^3 K)), at a fill factor of 0.6 at ~140 K/s
#: (aluminium ~320 K/s): no coil carries it for more than a second.  Continuous ratings
#: are 2-10 A/mm^2 (up to ~30 water-cooled); the bundled U-magnet example reaches
#: 32 A/mm^2 at 80 A, the top of its documented grids.
MAX_CURRENT_DENSITY_A_PER_M2 = 100e6


@dataclass(frozen=True)
class PlausibleRange:
    """Bounds beyond which an input lies far outside a magnet's physical range.

    Inputs beyond them are computed anyway but raise a :class:`PlausibilityWarning`:
    they are almost always a unit mistake (a gap of ``10`` meant as 10 mm, a current
    in mA) or a typo.

    Attributes
    ----------
    max_gap_m : float
        Largest plausible gap [m]: the smallest pole-face dimension (a gap as wide as
        the pole leaves the equivalent circuit's air-gap tubes, made for ``s << w``,
        far outside their range).
    max_current_A : float
        Largest plausible circuit current magnitude [A]: the current at which the
        winding carries :data:`MAX_CURRENT_DENSITY_A_PER_M2` over its cross-section.
    gap_basis, current_basis : str
        Where the bounds come from (for the warning text).
    """

    max_gap_m: float
    max_current_A: float
    gap_basis: str
    current_basis: str

    @classmethod
    def from_geometry(cls, *, gap_m: float, gap_basis: str, turns: float,
                      winding_area_m2: float, winding: str) -> PlausibleRange:
        """Bounds from a pole dimension and one coil (``turns`` on ``winding_area_m2``).

        Parameters
        ----------
        gap_m : float
            The largest plausible gap [m] (a pole dimension of the magnet).
        gap_basis : str
            What ``gap_m`` is, for the warning text (e.g. ``"the pole width"``).
        turns : float
            Turns of the coil [-].
        winding_area_m2 : float
            Copper cross-section of the coil's winding [m^2]; the current bound is
            ``MAX_CURRENT_DENSITY_A_PER_M2 * winding_area_m2 / turns`` [A].
        winding : str
            Name of the winding, for the warning text.

        Returns
        -------
        PlausibleRange
        """
        current = MAX_CURRENT_DENSITY_A_PER_M2 * winding_area_m2 / turns
        basis = (f"{MAX_CURRENT_DENSITY_A_PER_M2 / 1e6:g} A/mm^2 in {winding} "
                 f"({winding_area_m2 * 1e6:.4g} mm^2, {turns:g} turns)")
        return cls(float(gap_m), float(current), gap_basis, basis)

    @renamed_keywords(gaps="gaps_m", currents="currents_A")
    def check(self, *, gaps_m: Any = None, currents_A: Any = None, where: str = "",
              stacklevel: int | None = None) -> None:
        """Warn (:class:`PlausibilityWarning`) if gaps [m] or currents [A] exceed the bounds.

        ``gaps_m`` and ``currents_A`` are numbers or arrays of any shape (NaN ignored).

        Old keyword names (``gaps``, ``currents``) are deprecated aliases for one release.

        Parameters
        ----------
        gaps_m : float or array_like, optional
            Gaps [m] to check against :attr:`max_gap_m`.
        currents_A : float or array_like, optional
            Currents [A] to check (by magnitude) against :attr:`max_current_A`.
        where : str
            Prefix of the warning text (what is being checked, e.g. a command or key).
        stacklevel : int, optional
            Passed to :func:`warnings.warn`; default: the first caller outside maglevkit
            (:func:`~maglevkit.validation.external_stacklevel`), so the warning points at
            the user's line through any depth of maglevkit calls and wrappers.
        """
        prefix = f"{where}: " if where else ""
        if stacklevel is None:
            stacklevel = external_stacklevel()
        if gaps_m is not None:
            g = np.asarray(gaps_m, dtype=float)
            worst = float(np.nanmax(g)) if g.size and not np.all(np.isnan(g)) else 0.0
            if worst > self.max_gap_m:
                warnings.warn(
                    f"{prefix}gap {worst:.6g} m is larger than {self.gap_basis} "
                    f"({self.max_gap_m:.6g} m), far outside this magnet's range (gaps are in "
                    "metres: 10 mm is 0.01)", PlausibilityWarning, stacklevel=stacklevel)
        if currents_A is not None:
            c = np.abs(np.asarray(currents_A, dtype=float))
            worst = float(np.nanmax(c)) if c.size and not np.all(np.isnan(c)) else 0.0
            # rounding allowance 1e-9: the bound itself is a product of file values
            if worst > self.max_current_A * (1.0 + 1e-9):
                warnings.warn(
                    f"{prefix}current {worst:.6g} A exceeds {self.max_current_A:.4g} A, "
                    f"i.e. {self.current_basis}; no coil carries this (currents are in "
                    "amperes)", PlausibilityWarning, stacklevel=stacklevel)


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
    plausible_range : PlausibleRange or None
        Gaps and currents beyond which inputs raise a :class:`PlausibilityWarning`
        (from the magnet's geometry; None for kinds without such bounds).
    """

    name: str
    kind: str
    network: Network
    parameters: Mapping[str, Any]
    provenance: Mapping[str, str] = field(default_factory=dict)
    options: ModelOptions = field(default_factory=ModelOptions)
    source: str = ""
    plausible_range: PlausibleRange | None = None

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
    def default_eddy_modes(self) -> int:
        """The reduced model's default ``eddy_modes`` on maps of this magnet [-].

        From the file's ``[reduced] eddy_modes`` (:data:`REDUCED_EDDY_MODES`; absent: 0,
        eq. 8 with one ``R_ec``).  The key describes the magnet as its file builds it, so
        it is 0 when the magnet is built without eddy currents (``eddy_currents=False``:
        no eddy network to fit) or with another ``eddy_model`` than the file's (e.g.
        ``with_options(eddy_model="lumped")`` of a ladder file: the network was chosen
        for the ladder's diffusion; the lumped elements' maps are eq. 8's).
        ``build_maps`` writes it into the maps
        (``CharacteristicMaps.default_eddy_modes``); entry points whose ``eddy_modes``
        option is unset take it.
        """
        file_model = self.parameters.get("magnet", {}).get("eddy_model", "lumped")
        if not self.options.eddy_currents or self.options.eddy_model != file_model:
            return 0
        table = self.parameters.get("reduced")
        return int(_reduced_table(table, self.source)["eddy_modes"])

    @property
    def calibration(self) -> dict[str, float]:
        """The calibration factors applied to the network (from the file's
        ``[calibration]`` table; empty for an uncalibrated magnet).  Their tags and the
        fitted data's SHA-256 are in :attr:`provenance` (``"calibration.NAME"``,
        ``"calibration.data_sha256"``)."""
        table = self.parameters.get("calibration")
        return {k: float(v) for k, v in (table or {}).items() if k in PARAMETERS}

    @property
    def parameter_hash(self) -> str:
        """SHA-256 of the parameters and physics options (identifies a magnet for maps)."""
        blob = json.dumps({"parameters": self.parameters, "options": self.options.__dict__},
                          sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()

    def with_options(self, **changes: Any) -> Magnet:
        """Rebuild this magnet with some physics switches changed.

        Parameters
        ----------
        **changes : bool, str or int
            Any of ``saturation``, ``fringing``, ``leakage``, ``eddy_currents`` (bool),
            ``eddy_model`` (str), ``eddy_layers`` (int); see :class:`ModelOptions`.
            ``end_effects`` (bool, kinds in :data:`END_EFFECTS_KINDS`) is a key of the
            ``[magnet]`` table: it is set there, so ``parameters`` and
            ``parameter_hash`` of the result show it.

        Raises
        ------
        InputError
            An unknown switch name, a value that is not True/False, or ``end_effects``
            for a kind without it.
        """
        unknown = sorted(set(changes) - {*OPTION_NAMES, "end_effects"})
        if unknown:
            raise InputError(f"with_options: unknown switch(es) {unknown}; the physics "
                             f"switches are {', '.join(SWITCH_NAMES)} (True or False), "
                             f"eddy_model ({' or '.join(map(repr, EDDY_MODELS))}), "
                             f"eddy_layers (1 ... {max(LADDER_COEFFICIENTS)}) and "
                             "end_effects (True or False)")
        params = self.parameters
        if "end_effects" in changes:
            ends = flag(changes.pop("end_effects"), "end_effects")
            if self.kind not in END_EFFECTS_KINDS:
                raise InputError(f"with_options: end_effects is not a key of kind "
                                 f"{self.kind!r} (only of {', '.join(END_EFFECTS_KINDS)})")
            params = {**params, "magnet": {**params["magnet"], "end_effects": ends}}
        opts = {**self.options.__dict__, **changes}
        return _build(params, options=ModelOptions(**opts), source=self.source,
                      provenance=self.provenance, check_provenance=False)


# ----------------------------------------------------------------- schema helpers
_CHECKS = ("positive", "nonnegative", "any")
_KINDS = (float, int, bool, str, list)


@dataclass(frozen=True)
class Schema:
    """One key of a parameter table: type, whether required, unit and a check.

    ``kind`` is ``float``, ``int``, ``bool``, ``str`` or ``list``.  ``check`` is one of
    ``"positive"``, ``"nonnegative"``, ``"any"`` and applies to ``float`` and ``int``
    values alike.  ``whole=True`` (for ``float``) requires a whole number (e.g. turns)
    and still returns a float; an ``int`` key accepts a float only if it is whole
    (``poles = 12.0``) and returns an int.
    """

    kind: type
    required: bool = True
    unit: str = ""
    check: str = "positive"
    default: Any = None
    whole: bool = False

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise TypeError(f"Schema kind {self.kind!r} is not one of {_KINDS}")
        if self.check not in _CHECKS:
            raise TypeError(f"Schema check {self.check!r} is not one of {_CHECKS}")


def _number(v: Any, sc: Schema, key: str, where: str) -> float | int:
    """A numeric value of a parameter table, checked against its schema."""
    unit = f" {sc.unit}" if sc.unit and sc.unit != "-" else ""
    whole = sc.kind is int or sc.whole
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        expected = ("a whole number" if sc.kind is int
                    else "a number (a whole count)" if whole else f"a number [{sc.unit}]")
        raise ParameterFileError(f"[{where}] {key} = {v!r}: expected {expected}")
    if isinstance(v, int) and abs(v) > 2 ** 53:
        # beyond float (was: OverflowError) or beyond exact counts; not all its digits
        text = str(v)
        shown = text if len(text) <= 20 else f"{text[:8]}...{text[-4:]} ({len(text)} digits)"
        raise ParameterFileError(f"[{where}] {key} = {shown}{unit}: too large (at most "
                                 f"2^53 = {2 ** 53})")
    if not math.isfinite(v):
        raise ParameterFileError(f"[{where}] {key} = {v!r}: must be finite")
    if whole and not float(v).is_integer():
        raise ParameterFileError(f"[{where}] {key} = {v!r}{unit}: must be a whole number "
                                 "(a count)")
    if sc.check == "positive" and v <= 0:
        raise ParameterFileError(f"[{where}] {key} = {v!r}{unit}: must be > 0")
    if sc.check == "nonnegative" and v < 0:
        raise ParameterFileError(f"[{where}] {key} = {v!r}{unit}: must be >= 0")
    return int(v) if sc.kind is int else float(v)


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
        if sc.kind is float or sc.kind is int:
            v = _number(v, sc, key, where)
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


#: What a length of a magnet file can mean at all [m] (``Plausible.physical_low`` /
#: ``physical_high`` of every length of :data:`MAGNET_PLAUSIBLE`): below 10 nm (a few dozen
#: atoms) no iron part, sheet or clearance, above 10 km no part of an electromagnet.  A
#: positive length outside is refused (:class:`~maglevkit.errors.ParameterFileError`
#: naming the key, the value and these limits) before the builders, whose laws overflow
#: or divide by zero far out (a guidance rail 1e150 m thick: ``thickness**3`` of the
#: ladder's Saint-Venant factor overflowed).  Every bundled value times 1000 or 1/1000
#: lies inside: such a unit slip warns, as before.
MAGNET_LENGTH_PHYSICAL_M = (1e-8, 1e4)


def _lengths(low: float, high: float, *names: str) -> dict[str, Plausible]:
    lo, hi = MAGNET_LENGTH_PHYSICAL_M
    return {name: Plausible(low, high, "m", physical_low=lo, physical_high=hi,
                            physical_note="no part or clearance of an electromagnet")
            for name in names}


#: The plausible magnitudes of every dimensional key of a magnet file, of all kinds
#: (``"table.key"``; :func:`~maglevkit.validation.check_plausible`).  Sizes of iron parts
#: and coils 2 mm ... 3 m, clearances and grooves 0.2 mm ... 0.5 m, resistances
#: 5 mohm ... 100 ohm, nominal gaps 1 ... 100 mm, nominal currents 0.3 ... 3000 A: every
#: bundled file lies inside, the same file with one value times 1000 or 1/1000 outside.
#: Lengths beyond :data:`MAGNET_LENGTH_PHYSICAL_M` are refused, not warned.
MAGNET_PLAUSIBLE: dict[str, Plausible] = {
    **_lengths(2e-3, 3.0, *(f"magnet.{k}" for k in (
        "pole_width", "leg_height", "yoke_thickness", "window_width", "coil_thickness",
        "coil_height", "pole_length", "core_height", "back_height", "back_width",
        "pole_bar_height", "pole_bar_thickness", "pole_bar_distance", "leg_length",
        "leg_thickness", "yoke_width"))),
    **_lengths(5e-3, 5.0, "magnet.depth"),
    **_lengths(0.02, 2.0, "magnet.pole_pitch"),
    **_lengths(0.05, 10.0, "magnet.section_length"),
    **_lengths(2e-4, 0.5, "magnet.coil_gap_to_pole_face", "magnet.coil_to_face",
               "magnet.lig_groove_width", "magnet.lig_groove_depth"),
    **_lengths(5e-5, 5e-3, "magnet.sheet_thickness"),
    **_lengths(5e-3, 5.0, "magnet.air_margin"),
    **_lengths(2e-3, 3.0, "rail.thickness", "rail.width", "rail.height", "stator.slot_pitch",
               "stator.slot_opening", "stator.slot_depth", "stator.yoke_height",
               "stator.width"),
    **{f"magnet.{k}": Plausible(5e-3, 100.0, "ohm")
       for k in ("resistance", "resistance_per_pole", "resistance_per_yoke")},
    **{f"{t}.resistivity": Plausible(1e-8, 1e-5, "ohm m") for t in ("magnet", "rail")},
    **_lengths(1e-3, 0.1, "operating.nominal_gap"),
    "operating.nominal_current": Plausible(0.3, 3000.0, "A"),
}


OPERATING_SCHEMA = {
    "nominal_gap": Schema(float, unit="m"),
    "nominal_current": Schema(float, unit="A"),
}

#: The values of ``[reduced] eddy_modes`` (and of the reduced model's ``eddy_modes``
#: option): 0 is the paper's eq. 8 with one eddy resistor ``R_ec``; ``m`` = 1, 2, 3 the
#: RL eddy network with ``m`` branches fitted to the detailed model's voltage step
#: (``CurrentModel(maps, eddy_modes=m)``, docs/reduction.md, "More eddy modes").  The
#: one list of them (``maglevkit.reduction.eddy_network.EDDY_NETWORK_MODES`` is its
#: nonzero part).
REDUCED_EDDY_MODES = (0, 1, 2, 3)

#: The ``[reduced]`` table of a magnet file: the reduced model's defaults on maps of this
#: magnet (an option given to an entry point wins; docs/magnets.md, "Which eddy model
#: the bundled files use").
REDUCED_SCHEMA = {
    "eddy_modes": Schema(int, required=False, unit="-", check="any", default=0),
}


def _reduced_table(table: Any, source: str) -> dict[str, Any]:
    """The ``[reduced]`` table, validated (absent: the defaults, ``eddy_modes = 0``).

    Raises
    ------
    ParameterFileError
        Unknown keys, or ``eddy_modes`` not one of :data:`REDUCED_EDDY_MODES` (named with
        its value and the allowed ones).
    """
    if table is None:
        return {k: sc.default for k, sc in REDUCED_SCHEMA.items()}
    label = f"{source or 'parameters'}: " if source else ""
    try:
        out = take(table, REDUCED_SCHEMA, "reduced")
    except ParameterFileError as exc:
        raise ParameterFileError(f"{label}{exc}") from None
    if out["eddy_modes"] not in REDUCED_EDDY_MODES:
        raise ParameterFileError(
            f"{label}[reduced] eddy_modes = {table['eddy_modes']!r}; allowed are "
            f"{', '.join(map(str, REDUCED_EDDY_MODES))} (0: eq. 8 with one R_ec; 1-3: the "
            "RL eddy network's branches)")
    return out


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


def resistivity(given: float | None, material: Material, where: str) -> float:
    """Electrical resistivity [ohm m] of an eddy-current path: ``given`` (the file's
    ``resistivity``) or else the material's built-in value.

    Raises
    ------
    ParameterFileError
        Neither is known (the message names the table ``where`` and the material).
    """
    if given is not None:
        return given
    if material.resistivity_ohm_m is None:
        raise ParameterFileError(
            f"[{where}] material {material.name!r} has no built-in resistivity; give "
            "'resistivity' (ohm m) or build the magnet with eddy_currents=False")
    return material.resistivity_ohm_m


_MATERIAL_SCHEMA = {
    "H": Schema(list, required=False, unit="A/m"),
    "B": Schema(list, required=False, unit="T"),
    "csv": Schema(str, required=False),
    "interpolation": Schema(str, required=False, default="smooth"),
    "resistivity": Schema(float, required=False, unit="ohm m"),
}


def _parse_materials(raw: Any, source: str = "") -> dict[str, Material]:
    """``[materials.NAME]`` tables: ``H``/``B`` lists or ``csv`` (relative to the file's folder)."""
    if raw is None:
        return {}
    if not isinstance(raw, Mapping):
        raise ParameterFileError("[materials] must hold tables like [materials.my_steel]")
    out: dict[str, Material] = {}
    for name, tab in raw.items():
        where = f"materials.{name}"
        t = take(tab, _MATERIAL_SCHEMA, where)
        lists = (t["H"] is not None) + (t["B"] is not None)
        if (lists, t["csv"] is not None) not in ((2, False), (0, True)):
            raise ParameterFileError(f"[{where}]: give the B-H points either as lists H [A/m] and "
                                     "B [T] or as csv = \"file.csv\" (columns H [A/m], B [T])")
        try:
            if t["csv"] is not None:
                path = Path(t["csv"])
                if not path.is_absolute() and source and Path(source).is_file():
                    path = Path(source).parent / path
                H, B = read_bh_csv(path)
            else:
                H, B = tuple(t["H"]), tuple(t["B"])
            out[normalise_name(name)] = TabulatedBH(H, B, name=name, resistivity_ohm_m=t["resistivity"],
                                                    interpolation=t["interpolation"])
        except MaterialError as exc:
            raise ParameterFileError(f"[{where}]: {exc}") from None
    return out


# ----------------------------------------------------------------- registry and loading
Builder = Callable[[Mapping[str, Any], Mapping[str, Material], ModelOptions], tuple[str, Network]]
RangeFunction = Callable[[Mapping[str, Any]], PlausibleRange]
_BUILDERS: dict[str, tuple[Builder, tuple[str, ...]]] = {}
_RANGES: dict[str, RangeFunction] = {}

#: Provenance tags a ``[provenance]`` entry must start with (README, "Parameter files").
PROVENANCE_TAGS = ("[P]", "[R]", "[E]")


def register_kind(kind: str, builder: Builder, tables: tuple[str, ...],
                  plausible_range: RangeFunction | None = None) -> None:
    """Register a builder for ``[magnet] kind = KIND``; ``tables`` are its allowed top-level
    tables; ``plausible_range`` maps the (validated) parameters to the magnet's
    :class:`PlausibleRange`."""
    _BUILDERS[kind] = (builder, tables)
    if plausible_range is not None:
        _RANGES[kind] = plausible_range


def build_magnet(parameters: Mapping[str, Any], *, options: ModelOptions | None = None,
                 source: str = "", provenance: Mapping[str, str] | None = None,
                 file_options: tuple[str, ...] | None = None) -> Magnet:
    """Build a :class:`Magnet` from a parsed parameter dictionary.

    Parameters
    ----------
    parameters : mapping
        The parsed parameter file: a ``[magnet]`` table with ``kind`` and the kind's
        tables (lengths in m, currents in A, resistivities in ohm m, as in the bundled
        TOML files).
    options : ModelOptions, optional
        Physics switches (saturation, eddy currents, ...); default all on.
    source : str
        Where the parameters came from (a file name), used in messages.
    provenance : mapping of str to str, optional
        Extra ``"table.key"`` -> provenance tag entries (``[P]``, ``[R]``, ``[E]`` ...),
        merged under the ``[provenance]`` table of ``parameters`` (which wins).
    file_options : tuple of str, optional
        The options (of :data:`FILE_OPTION_NAMES`: ``eddy_model``, ``eddy_layers``) that
        the ``[magnet]`` table sets where it has them, instead of ``options``.  Default:
        all of them when ``options`` is None, none otherwise.

    Returns
    -------
    Magnet

    Raises
    ------
    ParameterFileError
        Unknown, missing or invalid tables and values; a length that cannot be physical
        (outside :data:`MAGNET_LENGTH_PHYSICAL_M`), naming the key, the value and the limits.
    InputError
        ``options.eddy_model`` not one the kind's builder has (:func:`eddy_models_of_kind`).

    Warns
    -----
    ProvenanceWarning
        No ``[provenance]`` table, values without an entry in it (listed by name), or
        entries whose tag does not start with ``[P]``, ``[R]`` or ``[E]``.
    PlausibilityWarning
        A dimensional value outside its plausible range (:data:`MAGNET_PLAUSIBLE`; most
        likely a unit slip such as mm typed into a metre key), naming the key.
    """
    if file_options is None:
        file_options = FILE_OPTION_NAMES if options is None else ()
    unknown = sorted(set(file_options) - set(FILE_OPTION_NAMES))
    if unknown:
        raise InputError(f"file_options = {file_options!r}: {unknown} cannot come from a "
                         f"file; allowed are {', '.join(FILE_OPTION_NAMES)}")
    return _build(parameters, options=options, source=source, provenance=provenance,
                  check_provenance=True, from_file_keys=tuple(file_options))


def _build(parameters: Mapping[str, Any], *, options: ModelOptions | None, source: str,
           provenance: Mapping[str, str] | None, check_provenance: bool,
           from_file_keys: tuple[str, ...] = ()) -> Magnet:
    if options is not None and not isinstance(options, ModelOptions):
        raise InputError(f"options = {options!r}: expected a ModelOptions (e.g. "
                         "ModelOptions(saturation=False)) or None")
    options = options or ModelOptions()
    if not isinstance(parameters, Mapping) or "magnet" not in parameters:
        raise ParameterFileError(f"{source or 'parameters'}: missing the [magnet] table")
    mag = parameters["magnet"]
    if not isinstance(mag, Mapping) or "kind" not in mag:
        raise ParameterFileError(f"{source or 'parameters'}: [magnet] needs a 'kind' key; "
                                 f"known kinds: {', '.join(sorted(_BUILDERS))}")
    kind = mag["kind"]
    if not isinstance(kind, str) or kind not in _BUILDERS:
        raise ParameterFileError(f"[magnet] kind = {kind!r} is unknown; known kinds: "
                                 f"{', '.join(sorted(_BUILDERS))}")
    builder, tables = _BUILDERS[kind]
    from_file = "eddy_model" in from_file_keys and "eddy_model" in mag
    allowed_models = eddy_models_of_kind(kind)
    if from_file and mag["eddy_model"] not in EDDY_MODELS:     # a slip: name this kind's
        raise ParameterFileError(f"{source or 'parameters'}: [magnet] eddy_model = "
                                 f"{mag['eddy_model']!r}; allowed for kind {kind!r} are "
                                 f"{', '.join(map(repr, allowed_models))}")
    options = _file_options(options, mag, source or "parameters", from_file_keys)
    if options.eddy_model not in allowed_models:
        error = ParameterFileError if from_file else InputError
        raise error(f"{source or 'parameters'}: [magnet] " * from_file
                    + f"eddy_model = {options.eddy_model!r} is not available for kind "
                    f"{kind!r}: use {' or '.join(map(repr, reversed(allowed_models)))} "
                    f"('ladder': kinds {', '.join(LADDER_KINDS)}; 'ladder_split': "
                    f"kind {', '.join(LADDER_SPLIT_KINDS)})")
    allowed = {"magnet", "materials", "provenance", "operating", "calibration", "reduced",
               *tables}
    unknown = sorted(set(parameters) - allowed)
    if unknown:
        raise ParameterFileError(f"unknown table(s) {unknown}; a {kind!r} file may have: "
                                 f"{', '.join(sorted(allowed))}")
    materials = _parse_materials(parameters.get("materials"), source)
    prov = dict(provenance or {})
    raw_prov = parameters.get("provenance", {})
    if not isinstance(raw_prov, Mapping):
        raise ParameterFileError("[provenance] must map 'table.key' to a tag string")
    if "operating" in parameters:
        take(parameters["operating"], OPERATING_SCHEMA, "operating")
    if "reduced" in parameters:
        _reduced_table(parameters["reduced"], source)
    if check_provenance:
        _warn_eddy_keys(parameters, options, source or "parameters", from_file_keys)
    factors, factor_tags = read_calibration(parameters.get("calibration"), source)
    if check_provenance:   # a first build (not with_options): warn once, before the builder
        # can refuse the value without naming its key (a unit slip is the likely cause)
        check_plausible(parameters, MAGNET_PLAUSIBLE, source or "parameters", stacklevel=4,
                        error=ParameterFileError)
    try:
        # the file's option keys are read above; the builders' [magnet] schemas lack them
        name, network = builder({**parameters, "magnet": {
            k: v for k, v in mag.items() if k not in FILE_OPTION_NAMES}}, materials, options)
    except ParameterFileError as exc:
        if not str(exc).startswith("[magnet]: unknown key(s)"):
            raise
        # the builder's schema lacks the option keys read above: list them as allowed too
        raise ParameterFileError(f"{exc}, {', '.join(FILE_OPTION_NAMES)}") from None
    except (ParameterError, MaterialError) as exc:
        hint = ""
        if "eddy-current element" in str(exc):
            # the element is internal: say which file values make it
            hint = ("; an eddy-current element's conductance comes from the material's "
                    "resistivity and the section and length of its iron part: one of those "
                    "values is absurd (a warning above names the key when one lies outside "
                    "its plausible range)")
        raise ParameterFileError(f"{source or 'parameters'}: {exc}{hint}") from None
    # After the builder, so that a missing or misspelt value is reported as such rather
    # than as a provenance entry that names nothing.
    for key, tag in raw_prov.items():
        table, _, sub = str(key).partition(".")
        if table not in parameters or not isinstance(parameters[table], Mapping) \
                or sub not in parameters[table]:
            raise ParameterFileError(f"[provenance] {key!r} names no value of this file")
        if not isinstance(tag, str):
            raise ParameterFileError(f"[provenance] {key!r} = {tag!r}: expected a string "
                                     f"starting with one of {', '.join(PROVENANCE_TAGS)}")
        prov[str(key)] = tag
    if check_provenance:
        _warn_provenance(parameters, raw_prov, source)
    # The physics switches hold for every kind, whether or not its builder reads them.
    network = network.with_options(saturation=options.saturation,
                                   eddy_currents=options.eddy_currents)
    if factors:   # a calibrated file: its fitted factors on the built network
        network = with_factors(network, factors,
                               where=f"{source or 'parameters'}: [calibration]")
        prov.update(factor_tags)
        name = f"{name} (calibrated)"
    ranges = _RANGES.get(kind)
    return Magnet(name=name, kind=kind, network=network, parameters=_plain(parameters),
                  provenance=prov, options=options, source=source,
                  plausible_range=None if ranges is None else ranges(parameters))


def _file_options(options: ModelOptions, mag: Mapping[str, Any], source: str,
                  keys: tuple[str, ...]) -> ModelOptions:
    """``options`` with the options named in ``keys`` (of :data:`FILE_OPTION_NAMES`: the
    ones the caller did not give) taken from the file's ``[magnet]`` table ``mag`` where it
    has them.

    Raises
    ------
    ParameterFileError
        A file value that :class:`ModelOptions` refuses, naming the key.
    """
    chosen = {key: mag[key] for key in keys if key in mag}
    try:
        return replace(options, **chosen)
    except InputError as exc:
        raise ParameterFileError(f"{source}: [magnet] {exc}") from None


#: The fewest ladder layers checked against a FEM (docs/validation_fem.md: 4, 6 and 8
#: layers on the U-magnet, TR09 and guidance cuts; 4 already at the edge of the 5 % t63
#: aim): a file with fewer is warned.
LADDER_LAYERS_CHECKED_MIN = 4


def _warn_eddy_keys(parameters: Mapping[str, Any], options: ModelOptions, label: str,
                    from_file_keys: tuple[str, ...]) -> None:
    """PlausibilityWarning for a file's eddy keys that do nothing or leave what was checked.

    Only the file's own choices are judged (an option given to :func:`load_magnet` wins
    over the file and is taken as meant): ``eddy_layers`` with a model that has no ladder,
    fewer than :data:`LADDER_LAYERS_CHECKED_MIN` layers, and ``[reduced] eddy_modes > 0``
    on lumped eddy elements (the network is identified from the ladder's diffusion; on a
    lumped element it followed the TR09 magnet's gap motion no better than eq. 8:
    27.7 against 24.8 % current error at 50 Hz, docs/decisions.md, switch26m).
    """
    mag = parameters["magnet"]
    model_from_file = "eddy_model" in from_file_keys
    ladder = options.eddy_model != "lumped"          # EDDY_MODELS' ladders
    if "eddy_layers" in mag and "eddy_layers" in from_file_keys:
        if model_from_file and not ladder:
            warnings.warn(f"{label}: [magnet] eddy_layers = {mag['eddy_layers']!r} has no "
                          f"effect with eddy_model = {options.eddy_model!r}; it sets the "
                          "layers of eddy_model = 'ladder' (or 'ladder_split')",
                          PlausibilityWarning, stacklevel=5)
        elif ladder and options.eddy_layers < LADDER_LAYERS_CHECKED_MIN:
            warnings.warn(f"{label}: [magnet] eddy_layers = {options.eddy_layers}: the "
                          f"ladder was checked against a FEM with "
                          f"{LADDER_LAYERS_CHECKED_MIN} ... {max(LADDER_COEFFICIENTS)} "
                          "layers (6 for the TR09 "
                          "magnets, 8 for the guidance magnet); fewer resolve the "
                          "diffusion too coarsely", PlausibilityWarning, stacklevel=5)
    reduced = parameters.get("reduced")
    if model_from_file and options.eddy_currents and not ladder \
            and isinstance(reduced, Mapping) and reduced.get("eddy_modes", 0) not in (0, None):
        warnings.warn(f"{label}: [reduced] eddy_modes = {reduced['eddy_modes']!r} with "
                      f"eddy_model = {options.eddy_model!r}: the eddy network is meant for "
                      "the diffusing ladder (eddy_model = 'ladder'); on lumped eddy "
                      "elements it followed gap motion no better than eq. 8 (eddy_modes = "
                      "0; TR09 at 50 Hz: 27.7 against 24.8 %)",
                      PlausibilityWarning, stacklevel=5)


def _warn_provenance(parameters: Mapping[str, Any], raw_prov: Mapping[str, Any],
                     source: str) -> None:
    """ProvenanceWarning for values without a provenance entry and for malformed tags.

    Every value of every table needs an entry ``"table.key"`` (a ``[materials.NAME]``
    table: ``"materials.NAME"``), except the identity keys ``magnet.kind`` and
    ``magnet.name``.
    """
    label = source or "parameters"
    # [calibration] carries its own provenance ([calibration.provenance], read_calibration)
    needed = [f"{table}.{key}" for table, values in parameters.items()
              if table not in ("provenance", "calibration") and isinstance(values, Mapping)
              for key in values
              if not (table == "magnet" and key in ("kind", "name"))]
    missing = [k for k in needed if k not in raw_prov]
    if "provenance" not in parameters:
        warnings.warn(f"{label}: no [provenance] table; every value should carry a tag "
                      f"({', '.join(PROVENANCE_TAGS)}: published, widely quoted, estimate), "
                      f"e.g. \"{needed[0] if needed else 'magnet.turns'}\" = \"[E] estimate\"",
                      ProvenanceWarning, stacklevel=4)
    elif missing:
        warnings.warn(f"{label}: [provenance] has no entry for {', '.join(missing)}; every "
                      f"value should carry a tag ({', '.join(PROVENANCE_TAGS)})",
                      ProvenanceWarning, stacklevel=4)
    bad = [k for k, tag in raw_prov.items() if not str(tag).startswith(PROVENANCE_TAGS)]
    if bad:
        warnings.warn(f"{label}: [provenance] tag(s) of {', '.join(map(str, bad))} do not start "
                      f"with {', '.join(PROVENANCE_TAGS)}", ProvenanceWarning, stacklevel=4)


CALIBRATION_KEYS = ("data_sha256", "residual_rms", "undetermined", "confidence_95",
                    "provenance")
"""Keys of a ``[calibration]`` table besides the factors of
:data:`~maglevkit.circuit.factors.PARAMETERS` (written by
:func:`maglevkit.calibration.write_calibrated_toml`)."""


def read_calibration(table: Any, source: str = "") -> tuple[dict[str, float], dict[str, str]]:
    """The factors of a parameter file's ``[calibration]`` table and their provenance.

    Parameters
    ----------
    table : mapping or None
        The ``[calibration]`` table (None: an uncalibrated file): factor names of
        :data:`~maglevkit.circuit.factors.PARAMETERS` with their values (unit of the
        factor), ``data_sha256`` (the fitted data file's SHA-256), ``residual_rms``,
        ``undetermined``, ``[calibration.confidence_95]`` and ``[calibration.provenance]``
        (a ``calibrated ...`` tag per factor).
    source : str
        The file, for messages.

    Returns
    -------
    factors : dict
        Factor name -> value.
    provenance : dict
        ``"calibration.NAME"`` -> tag, per factor.

    Raises
    ------
    ParameterFileError
        An unknown key, a value that is not a finite number within the factor's bounds, a
        provenance entry for no factor, or a factor without a ``calibrated`` tag.
    """
    if table is None:
        return {}, {}
    where = f"{source or 'parameters'}: [calibration]"
    if not isinstance(table, Mapping):
        raise ParameterFileError(f"{where} must be a table")
    unknown = sorted(set(table) - set(PARAMETERS) - set(CALIBRATION_KEYS))
    if unknown:
        raise ParameterFileError(f"{where}: unknown key(s) {unknown}; allowed are the factors "
                                 f"{', '.join(PARAMETERS)} and {', '.join(CALIBRATION_KEYS)}")
    factors: dict[str, float] = {}
    for name in (k for k in table if k in PARAMETERS):
        v, spec = table[name], PARAMETERS[name]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or not spec.lower <= v <= spec.upper:
            raise ParameterFileError(f"{where} {name} = {v!r}: expected a number in "
                                     f"[{spec.lower:g}, {spec.upper:g}] {spec.unit}")
        factors[name] = float(v)
    tags = table.get("provenance", {})
    if not isinstance(tags, Mapping):
        raise ParameterFileError(f"{where}.provenance must map factor names to tags")
    stray = sorted(set(tags) - set(factors))
    if stray:
        raise ParameterFileError(f"{where}.provenance: {stray} name no factor of the table")
    untagged = sorted(n for n in factors if not str(tags.get(n, "")).startswith("calibrated"))
    if untagged:
        raise ParameterFileError(f"{where}: factor(s) {untagged} lack a 'calibrated ...' tag "
                                 "in [calibration.provenance] (which data fixed them?)")
    sha = table.get("data_sha256", "")
    prov = {f"calibration.{n}": str(tags[n]) for n in factors}
    if sha:
        prov["calibration.data_sha256"] = str(sha)
    return factors, prov


def _plain(obj: Any) -> Any:
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_plain(v) for v in obj]
    return obj


def bundled_magnets() -> list[str]:
    """Names of the parameter files shipped with maglevkit."""
    return bundled_files("")


def load_magnet(source: str | Path, *, saturation: bool = True, fringing: bool = True,
                leakage: bool = True, eddy_currents: bool = True, eddy_model: str | None = None,
                eddy_layers: int | None = None) -> Magnet:
    """Load a magnet from a TOML file path or a bundled name (e.g. ``"u-magnet"``).

    Parameters
    ----------
    source : str or path
        A bundled name (:func:`bundled_magnets`) or a ``.toml`` file.
    saturation, fringing, leakage, eddy_currents : bool
        Physics switches (:class:`ModelOptions`); True or False only.
    eddy_model : str
        ``"lumped"``, ``"ladder"`` (diffusing eddy currents, ``eddy_layers`` nested tubes
        per iron part) or ``"ladder_split"`` (the ladder, U-magnet rail split under and
        between the poles); :class:`ModelOptions`.  None (default): the file's
        ``[magnet] eddy_model``, else ``"lumped"``.
    eddy_layers : int or None
        Tubes per iron part of the ladder (1 ... 8); None (default): the file's
        ``[magnet] eddy_layers``, else 6.

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    InputError
        ``source`` is not a name or path, a switch is not True/False, an unknown
        ``eddy_model`` or one the magnet's kind lacks (:func:`eddy_models_of_kind`), or
        ``eddy_layers`` not a whole number in 1 ... 8.

    Warns
    -----
    ProvenanceWarning
        The file lacks provenance entries (see :func:`build_magnet`).
    PlausibilityWarning
        A dimensional value far outside its plausible range (see :func:`build_magnet`).
    """
    default = ModelOptions()   # the options the file does not set
    options = ModelOptions(saturation=saturation, fringing=fringing, leakage=leakage,
                           eddy_currents=eddy_currents,
                           eddy_model=default.eddy_model if eddy_model is None else eddy_model,
                           eddy_layers=default.eddy_layers if eddy_layers is None
                           else eddy_layers)
    from_file = tuple(k for k, v in (("eddy_model", eddy_model), ("eddy_layers", eddy_layers))
                      if v is None)
    params, label = read_parameter_file(source, what="magnet")
    try:
        return build_magnet(params, options=options, source=label, file_options=from_file)
    except ParameterFileError as exc:   # every message names the file (as a vehicle's)
        if str(exc).startswith(label):
            raise
        raise type(exc)(f"{label}: {exc}") from None
