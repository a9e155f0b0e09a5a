"""Design optimisation of a magnet's geometry and coil (issue 25, part 3; docs/design.md).

The geometry and turns of a lumped U-magnet or of a levitation magnet (TR09) -- on the
network its file chooses (``flux_paths``: the U-magnet's ``"standard"`` or ``"split"``, the
levitation magnet's ``"paper"`` or the FEM-checked ``"split"``, with the file's
``end_effects``) or the spec's ``[design] flux_paths`` -- a user-chosen subset of the kind's variables
(:data:`KIND_VARIABLES`, with bounds) -- are optimised for an objective -- magnet mass
(iron + conductor) or resistive power at the nominal operating point -- under constraints
from a design spec (:func:`read_design_spec`).  Every circuit carries the same current:

* ``force_nominal``: the force per circuit (the magnet's force over its circuits; the
  TR09's half magnet) at ``nominal_gap_m`` equals ``force_N``; the current that holds
  it is the nominal current ``I_n`` (an optimisation variable);
* ``force_reserve``: at ``reserve_gap_m`` the coils at the peak current density
  ``peak_current_density_A_per_m2`` pull at least ``reserve_factor * force_N`` per circuit;
* ``flux_density``: ``|B|`` in every iron path of the magnet (U-magnet: legs, yoke, not
  the rail; levitation magnet: pole cores and pole back, not the stator) at the nominal
  point is at most ``max_flux_density_T``;
* ``current_density``: ``N_c I_n / (k_fill h_c t_c)`` at most
  ``current_density_A_per_m2`` (continuous rating; ``N_c`` the turns through one coil
  section: ``N/2`` per U-magnet leg, ``turns_per_pole``);
* ``voltage``: ``U = R I_n + L~ dI/dt + |dpsi/ds| v`` at most ``supply_voltage_V`` for
  circuit 1, with ``L~ = dpsi/dI`` and ``dpsi/ds`` of the statics at the nominal point
  (all currents and all gaps together), ``v = gap_rate_m_per_s`` and ``dI/dt =
  current_rate_A_per_s``: the chopper must hold the current against the gap moving at
  ``v`` while ramping it at ``dI/dt``;
* geometry (each only when a variable enters it): U-magnet: the coil fits its leg, the two
  coils fit the window, the magnet fits its rail; levitation magnet: the coil fits its
  core (``coil_height + coil_to_face <= core_height``), two coils fit between neighbouring
  cores (``2 coil_thickness + window_clearance_m <= pole_pitch - pole_length``), the
  stator covers the face (``pole_width <= stator.width``), the LIG grooves leave a face.

Gradients are exact (CasADi AD) by the *simultaneous* approach: the loop fluxes of the
network at the two static points are NLP variables and the network's loop law
``r(x; s, I, p) = 0`` (:func:`maglevkit.circuit.assembly.assemble` of the kind's one
builder, :func:`maglevkit.magnets.u_magnet.lumped_network` or
:func:`maglevkit.magnets.levitation.levitation_network`, evaluated with CasADi symbols for
the geometry) is an equality constraint; ``L~`` and ``dpsi/ds`` are ``psi_x y + psi_q``
with the implicit derivatives ``y = dx/dq`` (``q = (I, s)``) as NLP variables too, under
their linear law ``r_x y + r_q = 0``.  IPOPT (``nlpsol("ipopt")``) solves the NLP.  The
levitation builder's comparisons of geometry values are decided at the start and checked
at the optimum (:class:`~maglevkit.magnets.levitation.GeometryBranches`; decided again
there once, else refused).  :func:`design_sensitivities` gives the same statics' exact
design derivatives by the nested route (CasADi ``rootfinder``, implicit function
theorem), as calibration does.

The windings (docs/design.md): U-magnet (both legs in series, ``N/2`` turns each): mean
turn ``l_t = 2 (w_p + d) + pi t_c``, ``R = rho_el N^2 l_t / (2 k_fill h_c t_c)``, conductor
mass ``2 k_fill h_c t_c l_t rho_m,c``; iron mass ``(2 w_p h_l + (w_w + 2 w_p) t_y) d
rho_m,fe``.  Levitation magnet (``P`` poles, one coil of ``N`` turns per pole core
``l_p x w_p``): ``l_t = 2 (l_p + w_p) + pi t_c``, ``R_pole = rho_el N^2 l_t / (k_fill h_c
t_c)``, conductor mass ``P k_fill h_c t_c l_t rho_m,c``, iron mass ``P (l_p w_p h_core +
tau h_b w_b) rho_m,fe`` (cores and the pole back along the magnet's ``P tau``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ._interrupt import sigint_received
from .errors import InputError, MaglevkitError, MaglevkitWarning, ParameterFileError
from .magnets.base import MAGNET_PLAUSIBLE
from .validation import Plausible, check_plausible, real_number

__all__ = ["VARIABLES", "KIND_VARIABLES", "OBJECTIVES", "DESIGN_PLAUSIBLE", "DesignSpec",
           "DesignConstraint", "DesignResult", "DesignSpecError", "read_design_spec",
           "design_magnet", "design_parameters",
           "design_sensitivities", "evaluate_design", "write_design_toml", "pareto_front",
           "plot_pareto"]


class DesignSpecError(ParameterFileError):
    """A design spec is malformed: unknown, missing or bad keys (the message names the key,
    its value and what is allowed)."""


KIND_VARIABLES: dict[str, dict[str, str]] = {
    "u_magnet": {
        "pole_width": "m",
        "depth": "m",
        "leg_height": "m",
        "yoke_thickness": "m",
        "window_width": "m",
        "coil_thickness": "m",
        "coil_height": "m",
        "turns": "-",
    },
    "levitation_magnet": {
        "pole_width": "m",
        "pole_length": "m",
        "core_height": "m",
        "coil_height": "m",
        "coil_thickness": "m",
        "back_height": "m",
        "back_width": "m",
        "turns_per_pole": "-",
    },
}
"""Design variables per magnet kind (keys of the magnet's ``[magnet]`` table) and their
units.  The turns (``turns``, ``turns_per_pole``) are optimised as a real number and
rounded in the written file."""

VARIABLES: dict[str, str] = {k: u for kv in KIND_VARIABLES.values() for k, u in kv.items()}
"""Every design variable of any kind (:data:`KIND_VARIABLES`) and its unit."""


OBJECTIVES = ("mass", "power")
"""``mass``: iron + conductor [kg]; ``power``: ``R I_n^2`` of all circuits at the nominal
point [W]."""

# spec keys: (unit, default or None = required, lower bound (exclusive?), description)
_REQUIREMENTS: dict[str, tuple[str, float | None, float, bool]] = {
    "nominal_gap_m": ("m", None, 0.0, True),
    "force_N": ("N", None, 0.0, True),
    "reserve_gap_m": ("m", None, 0.0, True),
    "reserve_factor": ("-", 1.0, 0.0, True),
    "max_flux_density_T": ("T", None, 0.0, True),
    "current_density_A_per_m2": ("A/m^2", None, 0.0, True),
    "peak_current_density_A_per_m2": ("A/m^2", None, 0.0, True),
    "supply_voltage_V": ("V", None, 0.0, True),
    "gap_rate_m_per_s": ("m/s", 0.0, 0.0, False),
    "current_rate_A_per_s": ("A/s", 0.0, 0.0, False),
    "window_clearance_m": ("m", 0.002, 0.0, True),
}
_COIL: dict[str, tuple[str, float | None, float, bool]] = {
    "conductor_resistivity_ohm_m": ("ohm m", 1.72e-8, 0.0, True),
    "fill_factor": ("-", 0.6, 0.0, True),
    "iron_density_kg_per_m3": ("kg/m^3", 7850.0, 0.0, True),
    "conductor_density_kg_per_m3": ("kg/m^3", 8960.0, 0.0, True),
}
_RENAMED = {"copper_resistivity_ohm_m": "conductor_resistivity_ohm_m",
            "copper_density_kg_per_m3": "conductor_density_kg_per_m3"}
COIL_DEFAULTS = {k: v[1] for k, v in _COIL.items()}
"""Defaults of the ``[coil]`` table: annealed copper at 20 C (1.72e-8 ohm m, 8960 kg/m^3),
steel 7850 kg/m^3, conductor fill factor 0.6 of the winding cross-section (an estimate for
round wire).  The conductor keys name no metal: the TR09 coils are aluminium strip."""

#: The plausible magnitudes of a design spec's dimensional keys
#: (:func:`~maglevkit.validation.check_plausible`): a value outside is most likely a unit
#: slip (mm typed into a metre key, kN into a newton key, A/mm^2 into A/m^2, gauss into
#: tesla) and warns.  The bundled spec lies inside and the same spec with any one value
#: times 1000 or 1/1000 outside; the variables' bounds take the magnet file's ranges.
#: Values that cannot be physical are refused before solving (``physical_low`` /
#: ``physical_high``): a gap above 1 m (metres for millimetres: ``nominal_gap_m = 10``
#: ran IPOPT's 500 iterations, review25), a flux density in the iron above 10 T (iron
#: saturates near 2 T; 15000 is gauss), a force reserve below 1 (the magnet at its peak
#: current would not hold its own nominal force: no reserve).
DESIGN_PLAUSIBLE: dict[str, Plausible] = {
    "requirements.nominal_gap_m": Plausible(
        1e-3, 0.1, "m", physical_high=1.0,
        physical_note="an electromagnet's gap of a metre or more is no gap"),
    "requirements.reserve_gap_m": Plausible(
        1e-3, 0.1, "m", physical_high=1.0,
        physical_note="an electromagnet's gap of a metre or more is no gap"),
    "requirements.force_N": Plausible(1.0, 2e5, "N"),
    "requirements.reserve_factor": Plausible(
        1.0, 10.0, "-", physical_low=1.0,
        physical_note="a force reserve below 1 does not hold the nominal force"),
    "requirements.max_flux_density_T": Plausible(
        0.1, 2.5, "T", physical_high=10.0,
        physical_note="iron saturates near 2 T"),
    "requirements.current_density_A_per_m2": Plausible(1e5, 1e8, "A/m^2"),
    "requirements.peak_current_density_A_per_m2": Plausible(1e5, 1e8, "A/m^2"),
    "requirements.supply_voltage_V": Plausible(1.0, 1e4, "V"),
    "requirements.gap_rate_m_per_s": Plausible(1e-3, 10.0, "m/s"),
    "requirements.window_clearance_m": Plausible(2e-4, 0.5, "m"),
    "coil.conductor_resistivity_ohm_m": Plausible(1e-8, 1e-5, "ohm m"),
    "coil.fill_factor": Plausible(0.05, 1.0, "-"),
    "coil.iron_density_kg_per_m3": Plausible(1e3, 3e4, "kg/m^3"),
    "coil.conductor_density_kg_per_m3": Plausible(1e3, 3e4, "kg/m^3"),
    **{f"variables.{k}": MAGNET_PLAUSIBLE[f"magnet.{k}"] for k, u in VARIABLES.items()
       if u == "m"},
}
# the deprecated [coil] names (_RENAMED) are checked with their new key's range: the check
# runs on the file before the old names are mapped to the new ones
DESIGN_PLAUSIBLE.update({f"coil.{old}": DESIGN_PLAUSIBLE[f"coil.{new}"]
                         for old, new in _RENAMED.items()})

FORCE_PLAUSIBLE_FACTOR = 100.0
"""A spec's ``force_N`` more than this factor away from the base magnet's force per
circuit at its ``[operating]`` point warns (a unit slip: kN typed into the newton key); a
design a hundred times stronger or weaker than its base is another magnet."""

GEOMETRY_MARGIN_M = 1e-9
"""The geometry constraints hold with this margin [m], so that the written file passes the
loader's strict checks (IPOPT meets constraints to ~1e-10 m here, from either side)."""

ACTIVE_TOL = 1e-6
"""A constraint is reported active when its relative slack (slack / its bound) is at most
this: IPOPT stops at a relative tolerance of 1e-10 here, so a slack of 1e-6 is far from
rounding and far below any margin a user would call slack."""


@dataclass(frozen=True)
class DesignSpec:
    """A design problem (:func:`read_design_spec`).

    Attributes
    ----------
    magnet : Magnet
        The base U-magnet (its fixed geometry, material, rail; start of the search).
    objective : str
        One of :data:`OBJECTIVES`.
    variables : dict
        Design variable -> (lower, upper) bounds [m, turns -].
    requirements : dict
        The ``[requirements]`` values (SI, module docstring).
    coil : dict
        The ``[coil]`` values (resistivity [ohm m], fill factor [-], densities [kg/m^3]).
    provenance : dict
        ``"table.key"`` -> tag of the spec's values.
    source : str
        The spec file.
    """

    magnet: Any
    objective: str
    variables: dict[str, tuple[float, float]]
    requirements: dict[str, float]
    coil: dict[str, float]
    provenance: dict[str, str] = field(default_factory=dict)
    source: str = "<memory>"

    @property
    def kind(self) -> str:
        """The base magnet's kind (a key of :data:`KIND_VARIABLES`)."""
        return str(self.magnet.parameters["magnet"]["kind"])


def _number(table: Mapping[str, Any], key: str, where: str,
            schema: tuple[str, float | None, float, bool]) -> float:
    unit, default, lower, strict = schema
    if key not in table:
        if default is None:
            raise DesignSpecError(f"[{where}] missing required key {key!r} [{unit}]")
        return float(default)
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise DesignSpecError(f"[{where}] {key} = {v!r}: expected a finite number [{unit}]")
    if (v <= lower) if strict else (v < lower):
        raise DesignSpecError(f"[{where}] {key} = {v!r} [{unit}]: must be "
                              f"{'>' if strict else '>='} {lower:g}")
    return float(v)


def _table(doc: Mapping[str, Any], name: str) -> Mapping[str, Any]:
    t = doc.get(name, {})
    if not isinstance(t, Mapping):
        raise DesignSpecError(f"[{name}] must be a table")
    return t


def read_design_spec(source: str | Path | Mapping[str, Any], *, base_dir: str | Path = "."
                     ) -> DesignSpec:
    """Read and check a design spec (TOML file or its parsed contents).

    Tables: ``[design]`` (``magnet``: a bundled name or a parameter file, relative to the
    spec; ``objective``; optional ``flux_paths``: another of the magnet's networks than
    its file's), ``[variables]`` (``name = [lower, upper]`` per design variable
    of :data:`VARIABLES`), ``[requirements]`` (module docstring), optional ``[coil]``
    (:data:`COIL_DEFAULTS`) and ``[provenance]`` (``"table.key" = "[E] ..."``).

    Parameters
    ----------
    source : str, path or mapping
        A bundled spec name (``maglevkit list designs``), a spec file, or its parsed TOML.
    base_dir : path
        Folder that a relative ``magnet`` path is taken from when ``source`` is a mapping.

    Returns
    -------
    DesignSpec

    Raises
    ------
    DesignSpecError
        Unknown, missing or bad keys (named with their table), a value that cannot be
        physical (outside :data:`DESIGN_PLAUSIBLE`'s ``physical_low`` / ``physical_high``:
        a gap above 1 m, a flux density above 10 T, a reserve factor below 1; before
        anything is solved), bounds that are empty or
        exclude nothing feasible, a base magnet that is neither a lumped U-magnet nor a
        levitation magnet, a variable the network's geometry does not admit (one it
        decides its structure on, or one neither its statics nor the winding depend on).

    Warns
    -----
    PlausibilityWarning
        A value outside its plausible range (:data:`DESIGN_PLAUSIBLE`: most likely a unit
        slip), naming the key, its unit and the likely slip.
    """
    from .magnets import build_magnet, load_magnet
    from .parameter_files import read_parameter_file

    if isinstance(source, Mapping):
        doc, label, folder = dict(source), "<memory>", Path(base_dir)
    else:
        try:
            doc, label = read_parameter_file(source, what="design spec", folder="designs",
                                             table="design")
        except MaglevkitError as exc:
            raise DesignSpecError(str(exc)) from None
        folder = Path(label).parent if Path(label).suffix == ".toml" else Path(base_dir)
    unknown = sorted(set(doc) - {"design", "variables", "requirements", "coil", "provenance"})
    if unknown:
        raise DesignSpecError(f"unknown table(s) {unknown}; allowed: design, variables, "
                              "requirements, coil, provenance")
    # before the schema's own checks, so that a slipped value it then refuses (e.g.
    # fill_factor = 600 for 0.6) is named with its unit and likely slip first (issue 27)
    flagged = check_plausible(doc, DESIGN_PLAUSIBLE, label, stacklevel=3,
                              error=DesignSpecError)
    design = _table(doc, "design")
    bad = sorted(set(design) - {"magnet", "objective", "flux_paths"})
    if bad:
        raise DesignSpecError(f"[design] unknown key(s) {bad}; allowed: magnet, objective, "
                              "flux_paths")
    if "magnet" not in design or not isinstance(design["magnet"], str):
        raise DesignSpecError("[design] magnet: expected a bundled magnet name (e.g. "
                              "\"u-magnet\") or a parameter file path")
    objective = design.get("objective", "mass")
    if objective not in OBJECTIVES:
        raise DesignSpecError(f"[design] objective = {objective!r}: expected one of "
                              f"{list(OBJECTIVES)}")
    name = design["magnet"]
    ref = folder / name if name.endswith(".toml") and not Path(name).is_absolute() else name
    try:
        magnet = load_magnet(ref)       # its provenance and plausibility warnings show
    except MaglevkitError as exc:
        raise DesignSpecError(f"[design] magnet = {name!r}: {exc}") from None
    params = magnet.parameters
    kind = params["magnet"].get("kind")
    if "flux_paths" in design:
        # another of the magnet's own networks than its file's (named in the spec, never
        # silently): the levitation magnet's "paper" / "split", the U-magnet's "standard" /
        # "split" (lumped discretisation)
        paths = _flux_paths_of(kind)
        if design["flux_paths"] not in paths:
            raise DesignSpecError(f"[design] flux_paths = {design['flux_paths']!r}: expected "
                                  f"one of {list(paths)} for magnet = {name!r} (a {kind}); "
                                  "omit it to design on the file's own network")
        p = {k: dict(v) if isinstance(v, Mapping) else v for k, v in params.items()}
        p["magnet"]["flux_paths"] = design["flux_paths"]
        if kind == "levitation_magnet" and design["flux_paths"] != "split":
            p["magnet"].pop("coil_segments", None)      # a key of the split network only
        p.setdefault("provenance", {})["magnet.flux_paths"] = "[E] design spec: [design] flux_paths"
        magnet = build_magnet(p, source=str(ref))
        params = magnet.parameters
    if (kind == "u_magnet" and params["magnet"].get("discretisation", "lumped") != "lumped") \
            or kind not in KIND_VARIABLES:
        raise DesignSpecError(f"[design] magnet = {name!r}: design optimisation supports the "
                              "U-magnet's lumped network (kind = \"u_magnet\", discretisation "
                              "= \"lumped\"; flux_paths \"standard\" or \"split\") and the "
                              "levitation magnet (kind = \"levitation_magnet\", flux_paths "
                              "\"paper\" or \"split\")")
    allowed = KIND_VARIABLES[kind]
    if "calibration" in params:
        # the design rebuilds the network from the geometry: the factors would be lost
        raise DesignSpecError(f"[design] magnet = {name!r} is calibrated ([calibration] "
                              f"{sorted(magnet.calibration)}); design optimisation rebuilds the "
                              "network from the geometry without calibration factors: give "
                              "the uncalibrated file")
    variables: dict[str, tuple[float, float]] = {}
    vt = _table(doc, "variables")
    if not vt:
        raise DesignSpecError(f"[variables] is empty: give at least one of {list(VARIABLES)} "
                              "as name = [lower, upper]")
    for key, b in vt.items():
        if key not in allowed:
            raise DesignSpecError(f"[variables] unknown design variable {key!r} for a "
                                  f"{kind}; the documented set: {list(allowed)}")
        if (not isinstance(b, list) or len(b) != 2
                or any(isinstance(x, bool) or not isinstance(x, (int, float))
                       or not math.isfinite(x) for x in b)):
            raise DesignSpecError(f"[variables] {key} = {b!r}: expected [lower, upper] "
                                  f"[{allowed[key]}]")
        lo, hi = float(b[0]), float(b[1])
        if not 0.0 < lo < hi:
            raise DesignSpecError(f"[variables] {key} = {b!r}: expected 0 < lower < upper "
                                  f"[{allowed[key]}]")
        if key == "turns" and lo < 2.0:
            raise DesignSpecError(f"[variables] turns = {b!r}: at least 2 turns (one per leg)")
        if key == "turns_per_pole" and lo < 1.0:
            raise DesignSpecError(f"[variables] turns_per_pole = {b!r}: at least 1 turn")
        variables[key] = (lo, hi)
    _kind(kind).check_bounds(params, variables)
    rt = _table(doc, "requirements")
    bad = sorted(set(rt) - set(_REQUIREMENTS))
    if bad:
        raise DesignSpecError(f"[requirements] unknown key(s) {bad}; allowed: "
                              f"{', '.join(_REQUIREMENTS)}")
    req = {k: _number(rt, k, "requirements", s) for k, s in _REQUIREMENTS.items()}
    if "requirements.force_N" not in flagged and "operating" in params:
        # the generic 1 N - 200 kN spans both kinds; against the base magnet's own force
        # at its operating point a kN-for-N slip of a TR09 spec (17.47 for 17470) shows
        from .models.statics import solve_statics

        op = params["operating"]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", MaglevkitWarning)
            f0 = float(np.asarray(solve_statics(magnet, gaps_m=op["nominal_gap"],
                                                currents_A=op["nominal_current"]).force_N)
                       ) / len(magnet.network.circuits)
        check_plausible(doc, {"requirements.force_N": Plausible(
            f0 / FORCE_PLAUSIBLE_FACTOR, f0 * FORCE_PLAUSIBLE_FACTOR, "N")}, label,
            stacklevel=3)
    ct = _table(doc, "coil")
    for old, new in _RENAMED.items():
        if old not in ct:
            continue
        if new in ct:
            raise DesignSpecError(f"[coil] {old} = {ct[old]!r} and {new} = {ct[new]!r}: give "
                                  f"{new} only ({old} is its deprecated old name)")
        # the old name stays a deprecated alias for one release (the winding may be
        # aluminium, as the TR09's strip coils, so the key names no metal any more)
        warnings.warn(f"{label}: [coil] {old} is deprecated; use {new} (same value and unit)",
                      DeprecationWarning, stacklevel=3)
        ct = {**{k: v for k, v in ct.items() if k != old}, new: ct[old]}
    bad = sorted(set(ct) - set(_COIL))
    if bad:
        raise DesignSpecError(f"[coil] unknown key(s) {bad}; allowed: {', '.join(_COIL)}")
    coil = {k: _number(ct, k, "coil", s) for k, s in _COIL.items()}
    if coil["fill_factor"] > 1.0:
        raise DesignSpecError(f"[coil] fill_factor = {coil['fill_factor']!r}: must be <= 1")
    prov = _table(doc, "provenance")
    for k, v in prov.items():
        if not isinstance(v, str) or not v.startswith(("[P]", "[R]", "[E]")):
            raise DesignSpecError(f"[provenance] {k!r} = {v!r}: expected a tag starting "
                                  "with [P], [R] or [E]")
        table, _, key = k.partition(".")
        if table not in ("design", "variables", "requirements", "coil") \
                or not isinstance(doc.get(table), Mapping) or key not in doc[table]:
            raise DesignSpecError(f"[provenance] {k!r}: tags a key the spec does not give; "
                                  "expected \"table.key\" of one of its values (e.g. "
                                  "\"requirements.force_N\")")
    spec = DesignSpec(magnet=magnet, objective=objective, variables=variables,
                      requirements=req, coil=coil, provenance=dict(prov), source=label)
    # the network with the variables as symbols: refuses a variable this network's
    # geometry does not admit (DesignSpecError naming it); ~0.1-0.4 s
    _Problem(spec)
    return spec


def _flux_paths_of(kind: Any) -> tuple[str, ...]:
    """The networks (``flux_paths`` values) of a magnet kind the design can build."""
    if kind == "levitation_magnet":
        from .magnets.levitation import FLUX_PATHS as lev_paths

        return tuple(lev_paths)
    if kind == "u_magnet":
        from .magnets.u_magnet import FLUX_PATHS as u_paths

        return tuple(u_paths)
    return ()


# ---------------------------------------------------------------------------- the kinds
class _Kind:
    """What differs between the magnet kinds: the network builder, the winding's laws,
    the geometry constraints and which iron is the magnet's.  Every method works on
    numbers and on CasADi expressions alike (one law for the optimiser and the check)."""

    kind = ""
    turns_key = ""
    resistance_key = ""
    #: the table of the fixed counterpart (rail, stator) and its schema's module
    fixed_table = ""

    @property
    def variables(self) -> dict[str, str]:
        return KIND_VARIABLES[self.kind]

    def tables(self, params: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        """The checked ``[magnet]`` table and the rail's / stator's (numbers)."""
        raise NotImplementedError

    def laws(self, m: Mapping[str, Any], turns: Any, coil: Mapping[str, float]
             ) -> dict[str, Any]:
        """Winding resistance (file value, per circuit, all circuits), masses, the
        winding's cross-section and the turns through it."""
        raise NotImplementedError

    def geometry(self, m: Mapping[str, Any], fixed: Mapping[str, Any],
                 req: Mapping[str, float]) -> list[tuple[str, Any, tuple[str, ...]]]:
        """``(name, slack [m] >= 0, the variables that enter it)`` per geometry constraint."""
        raise NotImplementedError

    def magnet_iron(self, element: str) -> bool:
        """Whether an iron path belongs to the magnet (its flux density is limited)."""
        raise NotImplementedError

    def network(self, m: Mapping[str, Any], spec: DesignSpec, options: Any,
                branches: Any) -> Any:
        """The network with the (partly symbolic) ``[magnet]`` table ``m``."""
        raise NotImplementedError

    def check_bounds(self, params: Mapping[str, Any],
                     variables: Mapping[str, tuple[float, float]]) -> None:
        """Spec checks of the bounds that the kind's loader would refuse at any value."""


def _iron_material(network: Any, prefix: str) -> Any:
    from .circuit.elements import IronPath

    return next(el.material for b in network.branches for el in b.elements
                if isinstance(el, IronPath) and el.name.startswith(prefix))


class _UMagnetKind(_Kind):
    kind, turns_key, resistance_key, fixed_table = "u_magnet", "turns", "resistance", "rail"

    def tables(self, params: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        from .magnets.base import take
        from .magnets.u_magnet import MAGNET_SCHEMA, RAIL_SCHEMA

        return (take(_builder_keys(params["magnet"]), MAGNET_SCHEMA, "magnet"),
                take(params["rail"], RAIL_SCHEMA, "rail"))

    def laws(self, m: Mapping[str, Any], turns: Any, coil: Mapping[str, float]
             ) -> dict[str, Any]:
        # both legs in series, N/2 turns on each leg's coil h_c x t_c
        wp, d, hl, ty = m["pole_width"], m["depth"], m["leg_height"], m["yoke_thickness"]
        ww, tc, hc = m["window_width"], m["coil_thickness"], m["coil_height"]
        k = coil["fill_factor"]
        mean_turn = 2.0 * (wp + d) + math.pi * tc
        area = hc * tc                                           # one leg's coil section
        resistance = coil["conductor_resistivity_ohm_m"] * turns**2 * mean_turn / (2.0 * k * area)
        iron = (2.0 * wp * hl + (ww + 2.0 * wp) * ty) * d * coil["iron_density_kg_per_m3"]
        conductor = 2.0 * k * area * mean_turn * coil["conductor_density_kg_per_m3"]
        return {"resistance_ohm": resistance, "circuit_resistance_ohm": resistance,
                "total_resistance_ohm": resistance, "iron_mass_kg": iron,
                "conductor_mass_kg": conductor, "mass_kg": iron + conductor,
                "coil_area_m2": area, "coil_turns": 0.5 * turns}

    def geometry(self, m: Mapping[str, Any], fixed: Mapping[str, Any],
                 req: Mapping[str, float]) -> list[tuple[str, Any, tuple[str, ...]]]:
        return [
            ("coil_fits_leg", m["leg_height"] - m["coil_height"] - m["coil_gap_to_pole_face"],
             ("leg_height", "coil_height")),
            ("coils_fit_window", m["window_width"] - 2.0 * m["coil_thickness"]
             - req["window_clearance_m"], ("window_width", "coil_thickness")),
            ("magnet_fits_rail", fixed["width"] - m["window_width"] - 2.0 * m["pole_width"],
             ("window_width", "pole_width"))]

    def magnet_iron(self, element: str) -> bool:
        return element != "iron_rail"

    def network(self, m: Mapping[str, Any], spec: DesignSpec, options: Any,
                branches: Any) -> Any:
        from .magnets.u_magnet import lumped_network

        base = spec.magnet.network     # clips its geometry branches itself (symbolic)
        return lumped_network(m, self.tables(spec.magnet.parameters)[1],
                              _iron_material(base, "iron_yoke"),
                              _iron_material(base, "iron_rail"), options)


def _builder_keys(table: Mapping[str, Any]) -> dict[str, Any]:
    """A ``[magnet]`` table without the model options a file may set (``eddy_model``,
    ``eddy_layers``: read by ``load_magnet``, not part of the builders' schemas)."""
    from .magnets.base import FILE_OPTION_NAMES

    return {k: v for k, v in table.items() if k not in FILE_OPTION_NAMES}


class _LevitationKind(_Kind):
    kind, turns_key, resistance_key = "levitation_magnet", "turns_per_pole", "resistance_per_pole"
    fixed_table = "stator"

    def tables(self, params: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        from .magnets.base import take
        from .magnets.levitation import MAGNET_SCHEMA, STATOR_SCHEMA

        return (take(_builder_keys(params["magnet"]), MAGNET_SCHEMA, "magnet"),
                take(params["stator"], STATOR_SCHEMA, "stator"))

    def laws(self, m: Mapping[str, Any], turns: Any, coil: Mapping[str, float]
             ) -> dict[str, Any]:
        # one coil of N turns around each pole core (l_p x w_p), section h_c x t_c on
        # each side; the pole back along the magnet's length (poles x pitch)
        poles, tau = m["poles"], m["pole_pitch"]
        lp, wp, hcore = m["pole_length"], m["pole_width"], m["core_height"]
        tc, hc, hb, wb = m["coil_thickness"], m["coil_height"], m["back_height"], m["back_width"]
        k = coil["fill_factor"]
        mean_turn = 2.0 * (lp + wp) + math.pi * tc
        area = hc * tc
        r_pole = coil["conductor_resistivity_ohm_m"] * turns**2 * mean_turn / (k * area)
        per_circuit = self._poles_per_circuit(m)
        iron = poles * (lp * wp * hcore + tau * hb * wb) * coil["iron_density_kg_per_m3"]
        conductor = poles * k * area * mean_turn * coil["conductor_density_kg_per_m3"]
        return {"resistance_ohm": r_pole, "circuit_resistance_ohm": per_circuit * r_pole,
                "total_resistance_ohm": poles * r_pole, "iron_mass_kg": iron,
                "conductor_mass_kg": conductor, "mass_kg": iron + conductor,
                "coil_area_m2": area, "coil_turns": turns}

    @staticmethod
    def _poles_per_circuit(m: Mapping[str, Any]) -> int:
        # the voltage bound's circuit is the first (circuit 1); m carries its count
        return int(m["_poles_in_circuit_1"])

    def geometry(self, m: Mapping[str, Any], fixed: Mapping[str, Any],
                 req: Mapping[str, float]) -> list[tuple[str, Any, tuple[str, ...]]]:
        rows: list[tuple[str, Any, tuple[str, ...]]] = [
            ("coil_fits_core", m["core_height"] - m["coil_height"] - m["coil_to_face"],
             ("core_height", "coil_height")),
            ("coils_fit_window", m["pole_pitch"] - m["pole_length"]
             - 2.0 * m["coil_thickness"] - req["window_clearance_m"],
             ("pole_length", "coil_thickness")),
            ("stator_covers_pole", fixed["width"] - m["pole_width"], ("pole_width",))]
        if m["lig_grooves"] > 0:
            rows.append(("grooves_leave_face", m["pole_length"]
                         - m["lig_grooves"] * m["lig_groove_width"], ("pole_length",)))
        return rows

    def magnet_iron(self, element: str) -> bool:
        return element.startswith(("iron_core_", "iron_back_"))

    def network(self, m: Mapping[str, Any], spec: DesignSpec, options: Any,
                branches: Any) -> Any:
        from .magnets.levitation import levitation_network, read_circuits

        params = spec.magnet.parameters
        names, assign = read_circuits(params["circuits"], m["poles"])
        base = spec.magnet.network
        return levitation_network(m, self.tables(params)[1], names, assign,
                                  _iron_material(base, "iron_core_"),
                                  _iron_material(base, "iron_teeth_"), options, branches)

    def check_bounds(self, params: Mapping[str, Any],
                     variables: Mapping[str, tuple[float, float]]) -> None:
        m, st = self.tables(params)
        if "pole_width" in variables and variables["pole_width"][1] > st["width"]:
            raise DesignSpecError(
                f"[variables] pole_width = {list(variables['pole_width'])!r}: the upper bound "
                f"exceeds the stator width {st['width']:g} m ([stator] width of the magnet "
                "file); the stator must cover the pole face")
        grooves = m["lig_grooves"] * m["lig_groove_width"]
        if "pole_length" in variables and variables["pole_length"][0] <= grooves:
            raise DesignSpecError(
                f"[variables] pole_length = {list(variables['pole_length'])!r}: the lower "
                f"bound leaves no pole face beside the {m['lig_grooves']} LIG grooves "
                f"({grooves:g} m); expected a lower bound > {grooves:g} m")


_KINDS = {k.kind: k for k in (_UMagnetKind(), _LevitationKind())}


def _kind(kind: str) -> _Kind:
    return _KINDS[kind]


def _tables(spec_or_params: Any) -> tuple[_Kind, dict[str, Any], dict[str, Any]]:
    """The kind and the checked ``[magnet]`` (with the count of circuit 1's poles for a
    levitation magnet) and rail / stator tables of a spec's magnet or a parameter dict."""
    params = spec_or_params.magnet.parameters if isinstance(spec_or_params, DesignSpec) \
        else spec_or_params
    kd = _kind(params["magnet"]["kind"])
    m, fixed = kd.tables(params)
    if isinstance(kd, _LevitationKind):
        from .magnets.levitation import read_circuits

        _, assign = read_circuits(params["circuits"], m["poles"])
        m["_poles_in_circuit_1"] = assign.count(1)
    return kd, m, fixed


# ---------------------------------------------------------------------------- the problem
class _Problem:
    """The symbolic statics of the magnet with the design variables as CasADi symbols;
    the builder's geometry comparisons decided at the design point ``at`` (default: the
    base magnet's values clipped into the bounds)."""

    def __init__(self, spec: DesignSpec, at: Mapping[str, float] | None = None) -> None:
        import casadi as ca

        from .circuit.assembly import assemble
        from .circuit.elements import IronPath
        from .magnets.levitation import GeometryBranches

        self.spec = spec
        base = spec.magnet
        kd, m, fixed = _tables(spec)
        self.kind = kd
        self.base_geometry = {k: m[k] for k in kd.variables}
        self.fixed = fixed
        self.names = tuple(spec.variables)
        self.p = ca.SX.sym("p", len(self.names))
        self.turns0 = float(m[kd.turns_key])
        g: dict[str, Any] = dict(m)
        for k, n in enumerate(self.names):
            if n != kd.turns_key:
                g[n] = self.p[k]
        self.geometry = g
        self.turns = (self.p[self.names.index(kd.turns_key)] if kd.turns_key in self.names
                      else self.turns0)
        point = {n: float(np.clip(self.base_geometry[n], *spec.variables[n]))
                 for n in self.names}
        point.update(at or {})
        p_at = self.value_vector(point)

        def value(expr: Any) -> float:
            return float(ca.Function("branch_value", [self.p], [expr])(p_at))

        branches = GeometryBranches(value)
        options = replace(base.options, eddy_currents=False)
        network_name = f"{kd.kind}'s {m.get('flux_paths', 'lumped')!r} network"
        try:
            net = kd.network(g, spec, options, branches)
        except RuntimeError as exc:
            if "truth value" not in str(exc):
                raise
            # the builder compares a varied value outside GeometryBranches (a choice of
            # structure, e.g. deep or shallow LIG grooves): no smooth law to optimise on.
            # Which one: rebuild with one symbol at a time (only on this failure)
            culprits = []
            for k, n in enumerate(self.names):
                if n == kd.turns_key:
                    continue
                try:
                    kd.network({**m, n: self.p[k]}, spec, options, GeometryBranches(value))
                except RuntimeError as one:
                    if "truth value" in str(one):
                        culprits.append(n)
            raise DesignSpecError(
                f"[variables] {culprits or list(self.names)}: the {network_name} decides its "
                "structure on this value (a comparison the builder makes outside "
                "GeometryBranches), so it cannot be a design variable there; the documented "
                f"set: {list(kd.variables)}") from None
        self.decisions = tuple(label for label, _ in branches.taken)
        self.conditions = ca.Function("design_branches", [self.p], [ca.vertcat(
            *[e for _, e in branches.taken])] if branches.taken else [ca.DM.zeros(0, 1)])
        eq = assemble(net)
        self.n_loops = eq.x.numel()
        n_circ = len(net.circuit_names)
        force = ca.sum1(eq.force) / n_circ          # per circuit, all at the same current
        psi = eq.psi[0]
        s = ca.SX.sym("s")
        current = ca.SX.sym("I")
        subs_from = ca.vertcat(eq.s, eq.I)
        subs_to = ca.vertcat(ca.repmat(s, eq.s.numel(), 1), ca.repmat(current, n_circ, 1))
        res, force, psi = (ca.substitute(e, subs_from, subs_to)
                           for e in (eq.residual, force, psi))
        # implicit derivatives at r = 0: y = dx/dq solves r_x y = -r_q, q = (I, s); y is
        # given (NLP variables with this linear law as their equality constraint: a
        # symbolic r_x^-1 of the TR09's 34 loops made building the NLP take ~50 s)
        q = ca.vertcat(current, s)
        nl = eq.x.numel()
        y_i, y_s = ca.SX.sym("y_I", nl), ca.SX.sym("y_s", nl)
        r_x, r_q = ca.jacobian(res, eq.x), ca.jacobian(res, q)
        sens = ca.vertcat(r_x @ y_i + r_q[:, 0], r_x @ y_s + r_q[:, 1])
        psi_x, psi_q = ca.jacobian(psi, eq.x), ca.jacobian(psi, q)
        dpsi = (psi_x @ y_i + psi_q[0], psi_x @ y_s + psi_q[1])
        flux_b = ca.substitute(eq.phi, subs_from, subs_to)
        b_names, b_expr = [], []
        for j, br in enumerate(net.branches):
            for el in br.elements:
                if isinstance(el, IronPath) and kd.magnet_iron(el.name):
                    b_names.append(el.name)
                    b_expr.append(flux_b[j] / el.cross_section_m2)
        self.iron_names = tuple(b_names)
        # statics of the network with turns0 at the effective current I N / N0
        self.point = ca.Function("design_point", [eq.x, s, current, self.p, y_i, y_s],
                                 [res, force, psi, sens, dpsi[0], dpsi[1], ca.vertcat(*b_expr)],
                                 ["x", "s", "I", "p", "y_I", "y_s"],
                                 ["r", "F", "psi", "r_y", "L", "dpsi_ds", "B"])
        self.jacobians = ca.Function("design_jacobians", [eq.x, s, current, self.p],
                                     [r_x, r_q])
        self.residual = ca.Function("design_residual", [eq.x, ca.vertcat(s, current, self.p)],
                                    [res])
        self.outputs = ca.Function("design_outputs", [eq.x, ca.vertcat(s, current, self.p)],
                                   [force, psi])
        self.laws = kd.laws(g, self.turns, spec.coil)
        # every varied geometry value must enter the network's statics or the winding's
        # laws: one that enters neither is not a dimension of this network (the objective
        # and constraints would be flat in it)
        entered = ca.vertcat(res, force, psi, ca.vertcat(*b_expr),
                             *[self.laws[k] for k in ("mass_kg", "total_resistance_ohm")])
        idle = [n for k, n in enumerate(self.names)
                if n != kd.turns_key and not ca.depends_on(entered, self.p[k])]
        if idle:
            raise DesignSpecError(
                f"[variables] {idle}: the {network_name} and the winding's laws do not "
                "depend on it, so it is no dimension of this network; the documented set: "
                f"{list(kd.variables)}")
        self.laws_fun = ca.Function("design_laws", [self.p], [self.laws[k] for k in (
            "circuit_resistance_ohm", "mass_kg", "coil_area_m2", "coil_turns",
            "total_resistance_ohm")])

    def value_vector(self, values: Mapping[str, float]) -> np.ndarray:
        return np.array([float(values[n]) for n in self.names])


def design_parameters(spec: DesignSpec, values: Mapping[str, float], *,
                      provenance: str = "") -> dict[str, Any]:
    """The magnet parameter file (as a dict) of a design: the base magnet's parameters with
    the design ``values`` (turns rounded to a whole number) and the winding resistance of
    the coil geometry (module docstring).

    Parameters
    ----------
    spec : DesignSpec
        The design problem.
    values : mapping
        Design variable -> value [m, turns -]; missing variables keep the base value.
    provenance : str
        Tag (after ``[E]`` and a space) for every changed value; empty: keep the base's tags.

    Returns
    -------
    dict
        TOML-ready parameters (``magnet``, ``rail``, ``provenance`` ...).

    Raises
    ------
    InputError
        An unknown variable, or a value that is not a finite number > 0 (named).
    """
    kd = _kind(spec.kind)
    unknown = sorted(set(values) - set(kd.variables))
    if unknown:
        raise InputError(f"design values: unknown variable(s) {unknown} for a {kd.kind}; the "
                         f"documented set: {list(kd.variables)}")
    params = {k: (dict(v) if isinstance(v, Mapping) else v)
              for k, v in spec.magnet.parameters.items()}
    mag = params["magnet"]
    for k, v in values.items():
        x = real_number(v, f"design values {k}", kd.variables[k], positive=True)
        mag[k] = int(round(x)) if k == kd.turns_key else x
    _, m, _ = _tables(params)
    mag[kd.resistance_key] = float(kd.laws(m, float(m[kd.turns_key]), spec.coil)[
        "resistance_ohm"])
    if provenance:
        prov = dict(params.get("provenance", {}))
        for k in (*values, kd.resistance_key):
            prov[f"magnet.{k}"] = f"[E] {provenance}"
        params["provenance"] = prov
    return params


def _build(spec: DesignSpec, values: Mapping[str, float]) -> Any:
    from .magnets import build_magnet

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MaglevkitWarning)
        return build_magnet(design_parameters(spec, values), options=replace(
            spec.magnet.options, eddy_currents=False), source=spec.source)


# ---------------------------------------------------------------------------- result
@dataclass(frozen=True)
class DesignConstraint:
    """One constraint at the optimum.

    Attributes
    ----------
    name : str
        ``force_nominal``, ``force_reserve``, ``flux_density``, ``current_density``,
        ``voltage``, ``coil_fits_leg``, ``coils_fit_window``, ``magnet_fits_rail``,
        ``max_power``, ``max_mass``, or ``<variable>_lower`` / ``<variable>_upper`` (the
        variable bounds).
    value : float
        The constrained quantity [unit].
    bound : float
        Its limit [unit].
    sense : str
        ``"=="``, ``"<="`` or ``">="`` (value sense bound).
    unit : str
    active : bool
        Equality, or relative slack at most :data:`ACTIVE_TOL`.
    sensitivity : float
        ``d(objective)/d(bound)`` at the optimum [objective unit per constraint unit], from
        IPOPT's Lagrange multiplier (the shadow price: what relaxing the bound by one unit
        saves; ~0 for an inactive constraint).
    detail : str
        For ``flux_density``: the iron path with the peak.
    """

    name: str
    value: float
    bound: float
    sense: str
    unit: str
    active: bool
    sensitivity: float = 0.0
    detail: str = ""

    @property
    def slack(self) -> float:
        """Distance to the bound in the feasible direction [unit] (negative: violated)."""
        if self.sense == ">=":
            return self.value - self.bound
        if self.sense == "<=":
            return self.bound - self.value
        return -abs(self.value - self.bound)


@dataclass(frozen=True)
class DesignResult:
    """Result of :func:`design_magnet`.

    Attributes
    ----------
    spec : DesignSpec
    values : dict
        Optimal design variables [m, turns -] (``turns`` unrounded).
    objective : str
        The objective minimised.
    objective_value : float
        Its value [kg or W].
    mass_kg, power_W, resistance_ohm, nominal_current_A, reserve_current_A : float
        Magnet mass [kg], ``R I_n^2`` of all circuits [W], circuit 1's winding resistance
        [ohm], nominal current and the current at the peak current density [A] (every
        circuit).
    constraints : dict
        Name -> :class:`DesignConstraint`.
    status : str
        IPOPT's return status.
    success : bool
        IPOPT converged (``Solve_Succeeded`` or ``Solved_To_Acceptable_Level``).
    iterations : int
        IPOPT iterations.
    decisions : tuple of str
        The network builder's geometry comparisons, decided at the start and held at the
        optimum (:class:`~maglevkit.magnets.levitation.GeometryBranches`).
    crossed : tuple of str
        Decisions the optimum crossed (empty for a result returned as a success).
    """

    spec: DesignSpec
    values: dict[str, float]
    objective: str
    objective_value: float
    mass_kg: float
    power_W: float
    resistance_ohm: float
    nominal_current_A: float
    reserve_current_A: float
    constraints: dict[str, DesignConstraint]
    status: str
    success: bool
    iterations: int
    decisions: tuple[str, ...] = ()
    crossed: tuple[str, ...] = ()

    @property
    def active(self) -> tuple[str, ...]:
        """Names of the active constraints."""
        return tuple(n for n, c in self.constraints.items() if c.active)


# ---------------------------------------------------------------------------- evaluation
def _nominal_current(magnet: Any, gap_m: float, force_N: float, i_hi: float) -> float:
    """Current of every circuit holding ``force_N`` per circuit at ``gap_m`` (force
    monotone in I: bisection on a grid, then Newton with the exact dF/dI of the statics)."""
    from .models.statics import solve_statics

    force_N = force_N * len(magnet.network.circuits)       # the whole magnet's force
    grid = np.linspace(0.0, i_hi, 41)[1:]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MaglevkitWarning)
        f = np.asarray(solve_statics(magnet, gaps_m=np.array([gap_m]), currents_A=grid,
                                     grid=True).force_N)[0]
        if f[-1] < force_N:
            return math.nan
        k = int(np.argmax(f >= force_N))
        lo = grid[k - 1] if k else 0.0
        f_lo = f[k - 1] if k else 0.0
        i = lo + (force_N - f_lo) / (f[k] - f_lo) * (grid[k] - lo)
        for _ in range(30):
            sol = solve_statics(magnet, gaps_m=gap_m, currents_A=i)
            fi = float(np.asarray(sol.force_N))
            dfdi = float(np.sum(np.asarray(sol.dforce_dcurrent_N_per_A)))
            step = (fi - force_N) / dfdi
            i -= step
            if abs(step) <= 1e-12 * i:
                break
    return float(i)


def evaluate_design(spec: DesignSpec, values: Mapping[str, float] | None = None, *,
                    magnet: Any = None) -> dict[str, Any]:
    """Re-solve a design's statics independently of the optimiser and return its
    constrained quantities (module docstring).

    The magnet is built by the ordinary loader path (:func:`design_parameters`, then
    :func:`~maglevkit.magnets.build_magnet`) or given, and its statics solved with
    :func:`~maglevkit.models.statics.solve_statics`; the nominal current is the root of
    ``F(nominal_gap, I) = force_N``.

    Parameters
    ----------
    spec : DesignSpec
        The design problem (requirements, coil data).
    values : mapping, optional
        Design variable -> value [m, turns -] (``turns`` rounded); ignored with ``magnet``.
    magnet : Magnet, optional
        A magnet to evaluate instead (e.g. loaded from a written design file).

    Returns
    -------
    dict
        ``nominal_current_A``, ``reserve_current_A``, ``force_reserve_N``,
        ``flux_density_T`` (peak ``|B|`` in the magnet's iron at the nominal point),
        ``flux_density_path``, ``current_density_A_per_m2``, ``voltage_V``,
        ``resistance_ohm`` (circuit 1), ``mass_kg``, ``power_W`` (all circuits), the
        geometry slacks ``<constraint>_m`` [m] (U-magnet: ``coil_fits_leg_m``,
        ``coils_fit_window_m``, ``magnet_fits_rail_m``; levitation magnet:
        ``coil_fits_core_m``, ``coils_fit_window_m``, ``stator_covers_pole_m``,
        ``grooves_leave_face_m``) and
        ``feasible`` (all constraints met; a nominal current that cannot be reached is
        infeasible).
    """
    from .circuit.elements import IronPath
    from .models.statics import solve_statics

    mag = magnet if magnet is not None else _build(spec, values or {})
    kd, m, fixed = _tables(dict(mag.parameters))
    turns = float(m[kd.turns_key])
    req, coil = spec.requirements, spec.coil
    laws = kd.laws(m, turns, coil)
    i_res = req["peak_current_density_A_per_m2"] * coil["fill_factor"] \
        * laws["coil_area_m2"] / laws["coil_turns"]
    circuits = mag.network.circuits
    out: dict[str, Any] = {"resistance_ohm": float(circuits[0].resistance_ohm),
                           "mass_kg": float(laws["mass_kg"]), "reserve_current_A": i_res}
    i_n = _nominal_current(mag, req["nominal_gap_m"], req["force_N"], 3.0 * i_res)
    out["nominal_current_A"] = i_n
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MaglevkitWarning)
        f_r = float(np.asarray(solve_statics(mag, gaps_m=req["reserve_gap_m"],
                                             currents_A=i_res).force_N)) / len(circuits)
        out["force_reserve_N"] = f_r
        if math.isfinite(i_n):
            sol = solve_statics(mag, gaps_m=req["nominal_gap_m"], currents_A=i_n)
            phi = np.asarray(sol.branch_flux_Wb).ravel()
            best, where = 0.0, ""
            for j, br in enumerate(mag.network.branches):
                for el in br.elements:
                    if isinstance(el, IronPath) and kd.magnet_iron(el.name):
                        b = abs(phi[j]) / el.cross_section_m2
                        if b > best:
                            best, where = b, el.name
            # circuit 1 while every circuit carries I_n and every gap moves together
            ldiff = float(np.asarray(sol.common_differential_inductance_H).ravel()[0])
            dpsi = float(np.asarray(sol.common_dpsi_dgap_Wb_per_m).ravel()[0])
            r_el = out["resistance_ohm"]
            out.update(flux_density_T=best, flux_density_path=where,
                       voltage_V=r_el * i_n + ldiff * req["current_rate_A_per_s"]
                       + abs(dpsi) * req["gap_rate_m_per_s"],
                       current_density_A_per_m2=laws["coil_turns"] * i_n
                       / (coil["fill_factor"] * laws["coil_area_m2"]),
                       power_W=sum(c.resistance_ohm for c in circuits) * i_n**2)
        else:
            out.update(flux_density_T=math.nan, flux_density_path="", voltage_V=math.nan,
                       current_density_A_per_m2=math.nan, power_W=math.nan)
    geometry = [name + "_m" for name, *_ in kd.geometry(m, fixed, req)]
    for name, slack, _ in kd.geometry(m, fixed, req):
        out[name + "_m"] = float(slack)
    rel = 1e-6
    out["feasible"] = bool(
        math.isfinite(i_n)
        and f_r >= req["reserve_factor"] * req["force_N"] * (1 - rel)
        and out["flux_density_T"] <= req["max_flux_density_T"] * (1 + rel)
        and out["current_density_A_per_m2"] <= req["current_density_A_per_m2"] * (1 + rel)
        and out["voltage_V"] <= req["supply_voltage_V"] * (1 + rel)
        and min(out[k] for k in geometry) >= -1e-12)
    return out


# ---------------------------------------------------------------------------- the NLP
@dataclass(frozen=True)
class _Setup:
    """The NLP of one spec (and start): IPOPT solver, bounds, constraint rows, scalings."""

    names: tuple[str, ...]
    lo: np.ndarray
    hi: np.ndarray
    vscale: np.ndarray
    n_loops: int
    rows: list[tuple[str, Any, float, str, str, float]]
    solver: Any
    z0: np.ndarray
    lbz: np.ndarray
    ubz: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    report: Any
    mass0: float
    power0: float
    iron_names: tuple[str, ...]
    problem: Any


_SETUPS: dict[tuple[int, tuple[tuple[str, float], ...]], tuple[DesignSpec, _Setup]] = {}
"""The last few NLPs built (by spec identity and start): a Pareto sweep re-solves one NLP
with other caps and objective weights instead of re-deriving it (1-2 s each)."""


def _setup(spec: DesignSpec, initial: Mapping[str, float] | None) -> _Setup:
    import casadi as ca

    key = (id(spec), tuple(sorted((initial or {}).items())))
    hit = _SETUPS.get(key)
    if hit is not None and hit[0] is spec:
        return hit[1]
    kd, m, _ = _tables(spec)
    req, coil = spec.requirements, spec.coil
    names = tuple(spec.variables)
    lo = np.array([spec.variables[n][0] for n in names])
    hi = np.array([spec.variables[n][1] for n in names])
    start = {n: float(np.clip(m[n], a, b)) for n, a, b in zip(names, lo, hi, strict=True)}
    if initial:
        for n, v in initial.items():
            if n not in spec.variables:
                raise InputError(f"initial {n} = {v!r}: not a design variable of the spec; "
                                 f"its variables: {list(names)}")
            x = real_number(v, f"initial {n}", kd.variables[n])
            a, b = spec.variables[n]
            if not a <= x <= b:
                raise InputError(f"initial {n} = {x!r} [{kd.variables[n]}]: outside its "
                                 f"bounds [{a!r}, {b!r}] ([variables] of the spec)")
            start[n] = x
    if kd.turns_key in start:
        start[kd.turns_key] = float(round(start[kd.turns_key]))
    # the builder's geometry comparisons are decided at the start (checked at the optimum)
    pb = _Problem(spec, at=start)
    ev0 = evaluate_design(spec, start)
    p0 = pb.value_vector(start)
    i_res0 = ev0["reserve_current_A"]
    i_n0 = ev0["nominal_current_A"]
    if not math.isfinite(i_n0):
        i_n0 = i_res0
    # start loop fluxes: the base-start magnet's statics (numeric network)
    from .models.statics import solve_statics

    mag0 = _build(spec, start)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MaglevkitWarning)
        x_n0 = np.asarray(solve_statics(mag0, gaps_m=req["nominal_gap_m"],
                                        currents_A=i_n0).loop_flux_Wb, dtype=float).ravel()
        x_r0 = np.asarray(solve_statics(mag0, gaps_m=req["reserve_gap_m"],
                                        currents_A=i_res0).loop_flux_Wb, dtype=float).ravel()
    # scaling: variables by their upper bounds, fluxes by the start's largest loop flux,
    # currents by the start's nominal current, loop laws by the nominal MMF
    vscale = hi.copy()
    xscale = max(float(np.max(np.abs(x_r0))), 1e-9)
    iscale = max(i_n0, 1e-9)
    mmf = max(float(pb.laws_fun(p0)[3]) * i_n0, 1.0)      # turns through a coil x I
    nl = pb.n_loops
    # start of dx/dI, dx/ds at the nominal point (the numeric network's Jacobians)
    eff0 = start.get(kd.turns_key, pb.turns0) / pb.turns0
    rx0, rq0 = (np.asarray(a) for a in pb.jacobians(x_n0, req["nominal_gap_m"], i_n0 * eff0,
                                                     p0))
    y0 = -np.linalg.solve(rx0, rq0)
    yscale = np.array([xscale / iscale, xscale / req["nominal_gap_m"]])
    w = ca.SX.sym("w", len(names))
    i_s = ca.SX.sym("i_n")
    xn_s = ca.SX.sym("x_n", nl)
    xr_s = ca.SX.sym("x_r", nl)
    yi_s = ca.SX.sym("y_I", nl)
    ys_s = ca.SX.sym("y_s", nl)
    p = w * vscale
    turns = p[names.index(kd.turns_key)] if kd.turns_key in names else pb.turns0
    i_n = i_s * iscale
    resistance, mass, area, coil_turns, r_total = pb.laws_fun(p)
    i_res = req["peak_current_density_A_per_m2"] * coil["fill_factor"] * area / coil_turns
    eff = turns / pb.turns0                 # the network carries turns0: I_eff = I N / N0
    rn, f_n, _, ry, l_n, dpsi_n, b_n = pb.point(xn_s * xscale, req["nominal_gap_m"], i_n * eff,
                                                p, yi_s * yscale[0], ys_s * yscale[1])
    rr, f_r, *_ = pb.point(xr_s * xscale, req["reserve_gap_m"], i_res * eff, p,
                           ca.DM.zeros(nl), ca.DM.zeros(nl))
    voltage = (resistance * i_n + eff**2 * l_n * req["current_rate_A_per_s"]
               + eff * ca.fabs(dpsi_n) * req["gap_rate_m_per_s"])
    power = r_total * i_n**2
    j_n = coil_turns * i_n / (coil["fill_factor"] * area)
    geo_rows = [(name, ca.substitute(slack, pb.p, p), needs)
                for name, slack, needs in kd.geometry(pb.geometry, pb.fixed, req)
                if any(n in names for n in needs)]
    rows: list[tuple[str, Any, float, str, str, float]] = []   # name, expr, bound, sense, unit, scale
    f_req = req["force_N"]
    rows.append(("force_nominal", f_n, f_req, "==", "N", f_req))
    rows.append(("force_reserve", f_r, req["reserve_factor"] * f_req, ">=", "N", f_req))
    bmax = req["max_flux_density_T"]
    for k in range(b_n.numel()):
        rows.append((f"flux_density:{pb.iron_names[k]}", b_n[k] ** 2, bmax**2, "<=", "T^2",
                     bmax**2))
    rows.append(("current_density", j_n, req["current_density_A_per_m2"], "<=", "A/m^2",
                 req["current_density_A_per_m2"]))
    rows.append(("voltage", voltage, req["supply_voltage_V"], "<=", "V",
                 req["supply_voltage_V"]))
    for name, slack, _ in geo_rows:
        rows.append((name, slack, GEOMETRY_MARGIN_M, ">=", "m", 0.01))
    # the sensitivities' laws in units of the loop law per unit current / per gap
    n_eq = 4 * nl
    g_parts = [rn / mmf, rr / mmf, ry[:nl] * (iscale / mmf),
               ry[nl:] * (req["nominal_gap_m"] / mmf)]
    lbg = [np.zeros(n_eq)]
    ubg = [np.zeros(n_eq)]
    for _, expr, bound, sense, _, scale in rows:
        g_parts.append((expr - bound) / scale)
        lbg.append(np.array([0.0 if sense in ("==", ">=") else -np.inf]))
        ubg.append(np.array([0.0 if sense in ("==", "<=") else np.inf]))
    z = ca.vertcat(w, i_s, xn_s, xr_s, yi_s, ys_s)
    mass0, power0 = ev0["mass_kg"], ev0.get("power_W", math.nan)
    if not (math.isfinite(power0) and power0 > 0.0):
        power0 = float(pb.laws_fun(p0)[4]) * i_n0**2
    # the caps of the epsilon-constraint sweeps: always in g, open unless given
    g_parts += [mass / mass0, power / power0]
    lbg.append(np.full(2, -np.inf))
    ubg.append(np.full(2, np.inf))
    weights = ca.SX.sym("weights", 2)           # (mass, power): the objective's choice
    f_obj = weights[0] * mass / mass0 + weights[1] * power / power0
    nlp = {"x": z, "p": weights, "f": f_obj, "g": ca.vertcat(*g_parts)}
    solver = ca.nlpsol("design", "ipopt", nlp, {
        "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
        "ipopt.tol": 1e-10, "ipopt.max_iter": 500, "ipopt.bound_relax_factor": 0.0,
        "error_on_fail": False})
    z0 = np.concatenate((p0 / vscale, [i_n0 / iscale], x_n0 / xscale, x_r0 / xscale,
                         y0[:, 0] / yscale[0], y0[:, 1] / yscale[1]))
    lbz = np.concatenate((lo / vscale, [0.0], np.full(4 * nl, -np.inf)))
    ubz = np.concatenate((hi / vscale, [np.inf], np.full(4 * nl, np.inf)))
    report = ca.Function("design_report", [z], [ca.vertcat(*[e for _, e, *_ in rows]), mass,
                                                power, resistance, i_n, i_res])
    out = _Setup(names=names, lo=lo, hi=hi, vscale=vscale, n_loops=nl, rows=rows,
                 solver=solver, z0=z0, lbz=lbz, ubz=ubz, lbg=np.concatenate(lbg),
                 ubg=np.concatenate(ubg), report=report, mass0=mass0, power0=power0,
                 iron_names=pb.iron_names, problem=pb)
    _SETUPS[key] = (spec, out)
    while len(_SETUPS) > 4:
        _SETUPS.pop(next(iter(_SETUPS)))
    return out


def design_magnet(spec: DesignSpec, *, objective: str | None = None,
                  max_power_W: float | None = None, max_mass_kg: float | None = None,
                  initial: Mapping[str, float] | None = None) -> DesignResult:
    """Optimise the design (module docstring): IPOPT on the simultaneous NLP.

    Parameters
    ----------
    spec : DesignSpec
        The design problem (:func:`read_design_spec`).
    objective : str, optional
        Overrides ``spec.objective`` (one of :data:`OBJECTIVES`).
    max_power_W : float, optional
        Extra constraint ``R I_n^2 <= max_power_W`` [W] (epsilon-constraint sweeps).
    max_mass_kg : float, optional
        Extra constraint ``mass <= max_mass_kg`` [kg].
    initial : mapping, optional
        Start values [m, turns -] (default: the base magnet's, clipped into the bounds).

    Returns
    -------
    DesignResult

    Raises
    ------
    InputError
        An unknown objective, a non-positive cap, start values outside the bounds.
    """

    obj = spec.objective if objective is None else objective
    if obj not in OBJECTIVES:
        raise InputError(f"objective = {obj!r}: expected one of {list(OBJECTIVES)}")
    for key, cap in (("max_power_W", max_power_W), ("max_mass_kg", max_mass_kg)):
        if cap is not None and not (isinstance(cap, (int, float)) and not isinstance(cap, bool)
                                    and math.isfinite(cap) and cap > 0.0):
            raise InputError(f"{key} = {cap!r}: expected a finite number > 0")
    start = initial
    for _ in range(2):
        res = _solve(spec, _setup(spec, start), obj, max_power_W, max_mass_kg)
        if not res.crossed:
            break
        # the optimum left a branch of the builder decided at the start: decide again
        # there and re-solve from it (once); the same again means it sits on the kink
        start = res.values
    else:
        res = replace(res, success=False, status=f"Branch_Crossed ({', '.join(res.crossed)})")
    if not res.success:
        hint = ("the optimum crosses a geometry branch of the network decided at its start "
                "(a kink of the network's laws; narrow the bounds to one side)"
                if res.crossed else "the values are where it stopped")
        warnings.warn(f"design_magnet: IPOPT did not converge ({res.status}); {hint}",
                      MaglevkitWarning, stacklevel=2)
    return res


def _solve(spec: DesignSpec, st: _Setup, obj: str, max_power_W: float | None,
           max_mass_kg: float | None) -> DesignResult:
    """One IPOPT solve of the NLP ``st`` and its report."""
    names, lo, hi, nl, rows = st.names, st.lo, st.hi, st.n_loops, st.rows
    req = spec.requirements
    bmax = req["max_flux_density_T"]
    ubg = st.ubg.copy()
    if max_mass_kg is not None:
        ubg[-2] = float(max_mass_kg) / st.mass0
    if max_power_W is not None:
        ubg[-1] = float(max_power_W) / st.power0
    solver = st.solver
    sol = solver(x0=st.z0, lbx=st.lbz, ubx=st.ubz, lbg=st.lbg, ubg=ubg,
                 p=[1.0, 0.0] if obj == "mass" else [0.0, 1.0])
    if sigint_received():
        # CasADi turns a Ctrl-C inside IPOPT into the status NonIpopt_Exception_Thrown:
        # without this the command went on (a Pareto sweep wrote its figure, exit 0)
        raise KeyboardInterrupt
    stats = solver.stats()
    zs = np.asarray(sol["x"]).ravel()
    lam = np.asarray(sol["lam_g"]).ravel()[4 * nl:]
    pv = zs[:len(names)] * st.vscale
    values = {n: float(v) for n, v in zip(names, pv, strict=True)}
    rv, mass_v, power_v, r_v, in_v, ir_v = (np.asarray(a).ravel() for a in st.report(zs))
    constraints: dict[str, DesignConstraint] = {}
    # shadow prices: g = (expr - bound)/scale in [lbg, ubg] and grad f + J^T lam_g +
    # lam_x = 0 (CasADi's signs), so d f*/d bound = -lam_g/scale (objective / its reference)
    ref = st.mass0 if obj == "mass" else st.power0
    b_rows = [k for k, r in enumerate(rows) if r[0].startswith("flux_density:")]
    for k, (name, _, bound, sense, unit, scale) in enumerate(rows):
        if k in b_rows:
            continue
        slack = (rv[k] - bound) if sense == ">=" else (bound - rv[k])
        active = bool(sense == "==" or slack <= ACTIVE_TOL * scale)
        constraints[name] = DesignConstraint(name, float(rv[k]), bound, sense, unit, active,
                                             float(-lam[k] / scale * ref))
    for name, cap, val, unit in (("max_mass", max_mass_kg, mass_v[0], "kg"),
                                 ("max_power", max_power_W, power_v[0], "W")):
        if cap is not None:
            constraints[name] = DesignConstraint(
                name, float(val), float(cap), "<=", unit,
                bool(cap - val <= ACTIVE_TOL * cap),
                float(-lam[len(rows) + (0 if name == "max_mass" else 1)] * ref
                      / (st.mass0 if name == "max_mass" else st.power0)))
    lam_x = np.asarray(sol["lam_x"]).ravel()
    for k, n in enumerate(names):
        unit = VARIABLES[n]
        for side, bound, sense in (("lower", lo[k], ">="), ("upper", hi[k], "<=")):
            slack = pv[k] - bound if sense == ">=" else bound - pv[k]
            constraints[f"{n}_{side}"] = DesignConstraint(
                f"{n}_{side}", float(pv[k]), float(bound), sense, unit,
                bool(slack <= ACTIVE_TOL * bound), float(-lam_x[k] / st.vscale[k] * ref)
                if slack <= ACTIVE_TOL * bound else 0.0, "variable bound")
    kb = max(b_rows, key=lambda k: rv[k])
    b_peak = math.sqrt(max(float(rv[kb]), 0.0))
    constraints["flux_density"] = DesignConstraint(
        "flux_density", b_peak, bmax, "<=", "T",
        bool(any(bmax**2 - rv[k] <= ACTIVE_TOL * bmax**2 for k in b_rows)),
        float(-2.0 * ref / bmax * sum(lam[k] for k in b_rows)), rows[kb][0].split(":", 1)[1])
    status = str(stats.get("return_status", ""))
    success = status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    pb = st.problem
    held = np.asarray(pb.conditions(pv)).ravel()
    # a decision holds while its condition is >= 0; IPOPT's steps end within ~1e-10 m
    crossed = tuple(d for d, c in zip(pb.decisions, held, strict=True) if c < -1e-9)
    return DesignResult(
        spec=spec, values=values, objective=obj,
        objective_value=float(mass_v[0] if obj == "mass" else power_v[0]),
        mass_kg=float(mass_v[0]), power_W=float(power_v[0]), resistance_ohm=float(r_v[0]),
        nominal_current_A=float(in_v[0]), reserve_current_A=float(ir_v[0]),
        constraints=constraints, status=status, success=success,
        iterations=int(stats.get("iter_count", -1)), decisions=pb.decisions, crossed=crossed)


# ---------------------------------------------------------------------------- gradients
def design_sensitivities(spec: DesignSpec, values: Mapping[str, float], *, gap_m: float,
                         current_A: float) -> dict[str, Any]:
    """Circuit force and flux linkage of a design at one point and their exact derivatives
    with respect to the design variables (nested route: CasADi ``rootfinder`` of the loop
    law, implicit function theorem ``dx/dp = -r_x^-1 r_p``).

    Parameters
    ----------
    spec : DesignSpec
        The design problem (its variables define ``p``).
    values : mapping
        Design variable -> value [m, turns -] (every variable of the spec).
    gap_m : float
        Gap of both poles [m].
    current_A : float
        Coil current [A].

    Returns
    -------
    dict
        ``force_N`` (per circuit: the magnet's force over its circuits, every circuit at
        ``current_A``), ``flux_linkage_Wb`` (circuit 1; floats), ``dforce_dp`` [N per unit]
        and ``dpsi_dp`` [Wb per unit] (dicts over the variables).
    """
    import casadi as ca

    from .models.statics import plausible_range, solve_statics

    gap_m = real_number(gap_m, "gap_m", "m", positive=True)
    current_A = real_number(current_A, "current_A", "A")
    missing = [n for n in spec.variables if n not in values]
    if missing:
        raise InputError(f"design_sensitivities: values for {missing} missing")
    pb = _Problem(spec, at=values)        # the builder's branches decided at this design
    tk = pb.kind.turns_key
    v = pb.value_vector(values)
    mag = _build(spec, values)
    rng = plausible_range(mag)
    if rng is not None:   # as solve_statics does (its own warnings are silenced below)
        rng.check(gaps_m=gap_m, currents_A=current_A, where="design_sensitivities")
    turns_r = float(mag.parameters["magnet"][tk])
    n_val = float(values[tk]) if tk in pb.names else pb.turns0
    if abs(n_val - turns_r) > 0.0:
        # start fluxes from the rounded magnet at the same ampere-turns
        cur0 = current_A * n_val / turns_r
    else:
        cur0 = current_A
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MaglevkitWarning)
        x0 = np.asarray(solve_statics(mag, gaps_m=gap_m, currents_A=cur0).loop_flux_Wb,
                        dtype=float).ravel()
    rf = ca.rootfinder("design_statics", "newton", pb.residual,
                       {"abstol": 1e-10, "abstolStep": 1e-16, "max_iter": 60,
                        "error_on_fail": True})
    P = ca.MX.sym("p", len(pb.names))
    turns = P[pb.names.index(tk)] if tk in pb.names else pb.turns0
    par = ca.vertcat(gap_m, current_A * turns / pb.turns0, P)
    xs = rf(ca.DM(x0), par)
    f, psi = pb.outputs(xs, par)
    psi = psi * turns / pb.turns0
    fun = ca.Function("design_sens", [P], [f, psi, ca.jacobian(f, P), ca.jacobian(psi, P)])
    f_v, psi_v, jf, jpsi = (np.asarray(a) for a in fun(v))
    return {"force_N": float(f_v.ravel()[0]), "flux_linkage_Wb": float(psi_v.ravel()[0]),
            "dforce_dp": {n: float(jf.ravel()[k]) for k, n in enumerate(pb.names)},
            "dpsi_dp": {n: float(jpsi.ravel()[k]) for k, n in enumerate(pb.names)}}


# ---------------------------------------------------------------------------- output
def write_design_toml(result: DesignResult, path: str | Path) -> Path:
    """Write the optimum as a magnet parameter file (loadable by
    :func:`~maglevkit.magnets.load_magnet`): the base magnet with the optimal values
    (``turns`` rounded), the coil's resistance, every changed value tagged ``[E] optimised:
    ...`` in ``[provenance]``, the operating point in ``[operating]`` (its current scaled by
    ``N / round(N)``: the optimum's ampere-turns, on which the statics depend, with the
    rounded turns), and a comment header
    with the objective, the active constraints and IPOPT's status.

    Parameters
    ----------
    result : DesignResult
        The optimum.
    path : path
        The file to write.

    Returns
    -------
    Path
    """
    from .parameter_files import toml_text

    spec = result.spec
    tag = (f"optimised: maglevkit design ({result.objective} minimised, spec "
           f"{Path(spec.source).name}; active: {', '.join(result.active) or 'none'})")
    params = design_parameters(spec, result.values, provenance=tag)
    params["magnet"]["name"] = f"{params['magnet'].get('name', 'magnet')} (optimised)"
    current = result.nominal_current_A
    tk = _kind(spec.kind).turns_key
    if tk in result.values:     # the same ampere-turns (so force, B, J) with the file's
        current *= result.values[tk] / params["magnet"][tk]     # rounded turns
    params["operating"] = {"nominal_gap": spec.requirements["nominal_gap_m"],
                           "nominal_current": current}
    prov = dict(params.get("provenance", {}))
    prov["operating.nominal_gap"] = f"[E] {tag}"
    prov["operating.nominal_current"] = f"[E] {tag}"
    params["provenance"] = prov
    header = [f"# {params['magnet']['name']}: written by maglevkit design "
              f"(IPOPT {result.status}, {result.iterations} iterations)",
              f"# objective {result.objective} = {result.objective_value:.6g} "
              f"({'kg' if result.objective == 'mass' else 'W'}); mass {result.mass_kg:.6g} kg, "
              f"power {result.power_W:.6g} W at {current:.6g} A",
              f"# active constraints: {', '.join(result.active) or 'none'}"]
    p = Path(path)
    p.write_text("\n".join(header) + "\n" + toml_text(params))
    return p


# ---------------------------------------------------------------------------- Pareto front
def pareto_front(spec: DesignSpec, *, points: int = 7) -> list[DesignResult]:
    """Mass vs resistive power: the epsilon-constraint sweep (minimum mass subject to
    ``R I_n^2 <= P_k`` for ``points`` caps between the minimum-power design's power and
    the minimum-mass design's).

    Parameters
    ----------
    spec : DesignSpec
        The design problem.
    points : int
        Designs on the front (>= 2), the two end points included.

    Returns
    -------
    list of DesignResult
        From the minimum-power end to the minimum-mass end.
    """
    if isinstance(points, bool) or not isinstance(points, int) or points < 2:
        raise InputError(f"points = {points!r}: expected an integer >= 2")
    low_p = design_magnet(spec, objective="power")
    low_m = design_magnet(spec, objective="mass")
    caps = np.linspace(low_p.power_W, low_m.power_W, points)
    front = [design_magnet(spec, objective="mass", max_power_W=float(c) * (1 + 1e-9))
             for c in caps[:-1]]
    return [*front, low_m]


def plot_pareto(front: Sequence[DesignResult], path: str | Path, *, title: str = "") -> Path:
    """Figure of the Pareto front (mass over resistive power), PNG.

    Parameters
    ----------
    front : sequence of DesignResult
        The designs (:func:`pareto_front`).
    path : path
        The PNG file.
    title : str
        Figure title (default: the spec's name).

    Returns
    -------
    Path
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .plotting import save

    ok = [r for r in front if r.success]
    if not ok:
        raise InputError("plot_pareto: no converged design on the front")
    # label each point with the two variables that change most along the front
    names = list(ok[0].values)
    spread = {n: np.ptp([r.values[n] for r in ok]) / max(abs(ok[0].values[n]), 1e-12)
              for n in names}
    shown = sorted(names, key=lambda n: -spread[n])[:2]
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    ax.plot([r.power_W for r in ok], [r.mass_kg for r in ok], "o-", color="C0",
            label="Pareto-optimal designs\n(epsilon constraint)")
    # number the points; their two most varying variables in a list beside the curve
    lines = []
    for j, r in enumerate(ok, start=1):
        ax.annotate(str(j), (r.power_W, r.mass_kg), textcoords="offset points", xytext=(5, 4),
                    fontsize=8, color="0.2")
        lines.append(f"{j}: " + ", ".join(f"{k} {r.values[k] * 1e3:.1f} mm"
                                          if VARIABLES[k] == "m" else f"{k} {r.values[k]:.0f}"
                                          for k in shown))
    ax.text(0.98, 0.80, "\n".join(lines), transform=ax.transAxes, ha="right", va="top",
            fontsize=7, color="0.3", family="monospace")
    pw = [r.power_W for r in ok]
    span = max(max(pw) - min(pw), 1e-9 * max(pw))
    ax.set_xlim(min(pw) - 0.06 * span, max(pw) + 0.1 * span)
    ax.margins(y=0.08)
    ax.set_xlabel("resistive power at the nominal point R I_n^2 (all circuits) [W]")
    ax.set_ylabel("magnet mass (iron + conductor) [kg]")
    ax.grid(True, alpha=0.3)
    ax.set_title(title or f"Pareto front: {Path(front[0].spec.source).name}")
    ax.legend(loc="upper right", fontsize=8)     # the list of designs below it
    return save(fig, path)
