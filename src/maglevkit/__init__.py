"""maglevkit: electromagnet models of EMS maglev vehicles (Transrapid type).

Layers (data flows one way): ``materials`` -> ``circuit`` -> ``magnets`` -> ``models``.
"""

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
from .errors import (
    InputError,
    MaglevkitError,
    MaterialError,
    OutOfRangeError,
    ParameterError,
    ParameterFileError,
    SolverError,
    TopologyError,
)
from .magnets import Magnet, ModelOptions, build_magnet, bundled_magnets, load_magnet
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
from .models import StaticSolution, coenergy, magnetic_energy, pole_force_eq6, solve_statics

__version__ = "0.1.0"

__all__ = [
    "MU0",
    "AirGap",
    "Branch",
    "Circuit",
    "Coil",
    "ConstantPermeability",
    "EddyCurrent",
    "GapLeakage",
    "IdealIron",
    "InputError",
    "IronPath",
    "LeakagePermeance",
    "MaglevkitError",
    "Magnet",
    "Material",
    "MaterialError",
    "ModelOptions",
    "Network",
    "OutOfRangeError",
    "ParameterError",
    "ParameterFileError",
    "SoftMagneticMaterial",
    "SolverError",
    "StaticSolution",
    "TabulatedBH",
    "TopologyError",
    "__version__",
    "build_magnet",
    "bundled_magnets",
    "carter_coefficient",
    "coenergy",
    "get_material",
    "load_magnet",
    "magnetic_energy",
    "material_names",
    "pole_force_eq6",
    "solve_statics",
]
