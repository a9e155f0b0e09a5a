"""Model reduction: characteristic maps and the current-based model (paper Sec. IV)."""

from .maps import CharacteristicMaps, build_maps, circuit_pole_groups, load_maps

__all__ = ["CharacteristicMaps", "build_maps", "circuit_pole_groups", "load_maps"]
