"""Parametric magnet topologies and their parameter files.

Characteristic numbers from the statics (saturation knee, coupling) are in
:mod:`maglevkit.models.characteristics`.
"""

from . import guidance as _guidance  # noqa: F401  (registers the "guidance_magnet" kind)
from . import levitation as _levitation  # noqa: F401  (registers the "levitation_magnet" kind)
from . import u_magnet as _u_magnet  # noqa: F401  (registers the "u_magnet" kind)
from .base import (
    MAX_CURRENT_DENSITY_A_PER_M2,
    Magnet,
    ModelOptions,
    PlausibleRange,
    build_magnet,
    bundled_magnets,
    load_magnet,
)
from .levitation import pole_gap_names

__all__ = [
    "MAX_CURRENT_DENSITY_A_PER_M2",
    "Magnet",
    "ModelOptions",
    "PlausibleRange",
    "build_magnet",
    "bundled_magnets",
    "load_magnet",
    "pole_gap_names",
]
