"""Shared fixtures: the bundled U-magnet parameters and variants of it."""

from __future__ import annotations

import copy
import sys
from importlib import resources
from typing import Any

import pytest

import maglevkit as mk

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def u_params() -> dict[str, Any]:
    """A fresh copy of the bundled U-magnet parameter dictionary."""
    text = (resources.files("maglevkit") / "data" / "u-magnet.toml").read_text()
    return copy.deepcopy(tomllib.loads(text))


def build_u(*, material: str | None = None, magnet: dict | None = None, rail: dict | None = None,
            **options: bool) -> mk.Magnet:
    """The U-magnet with changed parameters and physics switches (eddy currents off by default)."""
    p = u_params()
    if material is not None:
        p["magnet"]["material"] = material
        p["rail"]["material"] = material
    p["magnet"].update(magnet or {})
    p["rail"].update(rail or {})
    opts = {"eddy_currents": False, **options}
    return mk.build_magnet(p, options=mk.ModelOptions(**opts))


@pytest.fixture(scope="session")
def u_magnet() -> mk.Magnet:
    return mk.load_magnet("u-magnet", eddy_currents=False)
