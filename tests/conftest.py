"""Shared fixtures: the U-magnet and variants of it, hand-built linear networks with closed forms."""

from __future__ import annotations

import copy
import sys
from importlib import resources
from typing import Any

import pytest

import maglevkit as mk
from maglevkit.materials import MU0, ConstantPermeability

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


# A single flux loop: iron core (length L_FE, area AREA, mu_r) with an n-turn coil,
# closed by one air gap.  Reluctance Rm = L_FE/(mu0 mu_r A) + s/(mu0 A), L = n^2/Rm.
AREA = 4e-4       # m^2
L_FE = 0.2        # m
MU_R = 1000.0
TURNS = 200.0
R_EL = 1.5        # ohm
G_EC = 50.0       # S, eddy conductance of the core (R_ec = n^2/G = 800 ohm)


def loop_network(*, eddy: bool) -> mk.Network:
    els: list = [mk.IronPath("core_iron", L_FE, AREA, ConstantPermeability(MU_R))]
    if eddy:
        els.append(mk.EddyCurrent("core_eddy", G_EC))
    return mk.Network(
        (mk.Branch("core", "A", "B", tuple(els)),
         mk.Branch("gap", "B", "A", (mk.AirGap("airgap", gap_input="s", pole_area=AREA),))),
        (mk.Circuit("coil", R_EL, (mk.Coil("core", TURNS),)),),
        name="single loop",
    )


def loop_inductance(gap: float) -> float:
    rm = L_FE / (MU0 * MU_R * AREA) + gap / (MU0 * AREA)
    return TURNS**2 / rm


@pytest.fixture(scope="session")
def u_magnet() -> mk.Magnet:
    """The bundled U-magnet with eddy-current elements (statics ignore them)."""
    return mk.load_magnet("u-magnet")
