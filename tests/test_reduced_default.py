"""The reduced model's default from the magnet file: ``[reduced] eddy_modes`` (switch26m).

A magnet file names the reduced model that follows its detailed model (issue 26 item 2:
the bundled TR09 files on the ladder, whose reduced model is the 2-branch eddy network);
``Magnet.default_eddy_modes`` reads it, ``build_maps`` writes it into the maps (attribute
``reduced_eddy_modes``, kept by netCDF), and the entry points whose option is unset take
it (``maglevkit compare``, ``demo``, ``export fmu``, ``export_fmu``); an option given wins.
The entry points are checked against the library run with the option given explicitly
(``CurrentModel(maps, eddy_modes=m)``, ``compare_models``), an independent path.

The cheap magnet here is a copy of the bundled guidance file without its eddy-model lines
(66 branches, lumped eddy elements: its eddy network is fitted like any other) with a
``[reduced]`` table added.
"""

from __future__ import annotations

import json
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app
from maglevkit.errors import ParameterFileError, ProvenanceWarning
from maglevkit.magnets.base import REDUCED_EDDY_MODES
from maglevkit.reduction import default_eddy_modes
from maglevkit.reduction.eddy_network import EDDY_NETWORK_MODES
from maglevkit.reduction.maps import DEFAULT_EDDY_MODES_ATTRIBUTE

from .conftest import without_eddy_lines

GUIDANCE = "tr-guidance"
runner = CliRunner()


def _file(directory: Path, table: str | None, *, provenance: bool = True,
          name: str = "guidance.toml") -> str:
    """A copy of the bundled guidance file without its eddy-model lines (the lumped
    elements; guideswitch) with ``table`` (the body of a ``[reduced]`` table) added, tagged
    in ``[provenance]`` unless told otherwise."""
    text = without_eddy_lines(
        (resources.files("maglevkit") / "data" / f"{GUIDANCE}.toml").read_text())
    assert "\n[provenance]\n" in text and "\n[reduced]" not in text
    if table is not None:
        tags = "".join(f'"reduced.{line.split("=")[0].strip()}" = "[E] modelling choice"\n'
                       for line in table.splitlines() if "=" in line) if provenance else ""
        text = text.replace("\n[provenance]\n",
                            f"\n[reduced]\n{table}\n\n[provenance]\n{tags}", 1)
    path = directory / name
    path.write_text(text)
    return str(path)


#: A +20 % voltage step at the guidance magnet's nominal point (10 mm, 32 A; 1.5 ohm per
#: circuit), 50 ms: short, inside the small maps below (steady state 38.4 A).
STEP_SCENARIO = """
[scenario]
duration = 0.05
dt = 5e-4
initial_current = 32.0

[voltages]
all = {type = "step", initial = 48.0, final = 57.6, time = 0.005}

[gaps]
all = {type = "constant", value = 0.010}
"""


@pytest.fixture(scope="module")
def one_branch(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, mk.CharacteristicMaps, Path]:
    """The guidance copy with ``eddy_modes = 1``, its maps (small grid around the nominal
    point, 10 mm / 32 A) and their netCDF file."""
    directory = tmp_path_factory.mktemp("reduced")
    path = _file(directory, "eddy_modes = 1")
    mag = mk.load_magnet(path)
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.008, 0.012, 4),
                         currents_A=np.linspace(20.0, 45.0, 6), progress=False)
    (directory / "step.toml").write_text(STEP_SCENARIO)
    return path, maps, maps.to_netcdf(directory / "maps.nc")


def test_the_allowed_values_are_one_list() -> None:
    # eq. 8 and the branch counts the maps store a fit for: the fit's list is derived
    assert REDUCED_EDDY_MODES[0] == 0
    assert EDDY_NETWORK_MODES == REDUCED_EDDY_MODES[1:]


def test_the_bundled_files(tmp_path: Path) -> None:
    # switch26m: the TR09 levitation magnets on the ladder with the network as their
    # reduced model; guideswitch: the guidance magnet on the 8-layer ladder with the
    # 3-branch network; the U-magnet unchanged (no table: eq. 8)
    for name, layers, modes in (("tr09-standard", 6, 2), ("tr09-bow", 6, 2),
                                ("tr-guidance", 8, 3)):
        mag = mk.load_magnet(name)
        assert (mag.options.eddy_model, mag.options.eddy_layers) == ("ladder", layers)
        assert mag.default_eddy_modes == modes == default_eddy_modes(mag)
        assert mag.provenance["reduced.eddy_modes"].startswith("[E] modelling choice")
    mag = mk.load_magnet("u-magnet")
    assert mag.options.eddy_model == "lumped" and mag.default_eddy_modes == 0
    assert mk.load_magnet(_file(tmp_path, None)).default_eddy_modes == 0


def test_the_key_is_read_and_needs_provenance(tmp_path: Path) -> None:
    for m in REDUCED_EDDY_MODES:
        with warnings.catch_warnings():
            warnings.simplefilter("error", ProvenanceWarning)   # the tag above suffices
            mag = mk.load_magnet(_file(tmp_path, f"eddy_modes = {m}"))
        assert mag.default_eddy_modes == m
        assert mag.parameters["reduced"] == {"eddy_modes": m}
    with pytest.warns(ProvenanceWarning, match="reduced.eddy_modes"):
        mk.load_magnet(_file(tmp_path, "eddy_modes = 2", provenance=False))


@pytest.mark.parametrize("table, words", [
    ("eddy_modes = 4", ("[reduced] eddy_modes = 4", "allowed are 0, 1, 2, 3")),
    ("eddy_modes = -1", ("[reduced] eddy_modes = -1", "allowed are 0, 1, 2, 3")),
    ("eddy_modes = 2.5", ("[reduced] eddy_modes = 2.5", "whole number")),
    ('eddy_modes = "two"', ("[reduced] eddy_modes = 'two'", "whole number")),
    ("eddy_modes = true", ("[reduced] eddy_modes = True", "whole number")),
    ("eddy_mode = 2", ("[reduced]", "unknown key(s) ['eddy_mode']", "eddy_modes")),
])
def test_a_bad_value_is_refused_naming_the_key(tmp_path: Path, table: str,
                                               words: tuple[str, ...]) -> None:
    with pytest.raises(ParameterFileError) as err:
        mk.load_magnet(_file(tmp_path, table, provenance=False))
    for w in (*words, "guidance.toml"):
        assert w in str(err.value), str(err.value)


def test_the_key_describes_the_magnet_as_its_file_builds_it() -> None:
    # another eddy model than the file's, or no eddy currents: no network to follow
    mag = mk.load_magnet("tr09-standard")
    assert mk.load_magnet("tr09-standard", eddy_model="lumped").default_eddy_modes == 0
    assert mag.with_options(eddy_model="lumped").default_eddy_modes == 0
    assert mag.with_options(eddy_currents=False).default_eddy_modes == 0
    # the ladder with other layers is still the file's eddy model
    assert mag.with_options(eddy_layers=8).default_eddy_modes == 2
    assert mag.with_options(saturation=False).default_eddy_modes == 2


def test_the_maps_carry_it_through_netcdf(one_branch) -> None:
    path, maps, nc = one_branch
    assert maps.default_eddy_modes == 1 == default_eddy_modes(maps)
    assert int(maps.dataset.attrs[DEFAULT_EDDY_MODES_ATTRIBUTE]) == 1
    back = mk.load_maps(nc, magnet=mk.load_magnet(path))
    assert back.default_eddy_modes == 1 == default_eddy_modes(back)
    # the default is usable: the network with one branch is in these maps
    assert mk.CurrentModel(back, eddy_modes=back.default_eddy_modes).eddy_modes == 1
    # maps without the attribute (a bare network's, a table import, an older file): eq. 8
    bare = mk.CharacteristicMaps(maps.dataset.copy())
    del bare.dataset.attrs[DEFAULT_EDDY_MODES_ATTRIBUTE]
    assert bare.default_eddy_modes == 0
    mag = mk.load_magnet(path)
    assert default_eddy_modes(mag.network) == 0 and default_eddy_modes(mk.FluxModel(mag)) == 0
    with pytest.raises(mk.InputError, match="default_eddy_modes: expected a Magnet"):
        default_eddy_modes("tr09-standard")


def _compare_json(args: list[str], scenario: Path) -> tuple[dict, list[dict]]:
    res = runner.invoke(app, ["compare", *args, "--scenario", str(scenario), "--repeat", "1",
                              "--format", "json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    return data, data["rows"]


def test_compare_takes_the_file_default_and_an_option_wins(one_branch) -> None:
    from maglevkit.compare import ComparisonScenario, compare_models
    from maglevkit.models.scenario import load_scenario

    path, _, nc = one_branch
    mag = mk.load_magnet(path)
    maps = mk.load_maps(nc, magnet=mag)
    scenario = nc.parent / "step.toml"
    sc = load_scenario(scenario)
    case = ComparisonScenario("step", "scenario file", sc.duration_s, sc.dt_s,
                              gaps_m=sc.inputs_for(mag.network.gap_names, "gaps"),
                              voltages_V=sc.inputs_for(mag.network.circuit_names, "voltages"),
                              initial_current_A=sc.initial_current_A)
    expected = {m: compare_models(mag, mk.CurrentModel(maps, eddy_modes=m), [case],
                                  gap_m=0.0, current_A=0.0, repeat=0)[0]
                for m in (0, 1)}
    # the two reduced models differ on this scenario (else the test could not tell them)
    assert abs(expected[1].current_error[0] - expected[0].current_error[0]) > 1e-4
    for option, m in (([], 1), (["--eddy-modes", "0"], 0), (["--eddy-modes", "1"], 1)):
        header, rows = _compare_json([path, str(nc), *option], scenario)
        assert header["reduced_eddy_modes"] == m
        got = [r["current_nrms_percent"] for r in rows]
        # the same deterministic runs: equal to rounding of the JSON's decimal text
        np.testing.assert_allclose(got, 100 * expected[m].current_error, rtol=1e-12)


def test_a_bad_option_names_it(one_branch) -> None:
    path, _, nc = one_branch
    for cmd in (["compare", path, str(nc)], ["demo", "--magnet", path, "--quick"]):
        res = runner.invoke(app, [*cmd, "--eddy-modes", "4"])
        assert res.exit_code == 2 and "--eddy-modes 4: allowed are 0, 1, 2, 3" in \
            " ".join(res.output.split()), res.output
    res = runner.invoke(app, ["export", "fmu", path, str(nc), "--eddy-modes", "2",
                              "--motion-eddy"])
    assert res.exit_code == 2 and "--eddy-modes 2 with --motion-eddy" in res.output, res.output


def test_export_fmu_takes_the_maps_default(one_branch, tmp_path: Path) -> None:
    pytest.importorskip("fmpy")
    from fmpy import read_model_description

    from maglevkit.export import export_fmu

    path, maps, nc = one_branch
    # the start values the command takes from the file's nominal point (10 mm, 32 A)
    start = {"start_gaps_m": 0.010, "initial_currents_A": 32.0}
    guid = {label: export_fmu(maps, tmp_path / f"{label}.fmu", **start, **kw).guid
            for label, kw in (("default", {}), ("one", {"eddy_modes": 1}),
                              ("eq8", {"eddy_modes": 0}))}
    # the GUID is a hash of the FMU's content: the default is the network with one branch
    assert guid["default"] == guid["one"] != guid["eq8"]
    res = runner.invoke(app, ["export", "fmu", path, str(nc), "-o", str(tmp_path / "c.fmu")])
    assert res.exit_code == 0, res.output
    assert read_model_description(str(tmp_path / "c.fmu")).guid == guid["one"]
    res = runner.invoke(app, ["export", "fmu", path, str(nc), "-o", str(tmp_path / "d.fmu"),
                              "--eddy-modes", "0"])
    assert res.exit_code == 0, res.output
    assert read_model_description(str(tmp_path / "d.fmu")).guid == guid["eq8"]
    # the shielded-gap ladder is another reduced model: with it the default is not taken
    ladder = export_fmu(maps, tmp_path / "ladder.fmu", motion_eddy=True, **start)
    assert ladder.guid not in guid.values()
    # members given as maps with different defaults: say so instead of choosing one
    eq8_maps = mk.CharacteristicMaps(maps.dataset.copy())
    eq8_maps.dataset.attrs[DEFAULT_EDDY_MODES_ATTRIBUTE] = 0
    with pytest.raises(mk.InputError, match="default to different eddy_modes"):
        export_fmu({"a": maps, "b": eq8_maps}, tmp_path / "mixed.fmu")


@pytest.mark.parametrize("edit, words", [
    # the file's own lumped elements with the ladder's layer count: the key does nothing
    ({'eddy_model = "ladder"': 'eddy_model = "lumped"'},
     ("eddy_layers = 6 has no effect", "eddy_model = 'lumped'")),
    # fewer layers than any FEM check of the ladder (4, 6, 8)
    ({"eddy_layers = 6": "eddy_layers = 2"}, ("eddy_layers = 2", "4 ... 8 layers")),
    # the eddy network on lumped elements: measured no better than eq. 8 under gap motion
    ({'eddy_model = "ladder"': 'eddy_model = "lumped"'},
     ("[reduced] eddy_modes = 2 with eddy_model = 'lumped'", "eddy_modes = 0")),
])
def test_eddy_keys_that_do_nothing_or_leave_the_checked_range_are_warned(
        tmp_path: Path, edit: dict[str, str], words: tuple[str, ...]) -> None:
    text = (resources.files("maglevkit") / "data" / "tr09-standard.toml").read_text()
    for old, new in edit.items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "tr09-edited.toml"
    path.write_text(text)
    with pytest.warns(mk.PlausibilityWarning) as record:
        mk.load_magnet(path)
    messages = [str(w.message) for w in record if issubclass(w.category, mk.PlausibilityWarning)]
    assert any(all(w in m for w in words) for m in messages), messages


def test_eddy_keys_of_the_bundled_files_and_given_options_are_not_warned() -> None:
    # the bundled files as shipped, and an option given to load_magnet (it wins, as meant)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mk.PlausibilityWarning)
        for name in ("tr09-standard", "tr09-bow", "tr-guidance"):
            mk.load_magnet(name)
            mk.load_magnet(name, eddy_model="lumped")
        mk.load_magnet("tr09-standard", eddy_layers=2)
