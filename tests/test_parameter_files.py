"""One reader for every kind of TOML parameter file (magnets, guideways, vehicles)."""

from __future__ import annotations

from pathlib import Path

import pytest

import maglevkit as mk
from maglevkit.parameter_files import bundled_files, read_parameter_file
from maglevkit.vehicle.data import bundled_guideways, load_guideway
from maglevkit.vehicle.train import bundled_vehicles, load_vehicle


def test_bundled_lists_hold_only_their_own_kind() -> None:
    # the vehicle folder holds a guideway and a vehicle file; each list offers only its kind
    # (bundled_guideways() once listed "tr09", which load_guideway then refused)
    assert bundled_guideways() == ["guideway"]
    assert bundled_vehicles() == ["tr09"]
    assert set(bundled_files("vehicle")) == {"guideway", "tr09", "tr09-cross-section"}
    for name in bundled_guideways():
        load_guideway(name)
    for name in bundled_vehicles():
        load_vehicle(name)
    for name in mk.bundled_magnets():
        params, label = read_parameter_file(name, what="magnet")
        assert label == name and "magnet" in params


@pytest.mark.parametrize("load, what", [(mk.load_magnet, "magnet"), (load_guideway, "guideway"),
                                        (load_vehicle, "vehicle")])
def test_every_loader_fails_the_same_way(load, what: str, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(mk.InputError, match=f"expected a bundled {what} name"):
        load(None)
    with pytest.raises(mk.ParameterFileError, match=f"no bundled {what} of that name; "
                       f"bundled {what}s: "):
        load("nonesuch")
    with pytest.raises(mk.ParameterFileError, match=f"{what} file .* does not exist"):
        load(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[x\n")
    with pytest.raises(mk.ParameterFileError, match="not valid TOML"):
        load(bad)
