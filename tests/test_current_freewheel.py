"""``CurrentModel(freewheel=True)``: the chopper's diodes in the single-magnet reduced model.

Independent reference: with the diodes, a coil driven at -U_max discharges to I = 0 and
stays there (never below); the flux then decays through the eddy branch alone.  Without
them eq. 8 drives the current negative (out of the maps).  The table path, the
B-spline path and a bank of the same maps with ``freewheel=True`` give the same currents
(to the tables' interpolation difference against the B-splines, 1e-3 relative; bank and
table path run the same kernel: 1e-12).
"""
from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError


@pytest.fixture(scope="module")
def u_maps() -> mk.CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.004, 0.02, 9),
                         currents_A=np.linspace(0.0, 40.0, 21), progress=False)


def _discharge(model, n: int = 60, dt: float = 1e-3) -> np.ndarray:  # type: ignore[no-untyped-def]
    st = model.initial_state(gaps_m=0.010, currents_A=20.0)
    coil = []
    for _ in range(n):
        st, out = model.step(st, dt, -400.0, 0.010)
        coil.append(float(np.ravel(out.currents_A)[0]))
    return np.array(coil)


def test_diodes_hold_the_coil_current_at_zero(u_maps) -> None:  # type: ignore[no-untyped-def]
    free = _discharge(mk.CurrentModel(u_maps, freewheel=True))
    # eq. 8 without diodes drives I_L below zero: out of the maps (0 ... 40 A)
    with pytest.raises(OutOfRangeError):
        _discharge(mk.CurrentModel(u_maps))
    assert free.min() >= -1e-9                  # with them: never below zero
    assert free[-1] == pytest.approx(0.0, abs=1e-9)


def test_table_bspline_and_bank_paths_agree(u_maps) -> None:  # type: ignore[no-untyped-def]
    tables = _discharge(mk.CurrentModel(u_maps, freewheel=True), n=30)
    spline = _discharge(mk.CurrentModel(u_maps, freewheel=True, lookup="bspline"), n=30)
    np.testing.assert_allclose(spline, tables, rtol=0, atol=1e-3 * 20.0)
    bank = mk.MagnetBank({"m": u_maps}, freewheel=True)
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    coil = []
    for _ in range(30):
        st, out = bank.step(st, 1e-3, -400.0, 0.010)
        coil.append(float(out.currents_A[0]))
    np.testing.assert_allclose(coil, tables, rtol=0, atol=1e-12)


def test_refusals(u_maps) -> None:  # type: ignore[no-untyped-def]
    # an eddy network takes the diodes where its fitted R_0 is finite, as the U-magnet's is
    # (R_0 = inf is refused by name: tests/test_network_freewheel.py)
    net = mk.CurrentModel(u_maps, freewheel=True, eddy_modes=1)
    assert net.freewheel and net.eddy_modes == 1
    # the ladder has the diodes too (tests/test_reduced_motion_eddy.py,
    # test_freewheel_diodes_on_the_single_magnet_ladder), and a bank keeps them
    ladder = mk.CurrentModel(u_maps, freewheel=True, motion_eddy=True)
    assert ladder.freewheel and ladder.motion_eddy
    with pytest.raises(InputError, match="freewheel=True"):
        mk.MagnetBank({"m": ladder})
    assert mk.MagnetBank({"m": ladder}, freewheel=True, compiled="never").motion_eddy
    with pytest.raises(InputError, match="freewheel"):
        mk.CurrentModel(u_maps, freewheel="yes")
    with pytest.raises(InputError, match="freewheel=True"):
        mk.MagnetBank({"m": mk.CurrentModel(u_maps, freewheel=True)})
