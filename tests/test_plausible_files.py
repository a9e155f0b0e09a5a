"""Unit slips in parameter files: every dimensional key has a plausible range (issue 27).

One table of ranges per file kind (``MAGNET_PLAUSIBLE``, ``VEHICLE_PLAUSIBLE``,
``GUIDEWAY_PLAUSIBLE``) and one check (:func:`maglevkit.validation.check_plausible`).
"""

from __future__ import annotations

import copy
import re
import sys
import warnings
from importlib import resources
from pathlib import Path
from typing import Any

import pytest

import maglevkit as mk
from maglevkit.design import DESIGN_PLAUSIBLE, read_design_spec
from maglevkit.magnets.base import MAGNET_PLAUSIBLE
from maglevkit.validation import Plausible, check_plausible
from maglevkit.vehicle.crosssection import CROSS_SECTION_PLAUSIBLE, parse_cross_section
from maglevkit.vehicle.data import GUIDEWAY_PLAUSIBLE, parse_guideway
from maglevkit.vehicle.train import VEHICLE_PLAUSIBLE, parse_vehicle

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _bundled(path: str) -> dict[str, Any]:
    return tomllib.loads((resources.files("maglevkit") / "data" / path).read_text())


MAGNETS = {name: _bundled(f"{name}.toml") for name in mk.bundled_magnets()}
VEHICLES = {"tr09": _bundled("vehicle/tr09.toml")}
GUIDEWAYS = {"guideway": _bundled("vehicle/guideway.toml")}
CROSS_SECTIONS = {"tr09-cross-section": _bundled("vehicle/tr09-cross-section.toml")}
DESIGNS = {"u-magnet-design": _bundled("designs/u-magnet-design.toml"),
           "tr09-design": _bundled("designs/tr09-design.toml")}
KINDS = {
    "magnet": (MAGNETS, MAGNET_PLAUSIBLE, lambda p: mk.build_magnet(p, source="f")),
    "vehicle": (VEHICLES, VEHICLE_PLAUSIBLE, lambda p: parse_vehicle(p, "f")),
    "guideway": (GUIDEWAYS, GUIDEWAY_PLAUSIBLE, lambda p: parse_guideway(p, "f")),
    "cross-section": (CROSS_SECTIONS, CROSS_SECTION_PLAUSIBLE,
                      lambda p: parse_cross_section(p, "f")),
    # issue 27 "Must show" names the design specs too (their [variables] bounds are lists)
    "design": (DESIGNS, DESIGN_PLAUSIBLE, lambda p: read_design_spec(p)),
}


def dimensional_keys(params: dict[str, Any], ranges: dict[str, Plausible]) -> list[str]:
    return [name for name in ranges
            if name.partition(".")[2] in params.get(name.partition(".")[0], {})]


def scaled(params: dict[str, Any], name: str, factor: float) -> dict[str, Any]:
    p = copy.deepcopy(params)
    table, _, key = name.partition(".")
    v = p[table][key]
    p[table][key] = [x * factor for x in v] if isinstance(v, list) else v * factor
    return p


def test_the_issue_examples_warn_naming_the_key_unit_and_slip() -> None:
    u = copy.deepcopy(MAGNETS["u-magnet"])
    u["magnet"]["depth"] = 100          # mm typed into a metre key: was 1.5 MN at 20 A
    with pytest.warns(mk.PlausibilityWarning,
                      match=r"\[magnet\] depth = 100 m is above the plausible range .* "
                            r"1000 times too large: typed in mm instead of m"):
        mk.build_magnet(u)
    tr = scaled(MAGNETS["tr09-standard"], "magnet.pole_pitch", 1000)
    with pytest.warns(mk.PlausibilityWarning, match=r"\[magnet\] pole_pitch = 258"):
        mk.build_magnet(tr)
    tr = copy.deepcopy(MAGNETS["tr09-standard"])
    tr["operating"]["nominal_current"] = 3.35e7
    with pytest.warns(mk.PlausibilityWarning, match=r"\[operating\] nominal_current = 33500000"):
        mk.build_magnet(tr)
    veh = copy.deepcopy(VEHICLES["tr09"])
    veh["car_body"]["mass"] = 40.7      # tonnes typed into a kilogram key
    with pytest.warns(mk.PlausibilityWarning,
                      match=r"\[car_body\] mass = 40.7 kg is below .* typed in t \(tonnes\) "
                            "instead of kg"):
        parse_vehicle(veh, "tr09")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_bundled_files_are_plausible(kind: str) -> None:
    files, ranges, build = KINDS[kind]
    for params in files.values():
        with warnings.catch_warnings():
            warnings.simplefilter("error", mk.PlausibilityWarning)
            build(copy.deepcopy(params))
        assert dimensional_keys(params, ranges), "no dimensional key found"


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("factor", [1e3, 1e-3])
def test_every_unit_slip_of_every_dimensional_key_is_reported(kind: str, factor: float) -> None:
    # issue 27: 32 of 56 magnet files with a length times 1000 loaded silently
    files, ranges, build = KINDS[kind]
    for fname, params in files.items():
        for name in dimensional_keys(params, ranges):
            table, _, key = name.partition(".")
            refused: list[str] = []
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    build(scaled(params, name, factor))
                except mk.ParameterFileError as exc:   # a documented error may follow the
                    # warning; a value that cannot be physical (Plausible.physical_high,
                    # e.g. a design gap of metres) is refused instead, with the same words
                    refused = [str(exc)] if "cannot be physical" in str(exc) else []
            texts = [str(w.message) for w in caught
                     if w.category is mk.PlausibilityWarning] + refused
            assert any(f"[{table}] {key} = " in t for t in texts), (fname, name, factor, texts)
            unit = ranges[name].unit
            assert any(re.search(rf"\({key} is in {re.escape(unit)}\)", t) for t in texts)


def test_the_check_skips_zero_and_non_numbers_and_checks_lists() -> None:
    ranges = {"a.x": Plausible(1.0, 10.0, "m"), "a.y": Plausible(1.0, 10.0, "m"),
              "a.z": Plausible(1.0, 10.0, "m"), "b.w": Plausible(1.0, 10.0, "m")}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_plausible({"a": {"x": 0.0, "y": "text", "z": True}}, ranges) == []
    with pytest.warns(mk.PlausibilityWarning, match=r"\[a\] x = -2000"):
        assert check_plausible({"a": {"x": [2.0, -2000.0]}}, ranges) == ["a.x"]
    with pytest.raises(ValueError):
        Plausible(2.0, 1.0, "m")


@pytest.mark.parametrize("value", [1e150, 1e-150])
@pytest.mark.parametrize(("name", "key", "eddy_model"), [
    ("tr-guidance", "rail.thickness", "ladder"),        # was OverflowError (ladder's J_rect)
    ("tr09-standard", "magnet.back_height", "ladder"),
    ("u-magnet", "magnet.pole_width", "ladder_split"),  # 1e-150 was ZeroDivisionError
])
def test_a_length_that_cannot_be_physical_is_refused_naming_key_value_and_limits(
        name: str, key: str, eddy_model: str, value: float) -> None:
    # tidy26: an absurd length reached the builders' laws (float overflow / division by
    # zero, a traceback); the one plausibility table refuses it first, with the limits
    params = copy.deepcopy(MAGNETS[name])
    table, _, sub = key.partition(".")
    params[table][sub] = value
    params["magnet"]["eddy_model"] = eddy_model
    with pytest.raises(mk.ParameterFileError,
                       match=rf"\[{table}\] {sub} = {re.escape(repr(value))} m cannot be physical .*allowed "
                             r"are >= 1e-08 and <= 10000 m"):
        mk.build_magnet(params, source="f")


def test_the_length_limits_refuse_no_unit_slip_of_a_bundled_file() -> None:
    # the limits lie beyond every bundled length times 1000 / 1/1000 (those warn, see
    # above) and enclose every plausible range
    from maglevkit.magnets.base import MAGNET_LENGTH_PHYSICAL_M
    lo, hi = MAGNET_LENGTH_PHYSICAL_M
    for params in MAGNETS.values():
        for name in dimensional_keys(params, MAGNET_PLAUSIBLE):
            rng = MAGNET_PLAUSIBLE[name]
            if rng.unit != "m":
                continue
            assert (rng.physical_low, rng.physical_high) == (lo, hi), name
            table, _, key = name.partition(".")
            values = params[table][key]
            for v in values if isinstance(values, list) else [values]:
                assert lo < abs(v) / 1000 and abs(v) * 1000 < hi, (name, v)


def test_the_cli_refuses_an_absurd_length_with_one_line(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from maglevkit.cli import app
    text = (resources.files("maglevkit") / "data" / "tr-guidance.toml").read_text()
    bad = tmp_path / "bad.toml"
    # the bundled file builds the eddy ladder (whose thickness**3 overflowed at 1e300)
    assert re.search(r'(?m)^eddy_model = "ladder"', text)
    bad.write_text(re.sub(r"(?m)^(\[rail\]\n)thickness = .*$", r"\1thickness = 1e300", text))
    assert "thickness = 1e300" in bad.read_text()
    for command in (["statics", str(bad)], ["maps", "build", str(bad), "-o",
                                             str(tmp_path / "m.nc")]):
        res = CliRunner().invoke(app, command)
        assert res.exit_code == 2, (command, res.output)
        errors = [line for line in res.stderr.splitlines() if line.startswith("error")]
        assert len(errors) == 1 and "[rail] thickness = 1e+300 m cannot be physical" \
            in errors[0], res.stderr
        assert "Traceback" not in res.output
