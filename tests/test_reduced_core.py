"""ReducedCore: the facts of the reduced circuits derived once, and the one RK4 step."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.reduced.core import EXTRA_CELLS, ReducedCore, eq8_a, rk4_substep, substep_count, substep_counts

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)


@pytest.fixture(scope="module")
def guidance_maps() -> mk.CharacteristicMaps:
    # the lumped eddy elements by name (the file's is the ladder since guideswitch): a
    # cheap two-circuit network with eq. 8's jump resistance
    # two circuits, each driving its own poles: the averaging/share matrices are not trivial
    return mk.build_maps(mk.load_magnet("tr-guidance", eddy_model="lumped"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


def test_core_matches_maps_and_consumers(guidance_maps: mk.CharacteristicMaps) -> None:
    core = ReducedCore.from_maps(guidance_maps)
    groups = guidance_maps.pole_groups
    # averaging rows: each circuit's substitute gap is the mean of its own poles
    for j, c in enumerate(core.circuit_names):
        cols = [core.gap_names.index(g) for g in groups[c]]
        assert np.allclose(core.averaging[j, cols], 1.0 / len(cols))
        assert core.averaging[j].sum() == pytest.approx(1.0, rel=1e-15)
    # share columns: a circuit's force is shared equally by its poles, all of it
    assert np.allclose(core.share.sum(axis=0), 1.0, rtol=1e-15)
    # a = 1 + R_el/R_ec, each R_ec as the maps hold it
    for choice, var in (("fit", "eddy_resistance_fit_ohm"), ("jump", "eddy_resistance_ohm")):
        c2 = ReducedCore.from_maps(guidance_maps, eddy_resistance=choice)
        r_ec = guidance_maps.dataset[var].values
        assert np.array_equal(c2.eddy_resistance_ohm, r_ec)
        assert np.array_equal(c2.a, 1.0 + c2.resistance_ohm / r_ec)
    # the grid extension keeps the spacing at both ends
    ext = core.extended_gaps_m
    assert ext.size == GAPS.size + 2 * EXTRA_CELLS
    assert np.allclose(np.diff(ext), GAPS[1] - GAPS[0], rtol=1e-9)
    # consumers hold the same objects, not copies of their own
    model = mk.CurrentModel(guidance_maps)
    assert model.core.eddy_resistance == "fit"
    assert np.array_equal(model.resistance_ohm, core.resistance_ohm)
    bank = mk.MagnetBank({"m": model, "n": guidance_maps})
    assert np.array_equal(bank.eddy_resistance_ohm, np.concatenate([core.eddy_resistance_ohm] * 2))
    with pytest.raises(ValueError):
        core.a[0] = 2.0                             # read-only


def test_core_refuses_bad_choice(guidance_maps: mk.CharacteristicMaps) -> None:
    with pytest.raises(InputError, match=r"eddy_resistance = 'mean'; use 'fit' or 'jump'"):
        ReducedCore.from_maps(guidance_maps, eddy_resistance="mean")


def test_a_without_eddy_branch() -> None:
    assert eq8_a(2.0, math.inf) == 1.0
    assert np.array_equal(eq8_a(np.array([2.0, 2.0]), np.array([math.inf, 4.0])), [1.0, 1.5])


def test_substep_rule() -> None:
    # whole multiples (within rounding) need no extra sub-step; anything above does
    assert substep_count(1e-3, 1e-3) == 1
    assert substep_count(3e-3 * (1 + 1e-14), 1e-3) == 3
    assert substep_count(3.01e-3, 1e-3) == 4
    assert substep_count(1e-9, 1e-3) == 1
    assert list(substep_counts([1e-3, 2.5e-3, 0.0], 1e-3)) == [1, 3, 1]


def test_rk4_substep_order_four() -> None:
    # dx/dt = -x: one RK4 step is the 4th-order Taylor polynomial of exp(-h) exactly
    h = 0.1
    x1 = rk4_substep(1.0, h, lambda v: -v)
    assert x1 == pytest.approx(1 - h + h**2 / 2 - h**3 / 6 + h**4 / 24, rel=1e-15)
    # moving inputs through the stage functions: dx/dt = t over [0, h] integrates exactly
    x = rk4_substep(ca.DM(0.0), h, lambda v: 0.0 * v, lambda v: h / 2 + 0.0 * v,
                    lambda v: h + 0.0 * v)
    assert float(x) == pytest.approx(h**2 / 2, rel=1e-14)
