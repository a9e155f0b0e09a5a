"""A user's first hour (issue 27): flags, bad objects, non-finite results, interrupts, CLI."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.models.bank import MagnetBank

GAPS = np.linspace(0.006, 0.016, 4)
CURRENTS = np.linspace(0.0, 60.0, 4)


@pytest.fixture(scope="module")
def small_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, progress=False)


# ------------------------------------------------------------ wrong or unreported results
@pytest.mark.parametrize("value", ["no", 0, 1, None, "False"])
def test_current_model_refuses_a_flag_that_is_not_a_bool(small_maps, value) -> None:  # type: ignore[no-untyped-def]
    # was: extrapolate="no" extrapolated (a string counts as true); MagnetBank refused it
    with pytest.raises(mk.InputError, match=r"extrapolate = .*expected True or False"):
        mk.CurrentModel(small_maps, extrapolate=value)
    with pytest.raises(mk.InputError, match=r"extrapolate = .*expected True or False"):
        MagnetBank({"a": small_maps}, extrapolate=value)
    with pytest.raises(mk.InputError, match=r"jit = .*expected True or False"):
        mk.CurrentModel(small_maps, jit=value)
    assert mk.CurrentModel(small_maps, extrapolate=np.bool_(True)).extrapolate is True


def test_none_instead_of_a_state_or_members_is_an_input_error(small_maps) -> None:  # type: ignore[no-untyped-def]
    model = mk.CurrentModel(small_maps)
    with pytest.raises(mk.InputError, match="state must be a CurrentModelState .* got NoneType"):
        model.step(None, 1e-3, 0.0)
    for bad in (None, 3, "u-magnet"):
        with pytest.raises(mk.InputError, match="members = .*expected a mapping of names"):
            MagnetBank(bad)


def test_a_non_finite_statics_result_is_a_solver_error(u_magnet: mk.Magnet,
                                                      recwarn: pytest.WarningsRecorder) -> None:
    # was: --currents 1e200 gave F = nan with rc 0 (the residual came back as -inf)
    with pytest.raises(mk.SolverError, match=r"non-finite result .* I\[coil\]=1e\+200"):
        mk.solve_statics(u_magnet, gaps=0.01, currents=1e200)
    p = copy.deepcopy(dict(mk.load_magnet("tr09-standard").parameters))
    p["stator"]["slot_depth"] = 1e308        # was: F = nan from the API
    with pytest.warns(mk.PlausibilityWarning, match=r"\[stator\] slot_depth"):
        m = mk.build_magnet(p)
    with pytest.raises(mk.SolverError):
        mk.solve_statics(m, gaps=0.01, currents=30.0)
