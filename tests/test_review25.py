"""Issue 25 review (review25): what a new user met running the tables, calibration and
design commands -- Ctrl-C during ``calibrate`` and ``design`` (exit 130, no damaged file)
and ``compare`` on imported maps (a message that says what the maps are)."""

from __future__ import annotations

import csv
import subprocess
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app
from maglevkit.errors import ParameterFileError

from .test_first_hour import ENTRY, _interrupt

ROOT = Path(__file__).resolve().parents[1]
FEM_2MM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics_2mm.csv"
runner = CliRunner()


def _after(seconds: float):  # type: ignore[no-untyped-def]
    """Ready ``seconds`` after the first poll (the command is past its imports then)."""
    start: dict[str, float] = {}

    def ready(proc: subprocess.Popen[str], err: str) -> bool:
        start.setdefault("t", time.monotonic())
        return time.monotonic() - start["t"] > seconds

    return ready


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
def test_calibrate_interrupted_exits_130_and_writes_nothing(tmp_path: Path) -> None:
    # the cross-validated choice fits every subset of the five factors once per fitted gap
    # (31 x 5 lumped fits, tens of seconds): the signal meets a running least-squares fit
    cmd = [str(ENTRY), "calibrate", "u-magnet", str(FEM_2MM), "-o", "cal.toml",
           "--select-params", "--holdout-gaps", "0.014,0.016,0.018,0.020"]
    proc, err, _ = _interrupt(cmd, _after(6.0), group=False, cwd=tmp_path)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted", err
    assert "Traceback" not in err and "error:" not in err, err
    assert not (tmp_path / "cal.toml").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["stderr.txt"]   # no partial file either


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
def test_design_interrupted_during_the_pareto_sweep_keeps_a_whole_design_file(
        tmp_path: Path) -> None:
    # the optimum is written first, then the Pareto sweep runs (40 IPOPT solves): the signal
    # meets the sweep; the written design stays whole, the figure is not written
    cmd = [str(ENTRY), "design", "u-magnet-design", "-o", "design.toml", "--pareto",
           "front.png", "--pareto-points", "40"]
    proc, err, _ = _interrupt(cmd, lambda p, e: "wrote design.toml" in e, group=False,
                              cwd=tmp_path)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted", err
    assert "Traceback" not in err and "error:" not in err, err
    assert not (tmp_path / "front.png").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")            # complete and tagged
        mag = mk.load_magnet(tmp_path / "design.toml")
    assert "optimised" in str(mag.provenance)


def test_compare_on_imported_maps_says_they_are_imported(tmp_path: Path) -> None:
    # was: "these maps belong to magnet 'U-magnet (example)' (hash ...), not to 'U-magnet
    # (example)' (hash ...); rebuild them with `maglevkit maps build`" -- the same name
    # twice, and a hint away from the user's table
    mag = mk.load_magnet("u-magnet")
    s, i = (a.ravel() for a in np.meshgrid(np.linspace(0.006, 0.014, 5),
                                           np.linspace(0.0, 40.0, 5), indexing="ij"))
    psi = np.asarray(mk.solve_statics(mag, gaps_m=np.c_[s, s], currents_A=i[:, None])
                     .flux_linkage_Wb).ravel()
    table = tmp_path / "u.csv"
    with table.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["gap_m", "current_A", "flux_linkage_Wb"])
        w.writerows([repr(float(a)), repr(float(b)), repr(float(c))]
                    for a, b, c in zip(s, i, psi, strict=True))
    maps = mk.maps_from_table(table, magnet=mag)
    with pytest.raises(ParameterFileError, match=r"imported from the table '.*u\.csv' "
                                                 r"\(maglevkit maps import\).*maps build"):
        maps.check_magnet(mag)
    maps.to_netcdf(tmp_path / "m.nc")
    res = runner.invoke(app, ["compare", "u-magnet", str(tmp_path / "m.nc"), "--gap", "0.01",
                              "--current", "20", "--repeat", "1"])
    assert res.exit_code == 2, res.output
    assert "imported from the table" in res.stderr and "export fmu MAPS_FILE" in res.stderr
    assert "Traceback" not in res.output
    assert len(res.stderr.strip().splitlines()) == 1, res.stderr


def test_a_holdout_gap_without_data_names_the_option_and_the_gaps(tmp_path: Path) -> None:
    # was: "holdout gap 10.0 m: no data point ...; gaps in the data: [0.004, ...,
    # 0.018000000000000002, 0.02]" (a float's repr, no unit hint for a gap typed in mm)
    data = tmp_path / "d.csv"
    data.write_text("gap_m,current_A,flux_linkage_Wb\n"
                    + "".join(f"{0.006 + 0.006 * k},{c},{0.1 * c}\n"
                              for k in range(3) for c in (10.0, 20.0)))
    res = runner.invoke(app, ["calibrate", "u-magnet", str(data), "-o",
                              str(tmp_path / "c.toml"), "--holdout-gaps", "18"])
    assert res.exit_code == 2, res.output
    assert ("holdout gap 18 m: no data point at that gap (holdout_gaps_m, --holdout-gaps: in "
            "m); gaps in the data: 0.006, 0.012, 0.018 m") in " ".join(res.stderr.split())
