"""Model reduction: characteristic maps and the current-based model (paper Sec. IV)."""

from .maps import CharacteristicMaps, build_maps, circuit_pole_groups, load_maps
from .parameters import current_jump_admittance, eddy_resistance
from .transient import dl_ds_from_ramp, flux_held_ramp

__all__ = ["CharacteristicMaps", "build_maps", "circuit_pole_groups", "current_jump_admittance",
           "dl_ds_from_ramp", "eddy_resistance", "flux_held_ramp", "load_maps"]
