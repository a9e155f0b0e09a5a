"""Regression tests of the review of design, cross-section and the realistic default run
(review 1): documented values that were refused, unit slips that passed silently, values
that reached the model unchecked.  All fast (no time loop, no optimisation)."""

from __future__ import annotations

import copy
import math
import warnings
from importlib import resources
from typing import Any

import pytest
import tomllib

from maglevkit.design import DESIGN_PLAUSIBLE, evaluate_design, read_design_spec
from maglevkit.errors import InputError, ParameterFileError, PlausibilityWarning
from maglevkit.parameter_files import read_parameter_file
from maglevkit.vehicle.crossrun import (
    SCENARIO_PLAUSIBLE,
    Crosswind,
    TransitionCurve,
    parse_lateral,
)
from maglevkit.vehicle.data import parse_guideway
from maglevkit.vehicle.train import parse_vehicle


def bundled(folder: str, name: str, table: str) -> dict[str, Any]:
    doc, _ = read_parameter_file(name, what=table, folder=folder, table=table)
    return copy.deepcopy(doc)


def design_doc() -> dict[str, Any]:
    text = (resources.files("maglevkit") / "data" / "designs" / "u-magnet-design.toml").read_text()
    return tomllib.loads(text)


# ------------------------------------------------------------ the realistic default run
def test_guideway_precamber_zero_is_accepted_as_documented() -> None:
    """docs/vehicle.md: `precamber` optional, default 0; a file stating 0 was refused
    ("must be > 0").  0 now means no camber (no built-in profile); negative is refused."""
    doc = bundled("vehicle", "guideway", "guideway")
    doc["guideway"]["precamber"] = 0.0
    g = parse_guideway(doc, "test")
    assert g.span.precamber_m == 0.0
    doc["guideway"]["precamber"] = -2.7e-3
    with pytest.raises(ParameterFileError, match=r"precamber = -0.0027 m: must be >= 0"):
        parse_guideway(doc, "test")


def test_guideway_precamber_in_mm_warns() -> None:
    """2.7 (mm typed into the metre key) closed every gap with an error naming a circuit,
    not the key; it now warns with the key and the likely slip first."""
    doc = bundled("vehicle", "guideway", "guideway")
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        parse_guideway(doc, "test")                 # the bundled 2.7e-3 m: no warning
    doc["guideway"]["precamber"] = 2.7
    with pytest.warns(PlausibilityWarning, match=r"precamber = 2.7 m .*typed in mm"):
        parse_guideway(doc, "test")


def test_velocity_blend_zero_is_accepted_as_documented() -> None:
    """docs/vehicle.md: velocity_blend in [0, 1], default 0 (the gap rate only); a file
    stating 0 was refused ("must be > 0")."""
    doc = bundled("vehicle", "tr09", "vehicle")
    doc["control"]["velocity_blend"] = 0
    assert parse_vehicle(doc, "test").control_velocity_blend == 0.0
    doc["control"]["velocity_blend"] = -0.1
    with pytest.raises(ParameterFileError, match=r"velocity_blend = -0.1: must be >= 0"):
        parse_vehicle(doc, "test")


# ----------------------------------------------------------------------------- design
def test_design_plausible_ranges_catch_a_factor_1000_either_way() -> None:
    """The claim of DESIGN_PLAUSIBLE: every bundled value lies inside its range and the
    same value times 1000 or 1/1000 outside (so any such slip of one key warns)."""
    doc = design_doc()
    checked = 0
    for name, rng in DESIGN_PLAUSIBLE.items():
        table, _, key = name.partition(".")
        if key not in doc.get(table, {}):
            continue
        raw = doc[table][key]
        for v in (raw if isinstance(raw, list) else [raw]):
            if v == 0:
                continue
            assert rng.low <= abs(v) <= rng.high, name
            assert not rng.low <= abs(v) * 1000 <= rng.high, name
            assert not rng.low <= abs(v) / 1000 <= rng.high, name
            checked += 1
    assert checked >= 15     # 10 requirements, 4 coil keys, the 4 variables' 8 bounds


def test_design_spec_bundled_reads_without_plausibility_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        read_design_spec(design_doc())


@pytest.mark.parametrize(("table", "key", "value", "slip"), [
    ("requirements", "force_N", 0.8, "too small"),                 # kN typed into N
    # a 10 m / 6 m gap and 15000 T (gauss) cannot be physical: refused since fix25
    # (tests/test_fix25.py, the refusals name the key, the value and the range)
    ("requirements", "current_density_A_per_m2", 5.0, "check its unit"),  # A/mm^2
    ("requirements", "supply_voltage_V", 0.06, "too small"),       # kV
    ("variables", "pole_width", [15.0, 50.0], "typed in mm"),
])
def test_design_spec_unit_slip_warns(table: str, key: str, value: Any, slip: str) -> None:
    """These ran silently (0.8 N: a 3.5 kg magnet 'optimum'; 10 m gap: 500 IPOPT
    iterations; 15000 T: an optimum as if there were no iron limit)."""
    doc = design_doc()
    doc[table][key] = value
    with pytest.warns(PlausibilityWarning, match=rf"\[{table}\] {key} = .*{slip}"):
        read_design_spec(doc)


@pytest.mark.parametrize("bad", [math.nan, math.inf, "0.02", True, -0.02])
def test_design_values_must_be_positive_numbers(bad: Any) -> None:
    """A NaN pole width was reported as '[magnet] resistance = nan' (the wrong key) and a
    string was converted silently; now the variable is named."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        spec = read_design_spec(design_doc())
    values = {"pole_width": bad, "coil_height": 0.05, "coil_thickness": 0.02,
              "leg_height": 0.07}
    with pytest.raises(InputError, match=r"design values pole_width \[m\]"):
        evaluate_design(spec, values)


# ----------------------------------------------------------------------- cross-section
def test_scenario_unit_slips_warn() -> None:
    """A radius in km (4 m at 400 km/h: 3000 m/s^2), a gust in kN (10 N: nothing happens)
    and a rail irregularity in mm (0.3 m RMS: gap -507 mm at t = 0) ran without a word."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        TransitionCurve(4000.0, math.radians(12.0), 300.0)
        TransitionCurve(math.inf, 0.0, 0.0)
        Crosswind(1.0e4)
        Crosswind(0.0)
        parse_lateral("random:0.3e-3:1+girders:0.5e-3")
    with pytest.warns(PlausibilityWarning, match=r"radius_m = 4.0 m .*typed in km"):
        TransitionCurve(4.0, math.radians(12.0), 300.0)
    with pytest.warns(PlausibilityWarning, match=r"radius_m = 4000000.0 m .*typed in mm"):
        TransitionCurve(4.0e6, math.radians(12.0), 300.0)
    with pytest.warns(PlausibilityWarning, match=r"peak_force_N = 10.0 N .*too small"):
        Crosswind(10.0)
    with pytest.warns(PlausibilityWarning, match=r"--lateral: \[lateral\] rms_m = 0.3 m"):
        parse_lateral("random:0.3:1")
    with pytest.warns(PlausibilityWarning, match=r"--lateral: \[lateral\] height_m = 0.5 m"):
        parse_lateral("girders:0.5")
    assert set(SCENARIO_PLAUSIBLE) == {"curve.radius_m", "crosswind.peak_force_N",
                                       "lateral.rms_m", "lateral.height_m"}


def test_cross_section_vehicle_is_listed_and_has_a_template(tmp_path: Any) -> None:
    """docs/cross_section.md names tr09-cross-section as a bundled vehicle, but `list
    vehicles` did not show it, `template vehicle tr09-cross-section` refused it and a
    misspelt name listed 'bundled vehicles: tr09' only."""
    from pathlib import Path

    from typer.testing import CliRunner

    from maglevkit.cli import app
    from maglevkit.vehicle.crosssection import load_cross_section
    from maglevkit.vehicle.train import load_vehicle

    runner = CliRunner()
    res = runner.invoke(app, ["list", "vehicles"])
    assert res.exit_code == 0
    assert "tr09-cross-section TR09-type cross-section" in " ".join(res.stdout.split())
    assert "  tr09 " in res.stdout
    res = runner.invoke(app, ["template", "vehicle", "tr09-cross-section"])
    assert res.exit_code == 0, res.output
    path = Path(tmp_path) / "xs.toml"
    path.write_text(res.stdout)
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # a template loads without any warning
        load_cross_section(path)
    res = runner.invoke(app, ["template", "vehicle"])    # the default stays the train
    assert "made from the bundled 'tr09'" in res.stdout
    with pytest.raises(ParameterFileError, match=r"bundled cross-section vehicles .*: "
                                                 r"tr09-cross-section"):
        load_vehicle("tr09-cross-sectoin")


def test_design_file_with_rounded_turns_holds_the_required_force(tmp_path: Any) -> None:
    """With `turns` a design variable the file got round(N) turns but the current of the
    unrounded N: 311 turns at 29.80 A gave 799.2 N, not the 800 N required.  The written
    current now keeps the optimum's ampere-turns (the statics depend on N I only)."""
    from pathlib import Path

    from maglevkit import load_magnet
    from maglevkit.design import design_magnet, write_design_toml
    from maglevkit.models.statics import solve_statics

    doc = design_doc()
    doc["variables"]["turns"] = [100.0, 2000.0]
    spec = read_design_spec(doc)
    res = design_magnet(spec)
    assert res.success
    n_opt = res.values["turns"]
    assert abs(n_opt - round(n_opt)) > 0.05      # the rounding matters in this case
    path = write_design_toml(res, Path(tmp_path) / "d.toml")
    params = tomllib.loads(path.read_text())
    n, i_n = params["magnet"]["turns"], params["operating"]["nominal_current"]
    assert n == round(n_opt)
    assert n * i_n == pytest.approx(n_opt * res.nominal_current_A, rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        sol = solve_statics(load_magnet(path), gaps_m=spec.requirements["nominal_gap_m"],
                            currents_A=i_n)
    # IPOPT's tolerance 1e-10 on the scaled force equality; the re-solve's own ~1e-12
    assert float(sol.force_N) == pytest.approx(spec.requirements["force_N"], rel=1e-8)


def test_cross_section_refuses_the_deprecated_speed_option() -> None:
    """`--speed 400` (the deprecated name of --speed-kmh) was ignored by the cross-section
    run, which then went at 0 km/h without a word."""
    from typer.testing import CliRunner

    from maglevkit.cli import app

    res = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                                   "--speed", "400", "--duration", "0.05"])
    assert res.exit_code == 2
    assert "--speed 400: use --speed-kmh for a cross-section run" in res.stderr
    assert "Traceback" not in res.output


def test_cross_section_dataset_records_the_scenario(tmp_path: Any) -> None:
    """The heave-pitch run's file names its failures and touchdown; the cross-section's
    had none of its scenario (failures, curve, gust, irregularities, touchdown)."""
    import xarray as xr

    from maglevkit.vehicle.crossrun import CrossSectionModel
    from maglevkit.vehicle.simulation import Failure

    curve = TransitionCurve(4000.0, math.radians(12.0), 300.0)
    gust = Crosswind(5.0e3, rise_s=0.1, hold_s=0.0, start_s=0.0)
    run = CrossSectionModel().run(speed_m_per_s=100.0, duration_s=0.01, loop="python",
                                  curve=curve, crosswind=gust,
                                  failures=[Failure("guidance_left/front", 0.005)],
                                  lateral=parse_lateral("girders:0.5e-3:3"))
    path = run.to_netcdf(tmp_path / "x.nc")
    with xr.open_dataset(path) as ds:
        attrs = dict(ds.attrs)
    assert attrs["failures"] == "guidance_left/front@0.005"
    assert attrs["touchdown"] == ""
    assert attrs["curve"] == repr(curve) and attrs["crosswind"] == repr(gust)
    assert attrs["vertical_irregularity"] == ""
    assert attrs["lateral_irregularity"].startswith("JointSteps(step_m=0.0005")


@pytest.mark.parametrize("option", ["vertical", "lateral"])
def test_cross_section_irregularity_must_be_a_profile(option: str) -> None:
    """A text spec passed where a Profile belongs raised "TypeError: 'str' object is not
    callable"; now an InputError naming the option and the parser to use."""
    from maglevkit.vehicle.crossrun import CrossSectionModel

    with pytest.raises(InputError, match=rf"{option} = 'random:0.3e-3': expected an "
                                         r"irregularity Profile .*parse_"):
        CrossSectionModel().run(speed_m_per_s=100.0, duration_s=0.01, loop="python",
                                **{option: "random:0.3e-3"})


def test_cross_section_warns_of_a_scenario_the_run_never_reaches() -> None:
    """`--curve 4000:12:300:1e6` (start in mm?) or a gust after the end ran as a straight,
    calm run without a word."""
    from maglevkit.errors import MaglevkitWarning
    from maglevkit.vehicle.crossrun import CrossSectionModel

    model = CrossSectionModel()
    with pytest.warns(MaglevkitWarning, match=r"the curve starts at 1e\+06 m, but the run "
                                              r"covers 1 m .*never enters it"):
        model.run(speed_m_per_s=100.0, duration_s=0.01, loop="python",
                  curve=TransitionCurve(4000.0, math.radians(12.0), 300.0, 1.0e6))
    with pytest.warns(MaglevkitWarning, match=r"crosswind starts at 5 s, after the run's "
                                              r"0.01 s"):
        model.run(speed_m_per_s=100.0, duration_s=0.01, loop="python",
                  crosswind=Crosswind(1.0e4, start_s=5.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MaglevkitWarning)     # reached: no warning
        model.run(speed_m_per_s=100.0, duration_s=0.01, loop="python",
                  curve=TransitionCurve(4000.0, math.radians(12.0), 300.0, 0.5),
                  crosswind=Crosswind(1.0e4, start_s=0.0))


def test_cross_section_standing_in_a_sudden_curve_is_not_warned() -> None:
    """At 0 m/s a curve without transition from 0 m is entered at once (the field is the
    banked plane's): no 'never enters' warning there."""
    from maglevkit.errors import MaglevkitWarning
    from maglevkit.vehicle.crossrun import CrossSectionModel

    with warnings.catch_warnings():
        warnings.simplefilter("error", MaglevkitWarning)
        run = CrossSectionModel().run(speed_m_per_s=0.0, duration_s=0.01, loop="python",
                                      curve=TransitionCurve(4000.0, math.radians(12.0), 0.0))
    # a_y = -g sin c on the banked plane at rest (track_field_path's law)
    assert float(run.dataset["field_a_y"][0]) == pytest.approx(
        -9.80665 * math.sin(math.radians(12.0)), rel=1e-12)


def test_design_provenance_of_a_key_the_spec_does_not_give() -> None:
    """A misspelt provenance key ("requirements.forse_N") was accepted and the real key
    lost its tag without a word."""
    from maglevkit.design import DesignSpecError

    doc = design_doc()
    doc["provenance"]["requirements.forse_N"] = doc["provenance"].pop("requirements.force_N")
    with pytest.raises(DesignSpecError, match=r"\[provenance\] 'requirements.forse_N': tags "
                                              r"a key the spec does not give"):
        read_design_spec(doc)
