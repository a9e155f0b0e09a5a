"""Which public callables of maglevkit take a physical quantity under a name without a unit.

Issue 22, item 7: input names carry their unit (``gap_m``, ``dt_s``, ``voltages_V``), the way
the result fields do.  This audit lists every named parameter of a public callable (the
same set ``tools/docstring_audit.py`` audits: exported functions, constructors and public
methods) whose name contains a word for a physical quantity (``gap``, ``current``, ``dt``,
``force``, ...) but does not end in a unit (``_m``, ``_A``, ``_s``, ``_N_per_m``, ...).

Each finding is renamed, or listed in ``ALLOWED`` with the reason it keeps its name (a name
string, a dimensionless ratio, a CasADi symbol, ...), or in ``DEFERRED`` with the reason it
was not renamed yet (that list may only shrink).  ``tests/test_unit_names.py``
runs the audit: a new unit-less quantity name fails, and so does an allow-list entry that
no longer matches anything.  Run as a script to print the findings and the allowed names:
``python tools/unit_name_audit.py``.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from pathlib import Path

#: Words that denote a physical (dimensional) quantity when they appear in a parameter name.
QUANTITY_WORDS = frozenset({
    "gap", "gaps", "current", "currents", "voltage", "voltages", "dt", "time", "times",
    "duration", "force", "forces", "flux", "area", "radius", "width", "height", "length",
    "thickness", "distance", "resistance", "resistivity", "conductance", "inductance",
    "frequency", "amplitude", "mass", "damping", "stiffness", "gravity", "speed", "velocity",
    "acceleration", "position", "offset", "pitch", "wavelength", "energy", "power", "load",
    "deflection", "omega", "opening", "rate", "rates", "step", "sample", "period", "bandwidth",
    "weight", "weights", "inertia", "preload", "change", "initial", "final", "start", "stop",
    "t",
})

#: Unit tokens: a name ends in a unit when its last ``_``-separated tokens all are units.
UNIT_TOKENS = frozenset({
    "m", "m2", "m3", "s", "s2", "A", "V", "N", "Hz", "hz", "Wb", "H", "T", "J", "W", "kg",
    "ohm", "rad", "S", "Pa", "per", "bytes",
})

#: The modules whose ``__all__`` the audit reads: those of ``tools/docstring_audit.py`` plus
#: the top-level modules with an API of their own.
MODULES = ("maglevkit", "maglevkit.materials", "maglevkit.circuit", "maglevkit.magnets",
           "maglevkit.models", "maglevkit.reduction", "maglevkit.reduced", "maglevkit.control",
           "maglevkit.vehicle", "maglevkit.export", "maglevkit.sweep", "maglevkit.plant",
           "maglevkit.simulation", "maglevkit.compare", "maglevkit.design",
           "maglevkit.calibration", "maglevkit.figures")

#: Names (``param``: everywhere, or ``qualified.callable:param``) that contain a quantity
#: word but are no quantity with a unit (names, switches, ratios, objects, symbols), with
#: the reason they keep their name.
ALLOWED: dict[str, str] = {
    # names, switches, counts and objects, not values of a quantity
    "gap_input": "the name of a gap input (a string)",
    "gap_inputs": "'circuit' or 'pole' (a string)",
    "gap_names": "names (strings)",
    "eddy_currents": "a switch (bool)",
    "eddy_resistance": "a choice of R_ec ('fit' or 'jump', a string), not a resistance",
    "live_step": "a switch (bool)",
    "stop_at_flag": "a switch (bool)",
    "time_series": "a switch (bool)",
    "pole_forces": "a switch (bool): also return the pole forces",
    "voltage_limited": "flags (bool per sample)",
    "current_basis": "a label (string) saying where the bound comes from",
    "gap_basis": "a label (string) saying where the bound comes from",
    "initial_state": "a model state object (FluxState, BankState, ...), not a number",
    "final_state": "a model state object, not a number",
    "force_frames": "the frames the force points belong to (indices)",
    "force_points": "ForcePoint objects (body, point, direction)",
    "maglevkit.circuit.assembly.NetworkEquations:force": "a CasADi expression of the "
        "assembled network (record of symbolic expressions; units in its docstring)",
    "maglevkit.circuit.assembly.NetworkEquations:gap_energy": "a CasADi expression, as above",
    "maglevkit.reduced.bank.MagnetBank.circuit_expressions:gap_rate": "a CasADi symbol of "
        "the code generator (its inputs are named by the law's symbols: s, u, k, gap_rate)",
    "maglevkit.reduced.bank.MagnetBank.ladder_expressions:gap_rate": "a CasADi symbol, as "
        "above",
    "maglevkit.reduced.current.CurrentModelLinearization:C_current": "a state-space output "
        "matrix (named C as in the control literature; mixed units per entry)",
    # ratios and dimensionless factors
    "current_error": "a relative error (dimensionless)",
    "force_error": "a relative error (dimensionless)",
    "current_error_range": "a relative error (dimensionless)",
    "force_error_range": "a relative error (dimensionless)",
    "current_error_ac": "a relative error (dimensionless)",
    "force_error_ac": "a relative error (dimensionless)",
    "relative_current_change": "a fraction of the current (dimensionless)",
    "maglevkit.figures.coupling_response:step": "a relative voltage step (dimensionless)",
    "step_points": "a count of simulated steps (an integer)",
    "gap_factors": "multiples of the nominal gap (dimensionless)",
    "force_full": "Fig6Data: F/F0 (dimensionless)",
    "force_linear": "Fig6Data: F/F0 (dimensionless)",
    "inductance_full": "Fig7Data: L/L0 (dimensionless)",
    "inductance_linear": "Fig7Data: L/L0 (dimensionless)",
    "step_current": "Fig7Data: I/I0 (dimensionless)",
    "step_inductance_full": "Fig7Data: tau R_el / L0 (dimensionless)",
    "step_inductance_linear": "Fig7Data: tau R_el / L0 (dimensionless)",
    "relative_gap_change": "a fraction of the gap (dimensionless)",
    "relative_step": "a fraction of the current (dimensionless)",
    "gap_rate_tolerance": "a relative tolerance (dimensionless)",
    "control_damping": "a damping ratio (dimensionless)",
    "damping_ratio": "a damping ratio (dimensionless)",
    "control_velocity_blend": "a blend factor (dimensionless)",
    "velocity_blend": "a blend factor (dimensionless)",
    "setpoint_weight": "a weight of the set point (dimensionless)",
    "pole_weights": "weights w_p [-] of the force points (the poles a point stands for)",
    "eddy_resistance_scale": "a factor on R_ec (dimensionless)",
    "resistance_scale": "a factor on R_el (dimensionless)",
    "external_force_fraction": "a fraction of the weight (dimensionless)",
    "real_time_factor": "a ratio of times (dimensionless)",
    "gravity_force": "generalised forces Q of the mechanics' coordinates: N for a translation, "
                     "N m for a rotation (mixed units; the docstring says which)",
    # signals are unit-agnostic: the same Step drives a voltage [V] or a gap [m]
}

def _each(quals: tuple[str, ...], param: str, reason: str) -> None:
    for q in quals:
        ALLOWED[f"maglevkit.{q}:{param}"] = reason


_SIGNALS = "the unit of the input the signal drives (V or m): a Signal is unit-agnostic"
_each(("models.signals.Ramp", "models.signals.Step"), "initial", "the value before the change, "
      "in " + _SIGNALS)
_each(("models.signals.Ramp", "models.signals.Step"), "final", "the value after the change, "
      "in " + _SIGNALS)
_each(("models.signals.Sine",), "amplitude", "in " + _SIGNALS)
_each(("models.signals.Sine",), "offset", "in " + _SIGNALS)
# (a signal's times, frequency and phase carry units since session 22: every simulator
# samples signals on its time grid in s, so they are s, Hz and rad)
_each(("models.flux.SimulationResult.energy_balance",), "start", "a sample index")
_each(("models.flux.SimulationResult.energy_balance",), "stop", "a sample index")
_each(("circuit.network.Branch",), "start", "a node name (a string)")
_each(("calibration.calibrate",), "initial", "start values of the calibration factors "
      "(a mapping of dimensionless factors)")
_each(("calibration.Calibration",), "nominal_step_points", "a list of per-sample report "
      "records (dicts with unit-named keys: time_s, current_A, ...), like nominal_points")
for _name in ("step_holdout", "nominal_step_holdout"):
    _each(("calibration.Calibration",), _name, "a list of per-sample report records of the "
          "held-out voltage steps (dicts with unit-named keys), like step_points")
_each(("calibration.ParameterSetScore",), "per_gap", "a mapping gap [m] -> worst relative "
      "error [-] at that left-out gap (the keys are gaps in m, the values dimensionless)")
_each(("design.design_magnet",), "initial", "start values of the design variables (a mapping "
      "of several units, each named in docs/design.md)")
_each(("control.cascade.design_gap_controller", "vehicle.crossrun.CrossSectionModel"),
      "damping", "a damping ratio zeta [-]")
_each(("vehicle.mechanics.VehicleMechanics.state_matrices",
       "vehicle.mechanics.VehicleMechanics.discretize",
       "vehicle.multibody.PlanarMultibody.state_matrices",
       "vehicle.multibody.PlanarMultibody.discretize",
       "vehicle.crossrun.CrossSectionModel.discretize"), "damping",
      "a switch (bool): with or without the dampers")
_each(("vehicle.multibody.PlanarMultibody.natural_frequencies_Hz",), "stiffness",
      "a stiffness matrix over mixed degrees of freedom (N/m and N m/rad): no single unit")
_each(("figures.fig6_data", "figures.fig7_data"), "max_current", "a multiple of the "
      "saturation knee I0 (dimensionless; the curves are normalised)")
_each(("figures.Fig6Data", "figures.Fig7Data"), "current", "I/I0 (dimensionless, normalised "
      "curves)")


#: Names that denote a quantity and should carry its unit, not renamed yet, with the
#: reason.  This list may only shrink (the test fails on a stale entry); it is empty since
#: units22b renamed the last ones (``Circuit.resistance_ohm``, ``resistivity_ohm_m``, the
#: element laws' ``gap_m``/``flux_Wb``, ``VehicleMechanics(gravity_m_per_s2)``,
#: ``simulate(times_s)``, ``SolverError(time_s)``).
DEFERRED: dict[str, str] = {}


PREFIX = "maglevkit."


def _docstring_audit():  # type: ignore[no-untyped-def]
    path = Path(__file__).resolve().parent / "docstring_audit.py"
    spec = importlib.util.spec_from_file_location("docstring_audit", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("docstring_audit", module)
    spec.loader.exec_module(module)
    return module


def has_unit(name: str) -> bool:
    """True when ``name`` ends in unit tokens (``gap_m``, ``kd_s_per_m``, ``area_m2``)."""
    tokens = name.split("_")
    return len(tokens) > 1 and tokens[-1] in UNIT_TOKENS


def names_quantity(name: str) -> bool:
    """True when a ``_``-separated token of ``name`` is a word of :data:`QUANTITY_WORDS`."""
    return any(tok in QUANTITY_WORDS for tok in name.lower().split("_"))


def exception_constructors() -> dict[str, object]:
    """``qualified name -> __init__`` of the exported exception classes that define one
    (``SolverError(message, *, time_s, ...)``): ``docstring_audit.public_callables`` leaves
    exceptions out, but their keywords are public API too."""
    out: dict[str, object] = {}
    for module_name in MODULES:
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if inspect.isclass(obj) and issubclass(obj, BaseException) \
                    and "__init__" in vars(obj):
                out[f"{obj.__module__}.{obj.__qualname__}"] = vars(obj)["__init__"]
    return out


def findings() -> dict[str, list[str]]:
    """``qualified callable name -> parameters that name a quantity without a unit``."""
    audit = _docstring_audit()
    out: dict[str, list[str]] = {}
    callables = list(audit.public_callables(MODULES)) + list(exception_constructors().items())
    for qualname, func in callables:
        bad = [p for p in audit.parameters(func) if names_quantity(p) and not has_unit(p)]
        if bad:
            out[qualname] = bad
    return out


def _listed(table: dict[str, str], qualname: str, param: str) -> bool:
    return param in table or f"{qualname}:{param}" in table


def allowed(qualname: str, param: str) -> bool:
    """True when :data:`ALLOWED` or :data:`DEFERRED` lists ``param`` (everywhere or for
    ``qualname``)."""
    return _listed(ALLOWED, qualname, param) or _listed(DEFERRED, qualname, param)


def violations() -> dict[str, list[str]]:
    """The findings that :data:`ALLOWED` does not cover (empty when the API is clean)."""
    out = {}
    for qualname, params in findings().items():
        bad = [p for p in params if not allowed(qualname, p)]
        if bad:
            out[qualname] = bad
    return out


def stale_allowances() -> list[str]:
    """Entries of :data:`ALLOWED` and :data:`DEFERRED` that no finding uses any more."""
    used: set[str] = set()
    for qualname, params in findings().items():
        for p in params:
            used.update({p, f"{qualname}:{p}"})
    return sorted((set(ALLOWED) | set(DEFERRED)) - used)


if __name__ == "__main__":
    found = findings()
    for key in sorted(found):
        marks = [p + (" (deferred)" if _listed(DEFERRED, key, p) and not _listed(ALLOWED, key, p)
                      else "" if allowed(key, p) else " (NOT ALLOWED)") for p in found[key]]
        print(f"{key.removeprefix(PREFIX)}: {', '.join(marks)}")
    bad = violations()
    print(f"{sum(map(len, found.values()))} unit-less quantity names in {len(found)} callables;"
          f" {sum(map(len, bad.values()))} not allowed; stale allowances: "
          f"{stale_allowances() or 'none'}")
