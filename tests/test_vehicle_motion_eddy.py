"""Vehicles flying shielded-gap ladder magnets (``motion_eddy``; docs/vehicle.md, "Magnets
with the shielded-gap ladder"): compiled step against the reference loop for both
vehicles, the vehicle's currents replayed by ``CurrentModel(maps, motion_eddy=True)`` and
held against the detailed flux model, the option in the vehicle file, the CLI and its
refusals."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from maglevkit.errors import InputError, ParameterFileError
from maglevkit.vehicle.simulation import Failure, VehicleModel, VehicleRun, parse_irregularity
from maglevkit.vehicle.train import load_vehicle, parse_vehicle

from .test_vehicle_compiled import heave_pitch_runs, loops_agree

# Compiled and reference loops do the same arithmetic in another order (as
# tests/test_vehicle_compiled.py, whose bound this is: measured there 5.4e-13 of a
# variable's largest value without the ladder; here <= 5e-14 on the run below).
RTOL = 1e-10

_LUMPED: dict[str, str] = {}


def lumped_tr09() -> dict[str, str]:
    """Paths of the bundled TR09 magnet files (``"tr09-standard"``, ``"tr09-bow"``) and
    of the guidance file (``"tr-guidance"``, since guideswitch) with
    the lumped eddy elements and eq. 8 as their reduced model (``eddy_model = "lumped"``,
    ``[reduced] eddy_modes = 0``; network hashes as the bundled files' before issue 26's
    eddy switch), and of the bundled vehicle file ``"tr09"`` flying them.  The
    shielded-gap ladders (``motion_eddy``) are fitted from the lumped elements' current
    jump: the three-state ladder has no fit on the diffusing ladder's maps, the two-state
    one a 17 % residual there (4.7 % here), so their tests fly these files (written once
    per session into a temporary folder)."""
    if not _LUMPED:
        import atexit
        import shutil
        import tempfile
        from pathlib import Path

        from maglevkit.parameter_files import read_parameter_file, toml_text

        from .conftest import tr09_params

        folder = Path(tempfile.mkdtemp(prefix="maglevkit-lumped-tr09-"))
        atexit.register(shutil.rmtree, folder, True)
        for name in ("tr09-standard", "tr09-bow"):
            p = tr09_params(name)
            p["magnet"]["eddy_model"] = "lumped"
            p["reduced"]["eddy_modes"] = 0
            _LUMPED[name] = str(folder / f"{name}-lumped.toml")
            Path(_LUMPED[name]).write_text(toml_text(p))
        # the guidance magnet's lumped file (guideswitch put the bundled one on the ladder)
        from importlib import resources

        from .conftest import without_eddy_lines

        _LUMPED["tr-guidance"] = str(folder / "tr-guidance-lumped.toml")
        Path(_LUMPED["tr-guidance"]).write_text(without_eddy_lines(
            (resources.files("maglevkit") / "data" / "tr-guidance.toml").read_text()))
        v, _ = read_parameter_file("tr09", what="vehicle", folder="vehicle", table="vehicle")
        v["vehicle"].update(standard_magnet=_LUMPED["tr09-standard"],
                            bow_magnet=_LUMPED["tr09-bow"])
        _LUMPED["tr09"] = str(folder / "tr09-lumped.toml")
        Path(_LUMPED["tr09"]).write_text(toml_text(v))
    return dict(_LUMPED)


def lumped_train() -> Any:
    """The bundled train on :func:`lumped_tr09`'s magnet files."""
    return load_vehicle(lumped_tr09()["tr09"])


@pytest.fixture(scope="module")
def ladder_model() -> VehicleModel:
    return VehicleModel(lumped_train(), motion_eddy=True)


def record_bank_inputs(m: VehicleModel, **run_kw: Any
                       ) -> tuple[VehicleRun, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Fly ``m`` in the reference loop (``loop="python"``, ``run_kw`` as for
    ``VehicleModel.run``) and record what its bank's ``step`` received each step:
    (voltages V, gaps m, gap rates m/s) per circuit, without the loop's first, discarded
    step (the one that compiles the kernel)."""
    calls: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    step = m.bank.step

    def spy(state: Any, dt: float, u: Any, gaps: Any, rates: Any, **kw: Any) -> Any:
        calls.append((np.array(u, dtype=float), np.array(gaps, dtype=float),
                      np.array(rates, dtype=float)))
        return step(state, dt, u, gaps, rates, **kw)

    m.bank.step = spy             # type: ignore[method-assign]
    run: VehicleRun = m.run(loop="python", **run_kw)
    return run, calls[1:]


def replay_circuits(m: VehicleModel, run: VehicleRun,
                    calls: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                    circuits: list[str], models: tuple[Any, ...],
                    eddy_shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Replay the vehicle's ``circuits`` (one magnet's) through single ``models``
    (``CurrentModel``/``FluxModel`` of the "standard" magnet): started at the run's first
    gaps and the trim currents, stepped at 1e-3 s with the recorded voltages, gaps and gap
    rates (each circuit's value given to its poles, via ``models[0]``'s pole groups).

    Returns the coil currents (len(models), n_t, n_circuits) in A, row 0 the run's, and
    ``models[0]``'s eddy state reshaped to ``eddy_shape`` per step (n_t, *eddy_shape) in
    A, row 0 zero."""
    ds = run.dataset
    names = list(ds.circuit.values)
    idx = [names.index(c) for c in circuits]
    maps = m.maps["standard"]
    gap_names = list(models[0].gap_names)

    def poles(circuit_values: np.ndarray) -> np.ndarray:
        out = np.empty(len(gap_names))
        for c, val in zip(models[0].circuit_names, circuit_values, strict=True):
            for p in maps.pole_groups[c]:
                out[gap_names.index(p)] = val
        return out

    g0, i0 = poles(ds.gap.values[0, idx]), m.trim_current_A[idx]
    states = [mod.initial_state(gaps_m=g0, currents_A=i0) for mod in models]
    n = len(calls)
    cur = np.empty((len(models), n + 1, len(idx)))
    eddy = np.zeros((n + 1, *eddy_shape))
    cur[:, 0] = ds.current.values[0, idx]
    for k, (u, g, r) in enumerate(calls):
        for j, mod in enumerate(models):
            states[j], out = mod.step(states[j], 1e-3, u[idx], poles(g[idx]), poles(r[idx]))
            cur[j, k + 1] = out.currents_A
        assert states[0].eddy_currents_A is not None
        eddy[k + 1] = np.reshape(states[0].eddy_currents_A, eddy_shape)
    return cur, eddy


def nmpc_runs(m: VehicleModel) -> VehicleRun:
    """The NMPC scenario of the eddy-state vehicles (400 km/h, bundled irregularity,
    0.3 s) flown in the NumPy loop and in compiled blocks; asserts no touchdown and that
    the two agree to 1e-7 of each variable's largest value (the bound of
    tests/test_vehicle_controllers.py's eq. 8 NMPC). Returns the NumPy loop's run."""
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=m.guideway.span.length_m)
    kw: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.3, irregularity=prof)
    a = m.run(loop="python", **kw)
    b = m.run(**kw)
    assert a.touchdown is None and b.touchdown is None and b.loop == "compiled"
    rel = {k: float(np.nanmax(np.abs(a.dataset[k].values - b.dataset[k].values))
                    / np.nanmax(np.abs(a.dataset[k].values)))
           for k in ("gap", "voltage", "current", "eddy_current", "force")}
    assert max(rel.values()) < 1e-7, rel
    return a


def test_heave_pitch_compiled_step_carries_the_eddy_currents(ladder_model: VehicleModel) -> None:
    """400 km/h, elastic guideway, sag + random irregularity, a circuit failure: the
    compiled step with I_e in its state equals the reference loop (bank.step) to RTOL,
    and the eddy currents are recorded and move."""
    m = ladder_model
    assert m.bank.motion_eddy
    rc, rp = heave_pitch_runs(m, RTOL)
    ie = rp.dataset.eddy_current
    assert ie.attrs["units"] == "A"
    # starts in the ladder's steady state (V_m = R_2 I_e = 0) and is driven by the gap
    # motion: amperes under this irregularity (measured peak 6.3 A), not rounding
    assert float(np.abs(ie.values[0]).max()) == 0.0
    assert float(np.abs(ie.values).max()) > 0.5
    assert "shielded-gap ladder" in rp.dataset.attrs["magnets"]
    # the chopper floor is the ladder's: the coil current never reverses (the diodes
    # and the floor U >= -R_a (I_L + I_e)); the failed circuit decays to 0 from above
    assert float(rp.dataset.current.values.min()) >= -1e-12


def test_cross_section_compiled_step_carries_the_eddy_currents() -> None:
    """The cross-section with ladder magnets: compiled block step and NumPy loop
    (controllers through the interface) agree, bound and the condition that the chopper
    does not clamp as in tests/test_crossrun.py::test_compiled_step_equals_the_numpy_loop.

    ``"levitation"`` (guidance magnets eq. 8) on that test's scenario: curve entry, gust,
    rail wave, a failure.  ``True`` (every magnet) warns about the guidance magnet's
    poorly fitted ladder (28 % residual since guidesat26's network; 49 % before, when it
    destabilised the loops under the curve entry: guidance currents to 143-168 A, a
    touchdown; measured): the gust alone here."""
    from maglevkit.errors import MaglevkitWarning
    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind, TransitionCurve
    from maglevkit.vehicle.irregularities import HarmonicProfile

    gust = Crosswind(5e3, rise_s=0.2, hold_s=0.1, start_s=0.2)
    full: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.8,
                                curve=TransitionCurve(4000.0, math.radians(12.0), 50.0),
                                crosswind=gust, lateral=HarmonicProfile(0.2e-3, 100.0),
                                failures=[Failure("guidance_left/front", 0.5)])
    lumped, guidance = lumped_tr09()["tr09-standard"], lumped_tr09()["tr-guidance"]
    lev = CrossSectionModel(levitation_magnet=lumped, guidance_magnet=guidance,
                            motion_eddy="levitation")
    with pytest.warns(MaglevkitWarning, match="guidance magnet '.*tr-guidance-lumped.toml'.*28 %"):
        every = CrossSectionModel(levitation_magnet=lumped, guidance_magnet=guidance,
                                  motion_eddy=True)
    for model, kw, eddy in ((lev, full, {"levitation": True, "guidance": False}),
                            (every, dict(speed_m_per_s=400 / 3.6, duration_s=0.5,
                                         crosswind=gust),
                             {"levitation": True, "guidance": True})):
        assert model.bank.motion_eddy
        # measured 5.6e-16 (levitation) on the full scenario
        a = loops_agree(model, RTOL, **kw)[1].dataset
        live = np.delete(a.guidance_current.values, 0, axis=1)
        assert live.min() > 5.0 and a.levitation_current.values.min() > 5.0
        for kind, moves in eddy.items():
            peak = float(np.abs(a[f"{kind}_eddy_current"].values).max())
            # eq. 8 circuits keep I_e = 0 exactly; ladder circuits carry 0.1-10 A here
            assert (peak > 0.05) if moves else (peak == 0.0), (kind, peak)


def test_without_the_option_the_vehicle_is_the_one_before() -> None:
    """motion_eddy=False (and a file without [magnets]) builds the eq. 8 bank and the step
    layout without I_e; the recorded runs (tests/test_vehicle_recorded_runs.py) check
    that its results are bit-identical to those recorded before the option."""
    train = lumped_train()     # eq. 8 the magnets' default (the bundled: the network)
    assert train.motion_eddy is False
    m = VehicleModel(train, rigid=True, motion_eddy=False)
    assert not m.bank.motion_eddy
    lay = m.step_function(1e-3).layout
    assert "I_e" not in lay.state and "I_e" not in lay.record
    run = m.run(speed_m_per_s=0.0, duration_s=0.01)
    assert "eddy_current" not in run.dataset


def test_ladder_vehicle_replayed_by_current_model_and_held_against_the_detailed_model() -> None:
    """A 50 Hz guideway wave (0.05 mm at 400 km/h, rigid guideway): circuit s2m4's gaps,
    gap rates and voltages as the vehicle's bank received them, replayed through

    * ``CurrentModel(maps, motion_eddy=True)`` -- the ladder on its own: the vehicle's
      coil and eddy currents to rounding (the same law, the same RK4 sub-steps);
    * ``CurrentModel(maps)`` -- eq. 8 -- and ``FluxModel`` -- the detailed model of the same
      network: the ladder's current departs from eq. 8's towards the detailed one
      (smaller amplitude, lagging phase, half the error)."""
    from maglevkit.models.flux import FluxModel
    from maglevkit.reduced.current import CurrentModel
    from maglevkit.vehicle.irregularities import HarmonicProfile

    v, f = 400 / 3.6, 50.0
    m = VehicleModel(lumped_train(), rigid=True, motion_eddy=True)
    run, calls = record_bank_inputs(m, speed_m_per_s=v, duration_s=0.3,
                                    irregularity=HarmonicProfile(0.05e-3, v / f))
    ds = run.dataset
    names = list(ds.circuit.values)
    idx = [names.index("s2m4/front"), names.index("s2m4/rear")]
    # the diodes never conduct (coil currents far above 0), where freewheel=True is
    # eq. 8's / the ladder's plain law, bit for bit (docs/bank.md)
    assert float(ds.current.values.min()) > 5.0
    maps = m.maps["standard"]
    ladder = CurrentModel(maps, motion_eddy=True, max_step_s=m.bank.max_step_s)
    eq8 = CurrentModel(maps, max_step_s=m.bank.max_step_s)
    flux = FluxModel(m.magnets["standard"])
    cur, eddy = replay_circuits(m, run, calls, ["s2m4/front", "s2m4/rear"],
                                (ladder, eq8, flux), (2,))
    veh_i, veh_e = ds.current.values[:, idx], ds.eddy_current.values[:, idx]
    # the same law and sub-steps, only the pole -> circuit gap average in between:
    # measured 2.8e-14 A (coil, ~50 A) and 1.3e-15 A (eddy); bound ~1e-12 relative
    assert np.abs(cur[0] - veh_i).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(eddy - veh_e).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(veh_e).max() > 0.1          # the ladder is at work, not idle
    # against the detailed model after the start (0.1 s), front circuit's 50 Hz
    # fundamental relative to its gap's; measured amplitude 12.18 / 10.58 / 9.98 A and
    # phase 90.4 / 87.7 / 81.8 deg (eq. 8 / ladder / detailed), RMS error over both
    # circuits 1.95 / 0.81 A (of a 7.1-7.8 A RMS variation)
    t = ds.time.values
    sel = t >= 0.1
    ph = np.exp(-2j * np.pi * f * t[sel])
    gap = ds.gap.values[sel, idx[0]]
    gain = 2 * np.mean((gap - gap.mean()) * ph)

    def fundamental(x: np.ndarray) -> complex:
        return complex(2 * np.mean((x - x.mean()) * ph) / gain)

    z_l, z_8, z_d = (fundamental(cur[j, sel, 0]) for j in range(3))
    assert abs(z_d) < abs(z_l) < abs(z_8)
    assert np.angle(z_d) < np.angle(z_l) < np.angle(z_8)
    err = [float(np.sqrt(np.mean((cur[j, sel] - cur[2, sel]) ** 2))) for j in (0, 1)]
    assert err[0] < 0.6 * err[1], err
    # and the ladder's departure from eq. 8 points where the detailed model's does
    d_l, d_d = cur[0, sel] - cur[1, sel], cur[2, sel] - cur[1, sel]
    corr = float(np.sum(d_l * d_d) / math.sqrt(np.sum(d_l ** 2) * np.sum(d_d ** 2)))
    assert corr > 0.9, corr


def test_vehicle_file_option_and_refusals(monkeypatch: pytest.MonkeyPatch) -> None:
    """[magnets] motion_eddy in the file; bad values and combinations name the option."""
    import tomllib

    from maglevkit.parameter_files import read_parameter_file

    params, label = read_parameter_file("tr09", what="vehicle", folder="vehicle",
                                        table="vehicle")
    with_table = {**params, "magnets": {"motion_eddy": True}}
    assert parse_vehicle(with_table, label).motion_eddy is True
    assert parse_vehicle(params, label).motion_eddy is False
    with pytest.raises(ParameterFileError, match="motion_eddy"):
        parse_vehicle({**params, "magnets": {"motion_eddy": "yes"}}, label)
    with pytest.raises(ParameterFileError, match="eddy_model"):
        parse_vehicle({**params, "magnets": {"eddy_model": "ladder"}}, label)
    assert tomllib.loads("[magnets]\nmotion_eddy = true\n")["magnets"]["motion_eddy"] is True
    train = load_vehicle()
    for kw, words in (({"magnets": "detailed"}, ("motion_eddy", "magnets", "detailed")),
                      ({"eddy_resistance_scale": 1.3}, ("motion_eddy", "eddy_resistance_scale")),
                      ({"motion_eddy": "yes"}, ("motion_eddy", "'yes'"))):
        with pytest.raises(InputError) as exc:
            VehicleModel(train, **{"motion_eddy": True, **kw})
        for w in words:
            assert w in str(exc.value), (kw, str(exc.value))
    # maps without a ladder (a magnet without eddy currents, old maps): the bow magnet's
    # here, its ladder variables NaN -> the error names the option and the magnet file
    import maglevkit.vehicle.mapcache as mapcache

    real = mapcache.vehicle_maps

    def no_ladder(magnet: Any, **kw: Any) -> Any:
        maps = real(magnet, **kw)
        if magnet.name != train.bow_magnet and "bow" not in magnet.name.lower():
            return maps
        ds = maps.dataset.copy()
        for name in ds.data_vars:
            if str(name).startswith("motion_eddy_"):
                ds[name] = ds[name].copy(data=np.full(ds[name].shape, np.nan))
        return type(maps)(ds)

    monkeypatch.setattr(mapcache, "vehicle_maps", no_ladder)
    with pytest.raises(InputError) as exc:
        VehicleModel(train, rigid=True, motion_eddy=True)
    text = str(exc.value)
    assert "motion_eddy" in text and repr(train.bow_magnet) in text
    assert "no shielded-gap ladder" in text
    VehicleModel(train, rigid=True)          # without the option the same maps fly
    from maglevkit.vehicle.crossrun import CrossSectionModel

    with pytest.raises(InputError, match="motion_eddy.*detailed"):
        CrossSectionModel(magnets="detailed", motion_eddy=True)
    with pytest.raises(InputError, match="motion_eddy = 'guidance'.*'levitation'"):
        CrossSectionModel(motion_eddy="guidance")


def test_cli_takes_the_option(tmp_path: Any) -> None:
    """``maglevkit vehicle run --motion-eddy`` flies the ladder and writes I_e."""
    import xarray as xr
    from typer.testing import CliRunner

    from maglevkit.cli import app

    out = tmp_path / "run.nc"
    res = CliRunner().invoke(app, ["vehicle", "run", "tr09", "--rigid", "--duration",
                                   "0.01", "--motion-eddy", "--no-progress", "-o", str(out)])
    assert res.exit_code == 0, res.output
    with xr.open_dataset(out) as ds:
        assert "eddy_current" in ds and "shielded-gap ladder" in ds.attrs["magnets"]
    res = CliRunner().invoke(app, ["vehicle", "run", "tr09", "--rigid", "--duration",
                                   "0.01", "--motion-eddy", "--magnets", "detailed",
                                   "--no-progress"])
    assert res.exit_code != 0 and "motion_eddy" in res.output


@pytest.mark.slow
def test_nmpc_flies_the_ladder_and_its_compiled_blocks_are_the_numpy_loop() -> None:
    """controller="mpc" with ladder magnets (one section, 400 km/h, bundled irregularity,
    0.3 s; ~1 min to design the ladder NMPCs once): every prediction model carries I_e,
    no touchdown, and the run in compiled blocks equals the NumPy loop as the eq. 8
    NMPC's does (tests/test_vehicle_controllers.py: bound 1e-7 of each variable's largest
    value, there measured up to 2.3e-9; here 3e-9 current, 5e-9 voltage and I_e)."""
    import dataclasses

    train = dataclasses.replace(lumped_train(), n_sections=1)
    m = VehicleModel(train, controller="mpc", motion_eddy=True)
    assert all(c.model.n_eddy == c.model.n_circuits for c in m.circuit_controllers.values())
    a = nmpc_runs(m)
    assert float(np.abs(a.dataset.eddy_current.values).max()) > 1.0     # measured 12.6 A
