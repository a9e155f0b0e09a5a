"""Shared fixtures: hand-built linear networks with closed-form answers, the U-magnet."""

from __future__ import annotations

import pytest

import maglevkit as mk
from maglevkit.materials import MU0, ConstantPermeability

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
    return mk.load_magnet("u-magnet")
