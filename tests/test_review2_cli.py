"""Defects found by the independent review of issues 24 and 27 (branch review2), each with
its regression test."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from .conftest import interrupt_after_steps


def test_cli_ctrl_c_writes_the_partial_cross_section_run(monkeypatch: pytest.MonkeyPatch,
                                                         tmp_path: Path) -> None:
    """Ctrl-C to ``vehicle run --vehicle tr09-cross-section -o`` printed only
    "interrupted" (rc 130): no report, no file, although the model hands the run up to
    there over (``VehicleRunInterrupted``) and the train's run is reported and written.
    Now as the train's: report with INTERRUPTED on stdout, the file written, rc 130."""
    from maglevkit.cli import app

    interrupt_after_steps(monkeypatch, 100)
    out = tmp_path / "x.nc"
    r = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                                 "--speed-kmh", "400", "--duration", "0.3", "-o", str(out)])
    assert r.exit_code == 130, r.output
    assert "interrupted: Ctrl-C: the run stopped at t = " in r.stderr
    assert r.stderr.count("interrupted") == 1, r.stderr
    assert "Traceback" not in r.output
    assert "INTERRUPTED (Ctrl-C: the run stopped at t = " in r.stdout
    assert "minimum guidance gap" in r.stdout
    assert f"wrote the run up to there to {out}" in r.stderr
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(out) as ds:
        # the compiled loop stops at a block's start: fewer records than the 301 of the
        # whole run, at least the initial one and a block
        assert 1 < ds.sizes["time"] < 301 and ds.attrs["interrupted"]
        assert {"levitation_gap", "guidance_gap"} <= set(ds.data_vars)
    assert [p.name for p in tmp_path.iterdir()] == ["x.nc"]      # no temporary file left


@pytest.mark.parametrize("controller", ["mpc", "pid"])
def test_cross_section_refuses_a_controller_it_does_not_have(controller: str,
                                                             tmp_path: Path) -> None:
    """``vehicle run --vehicle tr09-cross-section --controller mpc`` ran with the cascade
    controllers, rc 0, the option ignored without a word; now refused before the run,
    naming the option and what the cross-section has."""
    from maglevkit.cli import app

    out = tmp_path / "x.nc"
    r = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                                 "--controller", controller, "--duration", "0.1",
                                 "-o", str(out)])
    assert r.exit_code == 2, r.output
    assert r.stderr.startswith(f"error: --controller {controller}: the cross-section model "
                               "has cascade gap controllers only"), r.stderr
    assert "Traceback" not in r.output and not out.exists() and r.stdout == ""


def test_cross_section_notes_a_failure_after_the_end_of_the_run() -> None:
    """A failure after the run's end was noted for the train (issue 27) but ignored
    without a word for the cross-section; both now resolve failures through the one
    ``failure_times`` (name check, earliest time, the note)."""
    from maglevkit.cli import app
    from maglevkit.errors import MaglevkitWarning
    from maglevkit.vehicle.crossrun import CrossSectionModel
    from maglevkit.vehicle.simulation import parse_failure

    with pytest.warns(MaglevkitWarning, match=r"failure guidance_left/front@5: 5 s is after "
                                              r"the end of the run \(0.1 s, --duration\); "
                                              "the circuit does not fail in this run"):
        CrossSectionModel().run(speed_m_per_s=0.0, duration_s=0.1,
                                failures=[parse_failure("guidance_left/front@5")])
    r = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                                 "--duration", "0.1", "--no-progress",
                                 "--failure", "s2m4/front@0.05"])
    assert r.exit_code == 2, r.output
    assert ("error: failure: no circuit 's2m4/front'; circuits are levitation_left/front, "
            "levitation_left/rear,") in r.stderr, r.stderr


def test_failure_times_takes_the_earliest_and_refuses_unknown_circuits() -> None:
    import numpy as np

    from maglevkit.errors import InputError
    from maglevkit.vehicle.simulation import Failure, failure_times

    t = failure_times([Failure("b", 0.3), Failure("b", 0.2)], ["a", "b"], end_s=1.0)
    np.testing.assert_array_equal(t, [np.inf, 0.2])
    with pytest.raises(InputError, match="failure: no circuit 'c'; circuits are a, b"):
        failure_times([Failure("c", 0.1)], ["a", "b"], end_s=1.0)
    with pytest.raises(InputError, match="failures must be Failure objects"):
        failure_times(["a@0.1"], ["a", "b"], end_s=1.0)  # type: ignore[list-item]


def test_a_curve_superelevation_out_of_range_is_named_in_degrees() -> None:
    """``--curve 4000:120:300`` said "curve superelevation_rad = 2.0943951023931953 rad"
    for the 120 deg typed; now the degrees given come first, the range in both units."""
    from maglevkit.errors import InputError
    from maglevkit.vehicle.crossrun import parse_curve

    with pytest.raises(InputError) as err:
        parse_curve("4000:120:300")
    assert str(err.value) == ("--curve = '4000:120:300': curve superelevation 120 deg "
                              "(superelevation_rad = 2.0944 rad): must be in (-17.19, 17.19) "
                              "deg, i.e. (-0.3, 0.3) rad")
    assert parse_curve("4000:17:300").superelevation_rad < 0.3     # 17 deg is allowed


@pytest.mark.parametrize("vehicle", ["tr09", "tr09-cross-section"])
def test_a_bad_magnets_option_names_the_cli_option(vehicle: str) -> None:
    """``vehicle run --magnets detaild`` said "magnets = 'detaild'" (the Python keyword);
    now the CLI option is named too, for both vehicles."""
    from maglevkit.cli import app

    r = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", vehicle, "--magnets",
                                 "detaild", "--duration", "0.1", "--no-progress"])
    assert r.exit_code == 2, r.output
    assert ("error: magnets (--magnets) = 'detaild'; use 'reduced' or 'detailed'"
            in r.stderr), r.stderr


def test_vehicle_run_help_states_the_default_speed() -> None:
    """Without --speed-kmh a run stands still (0 km/h); the help did not say so (no
    default shown), so a first ``vehicle run --curve ...`` never entered its curve."""
    from maglevkit.cli import app

    r = CliRunner().invoke(app, ["vehicle", "run", "--help"], terminal_width=200)
    assert r.exit_code == 0
    assert "default 0, standing" in " ".join(r.stdout.split())



def test_a_magnet_file_s_errors_name_the_file(tmp_path: Path) -> None:
    """A typo in a magnet file's key said "error: [magnet]: unknown key(s) ['pole_pich']"
    without the file (a vehicle file's errors name it); now every message of
    ``load_magnet`` starts with the file, and names it once."""
    from importlib import resources

    import maglevkit as mk
    from maglevkit.errors import ParameterFileError

    text = (resources.files("maglevkit") / "data" / "tr09-standard.toml").read_text()
    assert "\npole_pitch" in text
    bad = tmp_path / "typo.toml"
    bad.write_text(text.replace("\npole_pitch", "\npole_pich", 1))
    with pytest.raises(ParameterFileError) as err:
        mk.load_magnet(bad)
    assert str(err.value).startswith(f"{bad}: [magnet]: unknown key(s) ['pole_pich']")
    no_kind = tmp_path / "no_kind.toml"
    no_kind.write_text("[magnet]\nname = 'x'\n")
    with pytest.raises(ParameterFileError) as err:   # this one named the file already
        mk.load_magnet(no_kind)
    assert str(err.value).startswith(str(no_kind))
    assert str(err.value).count(str(no_kind)) == 1


def test_a_superelevation_in_degrees_typed_as_radians_is_hinted() -> None:
    """A sweep file's or the API's ``curve_superelevation`` is in rad: 12 (degrees meant)
    is refused with the hint, which ``--curve`` (degrees) does not get."""
    from maglevkit.errors import InputError
    from maglevkit.vehicle.crossrun import TransitionCurve

    with pytest.raises(InputError, match=r"take it in rad \(12 deg = 0.2094 rad\), --curve in "
                                         r"deg: degrees typed as radians\?"):
        TransitionCurve(4000.0, 12.0, 300.0)
    with pytest.raises(InputError) as err:
        TransitionCurve(4000.0, 40.0, 300.0)      # not a plausible angle in degrees either
    assert "degrees typed" not in str(err.value)
