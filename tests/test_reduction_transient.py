"""R_ec from the detailed DAE and the paper's time-integration identification of the maps."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.models.experiments import differential_inductance_from_step, voltage_step_response
from maglevkit.reduction import build_maps
from maglevkit.reduction.parameters import current_jump_admittance, eddy_resistance
from maglevkit.reduction.transient import dl_ds_from_ramp, flux_held_ramp

from .conftest import G_EC, R_EL, TURNS, loop_network

# Small grid with eddy currents and saturation (60 A at 6 mm is deep in the knee).
GAPS = np.linspace(0.006, 0.012, 4)
CURRENTS = np.linspace(0.0, 60.0, 4)


@pytest.fixture(scope="module")
def both_maps(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    # the default executor ("auto"; in-process for this 16-point grid)
    return build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, method="both")


def test_eddy_resistance_of_one_loop_is_n2_over_g() -> None:
    # Linear algebra on a 3 x 3 system: exact up to rounding.
    for gap, current in ((0.002, 0.0), (0.01, 5.0)):
        r = eddy_resistance(loop_network(eddy=True), gap_m=gap, current_A=current)
        np.testing.assert_allclose(r, [TURNS**2 / G_EC], rtol=1e-12)
        y = current_jump_admittance(loop_network(eddy=True), gap_m=gap, current_A=current)
        np.testing.assert_allclose(y, [[1.0 / (R_EL + TURNS**2 / G_EC)]], rtol=1e-12)
    assert np.all(np.isinf(eddy_resistance(loop_network(eddy=False), gap_m=0.005, current_A=1.0)))


def test_eddy_resistance_is_the_instantaneous_current_jump(u_magnet: mk.Magnet) -> None:
    s, i0, r_el = 0.008, 30.0, float(u_magnet.network.resistances[0])
    r_ec = float(eddy_resistance(u_magnet, gap_m=s, current_A=i0)[0])
    du = 0.04
    res = voltage_step_response(u_magnet, gap_m=s, voltage_V=r_el * i0 + du, initial_current_A=i0,
                                duration_s=2e-6, dt_s=1e-6, rtol=1e-10, atol=1e-12)
    di = res.currents_A[1:, 0] - i0
    jump = 2.0 * di[0] - di[1]     # linear extrapolation of t = 1, 2 us back to t = 0+
    # Eddy modes of tau ~1 ms and ~0.24 ms carry the jump's decay (faster ones, down to
    # ~25 us, are weak): extrapolation error ~ (2 us / tau)^2 per mode; IDAS at rtol 1e-10
    # adds nothing visible.  Bound 1e-4.
    np.testing.assert_allclose(du / jump - r_el, r_ec, rtol=1e-4)
    # The single-exponential fit of differential_inductance_from_step extrapolates the
    # *slow* mode back to t = 0; it implies a smaller R_ec (measured 8.485 vs 22.374 ohm,
    # ratio 0.3792), because the fast eddy modes (several: every leg segment has its own)
    # decay within a few ms.  Documented in docs/reduction.md.  Window +-3 % around the
    # measured ratio (its value is checked independently in
    # test_default_eddy_resistance_against_an_independent_tail_fit).
    slow = differential_inductance_from_step(u_magnet, gap_m=s, current_A=i0).eddy_resistance_ohm
    assert 0.368 * r_ec < slow < 0.391 * r_ec


def test_default_eddy_resistance_of_one_loop_is_n2_over_g() -> None:
    """The step-fitted R_ec (the current-based model's default) on a network whose step
    response is exactly one exponential: one loop with one eddy element, R_ec = n^2/G.

    G is chosen so that R_ec = 10 R_el (the bundled magnets: 4-11): the current jump is
    then 9 % of the final change and the fit's intercept is well conditioned (with
    R_ec/R_el = 533, conftest's G_EC, the jump is 0.2 % and the fitted value is off by
    -10 %, a limit of the identification method, not of this loop).  Measured error
    -0.17 % (IDAS at rtol 1e-9 on a 1e-3 step); bound 0.5 %."""
    r_ec = 10.0 * R_EL
    net = loop_network(eddy=True, g_ec=TURNS**2 / r_ec)
    maps = build_maps(net, gaps_m=np.linspace(0.002, 0.008, 4), currents_A=np.linspace(0, 10, 4),
                      progress=False)
    assert float(maps.dataset["eddy_resistance_ohm"].values[0]) == pytest.approx(r_ec, rel=1e-12)
    fit = float(maps.dataset["eddy_resistance_fit_ohm"].values[0])
    assert fit == pytest.approx(r_ec, rel=5e-3)


def test_default_eddy_resistance_against_an_independent_tail_fit(u_magnet: mk.Magnet) -> None:
    """The default R_ec of the current-based model (``eddy_resistance_fit_ohm``, the slow
    eddy mode) against a second identification that shares no code with the library's:
    a FluxModel voltage step (own dt and tolerances) fitted by scipy's nonlinear least
    squares (curve_fit) with dI(t) = dI_inf - A exp(-t/tau) on t >= 5 ms only, where the
    fast eddy modes (tau ~1 ms and ~0.24 ms) have decayed (fit rms 2e-5 of dI_inf), so
    A is the slow mode's amplitude extrapolated to t = 0 and R_ec = dU/(dI_inf - A) - R_el.

    Measured: tail fit 8.60 ohm, tau 16.82 ms (8.61/8.62 ohm when starting at 10/20 ms);
    library 8.845 ohm, +2.8 %: its log-linear fit starts at 98 % of the remaining change
    (t ~ 0.3 ms), where the fast modes still add to the response.  Signed window
    +1.5 ... +4.0 % (the fit-start spread 0.2 % plus 1 % for tolerances and the machine),
    so R_ec x1.05 (+7.9 %) or x0.95 (-2.3 %) fails.  The current-based model must use the
    same value: its current jump after a step (eq. 8 outputs, 0.1 us after the step) gives
    the same ratio, and its single time constant equals the slow mode (measured
    16.838 vs 16.820 ms, +0.1 %; bound +-0.5 %)."""
    from scipy.optimize import curve_fit

    s, i0 = 0.012, 40.0                       # the maps' reference point (grid centre)
    maps = build_maps(u_magnet, gaps_m=np.linspace(0.008, 0.016, 5),
                      currents_A=np.linspace(0.0, 80.0, 5), progress=False)
    assert "s = 0.012 m, I = 40.0 A" in maps.dataset["eddy_resistance_fit_ohm"].attrs[
        "description"]
    fit_lib = float(maps.dataset["eddy_resistance_fit_ohm"].values[0])
    fm = mk.FluxModel(u_magnet, rtol=1e-9, atol=1e-11)
    r_el = float(fm.resistances[0])
    di_inf = 1e-3 * i0
    st = fm.initial_state(gaps_m=s, currents_A=i0)
    tau0 = 0.0137                             # L~/R_el (statics), sizes the window only
    res = mk.simulate(fm, (0.0, 6 * tau0), dt_s=tau0 / 25, gaps_m=st.gaps_m,
                      voltages_V=r_el * (i0 + di_inf), initial_state=st)
    t, di = res.time_s, res.currents_A[:, 0] - i0
    sel = t >= 5e-3

    def law(t: np.ndarray, a: float, tau: float) -> np.ndarray:
        return di_inf - a * np.exp(-t / tau)

    (amp, tau), _ = curve_fit(law, t[sel], di[sel], p0=(di_inf, 1.2 * tau0))
    assert np.sqrt(np.mean((law(t[sel], amp, tau) - di[sel]) ** 2)) < 1e-4 * di_inf
    r_tail = r_el * di_inf / (di_inf - amp) - r_el
    assert 1.015 < fit_lib / r_tail < 1.04, (fit_lib, r_tail)
    model = mk.CurrentModel(maps)
    _, out = model.step(model.initial_state(gaps_m=s, currents_A=i0), 1e-7, r_el * (i0 + di_inf),
                        gaps_m=s, gap_rates_m_per_s=0.0)
    r_model = r_el * di_inf / float(out.currents_A[0] - i0) - r_el
    assert 1.015 < r_model / r_tail < 1.04, (r_model, r_tail)
    lin = model.linearize(gap_m=s, current_A=i0)
    assert -1.0 / lin.A_per_s[0, 0] == pytest.approx(tau, rel=5e-3)


def test_eddy_resistance_of_the_standard_magnet_is_symmetric() -> None:
    # the lumped eddy elements (the file names the ladder since switch26m)
    tr = mk.load_magnet("tr09-standard", eddy_model="lumped")
    r = eddy_resistance(tr, gap_m=0.01, current_A=34.0)
    # front and rear half magnets are mirror images: equal to rounding
    assert np.all(np.isfinite(r)) and np.all(r > 0.0)
    np.testing.assert_allclose(r[0], r[1], rtol=1e-9)
    # the file's ladder: the split network's coil air lies beside the tubes, outside the
    # iron's eddy currents, so the coil links a path without an eddy element and its current
    # cannot jump at a voltage step: R_ec = inf (docs/magnets.md, element table)
    ladder = eddy_resistance(mk.load_magnet("tr09-standard"), gap_m=0.01, current_A=34.0)
    assert np.all(np.isinf(ladder))


def test_virtual_control_law_holds_the_flux_linkage(u_magnet: mk.Magnet) -> None:
    resp = flux_held_ramp(u_magnet, gap_m=0.008, current_A=30.0, gap_change_m=4e-4, duration_s=1.0,
                          samples=21)
    psi = resp.flux_linkage_Wb[:, 0]
    # U = R_el I is substituted exactly: psi' = 0 up to rounding (not a ZOH drift).
    assert np.ptp(psi) <= 1e-12 * abs(psi[0])
    # the gap opens, so the current must rise to keep psi
    assert resp.currents_A[-1, 0] > 1.01 * resp.currents_A[0, 0]
    np.testing.assert_allclose(resp.gaps_m[-1], 0.0084, rtol=1e-12)


def test_transient_and_statics_maps_agree(both_maps) -> None:  # type: ignore[no-untyped-def]
    ds = both_maps.dataset
    dl = ds["inductance_relative_difference"].values
    dd = ds["dL_ds_relative_difference"].values
    assert np.all(np.isfinite(dl)) and np.all(np.isfinite(dd))   # incl. I = 0 (I_eps limit)
    # Tolerance 0.5 %: the step method fits one exponential to a multi-mode response
    # (fit rms up to 0.9 %, L~ low by up to 0.28 % at 60 A, measured); its finite step
    # (1e-3 I) measures a chord of psi(I); dL/ds = -L~ dlnI/ds inherits that and adds the
    # eddy lag of the ramp (~1e-4 at T = 50 L~/R_el).  Measured max: 0.28 % / 0.33 %.
    assert np.max(np.abs(dl)) < 5e-3
    assert np.max(np.abs(dd)) < 5e-3
    np.testing.assert_allclose(ds["inductance_transient_H"].values,
                               ds["inductance_H"].values * (1 + dl), rtol=1e-12)
    r_ec = ds["eddy_resistance_ohm"].values
    assert np.all(np.isfinite(r_ec)) and np.all(r_ec > 0.0)
    step = ds["eddy_resistance_step_ohm"].values
    assert step.shape == (1, GAPS.size, CURRENTS.size) and np.all(step < r_ec[:, None, None])


def test_transient_maps_through_a_process_pool_are_identical(u_magnet: mk.Magnet,  # type: ignore[no-untyped-def]
                                                             both_maps) -> None:
    """The fixture runs the default path (executor="auto": in-process for a 16-point grid,
    below AUTO_POOL_MIN_POINTS); a 2-process pool must give the same maps."""
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(2) as ex:
        pooled = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, method="both", executor=ex,
                            progress=False)
    for name in both_maps.dataset.data_vars:
        # same compiled code on the same inputs: bit-identical
        assert np.array_equal(both_maps.dataset[name].values, pooled.dataset[name].values,
                              equal_nan=True), name


def _assert_transient_equals_both(tr, both) -> None:  # type: ignore[no-untyped-def]
    """Maps of method="transient" carry the transient variables of method="both"."""
    pairs = {"inductance_H": "inductance_transient_H", "dL_ds_H_per_m": "dL_ds_transient_H_per_m",
             "force_N": "force_N", "eddy_resistance_step_ohm": "eddy_resistance_step_ohm",
             "eddy_resistance_ohm": "eddy_resistance_ohm",
             "eddy_resistance_fit_ohm": "eddy_resistance_fit_ohm"}
    for a, b in pairs.items():
        # same compiled code on the same inputs, wherever it runs: bit-identical
        assert np.array_equal(tr.dataset[a].values, both.dataset[b].values, equal_nan=True), a


def test_dask_local_cluster_gives_identical_transient_maps(u_magnet: mk.Magnet,  # type: ignore[no-untyped-def]
                                                           both_maps) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, method="transient",
                            executor=client, progress=False)
    _assert_transient_equals_both(remote, both_maps)


def test_cli_maps_build_method_and_difference_plots(both_maps, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from typer.testing import CliRunner

    from maglevkit.cli import app

    runner = CliRunner()
    nc = tmp_path / "t.nc"
    res = runner.invoke(app, ["maps", "build", "u-magnet", "-o", str(nc), "--gaps",
                              "0.006:0.012:4", "--currents", "0:60:4", "--method", "transient"])
    assert res.exit_code == 0, res.output
    tr = mk.load_maps(nc, magnet=mk.load_magnet("u-magnet"))
    assert "transient" in tr.dataset.attrs["method"]
    _assert_transient_equals_both(tr, both_maps)
    res = runner.invoke(app, ["maps", "build", "u-magnet", "-o", str(tmp_path / "f.nc"),
                              "--method", "fit"])
    assert res.exit_code == 2 and "--method" in res.output
    # plot: maps of method "both" also get the per-point relative differences
    both_nc = both_maps.to_netcdf(tmp_path / "both.nc")
    res = runner.invoke(app, ["maps", "plot", str(both_nc), "--out", str(tmp_path / "b")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "b" / "maps_coil.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "b" / "maps_difference_coil.png").read_bytes()[:4] == b"\x89PNG"
    res = runner.invoke(app, ["maps", "plot", str(nc), "--out", str(tmp_path / "t")])
    assert res.exit_code == 0, res.output
    assert not (tmp_path / "t" / "maps_difference_coil.png").exists()
    with pytest.raises(mk.InputError, match="method='both'"):
        from maglevkit.reduction.plots import plot_method_differences

        plot_method_differences(tr, tmp_path / "x")


def test_transient_method_replaces_only_the_inductance_maps(u_magnet: mk.Magnet,  # type: ignore[no-untyped-def]
                                                            both_maps) -> None:
    tr = build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, method="transient")
    assert "transient" in tr.dataset.attrs["method"]
    np.testing.assert_array_equal(tr.dataset["inductance_H"].values,
                                  both_maps.dataset["inductance_transient_H"].values)
    np.testing.assert_array_equal(tr.dataset["force_N"].values,
                                  both_maps.dataset["force_N"].values)


def test_zero_current_uses_the_small_current_limit(u_magnet: mk.Magnet, both_maps) -> None:  # type: ignore[no-untyped-def]
    est = dl_ds_from_ramp(u_magnet, gap_m=float(GAPS[0]), current_A=0.0)
    assert est.current_A == pytest.approx(1e-4)
    assert est.dL_ds_H_per_m == both_maps.dataset["dL_ds_transient_H_per_m"].values[0, 0, 0]


@pytest.mark.parametrize(
    ("kwargs", "msg"),
    [
        ({"relative_gap_change": 0.5}, "relative_gap_change"),
        ({"current_A": -1.0}, ">= 0"),
        ({"circuit": 3}, "circuit"),
        ({"zero_current_A": 0.0}, "zero_current"),
    ],
)
def test_bad_ramp_inputs_raise(u_magnet: mk.Magnet, kwargs: dict, msg: str) -> None:
    args = {"gap_m": 0.01, "current_A": 10.0, **kwargs}
    with pytest.raises(mk.InputError, match=msg):
        dl_ds_from_ramp(u_magnet, **args)


def test_bad_method_and_ramp_raise(u_magnet: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match="method"):
        build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, method="fit")
    with pytest.raises(mk.InputError, match="keep the gaps > 0"):
        flux_held_ramp(u_magnet, gap_m=0.01, current_A=1.0, gap_change_m=-0.02, duration_s=1.0)
    with pytest.raises(mk.InputError, match="duration"):
        flux_held_ramp(u_magnet, gap_m=0.01, current_A=1.0, gap_change_m=1e-4, duration_s=0.0)
