"""Model reduction: characteristic maps and the current-based model (paper Sec. IV)."""

from .maps import (
    CharacteristicMaps,
    build_maps,
    circuit_pole_groups,
    default_eddy_modes,
    load_maps,
)
from .parameters import current_jump_admittance, eddy_resistance
from .tables_in import eddy_resistance_from_step, maps_from_table, read_table
from .transient import dl_ds_from_ramp, flux_held_ramp

__all__ = ["CharacteristicMaps", "build_maps", "circuit_pole_groups", "current_jump_admittance",
           "default_eddy_modes", "dl_ds_from_ramp", "eddy_resistance",
           "eddy_resistance_from_step", "flux_held_ramp", "load_maps", "maps_from_table",
           "read_table"]
