"""fix25: the last gaps of issue 25 (review25).

1. Maps imported from a table run through the bank and the FMU (``maglevkit export fmu
   MAPS_FILE``) as through ``CurrentModel``; ``compare`` keeps refusing them, saying why.
2. Design specs with unphysical values are refused before solving, implausible ones warned.
3. ``calibrate`` refuses a fit in which the data determine none of the parameters.
4. ``template magnet u_magnet`` documents ``flux_paths``; ``design --pareto`` and the suffix.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fmpy import simulate_fmu
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app

runner = CliRunner()
# bank (and FMU, which runs the bank's generated step) against CurrentModel on the same
# maps: per-cell polynomials against the B-spline, equal to rounding; tests/test_fmu.py
# measured at most 2.7e-14 relative on built maps and bounds at 1e-12 -- the same bound
# here (far below any physical difference: one map cell moves the force by > 1e-4).
# Measured on these imported maps: 0.0 for both comparisons (fix25)
REL = 1e-12


def _rel(a: Any, b: Any) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


# ---------------------------------------------------------------- 1. imported maps
@pytest.fixture(scope="module")
def magnet() -> mk.Magnet:
    return mk.load_magnet("u-magnet")


def _statics_csv(magnet: mk.Magnet, path: Path, currents_A: np.ndarray) -> Path:
    """A small statics CSV of the U-magnet (psi only, 9 gaps 6-14 mm x the currents), as a
    user's measured table would be."""
    s, i = (a.ravel() for a in np.meshgrid(np.linspace(0.006, 0.014, 9), currents_A,
                                           indexing="ij"))
    psi = np.asarray(mk.solve_statics(magnet, gaps_m=np.c_[s, s], currents_A=i[:, None])
                     .flux_linkage_Wb).ravel()
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["gap_m", "current_A", "flux_linkage_Wb"])
        w.writerows([repr(float(a)), repr(float(b)), repr(float(c))]
                    for a, b, c in zip(s, i, psi, strict=True))
    return path


@pytest.fixture(scope="module")
def table(magnet: mk.Magnet, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The maps' table: 0-40 A (the force comes by co-energy from psi)."""
    return _statics_csv(magnet, tmp_path_factory.mktemp("table") / "u.csv",
                        np.linspace(0.0, 40.0, 6))


@pytest.fixture(scope="module")
def points(magnet: mk.Magnet, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Calibration data: 5-40 A (calibration points need I > 0)."""
    return _statics_csv(magnet, tmp_path_factory.mktemp("points") / "p.csv",
                        np.linspace(5.0, 40.0, 4))


@pytest.fixture(scope="module")
def imported(table: Path, magnet: mk.Magnet) -> mk.CharacteristicMaps:
    # a finite R_ec so that eq. 8's eddy branch is exercised (inf would leave it out)
    return mk.maps_from_table(table, magnet=magnet, eddy_resistance_ohm=6.0)


@pytest.fixture(scope="module")
def imported_file(imported: mk.CharacteristicMaps,
                  tmp_path_factory: pytest.TempPathFactory) -> Path:
    return imported.to_netcdf(tmp_path_factory.mktemp("maps") / "imported.nc")


def _run(maps: mk.CharacteristicMaps, times: np.ndarray) -> tuple[Any, Any, np.ndarray,
                                                                  np.ndarray]:
    """CurrentModel and MagnetBank on the imported maps: a voltage step with both pole gaps
    moving (a sine of 1 mm at 20 Hz); returns both results, the circuit gap and voltage."""
    native = mk.CurrentModel(maps)
    bank = mk.MagnetBank({"m": maps}, compiled="never")
    s = 0.010 + 0.001 * np.sin(2 * np.pi * 20.0 * times)
    u = np.where(times > 0.005, 30.0, 20.0 * 1.3)
    pole = np.c_[s, s]
    ref = native.simulate(times, gaps_m=pole, voltages_V=u[:, None], initial_currents_A=20.0)
    got = bank.simulate(times, gaps_m=s[:, None], voltages_V=u[:, None],
                        initial_currents_A=20.0)
    return ref, got, s, u


def test_imported_maps_through_the_bank_equal_current_model(
        imported: mk.CharacteristicMaps) -> None:
    assert imported.dataset.attrs["table_source"].endswith("u.csv")
    times = np.arange(201) * 2.5e-4
    ref, got, s, u = _run(imported, times)
    assert _rel(got.currents_A, ref.currents_A) <= REL
    assert _rel(got.circuit_force_N, ref.circuit_force_N) <= REL
    assert _rel(got.inductor_currents_A, ref.inductor_currents_A) <= REL
    # MagnetBank.step, one communication step at a time, as the FMU calls it
    bank = mk.MagnetBank({"m": imported}, compiled="never")
    state = bank.initial_state(gaps_m=s[0], currents_A=20.0)
    for k in range(40):
        rate = (s[k + 1] - s[k]) / (times[k + 1] - times[k])
        state, out = bank.step(state, times[k + 1] - times[k],
                               [u[k]],
                               gap_rates_m_per_s=[rate])
        assert abs(out.currents_A[0] - ref.currents_A[k + 1, 0]) <= REL * abs(
            ref.currents_A[k + 1, 0]), k
    # the run moves the model (a constant run would agree trivially)
    assert np.ptp(ref.currents_A) > 0.05 * np.mean(ref.currents_A)
    assert np.ptp(ref.force_N) > 0.05 * np.mean(ref.force_N)


def test_cli_exports_imported_maps_and_the_fmu_equals_the_bank(
        imported: mk.CharacteristicMaps, imported_file: Path, tmp_path: Path) -> None:
    target = tmp_path / "imported.fmu"
    res = runner.invoke(app, ["export", "fmu", str(imported_file), "-o", str(target)])
    assert res.exit_code == 0, res.output
    assert "circuits coil" in res.stdout and f"wrote {target}" in res.stderr
    times = np.arange(201) * 2.5e-4
    ref, got, s, u = _run(imported, times)
    sd = np.r_[np.diff(s) / np.diff(times), 0.0]
    sig = np.zeros(times.size, dtype=[("time", float), ("coil.U", float), ("coil.s", float),
                                      ("coil.sdot", float)])
    sig["time"], sig["coil.U"], sig["coil.s"], sig["coil.sdot"] = times, u, s, sd
    out = simulate_fmu(str(target), start_time=0.0, stop_time=float(times[-1]),
                       output_interval=2.5e-4, input=sig, start_values={"coil.I0": 20.0},
                       output=["coil.I", "coil.F", "coil.I_L"])
    assert len(out) == times.size
    assert _rel(out["coil.I"], got.currents_A[:, 0]) <= REL
    assert _rel(out["coil.F"], got.circuit_force_N[:, 0]) <= REL
    assert _rel(out["coil.I_L"], got.inductor_currents_A[:, 0]) <= REL
    # start values: the maps alone start in the middle of the maps (6-14 mm, 0-40 A); with
    # the magnet the table describes, its nominal point (the U-magnet has none) or the
    # options'
    assert _starts(target) == {"coil.s": 0.010, "coil.I0": 20.0}
    with_magnet = tmp_path / "with.fmu"
    res = runner.invoke(app, ["export", "fmu", "u-magnet", str(imported_file), "-o",
                              str(with_magnet), "--gap", "0.008", "--current", "25"])
    assert res.exit_code == 0, res.output
    assert "of 'U-magnet (example)'" in res.stdout
    assert _starts(with_magnet) == {"coil.s": 0.008, "coil.I0": 25.0}


def _starts(path: Path) -> dict[str, float]:
    from fmpy import read_model_description

    md = read_model_description(str(path))
    return {v.name: float(v.start) for v in md.modelVariables
            if v.name in ("coil.s", "coil.I0")}


def _one_line_error(res: Any, *needles: str) -> None:
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    for needle in needles:
        assert needle in lines[0], res.output


def test_cli_export_fmu_checks_imported_maps(imported_file: Path, tmp_path: Path) -> None:
    out = ["-o", str(tmp_path / "x.fmu")]
    _one_line_error(runner.invoke(app, ["export", "fmu", str(imported_file), *out,
                                        "--eddy-modes", "2"]),
                    "--eddy-modes 2", "no eddy network", "allowed is 0")
    _one_line_error(runner.invoke(app, ["export", "fmu", str(imported_file), *out,
                                        "--motion-eddy"]), "--motion-eddy", "ladder")
    _one_line_error(runner.invoke(app, ["export", "fmu", "tr09-standard", str(imported_file),
                                        *out]),
                    "have the circuits coil", "front, rear", "--magnet tr09-standard")
    _one_line_error(runner.invoke(app, ["export", "fmu", "tr09-standard", *out]),
                    "one argument, 'tr09-standard'", "MAGNET MAPS_FILE")
    assert not (tmp_path / "x.fmu").exists()


def test_cli_export_fmu_alone_refuses_built_maps(magnet: mk.Magnet, tmp_path: Path) -> None:
    built = mk.build_maps(magnet, gaps_m=np.linspace(0.006, 0.014, 4),
                          currents_A=np.linspace(0.0, 40.0, 4), progress=False)
    path = built.to_netcdf(tmp_path / "built.nc")
    _one_line_error(runner.invoke(app, ["export", "fmu", str(path), "-o",
                                        str(tmp_path / "x.fmu")]),
                    "built from magnet 'U-magnet (example)'", "give it too")


def test_compare_refuses_imported_maps_saying_why(imported_file: Path) -> None:
    res = runner.invoke(app, ["compare", "u-magnet", str(imported_file), "--gap", "0.01",
                              "--current", "20", "--repeat", "1"])
    _one_line_error(res, "imported from the table", "detailed model",
                    "maglevkit maps build MAGNET", "maglevkit export fmu MAPS_FILE")


# ---------------------------------------------------------------- 2. design spec slips
def _spec_doc() -> dict[str, Any]:
    from importlib import resources

    import tomllib

    text = (resources.files("maglevkit") / "data" / "designs" / "u-magnet-design.toml"
            ).read_text()
    return tomllib.loads(text)


@pytest.mark.parametrize(("key", "value", "needles"), [
    # metres for millimetres: was 500 IPOPT iterations, then a failure naming no key
    ("nominal_gap_m", 10, ("[requirements] nominal_gap_m = 10 m cannot be physical",
                           "allowed are <= 1 m", "1000 times too large: typed in mm")),
    ("reserve_gap_m", 6.0, ("[requirements] reserve_gap_m = 6.0 m", "<= 1 m")),
    # gauss for tesla: was a run to exit 0
    ("max_flux_density_T", 15000, ("[requirements] max_flux_density_T = 15000 T",
                                   "allowed are <= 10 T", "gauss", "1.5 T")),
    # was accepted silently: a "reserve" that does not hold the nominal force
    ("reserve_factor", 0.5, ("[requirements] reserve_factor = 0.5 - cannot be physical",
                             "allowed are >= 1 -")),
])
def test_unphysical_spec_values_are_refused_before_solving(
        key: str, value: float, needles: tuple[str, ...],
        monkeypatch: pytest.MonkeyPatch) -> None:
    from maglevkit import design
    from maglevkit.design import DesignSpecError

    doc = _spec_doc()
    doc["requirements"][key] = value

    def no_magnet(*args: Any, **kwargs: Any) -> None:     # "before solving": before even
        raise AssertionError("the spec was read past its values")   # loading the magnet

    monkeypatch.setattr("maglevkit.magnets.load_magnet", no_magnet)
    with pytest.raises(DesignSpecError) as info:
        design.read_design_spec(doc)
    for needle in needles:
        assert needle in str(info.value), str(info.value)


@pytest.mark.parametrize(("key", "value"), [
    ("nominal_gap_m", 0.3),           # 300 mm: implausible for an EMS magnet, not impossible
    ("max_flux_density_T", 3.0),      # above iron's saturation: implausible
    ("reserve_factor", 20.0),         # a twentyfold reserve
])
def test_implausible_spec_values_warn_naming_the_key(key: str, value: float) -> None:
    from maglevkit import design
    from maglevkit.errors import PlausibilityWarning

    doc = _spec_doc()
    doc["requirements"][key] = value
    with pytest.warns(PlausibilityWarning, match=rf"\[requirements\] {key} = {value!r}"):
        try:
            design.read_design_spec(doc)
        except mk.MaglevkitError:
            pass      # later checks may refuse the spec (bounds); the warning came first


def test_cli_design_refuses_an_unphysical_spec(tmp_path: Path) -> None:
    spec = tmp_path / "spec.toml"
    text = (Path(mk.__file__).parent / "data" / "designs" / "u-magnet-design.toml").read_text()
    spec.write_text(text.replace("nominal_gap_m = 0.010", "nominal_gap_m = 10"))
    res = runner.invoke(app, ["design", str(spec), "-o", str(tmp_path / "d.toml")])
    assert res.exit_code == 2, res.output
    assert "nominal_gap_m = 10 m cannot be physical" in res.stderr
    assert not (tmp_path / "d.toml").exists()


def test_physical_limits_refuse_where_plausible_ranges_warn() -> None:
    import warnings

    from maglevkit.errors import PlausibilityWarning
    from maglevkit.validation import Plausible, check_plausible

    ranges = {"a.x": Plausible(1.0, 10.0, "m", physical_high=100.0)}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_plausible({"a": {"x": 5.0}}, ranges) == []
    with pytest.warns(PlausibilityWarning, match=r"\[a\] x = 50.0 m is above"):
        assert check_plausible({"a": {"x": 50.0}}, ranges) == ["a.x"]
    with pytest.raises(mk.InputError, match=r"\[a\] x = 500.0 m cannot be physical .*"
                                            r"allowed are <= 100 m"):
        check_plausible({"a": {"x": 500.0}}, ranges)
    # values <= 0 are left to the file's own checks (its "must be > 0"): warned only
    with pytest.warns(PlausibilityWarning, match=r"\[a\] x = -500.0 m is above"):
        assert check_plausible({"a": {"x": -500.0}}, ranges) == ["a.x"]
    with pytest.raises(ValueError, match="must enclose it"):
        Plausible(1.0, 10.0, "m", physical_high=5.0)


# ---------------------------------------------------------------- 3. nothing determined
def test_calibrate_refuses_when_the_data_determine_no_parameter(points: Path,
                                                               tmp_path: Path) -> None:
    out = tmp_path / "cal.toml"
    # R_el does not enter the statics: was exit 0 and a "calibrated" file of start values
    res = runner.invoke(app, ["calibrate", "u-magnet", str(points), "-o", str(out),
                              "--params", "resistance_scale"])
    _one_line_error(res, "cannot determine any of the fitted parameters ['resistance_scale']",
                    "voltage steps", "--steps")
    assert not out.exists()
    with pytest.raises(mk.DataError, match=r"eddy_conductance_scale, resistance_scale do not "
                                           r"enter the statics"):
        mk.calibrate(mk.load_magnet("u-magnet"), points,
                     parameters=["eddy_conductance_scale", "resistance_scale"])


def test_calibrate_with_some_parameters_undetermined_reports_them(points: Path,
                                                                  tmp_path: Path) -> None:
    out = tmp_path / "cal.toml"
    res = runner.invoke(app, ["calibrate", "u-magnet", str(points), "-o", str(out),
                              "--params", "leakage_factor,resistance_scale"])
    assert res.exit_code == 0, res.output
    rows = {ln.split()[0]: ln for ln in res.stdout.splitlines() if ln.strip()}
    assert "NOT DETERMINED" in rows["resistance_scale"]
    assert "NOT DETERMINED" not in rows["leakage_factor"]
    assert out.is_file()
    # the Python result says the same; select_parameters' folds are not refused
    cal = mk.calibrate(mk.load_magnet("u-magnet"), points,
                       parameters=["leakage_factor", "resistance_scale"])
    assert cal.undetermined == ("resistance_scale",)
    none = mk.calibrate(mk.load_magnet("u-magnet"), points, parameters=["resistance_scale"],
                        require_determined=False)
    assert none.undetermined == ("resistance_scale",)


# ---------------------------------------------------------------- 4. nits
def _template(name: str) -> str:
    res = runner.invoke(app, ["template", "magnet", name])
    assert res.exit_code == 0, res.output
    return res.stdout


def test_u_magnet_template_offers_flux_paths_with_its_provenance(tmp_path: Path) -> None:
    import warnings

    from maglevkit.errors import ProvenanceWarning

    text = _template("u_magnet")
    assert '# flux_paths = "window"' in text and '"standard"' in text and '"split"' in text
    assert '# "magnet.flux_paths" = "[E]' in text
    as_is, both, key_only = (tmp_path / f"{n}.toml" for n in ("as_is", "both", "key_only"))
    as_is.write_text(text)
    both.write_text(text.replace('# flux_paths = "window"', 'flux_paths = "window"')
                    .replace('# "magnet.flux_paths"', '"magnet.flux_paths"'))
    key_only.write_text(text.replace('# flux_paths = "window"', 'flux_paths = "window"'))
    with warnings.catch_warnings():
        warnings.simplefilter("error")         # neither the template nor its option warn
        assert "flux_paths" not in mk.load_magnet(as_is).parameters["magnet"]   # default
        assert mk.load_magnet(both).parameters["magnet"]["flux_paths"] == "window"
    # the provenance line is what keeps it quiet: without it the key warns
    with pytest.warns(ProvenanceWarning, match="magnet.flux_paths"):
        mk.load_magnet(key_only)
    # the levitation magnet's template is its bundled file as before (it sets flux_paths)
    tr09 = _template("tr09-standard")
    assert "# flux_paths" not in tr09 and 'flux_paths = "split"' in tr09


def test_design_pareto_format_follows_the_suffix(tmp_path: Path) -> None:
    res = runner.invoke(app, ["design", "--help"], terminal_width=200)
    assert "the format follows the suffix" in " ".join(res.stdout.split())
    # a suffix matplotlib cannot write: refused before solving, naming the option
    bad = runner.invoke(app, ["design", "u-magnet-design", "-o", str(tmp_path / "d.toml"),
                              "--pareto", str(tmp_path / "front.xyz")])
    _one_line_error(bad, "--pareto", "format 'xyz'", ".png")
    assert not (tmp_path / "d.toml").exists()
    jpg = tmp_path / "front.jpg"
    res = runner.invoke(app, ["design", "u-magnet-design", "-o", str(tmp_path / "d.toml"),
                              "--pareto", str(jpg), "--pareto-points", "2"])
    assert res.exit_code == 0, res.output
    assert jpg.read_bytes()[:3] == b"\xff\xd8\xff"       # a JPEG, not a PNG named .jpg


@pytest.mark.parametrize("name, kind", [("tr09-standard", "levitation_magnet"),
                                        ("tr-guidance", "guidance_magnet")])
def test_transrapid_templates_offer_end_effects_with_its_provenance(
        tmp_path: Path, name: str, kind: str) -> None:
    """Every magnet kind has the 2-D cut switch (issue 26); its template offers it (review26)."""
    import warnings

    text = _template(name)
    assert "# end_effects = false" in text and '# "magnet.end_effects" = "[E]' in text
    cut = tmp_path / f"{name}-cut.toml"
    cut.write_text(text.replace("# end_effects = false", "end_effects = false")
                   .replace('# "magnet.end_effects"', '"magnet.end_effects"'))
    with warnings.catch_warnings():
        warnings.simplefilter("error")         # the uncommented option with its tag is quiet
        mag = mk.load_magnet(cut)
    assert mag.parameters["magnet"]["end_effects"] is False and mag.kind == kind
