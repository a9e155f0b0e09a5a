"""Defects found by the independent review of issues 24 and 27 (branch review2), each with
its regression test."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from maglevkit._progress import ProgressReporter


def _ctrl_c_after(steps: int) -> Any:
    """A progress ``advance`` that raises KeyboardInterrupt (as Ctrl-C) once ``steps``
    steps are done: where both vehicles' time loops check for an interrupt."""
    original = ProgressReporter.advance

    def advance(rep: ProgressReporter, n: int = 1) -> None:
        original(rep, n)
        if rep.done >= steps:
            raise KeyboardInterrupt

    return advance


def test_cli_ctrl_c_writes_the_partial_cross_section_run(monkeypatch: pytest.MonkeyPatch,
                                                         tmp_path: Path) -> None:
    """Ctrl-C to ``vehicle run --vehicle tr09-cross-section -o`` printed only
    "interrupted" (rc 130): no report, no file, although the model hands the run up to
    there over (``VehicleRunInterrupted``) and the train's run is reported and written.
    Now as the train's: report with INTERRUPTED on stdout, the file written, rc 130."""
    from maglevkit.cli import app

    monkeypatch.setattr(ProgressReporter, "advance", _ctrl_c_after(100))
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
