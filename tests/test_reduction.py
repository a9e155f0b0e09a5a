"""Characteristic maps (statics method) and the current-based model (paper eq. 8)."""

from __future__ import annotations

import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.materials import MU0
from maglevkit.models.current import CurrentModel
from maglevkit.reduction import build_maps, load_maps

from .conftest import build_u

N_TURNS, AREA, R_EL = 600.0, 0.003, 2.0
GAPS = np.linspace(0.004, 0.020, 17)
CURRENTS = np.linspace(0.0, 80.0, 33)


@pytest.fixture(scope="module")
def ideal_maps() -> mk.reduction.CharacteristicMaps:  # type: ignore[name-defined]
    return build_maps(build_u(material="ideal", fringing=False, leakage=False), gaps=GAPS,
                      currents=CURRENTS)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    return build_maps(u_magnet, gaps=GAPS, currents=CURRENTS)


def test_maps_of_the_ideal_magnet_are_the_closed_forms(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    s, i = np.meshgrid(GAPS, CURRENTS, indexing="ij")
    l_exact = MU0 * N_TURNS**2 * AREA / (2 * s)
    # exact linear network: agreement to rounding
    np.testing.assert_allclose(ideal_maps.variable("inductance_H", "coil"), l_exact, rtol=1e-10)
    np.testing.assert_allclose(ideal_maps.variable("force_N", "coil"),
                               MU0 * (N_TURNS * i) ** 2 * AREA / (4 * s * s), rtol=1e-10,
                               atol=1e-9)
    # dL/ds = -L/s, including the I -> 0 limit (central difference, ~1e-8 relative)
    np.testing.assert_allclose(ideal_maps.variable("dL_ds_H_per_m", "coil"), -l_exact / s,
                               rtol=1e-6)


def test_maps_satisfy_eq9_reciprocity(u_magnet: mk.Magnet) -> None:
    """Eq. 9 / co-energy: dF/dI = -dL/ds I on the map grid, from knee to deep saturation.

    dF/dI by a 4th-order central difference along a fine current grid (h = 0.25 A); the
    truncation error scales as h^4: it is 2 % of max |dF/dI| at h = 2.5 A at the knee, so
    ~2e-6 here (measured 8e-5, dominated by the difference quotient of dL/ds in the maps).
    The bound 1e-3 is 12x above that and still fails for any wrong factor in eq. 9."""
    currents = np.linspace(0.0, 80.0, 321)
    maps = build_maps(u_magnet, gaps=np.linspace(0.004, 0.020, 4), currents=currents)
    f = maps.variable("force_N", "coil")
    dlds = maps.variable("dL_ds_H_per_m", "coil")
    h = currents[1] - currents[0]
    df = (-f[:, 4:] + 8 * f[:, 3:-1] - 8 * f[:, 1:-3] + f[:, :-4]) / (12 * h)
    rhs = -dlds[:, 2:-2] * currents[2:-2]
    assert np.max(np.abs(df - rhs)) < 1e-3 * np.max(np.abs(rhs))


def test_maps_round_trip_netcdf_bit_exactly(u_maps, u_magnet: mk.Magnet, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    p = u_maps.to_netcdf(tmp_path / "maps.nc")
    back = load_maps(p, magnet=u_magnet)
    for name in u_maps.dataset.data_vars:
        a = np.asarray(u_maps.dataset[name].values)
        b = np.asarray(back.dataset[name].values)
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), name
    assert back.dataset.attrs == u_maps.dataset.attrs
    assert back.dataset["force_N"].attrs["units"] == "N"


def test_maps_of_another_magnet_are_refused(u_maps, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    p = u_maps.to_netcdf(tmp_path / "maps.nc")
    other = build_u(magnet={"turns": 601})
    with pytest.raises(mk.ParameterFileError, match="belong to magnet"):
        load_maps(p, magnet=other)
    with pytest.raises(mk.ParameterFileError, match="belong to magnet"):
        load_maps(p, magnet=mk.load_magnet("u-magnet", saturation=False, eddy_currents=False))
    (tmp_path / "junk.nc").write_bytes(b"not netcdf")
    with pytest.raises(mk.ParameterFileError, match="netCDF"):
        load_maps(tmp_path / "junk.nc")


def test_executors_give_identical_maps(u_magnet: mk.Magnet, u_maps) -> None:  # type: ignore[no-untyped-def]
    with ThreadPoolExecutor(2) as ex:
        threaded = build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, executor=ex)
    for name in u_maps.dataset.data_vars:
        assert np.array_equal(u_maps.dataset[name].values, threaded.dataset[name].values,
                              equal_nan=True)


def test_process_pool_gives_identical_maps(u_magnet: mk.Magnet, u_maps) -> None:  # type: ignore[no-untyped-def]
    pooled = build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, executor="process")
    for name in u_maps.dataset.data_vars:
        assert np.array_equal(u_maps.dataset[name].values, pooled.dataset[name].values,
                              equal_nan=True)


@pytest.mark.parametrize(
    ("gaps", "currents", "msg"),
    [
        (np.linspace(0.0, 0.02, 5), CURRENTS, "> 0 m"),
        (np.array([0.004, 0.006, 0.01, 0.02]), CURRENTS, "equidistant"),
        (GAPS[:3], CURRENTS, "at least 4 points"),
        (GAPS[::-1], CURRENTS, "strictly increasing"),
        (GAPS, np.linspace(-10, 10, 5), ">= 0 A"),
        (GAPS, [0, 1, np.nan, 3], "finite"),
    ],
)
def test_bad_grids_raise(u_magnet: mk.Magnet, gaps, currents, msg: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(mk.InputError, match=msg):
        build_maps(u_magnet, gaps=gaps, currents=currents)


def test_current_model_step_response_is_the_rl_law(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    """Ideal linear magnet at fixed gap: I = U/R (1 - exp(-t R/L)), L = mu0 n^2 A/(2 s)."""
    model = CurrentModel(ideal_maps)
    t = np.linspace(0.0, 0.5, 501)
    s0, u = 0.01, 20.0
    res = mk.simulate(model, t, gaps=s0, voltages=u, initial_currents=0.0)
    l_exact = MU0 * N_TURNS**2 * AREA / (2 * s0)
    exact = u / R_EL * (1 - np.exp(-t * R_EL / l_exact))
    # CVODES at rtol 1e-8 and the B-spline through exact grid values (s0 is a grid node):
    # error < 1e-5 A on 10 A
    np.testing.assert_allclose(res.currents_A[:, 0], exact, atol=1e-5)


def test_current_model_virtual_control_law_isolates_dl_ds(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    """U = R_el I cancels the resistive terms of eq. 8: psi = L(s) I stays constant, so for
    L ~ 1/s the current follows I0 s(t)/s0 on a gap ramp."""
    model = CurrentModel(ideal_maps)
    t = np.linspace(0.0, 0.1, 1001)
    s0, sdot, i0 = 0.006, 0.05, 10.0
    gaps = (s0 + sdot * t)[:, None] * np.ones((1, 2))
    state = model.initial_state(gaps=s0, currents=i0)
    currents = [i0]
    for k in range(t.size - 1):
        state, out = model.step(state, t[k + 1] - t[k], voltages=R_EL * state.inductor_currents_A,
                                gaps=gaps[k], gap_rates=sdot)
        currents.append(float(out.currents_A[0]))
    # The control law is applied with a zero-order hold: psi drifts by about
    # (R/L) (dt/2) (Delta I / I) = (2/0.113) (5e-5) (0.83) = 0.07 % over the ramp; the
    # B-spline interpolation of 1/s adds < 0.01 %.  Bound: 0.2 %.
    np.testing.assert_allclose(currents, i0 * gaps[:, 0] / s0, rtol=2e-3)


def test_current_model_refuses_to_leave_its_maps(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    model = CurrentModel(ideal_maps)
    t = np.linspace(0.0, 0.5, 51)
    with pytest.raises(mk.OutOfRangeError, match="currents 0..80 A"):
        # 400 V / 2 ohm would settle at 200 A: leaves the 0..80 A map
        model.simulate(t, gaps=0.01, voltages=400.0, initial_currents=0.0)
    with pytest.raises(mk.OutOfRangeError, match="gaps 0.004..0.02 m"):
        model.simulate(t, gaps=0.03, voltages=1.0, initial_currents=0.0)
    with pytest.warns(UserWarning, match="extrapolating"):
        CurrentModel(ideal_maps, extrapolate=True).simulate(t, gaps=0.021, voltages=1.0,
                                                            initial_currents=0.0)
    with pytest.raises(mk.InputError, match="gaps must be > 0"):
        model.step(model.initial_state(gaps=0.01, currents=1.0), 1e-3, voltages=2.0, gaps=-0.01)
    with pytest.raises(mk.InputError, match="expected 1 values"):
        model.step(model.initial_state(gaps=0.01, currents=1.0), 1e-3, voltages=[2.0, 2.0],
                   gaps=0.01)


def test_dask_local_cluster_gives_identical_maps(u_magnet: mk.Magnet, u_maps) -> None:  # type: ignore[no-untyped-def]
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, executor=client)
    for name in u_maps.dataset.data_vars:
        assert np.array_equal(u_maps.dataset[name].values, remote.dataset[name].values,
                              equal_nan=True)


def test_cli_maps_build_and_plot(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from maglevkit.cli import app

    runner = CliRunner()
    nc = tmp_path / "m.nc"
    res = runner.invoke(app, ["maps", "build", "u-magnet", "-o", str(nc), "--gaps",
                              "0.004:0.02:5", "--currents", "0:40:5"])
    assert res.exit_code == 0, res.output
    maps = load_maps(nc, magnet=mk.load_magnet("u-magnet"))
    assert maps.dataset["force_N"].shape == (1, 5, 5)
    res = runner.invoke(app, ["maps", "plot", str(nc), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "maps_coil.png").read_bytes()[:4] == b"\x89PNG"
    res = runner.invoke(app, ["maps", "plot", str(tmp_path / "nope.nc")])
    assert res.exit_code == 2 and "does not exist" in res.output


def test_current_model_step_and_simulate_agree(u_maps) -> None:  # type: ignore[no-untyped-def]
    """The stepping interface and the batch simulation integrate the same ODE with the same
    input conventions.  With RK4 both evaluate the same compiled interval function (the batch
    run in power-of-two chunks: 50 intervals = 32 + 16 + 2), so they agree to rounding; bound
    1e-12 relative.  With CVODES (rtol 1e-8) restarted every step vs one continuous run the
    local errors accumulate differently: measured ~3e-7 relative; bound 1e-5."""
    for model, rel in ((CurrentModel(u_maps), 1e-12),
                       (CurrentModel(u_maps, method="cvodes"), 1e-5)):
        _check_step_vs_simulate(model, rel)


def _check_step_vs_simulate(model: CurrentModel, rel: float) -> None:
    t = np.linspace(0.0, 0.05, 51)
    gaps = 0.01 + 0.002 * np.sin(2 * np.pi * 20 * t)
    volts = np.where(t < 0.02, 30.0, 45.0)
    res = mk.simulate(model, t, gaps=np.repeat(gaps[:, None], 2, axis=1), voltages=volts,
                      initial_currents=15.0)
    state = model.initial_state(gaps=gaps[0], currents=15.0)
    for k in range(t.size - 1):
        rate = (gaps[k + 1] - gaps[k]) / (t[k + 1] - t[k])
        state, out = model.step(state, t[k + 1] - t[k], volts[k], gaps=gaps[k], gap_rates=rate)
        assert out.currents_A[0] == pytest.approx(res.currents_A[k + 1, 0], rel=rel)
        assert out.force_N == pytest.approx(res.force_N[k + 1], rel=rel)
    assert res.final_state.inductor_currents_A[0] == pytest.approx(
        state.inductor_currents_A[0], rel=rel)


@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("cc") is None,
                    reason="jit=True needs a C compiler")
def test_jit_compiled_current_model_matches_the_interpreted_one(u_maps) -> None:  # type: ignore[no-untyped-def]
    """Same arithmetic, compiled instead of interpreted: agreement to rounding (measured 0 on
    x86-64 with -O3, which does not reassociate floating point); bound 1e-12 relative."""
    kw = {"gaps": lambda t: 0.01 + 0.002 * np.sin(2 * np.pi * 20 * t),
          "voltages": lambda t: 30.0 if t < 0.02 else 45.0, "initial_currents": 15.0}
    ref = mk.simulate(CurrentModel(u_maps), (0, 0.05), dt=1e-3, **kw)
    jit = CurrentModel(u_maps, jit=True)
    res = mk.simulate(jit, (0, 0.05), dt=1e-3, **kw)
    np.testing.assert_allclose(res.currents_A, ref.currents_A, rtol=1e-12)
    np.testing.assert_allclose(res.force_N, ref.force_N, rtol=1e-12)
    state, out = jit.step(jit.initial_state(gaps=0.01, currents=15.0), 1e-3, 45.0)
    assert np.isfinite(out.force_N) and state.inductor_currents_A[0] > 15.0


def test_rk4_and_cvodes_agree_in_deep_saturation(u_maps) -> None:  # type: ignore[no-untyped-def]
    """Eq. 8 is not stiff (time constants >= ~4 ms on these maps); RK4 at 1 ms sub-steps vs
    CVODES at rtol 1e-11: measured 2.5e-6 relative; bound 2e-5."""
    kw = {"gaps": 0.0045, "voltages": lambda t: 40.0 if t < 0.005 else 150.0,
          "initial_currents": 20.0}
    ref = mk.simulate(CurrentModel(u_maps, method="cvodes", rtol=1e-11, atol=1e-12), (0, 0.1),
                      dt=1e-3, **kw)
    rk4 = mk.simulate(CurrentModel(u_maps), (0, 0.1), dt=1e-3, **kw)
    assert ref.currents_A.max() > 60.0   # deep into saturation
    np.testing.assert_allclose(rk4.currents_A, ref.currents_A, rtol=0, atol=2e-5 * 75)
    np.testing.assert_allclose(rk4.force_N, ref.force_N, rtol=0, atol=2e-5 * ref.force_N.max())


def test_bad_current_model_options(u_maps) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(mk.InputError, match="method = 'euler'"):
        CurrentModel(u_maps, method="euler")
    with pytest.raises(mk.InputError, match="max_step_s"):
        CurrentModel(u_maps, max_step_s=0.0)
