"""maglevkit: electromagnet models of EMS maglev vehicles (Transrapid type).

Layers (data flows one way; a module imports only from layers below it, checked by
import-linter's ``layers`` contract in ``pyproject.toml`` and ``tests/test_layers.py``):
``errors``, ``validation``, ... -> ``materials`` -> ``circuit`` -> ``magnets`` -> ``models``
(statics, flux DAE) -> ``reduction`` (maps) -> reduced circuits -> ``simulation``
(:func:`simulate` for every model) -> ``plant`` -> ``control`` -> ``vehicle`` ->
``export``, ``sweep``, ``compare``, ``figures`` -> ``cli``.

The public names are loaded on first use (PEP 562 module ``__getattr__``), so ``import
maglevkit`` (and every ``maglevkit`` command-line call) does not pay for CasADi, SciPy and
xarray before it needs them (docs/decisions.md, "Command-line conventions").
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._version import __version__
from .errors import (
    DataError,
    DataWarning,
    InputError,
    MaglevkitError,
    MaglevkitWarning,
    MaterialError,
    OutOfRangeError,
    ParameterError,
    ParameterFileError,
    PlausibilityWarning,
    ProvenanceWarning,
    SolverError,
    TopologyError,
)

if TYPE_CHECKING:  # the eager imports, for type checkers and IDEs
    from .calibration import calibrate
    from .circuit import (
        AirGap,
        Branch,
        Circuit,
        Coil,
        EddyCurrent,
        GapLeakage,
        IronPath,
        LeakagePermeance,
        Network,
        carter_coefficient,
    )
    from .magnets import (
        Magnet,
        ModelOptions,
        PlausibleRange,
        build_magnet,
        bundled_magnets,
        load_magnet,
    )
    from .materials import (
        MU0,
        ConstantPermeability,
        IdealIron,
        Material,
        SoftMagneticMaterial,
        TabulatedBH,
        get_material,
        material_names,
    )
    from .models import (
        FluxModel,
        FluxState,
        InductanceEstimate,
        Scenario,
        SimulationResult,
        StaticSolution,
        coenergy,
        differential_inductance_from_step,
        load_scenario,
        magnetic_energy,
        pole_force_eq6,
        solve_statics,
        voltage_step_response,
    )
    from .reduced import (
        BankOutputs,
        BankSimulation,
        BankState,
        BankStepper,
        CurrentModel,
        MagnetBank,
        ReducedSimulation,
    )
    from .reduction import CharacteristicMaps, build_maps, load_maps, maps_from_table
    from .simulation import simulate

_LAZY: dict[str, str] = {
    "AirGap": ".circuit",
    "Branch": ".circuit",
    "Circuit": ".circuit",
    "Coil": ".circuit",
    "EddyCurrent": ".circuit",
    "GapLeakage": ".circuit",
    "IronPath": ".circuit",
    "LeakagePermeance": ".circuit",
    "Network": ".circuit",
    "carter_coefficient": ".circuit",
    "Magnet": ".magnets",
    "ModelOptions": ".magnets",
    "PlausibleRange": ".magnets",
    "build_magnet": ".magnets",
    "bundled_magnets": ".magnets",
    "load_magnet": ".magnets",
    "MU0": ".materials",
    "ConstantPermeability": ".materials",
    "IdealIron": ".materials",
    "Material": ".materials",
    "SoftMagneticMaterial": ".materials",
    "TabulatedBH": ".materials",
    "get_material": ".materials",
    "material_names": ".materials",
    "BankOutputs": ".reduced",
    "BankSimulation": ".reduced",
    "BankState": ".reduced",
    "BankStepper": ".reduced",
    "CurrentModel": ".reduced",
    "FluxModel": ".models",
    "FluxState": ".models",
    "InductanceEstimate": ".models",
    "MagnetBank": ".reduced",
    "ReducedSimulation": ".reduced",
    "Scenario": ".models",
    "SimulationResult": ".models",
    "StaticSolution": ".models",
    "coenergy": ".models",
    "differential_inductance_from_step": ".models",
    "load_scenario": ".models",
    "magnetic_energy": ".models",
    "pole_force_eq6": ".models",
    "simulate": ".simulation",
    "solve_statics": ".models",
    "voltage_step_response": ".models",
    "CharacteristicMaps": ".reduction",
    "build_maps": ".reduction",
    "load_maps": ".reduction",
    "maps_from_table": ".reduction",
    "calibrate": ".calibration",
}
"""Public name -> the submodule that defines it (imported on first access)."""

_SUBPACKAGES = frozenset({"calibration", "circuit", "cli", "compare", "control", "design", "errors",
                          "export", "figures", "magnets", "materials", "models", "plant",
                          "plotting", "reduced", "reduction", "simulation", "sweep", "validation",
                          "vehicle"})


# Hidden from type checkers, which see the imports above: a typo such as
# ``maglevkit.laod_magnet`` stays a type error instead of becoming ``Any``.
if not TYPE_CHECKING:
    def __getattr__(name: str) -> Any:
        """Import a public name (or a subpackage) on first access and cache it here."""
        module = _LAZY.get(name)
        if module is not None:
            value = getattr(importlib.import_module(module, __name__), name)
        elif name in _SUBPACKAGES:
            value = importlib.import_module(f".{name}", __name__)
        else:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
        globals()[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(globals()) | set(__all__) | _SUBPACKAGES)


__all__ = [
    "AirGap",
    "BankOutputs",
    "BankSimulation",
    "BankState",
    "BankStepper",
    "Branch",
    "CharacteristicMaps",
    "Circuit",
    "Coil",
    "ConstantPermeability",
    "CurrentModel",
    "DataError",
    "DataWarning",
    "EddyCurrent",
    "FluxModel",
    "FluxState",
    "GapLeakage",
    "IdealIron",
    "InductanceEstimate",
    "InputError",
    "IronPath",
    "LeakagePermeance",
    "MU0",
    "MaglevkitError",
    "MaglevkitWarning",
    "Magnet",
    "MagnetBank",
    "Material",
    "MaterialError",
    "ModelOptions",
    "Network",
    "OutOfRangeError",
    "ParameterError",
    "ParameterFileError",
    "PlausibilityWarning",
    "PlausibleRange",
    "ProvenanceWarning",
    "Scenario",
    "SimulationResult",
    "SoftMagneticMaterial",
    "SolverError",
    "StaticSolution",
    "TabulatedBH",
    "TopologyError",
    "__version__",
    "ReducedSimulation",
    "build_magnet",
    "build_maps",
    "bundled_magnets",
    "calibrate",
    "carter_coefficient",
    "coenergy",
    "differential_inductance_from_step",
    "get_material",
    "load_magnet",
    "load_maps",
    "load_scenario",
    "magnetic_energy",
    "maps_from_table",
    "material_names",
    "pole_force_eq6",
    "simulate",
    "solve_statics",
    "voltage_step_response",
]
