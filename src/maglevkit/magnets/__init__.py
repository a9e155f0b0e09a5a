"""Parametric magnet topologies and their parameter files."""

from . import u_magnet as _u_magnet  # noqa: F401  (registers the "u_magnet" kind)
from .base import Magnet, ModelOptions, build_magnet, bundled_magnets, load_magnet

__all__ = ["Magnet", "ModelOptions", "build_magnet", "bundled_magnets", "load_magnet"]
