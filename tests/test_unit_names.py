"""Unit-carrying input names (issue 22, item 7): the old names stay as deprecated aliases
that give the same numbers."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.validation import renamed_keywords

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, progress=False)


def test_helper_translates_warns_and_refuses_both() -> None:
    @renamed_keywords(dt="dt_s")
    def f(x: float, dt_s: float = 1.0) -> float:
        return x * dt_s

    with warnings.catch_warnings():
        warnings.simplefilter("error")            # the new name: no warning at all
        assert f(2.0, dt_s=3.0) == 6.0 and f(2.0, 3.0) == 6.0
    with pytest.warns(DeprecationWarning, match=r"f: dt= is deprecated, use dt_s="):
        assert f(2.0, dt=3.0) == 6.0
    with pytest.raises(InputError, match=r"give dt_s= only"):
        f(2.0, dt=3.0, dt_s=3.0)


def test_current_model_step_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    cm = mk.CurrentModel(u_maps)
    st = cm.initial_state(gaps=0.010, currents=20.0)
    new, out_new = cm.step(st, dt_s=2e-3, voltages_V=50.0, gaps_m=0.0101,
                           gap_rates_m_per_s=0.05)
    with pytest.warns(DeprecationWarning, match=r"use voltages_V="):
        old, out_old = cm.step(st, dt=2e-3, voltages=50.0, gaps=0.0101, gap_rates=0.05)
    # the same call underneath: equal bit for bit
    assert np.array_equal(new.inductor_currents_A, old.inductor_currents_A)
    assert np.array_equal(out_new.circuit_force_N, out_old.circuit_force_N)


def test_bank_step_and_stepper_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    bank = mk.MagnetBank({"a": u_maps, "b": u_maps})
    st = bank.initial_state(gaps=0.010, currents=20.0)
    u = bank.resistance_ohm * 22.0
    _, o_new = bank.step(st, 1e-3, u, gaps_m=0.0101, gap_rates_m_per_s=0.01)
    with pytest.warns(DeprecationWarning, match=r"use gaps_m="):
        _, o_old = bank.step(st, 1e-3, u, gaps=0.0101, gap_rates=0.01)
    assert np.array_equal(o_new.circuit_force_N, o_old.circuit_force_N)
    s_new = bank.stepper(st, dt_s=1e-3)
    with pytest.warns(DeprecationWarning, match=r"use dt_s="):
        s_old = bank.stepper(st, dt=1e-3)
    s_new.advance(voltages_V=u, gaps_m=0.0101, gap_rates_m_per_s=0.01)
    with pytest.warns(DeprecationWarning, match=r"use gap_rates_m_per_s="):
        s_old.advance(voltages=u, gaps=0.0101, gap_rates=0.01)
    assert np.array_equal(s_new.circuit_force_N, s_old.circuit_force_N)
    # and equal to the bank's own step (the stepper is the same kernel)
    assert np.array_equal(s_new.circuit_force_N, o_new.circuit_force_N)
    with pytest.raises(InputError, match=r"give voltages_V= only"):
        s_new.advance(voltages=u, voltages_V=u)
