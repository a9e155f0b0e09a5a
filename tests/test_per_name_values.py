"""The one converter of per-name inputs (models.inputs.per_name_values): its messages name
the user's option, the value and what is allowed, the same style in all four users."""

from __future__ import annotations

import math

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.models.inputs import per_name_values

NAMES = ("a/front", "a/rear")


def test_forms_and_the_fast_path() -> None:
    v = np.array([1.0, 2.0])
    assert per_name_values(v, NAMES, "voltages", "V") is v          # no copy, no conversion
    assert per_name_values(3.0, NAMES, "voltages", "V").tolist() == [3.0, 3.0]
    assert per_name_values([1, 2], NAMES, "voltages", "V").tolist() == [1.0, 2.0]
    assert per_name_values({"a/rear": 2, "a/front": 1}, NAMES, "voltages", "V").tolist() == [1, 2]
    # finite=False passes NaN on (a kernel flags it), positive and allow_inf
    assert math.isnan(per_name_values([np.nan, 1.0], NAMES, "gaps", "m", finite=False)[0])
    assert per_name_values([1.0, math.inf], NAMES, "R", "ohm", positive=True,
                           allow_inf=True)[1] == math.inf


@pytest.mark.parametrize(("value", "options", "pattern"), [
    ({"a/front": 1.0, "x": 2.0}, {}, r"voltages: unknown names \['x'\], missing \['a/rear'\]; "
                                     r"give one value \[V\] per circuit: \['a/front', 'a/rear'\]"),
    ([1.0, 2.0, 3.0], {}, r"voltages: expected 2 values \[V\] \(one per circuit of "
                          r"\['a/front', 'a/rear'\], or one for all\), got shape \(3,\)"),
    ([1.0, math.nan], {}, r"voltages must be finite: circuit 'a/rear' = nan V"),
    ([1.0, math.inf], {"allow_inf": True, "positive": True}, None),
    ([1.0, -math.inf], {"allow_inf": True}, r"voltages must be finite \(or inf\): circuit "
                                            r"'a/rear' = -inf V"),
    ([1.0, 0.0], {"positive": True}, r"voltages must be > 0 V: circuit 'a/rear' = 0.0 V"),
    ([True, 1.0], {}, r"voltages \[V\] = \[True, 1.0\] \(list\) contains a bool"),
])
def test_messages(value: object, options: dict, pattern: str | None) -> None:
    if pattern is None:
        per_name_values(value, NAMES, "voltages", "V", **options)
        return
    with pytest.raises(InputError, match=pattern):
        per_name_values(value, NAMES, "voltages", "V", **options)


def test_the_users_share_the_message_style() -> None:
    """CurrentModel, MagnetBank, its stepper and the table import say the same."""
    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.004, 0.02, 5), currents_A=np.linspace(0, 40, 5),
                         progress=False)
    cm = mk.CurrentModel(maps)
    st = cm.initial_state(gaps_m=0.01, currents_A=10.0)
    with pytest.raises(InputError, match=r"voltages: expected 1 values \[V\] \(one per circuit"):
        cm.step(st, 1e-3, [1.0, 2.0])
    bank = mk.MagnetBank({"m": maps})
    bst = bank.initial_state(gaps_m=0.01, currents_A=10.0)
    with pytest.raises(InputError, match=r"voltages: expected 1 values \[V\] \(one per circuit"):
        bank.step(bst, 1e-3, [1.0, 2.0])
    with pytest.raises(InputError, match=r"voltages: unknown names \['x'\], missing"):
        bank.stepper(bst, 1e-3).advance({"x": 1.0})
    with pytest.raises(InputError, match=r"gaps must be > 0 m: gap '.*' = -0.01 m"):
        cm.initial_state(gaps_m=-0.01, currents_A=10.0)


def test_leading_axes_and_the_statics_and_sampled_inputs_share_it() -> None:
    """``leading=True`` (the statics' gap and current grids): arrays (..., n), mappings of
    equal-shaped arrays stacked along the last axis; the statics' converter and the
    sampled inputs of ``simulate`` give the same messages."""
    grid = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    assert per_name_values(grid, NAMES, "gaps", "m", kind="gap", leading=True) is grid
    got = per_name_values({"a/rear": np.array([2.0, 4.0]), "a/front": np.array([1.0, 3.0])},
                          NAMES, "gaps", "m", kind="gap", leading=True)
    assert got.tolist() == [[1.0, 2.0], [3.0, 4.0]]
    assert per_name_values(7.0, NAMES, "gaps", "m", leading=True).tolist() == [7.0, 7.0]
    with pytest.raises(InputError, match=r"gaps must be finite: gap 'a/rear' = inf m"):
        per_name_values([[1.0, 2.0], [3.0, math.inf]], NAMES, "gaps", "m", kind="gap",
                        leading=True)
    with pytest.raises(InputError, match=r"gaps: expected 2 values \[m\] along the last axis"):
        per_name_values(np.ones((2, 3)), NAMES, "gaps", "m", kind="gap", leading=True)
    mag = mk.load_magnet("u-magnet")
    with pytest.raises(InputError, match=r"circuit currents: unknown names \['x'\], missing "
                                         r"\['coil'\]; give one value \[A\] per circuit"):
        mk.solve_statics(mag, gaps_m=0.01, currents_A={"x": 1.0})
    with pytest.raises(InputError, match=r"voltages: unknown names \['x'\], missing \['coil'\]; "
                                         r"give one value \[V\] per name: \['coil'\]"):
        mk.simulate(mag, (0.0, 0.01), dt_s=1e-3, gaps_m=0.01, voltages_V={"x": 1.0})


def test_flux_model_step_shares_the_converter() -> None:
    """FluxModel.step takes its per-circuit and per-gap inputs through the same converter
    as the reduced models (it had a converter of its own with other messages)."""
    mag = mk.load_magnet("u-magnet")
    fm = mk.FluxModel(mag)
    st = fm.initial_state(gaps_m=0.01, currents_A=10.0)
    gap = fm.gap_names[0]
    with pytest.raises(InputError, match=r"voltages: expected 1 values \[V\] \(one per circuit"):
        fm.step(st, 1e-3, [1.0, 2.0])
    with pytest.raises(InputError, match=r"voltages: unknown names \['x'\], missing \['coil'\]; "
                                         r"give one value \[V\] per circuit: \['coil'\]"):
        fm.step(st, 1e-3, {"x": 1.0})
    with pytest.raises(InputError, match=r"voltages must be finite: circuit 'coil' = nan V"):
        fm.step(st, 1e-3, math.nan)
    with pytest.raises(InputError, match=rf"gaps must be finite: gap '{gap}' = inf m"):
        fm.step(st, 1e-3, 1.0, gaps_m=math.inf)
    n_g = len(fm.gap_names)
    with pytest.raises(InputError, match=rf"gap_rates: expected {n_g} values \[m/s\] \(one per gap"):
        fm.step(st, 1e-3, 1.0, gap_rates_m_per_s=np.zeros(n_g + 1))
    with pytest.raises(InputError, match=r"voltages \[V\] = True \(bool\) is a bool"):
        fm.step(st, 1e-3, True)
    # the accepted forms give the same step: one for all, a sequence, a mapping
    a = fm.step(st, 1e-3, 5.0)[0].currents_A
    b = fm.step(st, 1e-3, {"coil": 5.0}, gaps_m=[0.01] * n_g)[0].currents_A
    assert np.array_equal(a, b)
