"""Bad input of every kind raises a specific error that says what is wrong."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app

from .conftest import build_u, u_params

IRON = mk.IronPath("iron", 0.2, 1e-3, mk.get_material("AISI 1008"))
GAP = mk.AirGap("gap", gap_input="s", pole_area_m2=1e-3)


def loop_branches() -> list[mk.Branch]:
    return [mk.Branch("core", "a", "b", (IRON,)), mk.Branch("air", "b", "a", (GAP,))]


def coil() -> mk.Circuit:
    return mk.Circuit("c", 1.0, (mk.Coil("core", 100),))


def test_minimal_network_solves() -> None:
    net = mk.Network(tuple(loop_branches()), (coil(),))
    sol = mk.solve_statics(net, gaps_m=0.005, currents_A=2.0)
    assert sol.force_N > 0.0


@pytest.mark.parametrize(
    ("make", "exc", "msg"),
    [
        (lambda: mk.Network((*loop_branches(), mk.Branch("x", "c", "d", (mk.IronPath(
            "iron2", 0.1, 1e-3, mk.IdealIron()),))), (coil(),)), mk.TopologyError, "disconnected"),
        (lambda: mk.Network(tuple(loop_branches()), (mk.Circuit("c", 1.0, (mk.Coil("nope", 10),)),)),
         mk.TopologyError, "branch 'nope'.*does not exist"),
        (lambda: mk.Circuit("c", 1.0, ()), mk.TopologyError, "no coils"),
        (lambda: mk.Network((*loop_branches(), mk.Branch("core", "a", "b", ())), (coil(),)),
         mk.TopologyError, "duplicate branch name 'core'"),
        (lambda: mk.Network((mk.Branch("core", "a", "b", (IRON,)),
                             mk.Branch("air", "b", "a", (IRON,))), (coil(),)),
         mk.TopologyError, "duplicate element name 'iron'"),
        (lambda: mk.Network(tuple(loop_branches()), (coil(), coil())), mk.TopologyError,
         "duplicate circuit"),
        (lambda: mk.Network((mk.Branch("core", "a", "b", (IRON,)),), (coil(),)),
         mk.TopologyError, "no closed flux path"),
        (lambda: mk.Branch("loop", "a", "a", ()), mk.TopologyError, "two different nodes"),
        (lambda: mk.IronPath("i", 0.0, 1e-3), mk.ParameterError, "length_m = 0.0 must be"),
        (lambda: mk.IronPath("i", 0.1, -1e-3), mk.ParameterError, "cross_section"),
        (lambda: mk.AirGap("g", pole_area_m2=0.0), mk.ParameterError, "pole_area"),
        (lambda: mk.Coil("core", 0), mk.ParameterError, "turns = 0"),
        (lambda: mk.Coil("core", float("nan")), mk.ParameterError, "turns"),
        (lambda: mk.Circuit("c", 0.0, (mk.Coil("core", 10),)), mk.ParameterError, "resistance"),
        (lambda: mk.IronPath("i", 0.1, 1e-3, "adamantium"), mk.MaterialError, "unknown material"),
        (lambda: mk.EddyCurrent("e", conductance_S=-1.0), mk.ParameterError, "conductance"),
    ],
)
def test_topology_and_element_errors(make, exc: type, msg: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(exc, match=msg):
        make()


def test_dangling_coil_branch_is_rejected() -> None:
    branches = (*loop_branches(), mk.Branch("stub", "a", "z", (mk.IronPath("i3", 0.1, 1e-3),)))
    with pytest.raises(mk.TopologyError, match="dangling"):
        mk.Network(branches, (mk.Circuit("c", 1.0, (mk.Coil("stub", 10),)),))


@pytest.mark.parametrize(
    ("gaps", "currents", "msg"),
    [
        (0.0, 10.0, "gaps must be > 0"),
        (-0.001, 10.0, "gaps must be > 0"),
        (float("nan"), 10.0, "finite"),
        (np.inf, 10.0, "finite"),
        (0.01, float("nan"), "finite"),
        # the one per-name converter's messages (models.inputs.per_name_values)
        ({"left": 0.01}, 10.0, r"gaps: unknown names \[\], missing \['right'\]; give one "
                               r"value \[m\] per gap: \['left', 'right'\]"),
        ({"left": 0.01, "right": 0.01, "middle": 0.01}, 10.0,
         r"gaps: unknown names \['middle'\], missing \[\]"),
        (np.ones((3, 5)) * 0.01, 10.0, r"gaps: expected 2 values \[m\] along the last axis "
                                       r"\(one per gap of \['left', 'right'\], or one for "
                                       r"all\), got shape \(3, 5\)"),
        (0.01, {"coils": 3.0}, r"circuit currents: unknown names \['coils'\], missing "
                               r"\['coil'\]; give one value \[A\] per circuit"),
        ({"left": np.full(3, 0.01), "right": np.full(2, 0.01)}, 10.0,
         r"gaps: the values per gap must have one shape, got \{'left': \(3,\), "
         r"'right': \(2,\)\}"),
        (float("nan"), 10.0, r"gaps must be finite: gap 'left' = nan m"),
        ("ten millimetres", 10.0, "must be numbers"),
    ],
)
def test_statics_input_errors(u_magnet: mk.Magnet, gaps, currents, msg: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(mk.InputError, match=msg):
        mk.solve_statics(u_magnet, gaps_m=gaps, currents_A=currents)


def test_grid_needs_1d_inputs(u_magnet: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match="1-D"):
        mk.solve_statics(u_magnet, gaps_m=[[0.01]], currents_A=[1.0], grid=True)


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "magnet.toml"
    p.write_text(text)
    return p


def test_parameter_file_errors(tmp_path: Path) -> None:
    good = (Path(mk.__file__).parent / "data" / "u-magnet.toml").read_text()
    cases = [
        (good.replace("turns = 600", "turns = 600\nturnz = 3"), "unknown key\\(s\\) \\['turnz'\\]"),
        (good.replace("depth = 0.100", ""), "missing required key 'depth' \\[m\\]"),
        (good.replace("turns = 600", "turns = -600"), "turns = -600.0 - must be > 0|must be > 0"),
        (good.replace("turns = 600", "turns = \"many\""), "expected a number"),
        (good.replace("[rail]", "[rial]"), "unknown table|missing the \\[rail\\]"),
        (good.replace('material = "AISI 1008"', 'material = "AISI 1080"', 1),
         "unknown material 'AISI 1080'"),
        (good.replace('kind = "u_magnet"', 'kind = "v_magnet"'), "kind = 'v_magnet' is unknown"),
        (good.replace("width = 0.160", "width = 0.100"), "narrower than the magnet"),
        (good.replace("coil_height = 0.050", "coil_height = 0.090"), "coil must fit"),
        (good.replace("end_effects = false", "end_effects = 0"), "expected true or false"),
        (good + "\n[materials.bad]\nH = [0, 100]\nB = [0, 0.5, 0.9]\n", "pair up"),
        (good.replace("turns = 600", "turns = 600 600"), "not valid TOML"),
        (good.replace('"magnet.turns"', '"magnet.turnss"'), "names no value"),
    ]
    for text, msg in cases:
        with pytest.raises(mk.ParameterFileError, match=msg):
            mk.load_magnet(_write(tmp_path, text))
    with pytest.raises(mk.ParameterFileError, match="does not exist"):
        mk.load_magnet(tmp_path / "missing.toml")
    with pytest.raises(mk.ParameterFileError, match="bundled magnets: .*u-magnet"):
        mk.load_magnet("u-magent")


def test_tabulated_material_from_file(tmp_path: Path) -> None:
    p = u_params()
    p["magnet"]["material"] = "my_steel"
    p["materials"] = {"my_steel": {"H": [0, 100, 200, 1000, 10000], "B": [0, 0.5, 0.9, 1.4, 1.8]}}
    mag = mk.build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
    assert mk.solve_statics(mag, gaps_m=0.01, currents_A=30.0).force_N > 0.0
    p["materials"]["my_steel"]["resistivity"] = 1.6e-7
    assert mk.build_magnet(p).network.has_eddy_currents


def test_eddy_currents_need_a_resistivity() -> None:
    p = u_params()
    p["magnet"]["material"] = "M350-50A"  # no built-in resistivity
    with pytest.raises(mk.ParameterFileError, match="no built-in resistivity"):
        mk.build_magnet(p)
    assert build_u(material="M350-50A").network.has_eddy_currents is False


def test_solver_error_reports_state_and_reason() -> None:
    err = mk.SolverError("integration failed", time_s=0.0125, state={"I": [1.0, 2.5]},
                         reason="IDA_CONV_FAIL")
    text = str(err)
    assert "t = 0.0125 s" in text and "I=[1, 2.5]" in text and "IDA_CONV_FAIL" in text
    assert err.time_s == 0.0125 and err.reason == "IDA_CONV_FAIL"


runner = CliRunner()


def test_cli_reports_a_typo_in_a_file_without_traceback(tmp_path: Path) -> None:
    good = (Path(mk.__file__).parent / "data" / "u-magnet.toml").read_text()
    path = _write(tmp_path, good.replace("pole_width", "pole_widht"))
    res = runner.invoke(app, ["statics", str(path)])
    assert res.exit_code == 2
    assert "unknown key(s) ['pole_widht']" in res.output
    assert "Traceback" not in res.output


def test_cli_rejects_malformed_ranges() -> None:
    res = runner.invoke(app, ["statics", "u-magnet", "--gaps", "0.004:0.02"])
    assert res.exit_code != 0
    assert "start:stop:count" in res.output
    res = runner.invoke(app, ["statics", "u-magnet", "--gaps", "0:0.02:3"])
    assert res.exit_code == 2 and "gaps must be > 0" in res.output


def test_statics_failure_is_reported_not_returned(u_magnet: mk.Magnet,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """A point whose residual never meets the tolerance raises with the operating point."""
    from maglevkit.models import statics

    monkeypatch.setattr(statics, "_RESIDUAL_TOL", -1.0)  # no residual can satisfy this
    with pytest.raises(mk.SolverError, match=r"did not converge.*gap\[left\]=0.007.*I\[coil\]=12"):
        mk.solve_statics(u_magnet, gaps_m=0.007, currents_A=12.0)
