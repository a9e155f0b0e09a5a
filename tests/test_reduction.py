"""Characteristic maps (statics method) and the current-based model (paper eq. 8)."""

from __future__ import annotations

import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.materials import MU0
from maglevkit.reduced.current import CurrentModel
from maglevkit.reduction import build_maps, load_maps

from .conftest import build_u

N_TURNS, AREA, R_EL = 600.0, 0.003, 2.0
GAPS = np.linspace(0.004, 0.020, 17)
CURRENTS = np.linspace(0.0, 80.0, 33)


@pytest.fixture(scope="module")
def ideal_maps() -> mk.reduction.CharacteristicMaps:  # type: ignore[name-defined]
    return build_maps(build_u(material="ideal", fringing=False, leakage=False), gaps_m=GAPS,
                      currents_A=CURRENTS)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    return build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS)


def test_maps_of_the_ideal_magnet_are_the_closed_forms(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    s, i = np.meshgrid(GAPS, CURRENTS, indexing="ij")
    l_exact = MU0 * N_TURNS**2 * AREA / (2 * s)
    # exact linear network: agreement to rounding
    np.testing.assert_allclose(ideal_maps.variable("inductance_H", "coil"), l_exact, rtol=1e-10)
    np.testing.assert_allclose(ideal_maps.variable("force_N", "coil"),
                               MU0 * (N_TURNS * i) ** 2 * AREA / (4 * s * s), rtol=1e-10,
                               atol=1e-9)
    # dL/ds = -L/s, including the I -> 0 limit (central difference at h = 1e-6 s: measured
    # 2.0e-10 there, 4e-16 elsewhere); bound 2e-9
    np.testing.assert_allclose(ideal_maps.variable("dL_ds_H_per_m", "coil"), -l_exact / s,
                               rtol=2e-9)


def test_maps_satisfy_eq9_reciprocity(u_magnet: mk.Magnet) -> None:
    """Eq. 9 / co-energy: dF/dI = -dL/ds I on the map grid, from knee to deep saturation.

    dF/dI by a 4th-order central difference along a fine current grid (h = 0.25 A); the
    truncation error scales as h^4: it is 2 % of max |dF/dI| at h = 2.5 A at the knee, so
    ~2e-6 here (measured 8e-5, dominated by the difference quotient of dL/ds in the maps).
    The bound 1e-3 is 12x above that and still fails for any wrong factor in eq. 9."""
    currents = np.linspace(0.0, 80.0, 321)
    maps = build_maps(u_magnet, gaps_m=np.linspace(0.004, 0.020, 4), currents_A=currents)
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
        threaded = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, executor=ex)
    for name in u_maps.dataset.data_vars:
        assert np.array_equal(u_maps.dataset[name].values, threaded.dataset[name].values,
                              equal_nan=True)


def test_process_pool_gives_identical_maps(u_magnet: mk.Magnet, u_maps) -> None:  # type: ignore[no-untyped-def]
    pooled = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, executor="process")
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
        build_maps(u_magnet, gaps_m=gaps, currents_A=currents)


def test_current_model_step_response_is_the_rl_law(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    """Ideal linear magnet at fixed gap: I = U/R (1 - exp(-t R/L)), L = mu0 n^2 A/(2 s)."""
    model = CurrentModel(ideal_maps)
    t = np.linspace(0.0, 0.5, 501)
    s0, u = 0.01, 20.0
    res = mk.simulate(model, t, gaps_m=s0, voltages_V=u, initial_currents_A=0.0)
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
    state = model.initial_state(gaps_m=s0, currents_A=i0)
    currents = [i0]
    for k in range(t.size - 1):
        state, out = model.step(state, t[k + 1] - t[k], voltages_V=R_EL * state.inductor_currents_A,
                                gaps_m=gaps[k], gap_rates_m_per_s=sdot)
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
        model.simulate(t, gaps_m=0.01, voltages_V=400.0, initial_currents_A=0.0)
    with pytest.raises(mk.OutOfRangeError, match="gaps 0.004..0.02 m"):
        model.simulate(t, gaps_m=0.03, voltages_V=1.0, initial_currents_A=0.0)
    with pytest.warns(UserWarning, match="extrapolating"):
        CurrentModel(ideal_maps, extrapolate=True).simulate(t, gaps_m=0.021, voltages_V=1.0,
                                                            initial_currents_A=0.0)
    with pytest.raises(mk.InputError, match="gaps must be > 0"):
        model.step(model.initial_state(gaps_m=0.01, currents_A=1.0), 1e-3, voltages_V=2.0, gaps_m=-0.01)
    with pytest.raises(mk.InputError, match="expected 1 values"):
        model.step(model.initial_state(gaps_m=0.01, currents_A=1.0), 1e-3, voltages_V=[2.0, 2.0],
                   gaps_m=0.01)


def test_dask_local_cluster_gives_identical_maps(u_magnet: mk.Magnet, u_maps) -> None:  # type: ignore[no-untyped-def]
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, executor=client)
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
    res = mk.simulate(model, t, gaps_m=np.repeat(gaps[:, None], 2, axis=1), voltages_V=volts,
                      initial_currents_A=15.0)
    state = model.initial_state(gaps_m=gaps[0], currents_A=15.0)
    for k in range(t.size - 1):
        rate = (gaps[k + 1] - gaps[k]) / (t[k + 1] - t[k])
        state, out = model.step(state, t[k + 1] - t[k], volts[k], gaps_m=gaps[k], gap_rates_m_per_s=rate)
        assert out.currents_A[0] == pytest.approx(res.currents_A[k + 1, 0], rel=rel)
        assert out.force_N == pytest.approx(res.force_N[k + 1], rel=rel)
    assert res.final_state.inductor_currents_A[0] == pytest.approx(
        state.inductor_currents_A[0], rel=rel)


@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("cc") is None,
                    reason="jit=True needs a C compiler")
def test_jit_compiled_current_model_matches_the_interpreted_one(u_maps) -> None:  # type: ignore[no-untyped-def]
    """Same arithmetic, compiled instead of interpreted: agreement to rounding (measured 0 on
    x86-64 with -O3, which does not reassociate floating point); bound 1e-12 relative."""
    kw = {"gaps_m": lambda t: 0.01 + 0.002 * np.sin(2 * np.pi * 20 * t),
          "voltages_V": lambda t: 30.0 if t < 0.02 else 45.0, "initial_currents_A": 15.0}
    ref = mk.simulate(CurrentModel(u_maps), (0, 0.05), dt_s=1e-3, **kw)
    jit = CurrentModel(u_maps, jit=True)
    res = mk.simulate(jit, (0, 0.05), dt_s=1e-3, **kw)
    np.testing.assert_allclose(res.currents_A, ref.currents_A, rtol=1e-12)
    np.testing.assert_allclose(res.force_N, ref.force_N, rtol=1e-12)
    state, out = jit.step(jit.initial_state(gaps_m=0.01, currents_A=15.0), 1e-3, 45.0)
    assert np.isfinite(out.force_N) and state.inductor_currents_A[0] > 15.0


def test_rk4_and_cvodes_agree_in_deep_saturation(u_maps) -> None:  # type: ignore[no-untyped-def]
    """Eq. 8 is not stiff (time constants >= ~5 ms on these maps); RK4 at 1 ms sub-steps vs
    CVODES at rtol 1e-11: measured 6.4e-7 relative; bound 2e-5."""
    kw = {"gaps_m": 0.0045, "voltages_V": lambda t: 40.0 if t < 0.005 else 150.0,
          "initial_currents_A": 20.0}
    ref = mk.simulate(CurrentModel(u_maps, method="cvodes", rtol=1e-11, atol=1e-12), (0, 0.1),
                      dt_s=1e-3, **kw)
    rk4 = mk.simulate(CurrentModel(u_maps), (0, 0.1), dt_s=1e-3, **kw)
    assert ref.currents_A.max() > 60.0   # deep into saturation
    np.testing.assert_allclose(rk4.currents_A, ref.currents_A, rtol=0, atol=2e-5 * 75)
    np.testing.assert_allclose(rk4.force_N, ref.force_N, rtol=0, atol=2e-5 * ref.force_N.max())


def test_bad_current_model_options(u_maps) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(mk.InputError, match="method = 'euler'"):
        CurrentModel(u_maps, method="euler")
    with pytest.raises(mk.InputError, match="max_step_s"):
        CurrentModel(u_maps, max_step_s=0.0)


# ----------------------------------------------------------------- maps identity (hash)
SMALL_GAPS = np.linspace(0.006, 0.012, 4)
SMALL_CURRENTS = np.linspace(0.0, 40.0, 4)


def test_maps_identity_is_shared_by_magnet_and_flux_model(u_magnet: mk.Magnet,
                                                          tmp_path: Path) -> None:
    """Maps of a magnet fit the Magnet and FluxModel(magnet) alike (all four combinations),
    and are refused for another magnet and for other physics switches."""
    from_magnet = build_maps(u_magnet, gaps_m=SMALL_GAPS, currents_A=SMALL_CURRENTS)
    from_flux = build_maps(mk.FluxModel(u_magnet), gaps_m=SMALL_GAPS, currents_A=SMALL_CURRENTS)
    assert from_magnet.magnet_hash == from_flux.magnet_hash
    for maps in (from_magnet, from_flux):
        p = maps.to_netcdf(tmp_path / "m.nc")
        for target in (u_magnet, mk.FluxModel(u_magnet), mk.load_magnet("u-magnet")):
            load_maps(p, magnet=target)          # accepted: no exception
        refused = (build_u(magnet={"turns": 601}, eddy_currents=True),
                   mk.FluxModel(u_magnet, saturation=False),
                   mk.FluxModel(u_magnet, eddy_currents=False),
                   u_magnet.with_options(eddy_currents=False))
        for target in refused:
            with pytest.raises(mk.ParameterFileError, match="belong to magnet"):
                load_maps(p, magnet=target)
    # same physics switches through either route: accepted
    lin = build_maps(mk.FluxModel(u_magnet, saturation=False), gaps_m=SMALL_GAPS,
                     currents_A=SMALL_CURRENTS)
    lin.check_magnet(u_magnet.with_options(saturation=False))
    with pytest.raises(mk.ParameterFileError, match="belong to magnet"):
        lin.check_magnet(u_magnet)


def test_progress_bar_is_the_default_and_changes_nothing(u_magnet: mk.Magnet,
                                                         capsys: pytest.CaptureFixture) -> None:
    import inspect

    params = inspect.signature(build_maps).parameters
    assert params["progress"].default is True and params["executor"].default == "auto"
    quiet = build_maps(u_magnet, gaps_m=SMALL_GAPS, currents_A=SMALL_CURRENTS, progress=False)
    shown = build_maps(u_magnet, gaps_m=SMALL_GAPS, currents_A=SMALL_CURRENTS, progress=True)
    capsys.readouterr()      # whatever rich printed on the (non-terminal) capture
    for name in quiet.dataset.data_vars:
        assert np.array_equal(quiet.dataset[name].values, shown.dataset[name].values,
                              equal_nan=True), name


def test_default_executor_rule() -> None:
    """'auto': statics in this process at any size; transient points through a process pool
    from AUTO_POOL_MIN_POINTS (64) points on when there are >= 2 CPUs (measured break-even
    between 16 and 64 points on 2 cores, see maps.AUTO_POOL_MIN_POINTS)."""
    import os
    from concurrent.futures import ProcessPoolExecutor

    from maglevkit.reduction.maps import AUTO_POOL_MIN_POINTS, _as_executor

    assert AUTO_POOL_MIN_POINTS == 64
    for n in (16, 100_000):
        assert _as_executor("auto", "statics", n) == (None, False)
    assert _as_executor("auto", "transient", 63) == (None, False)
    ex, owned = _as_executor("auto", "both", 64)
    try:
        if (os.cpu_count() or 1) >= 2:
            assert isinstance(ex, ProcessPoolExecutor) and owned
        else:
            assert ex is None
    finally:
        if ex is not None:
            ex.shutdown()
    with pytest.raises(mk.InputError, match="executor must be"):
        _as_executor("threads", "statics", 16)


# ----------------------------------------------------------------- reciprocity, TR09
def test_tr09_maps_satisfy_eq9_reciprocity_per_circuit() -> None:
    """Eq. 9 per circuit of the TR09 standard magnet (front/rear half magnets).

    The maps run all circuits at the same current, so the derivative along the grid is
    dF_j/dI = sum_m dF_j/dI_m = -sum_m dpsi_m/ds_(j's poles) (co-energy reciprocity),
    while eq. 9 (one circuit, coupling neglected) takes only m = j: the two differ by the
    coupling term -sum_(m != j) dpsi_m/ds_(j's poles), computed here exactly from statics.
    With it the check is exact up to the finite difference: 4th-order central difference
    at h = 0.5 A (truncation ~h^4; a crude estimate from 2 % at 2.5 A gives <= 3e-5;
    measured 8.1e-7 of max |dF/dI| on 10-50 A, 8-12 mm); bound 1e-5.  Without it the
    residual is the neglected coupling itself: measured 1.052e-2 of max |dF/dI| on the
    split network (the bundled default since issue 26; the lumped "paper" network gave
    4.62e-3: the split network couples the half magnets more through its flank and pole-back
    paths), window 9.5e-3 ... 1.16e-2 (+-10 %: it is a property of the TR09 network, not of
    the numerics).  The maps' L~ is the circuit's *self*
    differential inductance dpsi_j/dI_j (other current held): against central differences
    of the solved flux linkages (h = 1e-4 I, truncation ~1e-9) measured <= 7.9e-9 at
    three nodes; bound 1e-7 (the mutual term it must not contain is 0.7-0.8 % of it).
    """
    tr = mk.load_magnet("tr09-standard")
    gaps = np.linspace(0.008, 0.012, 4)
    currents = np.linspace(10.0, 50.0, 81)
    maps = build_maps(tr, gaps_m=gaps, currents_A=currents)
    groups = maps.pole_groups
    net = tr.network
    gi = {g: k for k, g in enumerate(net.gap_names)}
    h = currents[1] - currents[0]
    s_grid = np.repeat(gaps[:, None], currents.size, axis=1)[:, 2:-2]
    i_grid = np.repeat(currents[None, :], gaps.size, axis=0)[:, 2:-2]
    sol = mk.solve_statics(tr, gaps_m=np.repeat(s_grid[..., None], len(gi), axis=-1),
                           currents_A=np.repeat(i_grid[..., None], len(net.circuits), axis=-1))
    for j, c in enumerate(maps.circuits):
        f = maps.variable("force_N", c)
        dlds = maps.variable("dL_ds_H_per_m", c)
        df = (-f[:, 4:] + 8 * f[:, 3:-1] - 8 * f[:, 1:-3] + f[:, :-4]) / (12 * h)
        eq9 = -dlds[:, 2:-2] * currents[2:-2]
        idx = [gi[g] for g in groups[c]]
        others = [m for m in range(len(maps.circuits)) if m != j]
        coupling = -sol.dpsi_dgap_Wb_per_m[..., others, :][..., idx].sum(axis=(-1, -2))
        scale = np.max(np.abs(df))
        assert np.max(np.abs(df - eq9 - coupling)) < 1e-5 * scale, c
        raw = np.max(np.abs(df - eq9))
        assert 9.5e-3 * scale < raw < 1.16e-2 * scale, (c, raw / scale)
    for k, m in ((0, 10), (2, 40), (3, 80)):
        s, i = float(gaps[k]), float(currents[m])
        hi = 1e-4 * i
        psi = mk.solve_statics(tr, gaps_m=s, currents_A=[[i + hi, i], [i - hi, i], [i, i + hi],
                                                     [i, i - hi]]).flux_linkage_Wb
        l_self = ((psi[0, 0] - psi[1, 0]) / (2 * hi), (psi[2, 1] - psi[3, 1]) / (2 * hi))
        for j, c in enumerate(maps.circuits):
            assert maps.variable("inductance_H", c)[k, m] == pytest.approx(l_self[j],
                                                                          rel=1e-7), (c, s, i)


# ----------------------------------------------------------------- linearisation
def _ode(model: CurrentModel, x: np.ndarray, u: np.ndarray, s: np.ndarray,
         sd: np.ndarray) -> np.ndarray:
    return np.asarray(model.ode(x, u, s, sd), dtype=float).ravel()


def test_linearization_matches_finite_differences_of_eq8(u_maps) -> None:  # type: ignore[no-untyped-def]
    """AD Jacobians vs central differences of the ODE right-hand side and the outputs, off
    a steady state (U != R I, gap moving) so that every term of eq. 8 contributes.
    Central differences with relative steps 1e-6: truncation ~1e-12 x third derivative,
    rounding ~1e-16/1e-6 = 1e-10 relative (measured 2e-10); bound 2e-9."""
    model = CurrentModel(u_maps)
    s0, i0, u0, sd0 = 0.0093, 23.0, 50.0, 0.05
    lin = model.linearize(gap_m=s0, current_A=i0, voltage_V=u0, gap_rate_m_per_s=sd0)
    x, u, s, sd = (np.array([v]) for v in (i0, u0, s0, sd0))
    np.testing.assert_allclose(lin.state_derivative_A_per_s, _ode(model, x, u, s, sd),
                               rtol=1e-14)

    def fd(fun, k: int, h: float) -> float:  # type: ignore[no-untyped-def]
        args = [x, u, s, sd]
        plus = [a.copy() for a in args]
        minus = [a.copy() for a in args]
        plus[k] += h
        minus[k] -= h
        return float((fun(*plus) - fun(*minus))[0] / (2 * h))

    def force(x, u, s, sd):  # type: ignore[no-untyped-def]
        return np.asarray(model.outputs_fun(x, u, s)[1], dtype=float).ravel()

    def coil(x, u, s, sd):  # type: ignore[no-untyped-def]
        return np.asarray(model.outputs_fun(x, u, s)[0], dtype=float).ravel()

    rhs = lambda *a: _ode(model, *a)  # noqa: E731
    checks = [(lin.A_per_s[0, 0], fd(rhs, 0, 1e-6 * i0)),
              (lin.B_A_per_V_s[0, 0], fd(rhs, 1, 1e-6 * u0)),
              # two poles share the substitute gap equally: per-pole entries sum to d/ds
              (lin.E_gap_A_per_m_s.sum(), fd(rhs, 2, 1e-6 * s0)),
              (lin.E_gap_rate_A_per_m.sum(), fd(rhs, 3, 1e-6 * sd0)),
              (lin.C_force_N_per_A[0, 0], fd(force, 0, 1e-6 * i0)),
              (lin.D_force_gap_N_per_m.sum(), fd(force, 2, 1e-6 * s0)),
              (lin.C_current[0, 0], fd(coil, 0, 1e-6 * i0)),
              (lin.D_current_A_per_V[0, 0], fd(coil, 1, 1e-6 * u0))]
    for ad, num in checks:
        assert ad == pytest.approx(num, rel=2e-9)
    assert lin.E_gap_A_per_m_s.shape == (1, 2)
    np.testing.assert_allclose(lin.E_gap_A_per_m_s[0, 0], lin.E_gap_A_per_m_s[0, 1], rtol=1e-15)


def test_linearization_at_a_steady_state_matches_the_statics(u_maps, u_magnet: mk.Magnet) -> None:  # type: ignore[no-untyped-def]
    """Against the detailed model's statics: at a steady operating point (on a map node) dF/dI of the
    linearisation equals the statics' dF/dI (= -dpsi/ds, co-energy) of the detailed model,
    and dF/ds equals the statics' dF/ds; A = -R_el / (a L~), D_current = 1/(R_el + R_ec).
    The spline derivative at a node of a 2.5 A x 1 mm grid differs from the exact one by
    the cubic interpolation error of a derivative, O(h^3 f''''): measured 4.8e-4 for dF/dI
    (bound 1e-3) and 7.8e-3 for dF/ds at 6 mm / 40 A, where the knee bends F(s) within
    one 1 mm cell (bound 1.5e-2; elsewhere < 1e-4).  A and D_current use map values at a
    node (the B-spline interpolates them): measured 3e-14; bound 1e-12."""
    model = CurrentModel(u_maps)
    for s0, i0 in ((0.010, 20.0), (0.006, 40.0), (0.014, 60.0)):
        lin = model.linearize(gap_m=s0, current_A=i0)
        np.testing.assert_allclose(lin.state_derivative_A_per_s, 0.0, atol=1e-12)
        sol = mk.solve_statics(u_magnet, gaps_m=s0, currents_A=i0)
        df_di = sol.dforce_dcurrent_N_per_A.sum()
        assert df_di == pytest.approx(-sol.dpsi_dgap_Wb_per_m.sum(), rel=1e-9)  # reciprocity
        assert lin.C_force_N_per_A[0, 0] == pytest.approx(df_di, rel=1e-3), (s0, i0)
        assert lin.D_force_gap_N_per_m.sum() == pytest.approx(sol.dforce_dgap_N_per_m.sum(),
                                                              rel=1.5e-2), (s0, i0)
        r_el, r_ec = model.resistance_ohm[0], model.eddy_resistance_ohm[0]
        lt = float(sol.differential_inductance_H[0, 0])
        assert lin.A_per_s[0, 0] == pytest.approx(-r_el / ((1 + r_el / r_ec) * lt), rel=1e-12)
        assert lin.D_current_A_per_V[0, 0] == pytest.approx(1 / (r_el + r_ec), rel=1e-12)
    with pytest.raises(mk.OutOfRangeError, match="outside the characteristic maps"):
        model.linearize(gap_m=0.03, current_A=10.0)
    with pytest.raises(mk.InputError, match="gaps must be > 0"):
        model.linearize(gap_m=-0.01, current_A=10.0)


def test_range_is_checked_in_rk4_sub_steps(ideal_maps) -> None:  # type: ignore[no-untyped-def]
    """One 0.1 s step (10 RK4 sub-steps of 10 ms) at U = 0 on a fast gap opening 4.1 -> 19.9
    mm of the ideal magnet: psi = L I is nearly held at first, so I rises from 66 A past the
    maps' 80 A (closed form I0 s/s0 exp(-R/k int s dt): peak 83.6 A at s = 7.3 mm, inside
    the 3-cell extension, so the integration itself stays finite), then the resistance
    wins and I ends at 9.3 A, inside the range.  The end check alone passes; the sub-step
    check must raise.  10 ms sub-steps (``max_step_s``) instead of the default 1 ms: the
    same generated sub-step loop and check for any count, 10 ms still resolve the peak
    (measured 83.7 A) and the end (9.34 A), and the compiler builds a 10-sub-step kernel
    in ~2.5 s instead of ~45 s for 100 (the cold-cache suite, docs/decisions.md suite10);
    the 5 ms samples below run on the default model."""
    coarse = CurrentModel(ideal_maps, max_step_s=0.01)
    state = coarse.initial_state(gaps_m=0.0041, currents_A=66.0)
    rate = (0.0199 - 0.0041) / 0.1
    with pytest.warns(UserWarning, match="extrapolating"):     # the end is inside: 9.3 A
        _, end = CurrentModel(ideal_maps, max_step_s=0.01, extrapolate=True).step(
            state, 0.1, 0.0, gap_rates_m_per_s=rate)
    assert 9.0 < float(end.currents_A[0]) < 10.0
    with pytest.raises(mk.OutOfRangeError, match="RK4 sub-step"):
        coarse.step(state, 0.1, 0.0, gap_rates_m_per_s=rate)
    with pytest.raises(mk.OutOfRangeError, match="RK4 sub-step"):
        coarse.simulate((0.0, 0.1), dt_s=0.1, gaps_m=lambda t: 0.0041 + rate * t, voltages_V=0.0,
                        initial_currents_A=66.0)
    model = CurrentModel(ideal_maps)
    # the same run on 5 ms samples: on the tables the kernel flags the step in which a
    # sub-step end leaves; the B-spline path sees it at an interval end (its own check)
    with pytest.raises(mk.OutOfRangeError, match=r"RK4 sub-step within t = 0\.01\.\.0\.015 s"):
        model.simulate(np.linspace(0.0, 0.1, 21), gaps_m=lambda t: 0.0041 + rate * t,
                       voltages_V=0.0, initial_currents_A=66.0)
    with pytest.raises(mk.OutOfRangeError, match=r"at t = 0\.015 s"):
        CurrentModel(ideal_maps, lookup="bspline").simulate(
            np.linspace(0.0, 0.1, 21), gaps_m=lambda t: 0.0041 + rate * t, voltages_V=0.0,
            initial_currents_A=66.0)
