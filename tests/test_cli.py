"""The command-line interface: help at every level, statics CSV and plot."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app

runner = CliRunner()


def _commands() -> list[str]:
    import typer.main

    group = typer.main.get_command(app)
    return sorted(group.commands)  # type: ignore[attr-defined]


def test_help_at_top_level() -> None:
    res = runner.invoke(app, ["--help"])
    assert res.exit_code == 0 and "statics" in res.output


@pytest.mark.parametrize("command", _commands())
def test_help_of_every_command(command: str) -> None:
    res = runner.invoke(app, [command, "--help"])
    assert res.exit_code == 0, res.output
    assert "Usage" in res.output


def test_statics_csv_and_plot(tmp_path: Path) -> None:
    out_csv, out_png = tmp_path / "s.csv", tmp_path / "s.png"
    res = runner.invoke(app, ["statics", "u-magnet", "--gaps", "0.006,0.012", "--currents",
                              "0:40:5", "--csv", str(out_csv), "--plot", str(out_png)])
    assert res.exit_code == 0, res.output
    with out_csv.open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["gap_m", "current_A", "force_N", "flux_linkage_Wb",
                       "differential_inductance_H", "dpsi_dgap_Wb_per_m"]
    assert len(rows) == 1 + 2 * 5
    data = np.array(rows[1:], dtype=float)
    # the CSV carries the same numbers as the library call
    sol = mk.solve_statics(mk.load_magnet("u-magnet", eddy_currents=False),
                           gaps_m=[0.006, 0.012], currents_A=np.linspace(0, 40, 5), grid=True)
    np.testing.assert_allclose(data[:, 2], sol.force_N.ravel(), rtol=1e-8)
    np.testing.assert_allclose(data[:, 5], sol.dpsi_dgap_Wb_per_m.sum(-1).ravel(), rtol=1e-8)
    assert out_png.stat().st_size > 10_000 and out_png.read_bytes()[:4] == b"\x89PNG"


def test_statics_csv_of_a_two_circuit_magnet(tmp_path: Path) -> None:
    out_csv = tmp_path / "s.csv"
    res = runner.invoke(app, ["statics", "tr09-standard", "--gaps", "0.010", "--currents",
                              "0,34", "--csv", str(out_csv)])
    assert res.exit_code == 0, res.output
    with out_csv.open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["gap_m", "current_A", "force_N", "force_N_front", "force_N_rear",
                       "flux_linkage_Wb_front", "flux_linkage_Wb_rear",
                       "mutual_inductance_H_front", "mutual_inductance_H_rear",
                       "mutual_dpsi_dgap_Wb_per_m_front", "mutual_dpsi_dgap_Wb_per_m_rear",
                       "differential_inductance_H_front", "differential_inductance_H_rear",
                       "dpsi_dgap_Wb_per_m_front", "dpsi_dgap_Wb_per_m_rear"]
    assert rows[1][2] == "0"            # no force at zero current, and no "-0"
    sol = mk.solve_statics(mk.load_magnet("tr09-standard", eddy_currents=False), gaps_m=0.010,
                           currents_A=34.0)
    data = dict(zip(rows[0], np.array(rows[2], dtype=float), strict=True))
    # 9 significant digits in the file
    for j, c in enumerate(("front", "rear")):
        poles = slice(0, 6) if c == "front" else slice(6, 12)   # p01-p06 front, p07-p12 rear
        other = slice(6, 12) if c == "front" else slice(0, 6)
        np.testing.assert_allclose(data[f"flux_linkage_Wb_{c}"], sol.flux_linkage_Wb[j],
                                   rtol=1e-8)
        np.testing.assert_allclose(data[f"force_N_{c}"], sol.pole_force_N[poles].sum(),
                                   rtol=1e-8)
        np.testing.assert_allclose(data[f"mutual_inductance_H_{c}"],
                                   sol.differential_inductance_H[j, 1 - j], rtol=1e-8)
        np.testing.assert_allclose(data[f"mutual_dpsi_dgap_Wb_per_m_{c}"],
                                   sol.dpsi_dgap_Wb_per_m[j, other].sum(), rtol=1e-8)
        np.testing.assert_allclose(data[f"differential_inductance_H_{c}"],
                                   sol.differential_inductance_H[j].sum(), rtol=1e-8)


@pytest.mark.parametrize("sub", ["build", "plot"])
def test_help_of_maps_subcommands(sub: str) -> None:
    res = runner.invoke(app, ["maps", sub, "--help"])
    assert res.exit_code == 0 and "Usage" in res.output


def test_demo_runs_the_whole_chain(tmp_path: Path) -> None:
    res = runner.invoke(app, ["demo", "--magnet", "u-magnet", "--quick", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    for name in ("statics.csv", "force_current.png", "maps.nc", "maps_coil.png",
                 "compare-closed-loop.png"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert "largest normalised RMS error" in res.output and "speed-up" in res.output
    # issue 27: the headline numbers come with what they mean
    assert "; acceptance limit 2 %: met" in res.output
    assert "not an acceptance metric but the error relative to how much the signal moves" \
        in res.output


def test_compare_cli_with_a_scenario_file(tmp_path: Path) -> None:
    nc = tmp_path / "m.nc"
    assert runner.invoke(app, ["maps", "build", "u-magnet", "-o", str(nc)]).exit_code == 0
    # issue 27: --gap/--current were ignored with --scenario (the JSON header claimed them)
    res = runner.invoke(app, ["compare", "u-magnet", str(nc), "--scenario", "step", "--gap",
                              "10", "--current", "33.5", "--format", "json"])
    assert res.exit_code == 2 and res.stdout == ""
    assert "--gap 10 and --current 33.5 with --scenario 'step': a scenario file sets its own" \
        in " ".join(res.stderr.split())
    res = runner.invoke(app, ["compare", "u-magnet", str(nc), "--scenario", "step",
                              "--out", str(tmp_path), "--format", "json"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "compare-step.png").is_file()
    header = json.loads(res.stdout)
    assert header["scenario"] == "step" and "gap_m" not in header
    # progress on stderr while it runs
    assert "compare: scenario 1/1 step ..." in res.stderr and "done in" in res.stderr
    res = runner.invoke(app, ["compare", "tr09-standard", str(nc), "--gap", "0.01",
                              "--current", "10"])
    assert res.exit_code == 2 and "belong to magnet" in res.output
