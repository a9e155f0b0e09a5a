"""The reduced model's eddy network (``CurrentModel(maps, eddy_modes=m)``, Fig. 8 extended).

Closed form on hand-made maps, the identification on the U-magnet with diffusing eddy
currents, the default left unchanged, the comparison with the detailed ``ladder_split``
model and bad input (docs/reduction.md, "More eddy modes").
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import scipy.linalg

import maglevkit as mk
from maglevkit.compare import compare_models, standard_scenarios
from maglevkit.reduction.eddy_network import fit_eddy_network, network_step_response
from maglevkit.reduction.maps import CharacteristicMaps

GAPS = np.linspace(0.006, 0.014, 5)
MAX_STEP = 1e-6
CURRENTS = np.linspace(0.0, 40.0, 9)


def _linear_maps(*, ltilde: float, r_el: float, r0: float, rk: list[float],
                 lk: list[float]) -> CharacteristicMaps:
    """Maps of one circuit with a constant inductance (``dL/ds = 0``) and a given eddy
    network with ``len(rk)`` branches, stored as ``build_maps`` stores it."""
    import xarray as xr

    g, c = np.linspace(0.005, 0.015, 6), np.linspace(0.0, 50.0, 6)
    shape = (1, g.size, c.size)
    m = len(rk)
    ds = xr.Dataset(
        {"force_N": (("circuit", "gap", "current"), np.full(shape, 100.0)),
         "inductance_H": (("circuit", "gap", "current"), np.full(shape, ltilde)),
         "dL_ds_H_per_m": (("circuit", "gap", "current"), np.zeros(shape)),
         "resistance_ohm": ("circuit", [r_el]),
         "eddy_resistance_fit_ohm": ("circuit", [r0]),
         "eddy_network_r0_ohm": (("circuit", "eddy_modes"), [[r0]]),
         "eddy_network_resistance_ohm": (("circuit", "eddy_modes", "eddy_branch"), [[rk]]),
         "eddy_network_inductance_H": (("circuit", "eddy_modes", "eddy_branch"), [[lk]]),
         "eddy_network_reference_inductance_H": ("circuit", [ltilde])},
        coords={"circuit": ["coil"], "gap": g, "current": c, "eddy_modes": [m],
                "eddy_branch": np.arange(1, m + 1)},
        attrs={"pole_groups": json.dumps({"coil": ["pole"]}), "gap_names": "pole",
               "magnet_hash": "synthetic"})
    return CharacteristicMaps(ds)


def _state_space_step(t: np.ndarray, *, ltilde: float, r_el: float, r0: float,
                      rk: np.ndarray, lk: np.ndarray) -> np.ndarray:
    """dI/dU of the circuit by Kirchhoff's laws and a matrix exponential (independent of
    ``network_step_response``'s eigen-decomposition).

    Node voltage ``U_L`` across ``L~ || R_0 || (R_k + L_k)``: ``U = R_el I + U_L``,
    ``I = I_L + U_L/R_0 + sum I_k`` gives ``U_L = (U - R_el (I_L + sum I_k))/(1 + R_el/R_0)``.
    """
    a = 1.0 + r_el / r0
    n = rk.size + 1
    minv = 1.0 / np.concatenate(([ltilde], lk))
    amat = minv[:, None] * (-(r_el / a) * np.ones((n, n)) - np.diag(np.concatenate(([0.0], rk))))
    b = minv / a
    out = []
    for tk in t:
        # z(t) = int_0^t exp(A tau) b dtau, from the augmented exponential
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n] = amat
        aug[:n, n] = b
        z = scipy.linalg.expm(aug * tk)[:n, n]
        u_l = (1.0 - r_el * z.sum()) / a
        out.append((1.0 - u_l) / r_el)
    return np.array(out)


@pytest.mark.parametrize(("r0", "rk", "lk"), [
    (40.0, [6.0], [2e-3]),
    (np.inf, [30.0, 8.0], [3e-3, 4e-3]),
    (120.0, [60.0, 20.0, 9.0], [1e-3, 4e-3, 8e-3]),
])
def test_step_response_of_a_known_network_is_the_closed_form(r0: float, rk: list[float],
                                                              lk: list[float]) -> None:
    ltilde, r_el, du = 0.05, 2.0, 4.0
    maps = _linear_maps(ltilde=ltilde, r_el=r_el, r0=r0, rk=rk, lk=lk)
    model = mk.CurrentModel(maps, eddy_modes=len(rk), max_step_s=MAX_STEP)
    t = np.linspace(0.0, 0.06, 121)
    # steady state at 10 A (20 V), then 20 + du V from t = 0 on
    res = mk.simulate(model, t, gaps_m=0.01, voltages_V=20.0 + du, initial_currents_A=10.0)
    exact = 10.0 + du * _state_space_step(t, ltilde=ltilde, r_el=r_el, r0=r0,
                                         rk=np.array(rk), lk=np.array(lk))
    # RK4 at 1 us against the matrix exponential; measured largest difference 6e-14 ..
    # 1.2e-13 of the step (lambda h <= 0.07 at the fastest branch: RK4's truncation error
    # is at rounding level); bound 1e-11 of the step
    assert np.max(np.abs(res.currents_A[:, 0] - exact)) < 1e-11 * du
    closed = 10.0 + du * network_step_response(t, ltilde=ltilde, r_el=r_el, r0=r0,
                                               rk=np.array(rk), lk=np.array(lk))
    assert np.max(np.abs(closed - exact)) < 1e-12 * du
    # the jump: dU/(R_el + R_0) at t = 0+, no jump for R_0 = inf
    lin = model.linearize(gap_m=0.01, current_A=10.0)
    assert lin.D_current_A_per_V[0, 0] == pytest.approx(1.0 / (r_el + r0) if np.isfinite(r0)
                                                        else 0.0, abs=1e-15)
    assert lin.A_per_s.shape == (1 + len(rk), 1 + len(rk))
    assert np.all(np.linalg.eigvals(lin.A_per_s).real < 0)


def test_the_fit_recovers_a_known_network() -> None:
    ltilde, r_el = 0.05, 2.0
    r0, rk, lk = 300.0, np.array([25.0, 7.0]), np.array([5e-3, 2e-2])
    t = np.unique(np.concatenate((np.geomspace(1e-6, 0.15, 200), np.linspace(0, 0.15, 101)[1:])))
    y = _state_space_step(t, ltilde=ltilde, r_el=r_el, r0=r0, rk=rk, lk=lk)
    one = fit_eddy_network(t, y, ltilde=ltilde, r_el=r_el, modes=1, r_ec_guess=5.0)
    two = fit_eddy_network(t, y, ltilde=ltilde, r_el=r_el, modes=2, r_ec_guess=5.0, start=one)
    # exact data of a 2-branch network: the 2-branch fit finds it (to the solver's
    # tolerance), the 1-branch fit cannot
    assert two.rms_residual < 1e-7 < one.rms_residual
    np.testing.assert_allclose(two.resistance_ohm, rk, rtol=1e-4)
    np.testing.assert_allclose(two.inductance_H, lk, rtol=1e-4)
    assert two.r0_ohm == pytest.approx(r0, rel=1e-4)


@pytest.fixture(scope="module")
def split_maps() -> CharacteristicMaps:
    mag = mk.load_magnet("u-magnet").with_options(eddy_model="ladder_split")
    return mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


def test_maps_store_the_fitted_network(split_maps: CharacteristicMaps, tmp_path) -> None:  # type: ignore[no-untyped-def]
    ds = split_maps.dataset
    assert list(ds["eddy_modes"].values) == [1, 2, 3]
    assert ds["eddy_network_resistance_ohm"].attrs["units"] == "ohm"
    assert ds["eddy_network_inductance_H"].attrs["units"] == "H"
    rk = ds["eddy_network_resistance_ohm"].values[0]
    lk = ds["eddy_network_inductance_H"].values[0]
    for i, m in enumerate((1, 2, 3)):
        assert np.all(rk[i, :m] > 0) and np.all(lk[i, :m] > 0)
        assert np.all(np.isnan(rk[i, m:]))
    # more branches fit the diffusing step better (measured at 10 mm / 20 A, reference
    # point of these maps: rms 7.4e-3, 1.8e-3, 8.0e-4 of the step; the single R_ec 0.15)
    rms = ds["eddy_network_fit_rms"].values[0]
    assert rms[0] < 1e-2 and rms[2] < rms[1] < rms[0]
    # the network is a reduced model of the step it was fitted to: the detailed model's
    # step again, against the closed form of the stored network
    from maglevkit.reduction.maps import _eddy_network_steps

    mag = mk.load_magnet("u-magnet").with_options(eddy_model="ladder_split")
    ts, ys, lt = _eddy_network_steps(mag.network, 0.010, 20.0)
    assert lt[0] == pytest.approx(float(ds["eddy_network_reference_inductance_H"][0]),
                                  rel=1e-12)
    fit = network_step_response(ts[0], ltilde=lt[0], r_el=2.0,
                                r0=float(ds["eddy_network_r0_ohm"].values[0, 2]),
                                rk=rk[2], lk=lk[2])
    assert np.sqrt(np.mean(((fit - ys[0]) * 2.0) ** 2)) == pytest.approx(rms[2], rel=1e-6)
    # netCDF round trip keeps them
    back = mk.load_maps(split_maps.to_netcdf(tmp_path / "m.nc"))
    for name in ("eddy_network_r0_ohm", "eddy_network_resistance_ohm", "eddy_network_inductance_H"):
        assert np.array_equal(back.dataset[name].values, ds[name].values, equal_nan=True)


def test_fitted_jump_tends_to_the_exact_one_on_the_lumped_magnet() -> None:
    """An independent check of the identification: with lumped eddy elements the detailed
    model's current jumps by exactly dU/(R_el + R_ec,jump) (eddy_resistance_ohm, from the
    implicit function theorem), and the fitted network's R_0 approaches it as branches are
    added: measured 21.69, 22.27, 22.37 ohm for m = 1, 2, 3 vs 22.374 ohm (TR09 standard:
    5.715, 5.732, 5.749 vs 5.747 ohm)."""
    maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)
    jump = float(maps.dataset["eddy_resistance_ohm"].values[0])
    r0 = maps.dataset["eddy_network_r0_ohm"].values[0]
    err = np.abs(r0 / jump - 1.0)
    # bounds: the measured errors 3.1e-2, 4.8e-3, 1.2e-4 with a factor ~2 (the fit stops at
    # its tolerance; a wrong network equation or step would be off by far more)
    assert err[0] < 0.06 and err[1] < 0.01 and err[2] < 3e-4
    assert err[2] < err[1] < err[0]


def test_eddy_reference_moves_the_identification_only() -> None:
    mag = mk.load_magnet("u-magnet")
    default = mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False)
    # the default point of these maps is 10 mm / 20 A: naming it changes nothing
    same = mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False,
                         eddy_reference=(0.010, 20.0))
    for name in default.dataset.data_vars:
        assert np.array_equal(default.dataset[name].values, same.dataset[name].values,
                              equal_nan=True), name
    moved = mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False,
                          eddy_reference=(0.008, 35.0))
    for name in ("force_N", "inductance_H", "dL_ds_H_per_m", "eddy_resistance_ohm"):
        assert np.array_equal(default.dataset[name].values, moved.dataset[name].values), name
    for name in ("eddy_resistance_fit_ohm", "eddy_network_r0_ohm",
                 "eddy_network_reference_inductance_H"):
        assert not np.array_equal(default.dataset[name].values, moved.dataset[name].values)
    assert "s = 0.008 m, I = 35.0 A" in moved.dataset["eddy_network_r0_ohm"].attrs["description"]
    assert "s = 0.008 m, I = 35.0 A" in moved.dataset["eddy_resistance_fit_ohm"].attrs[
        "description"]
    for bad, msg in (((0.003, 20.0), "outside the maps' grid"), ((0.01, 50.0), "outside"),
                     (0.01, "give \\(gap_m, current_A\\)"), (([0.01], 20.0), "one gap"),
                     (("a", 20.0), "string")):
        with pytest.raises(mk.InputError, match=msg):
            mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False,
                          eddy_reference=bad)


def _old(maps: CharacteristicMaps) -> CharacteristicMaps:
    """The maps as files of the previous version store them (no eddy network)."""
    ds = maps.dataset.drop_vars([v for v in maps.dataset.data_vars
                                 if str(v).startswith("eddy_network_")])
    return CharacteristicMaps(ds.drop_vars(["eddy_modes", "eddy_branch"]))


def test_default_is_unchanged(split_maps: CharacteristicMaps) -> None:
    """eddy_modes=0 (the default) and maps without the new variables give bit-identical
    results: the default path builds eq. 8 exactly as before."""
    models = [mk.CurrentModel(split_maps), mk.CurrentModel(split_maps, eddy_modes=0),
              mk.CurrentModel(_old(split_maps))]
    runs = [mk.simulate(m, (0.0, 0.1), dt_s=1e-3,
                        gaps_m=lambda t: 0.010 + 0.001 * np.sin(2 * np.pi * 5 * t),
                        voltages_V=lambda t: 40.0 if t < 0.02 else 48.0, initial_currents_A=20.0)
            for m in models]
    for r in runs[1:]:
        assert np.array_equal(r.currents_A, runs[0].currents_A)
        assert np.array_equal(r.force_N, runs[0].force_N)
        assert r.eddy_currents_A is None and r.final_state.eddy_currents_A is None
    st = models[0].initial_state(gaps_m=0.01, currents_A=20.0)
    assert st.eddy_currents_A is None
    assert models[0].linearize(gap_m=0.01, current_A=20.0).A_per_s.shape == (1, 1)


def test_eddy_modes_step_simulate_and_state(split_maps: CharacteristicMaps) -> None:
    model = mk.CurrentModel(split_maps, eddy_modes=2)
    st = model.initial_state(gaps_m=0.01, currents_A=20.0)
    assert st.eddy_currents_A is not None and st.eddy_currents_A.shape == (1, 2)
    assert np.all(st.eddy_currents_A == 0.0)
    res = mk.simulate(model, (0.0, 0.05), dt_s=1e-3, gaps_m=0.01,
                      voltages_V=lambda t: 40.0 if t < 0.01 else 48.0, initial_currents_A=20.0)
    assert res.eddy_currents_A is not None and res.eddy_currents_A.shape == (51, 1, 2)
    # the branches carry part of the step and decay
    assert np.max(res.eddy_currents_A) > 0.01
    # step() continues a simulation from its final state exactly as simulate() does
    more = mk.simulate(model, (0.05, 0.06), dt_s=1e-3, gaps_m=0.01, voltages_V=48.0,
                       initial_state=res.final_state)
    s = res.final_state
    for _ in range(10):
        s, out = model.step(s, 1e-3, 48.0)
    np.testing.assert_allclose(out.currents_A, more.currents_A[-1], rtol=1e-12)
    np.testing.assert_allclose(s.eddy_currents_A, more.final_state.eddy_currents_A,
                               rtol=1e-9, atol=1e-12)
    # outputs(state, U) agree with the step's outputs
    np.testing.assert_allclose(model.outputs(s, 48.0).currents_A, out.currents_A, rtol=1e-12)
    # linearisation: state (I_L, I_1, I_2); A against central differences of the ODE
    lin = model.linearize(gap_m=0.01, current_A=20.0)
    assert lin.A_per_s.shape == (3, 3) and lin.C_current.shape == (1, 3)
    x0 = np.array([20.0, 0.0, 0.0])
    u0 = 40.0

    def f(x: np.ndarray) -> np.ndarray:
        di, de = model.ode(x[:1], u0, 0.01, 0.0, x[1:])
        return np.concatenate([np.asarray(di).ravel(), np.asarray(de).ravel()])

    num = np.column_stack([(f(x0 + h) - f(x0 - h)) / 2e-4 for h in np.eye(3) * 1e-4])
    np.testing.assert_allclose(lin.A_per_s, num, rtol=1e-6, atol=1e-6 * np.abs(num).max())
    assert np.all(np.linalg.eigvals(lin.A_per_s).real < 0)


def test_rk4_sub_step_limit_is_accurate(split_maps: CharacteristicMaps) -> None:
    """RK4 at the sub-step limited by the fastest branch vs adaptive CVODES at rtol 1e-10:
    measured 2.6e-7 A on the 4 A step (m = 3, these maps: sub-step 61 us; 6.5e-8 of the
    step); bound 1e-6 of the step."""
    kw = dict(gaps_m=0.01, voltages_V=lambda t: 40.0 if t < 0.02 else 48.0, initial_currents_A=20.0)
    rk4 = mk.simulate(mk.CurrentModel(split_maps, eddy_modes=3), (0.0, 0.1), dt_s=1e-3, **kw)
    ref = mk.simulate(mk.CurrentModel(split_maps, eddy_modes=3, method="cvodes", rtol=1e-10,
                                      atol=1e-12), (0.0, 0.1), dt_s=1e-3, **kw)
    assert np.max(np.abs(rk4.currents_A - ref.currents_A)) < 1e-6 * 4.0


def test_bad_input(split_maps: CharacteristicMaps) -> None:
    for bad in (-1, 4, 1.5, True, "2", None):
        with pytest.raises(mk.InputError, match=r"eddy_modes = .*use 0 .* \[1, 2, 3\]"):
            mk.CurrentModel(split_maps, eddy_modes=bad)  # type: ignore[arg-type]
    with pytest.raises(mk.InputError, match="leave eddy_resistance out"):
        mk.CurrentModel(split_maps, eddy_modes=1, eddy_resistance="jump")
    with pytest.raises(mk.InputError, match="rebuild them with this version"):
        mk.CurrentModel(_old(split_maps), eddy_modes=1)
    model = mk.CurrentModel(split_maps, eddy_modes=1)
    plain = mk.CurrentModel(split_maps)
    with pytest.raises(mk.InputError, match="no eddy_currents_A"):
        model.step(plain.initial_state(gaps_m=0.01, currents_A=20.0), 1e-3, 40.0)
    with pytest.raises(mk.InputError, match=r"expected shape \(1, 1\)"):
        model.step(mk.reduced.current.CurrentModelState(0.0, np.array([20.0]),
                                                       np.array([0.01, 0.01]), np.zeros((1, 2))),
                   1e-3, 40.0)
    with pytest.raises(mk.InputError, match="eddy_modes=0"):
        plain.outputs(model.initial_state(gaps_m=0.01, currents_A=20.0))
    # the bank carries the branch currents (tests/test_bank_eddy_modes.py), not drops them
    assert mk.MagnetBank({"a": model}, compiled="never").n_eddy_states == 1
    # maps holding only some networks name the ones they hold
    one = _linear_maps(ltilde=0.1, r_el=2.0, r0=40.0, rk=[6.0], lk=[2e-3])
    with pytest.raises(mk.InputError, match=r"eddy_modes = 2: these maps hold eddy networks "
                                            r"with \[1\] branches"):
        mk.CurrentModel(one, eddy_modes=2)
    with pytest.raises(mk.InputError, match=r"use 'fit' or 'jump' \(or None"):
        mk.CurrentModel(split_maps, eddy_resistance="bogus")


def test_maps_without_eddy_currents_refuse_eddy_modes() -> None:
    mag = mk.load_magnet("u-magnet", eddy_currents=False)
    maps = mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False)
    assert np.all(np.isinf(maps.dataset["eddy_network_r0_ohm"].values))
    with pytest.raises(mk.InputError, match="no eddy network to use"):
        mk.CurrentModel(maps, eddy_modes=2)


# Measured AC-normalised errors (current, force) of CurrentModel(maps, eddy_modes=m) against
# the detailed U-magnet (maps 4-20 mm x 0-80 A, 17 x 33; scenarios at 10 mm / 20 A),
# 2026-12-02, docs/reduction.md "More eddy modes".  Bound: measured x 1.15 (as
# tests/test_compare.py: deterministic runs, the margin absorbs small numerical changes).
# Key: (eddy model of the detailed magnet, eddy_reference of build_maps, eddy_modes).
MEASURED = {
    # ladder_split, identified at the maps' reference point 12 mm / 40 A, m = 2.  Single
    # R_ec on the same runs: 10.76/4.87, 12.73/7.46, 0.70/0.33, 7.69/3.07, 22.00/4.74,
    # 5.88/1.35, 1.90/1.43 %
    ("ladder_split", None, 2): {
        "voltage step up": (0.05279, 0.06575),
        "voltage step down": (0.04374, 0.03257),
        "gap sine 0.5 Hz": (0.01134, 0.00591),
        "gap sine 5 Hz": (0.04882, 0.01891),
        "gap sine 50 Hz": (0.07519, 0.03905),
        "gap ramp": (0.03488, 0.01280),
        "closed loop": (0.01670, 0.01214),
    },
    # ladder_split, identified at the operating point, m = 2 (single R_ec fitted there:
    # 13.85/6.49, 18.80/14.65, 1.03/0.46, 10.32/4.42, 26.26/5.20, 9.44/2.67, 3.91/1.51 %)
    ("ladder_split", (0.010, 20.0), 2): {
        "voltage step up": (0.02547, 0.02325),
        "voltage step down": (0.06436, 0.07008),
        "gap sine 0.5 Hz": (0.00345, 0.00172),
        "gap sine 5 Hz": (0.02665, 0.01233),
        "gap sine 50 Hz": (0.07913, 0.03880),
        "gap ramp": (0.03446, 0.00908),
        "closed loop": (0.01789, 0.01222),
    },
    # lumped eddy elements, identified at the operating point, m = 1 (single R_ec fitted
    # there: 2.83/0.62, 3.29/0.26, 0.05/0.04, 0.40/0.95, 3.67/14.19, 0.40/0.30, 1.05/0.61 %)
    ("lumped", (0.010, 20.0), 1): {
        "voltage step up": (0.00231, 0.00196),
        "voltage step down": (0.00470, 0.00507),
        "gap sine 0.5 Hz": (0.00069, 0.00079),
        "gap sine 5 Hz": (0.00212, 0.00973),
        "gap sine 50 Hz": (0.02022, 0.14206),
        "gap ramp": (0.00297, 0.00395),
        "closed loop": (0.00849, 0.00476),
    },
}


@pytest.mark.slow
@pytest.mark.parametrize("key", list(MEASURED), ids=lambda k: f"{k[0]}-{k[1]}-m{k[2]}")
def test_eddy_modes_follow_the_detailed_model(key: tuple) -> None:
    eddy_model, reference, modes = key
    mag = mk.load_magnet("u-magnet").with_options(eddy_model=eddy_model)
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False,
                         eddy_reference=reference)
    results = compare_models(mk.FluxModel(mag), mk.CurrentModel(maps, eddy_modes=modes),
                             standard_scenarios(mag, gap_m=0.010, current_A=20.0),
                             gap_m=0.010, current_A=20.0, repeat=0)
    measured = MEASURED[key]
    assert {r.scenario.name for r in results} == set(measured)
    for r in results:
        cur, force = measured[r.scenario.name]
        assert np.nanmax(r.current_error_ac) < 1.15 * cur, (r.scenario.name, r.current_error_ac)
        assert np.nanmax(r.force_error_ac) < 1.15 * force, (r.scenario.name, r.force_error_ac)
        assert np.all(r.current_error < 0.02) and np.all(r.force_error < 0.02)


def test_the_compiled_network_loop_carries_the_branch_currents_between_calls(
        split_maps: CharacteristicMaps) -> None:
    """tidy26: the table path's compiled loop with eddy-network branches (cmnet; the bank's
    ``run_steps`` carries eq. 8's I_L only and refuses such members, see
    test_bank_eddy_modes) pads short runs with steps of 0 s; the branch currents reach the
    final state and a run continued from it equals one run over the whole span."""
    model = mk.CurrentModel(split_maps, eddy_modes=2)

    def gap(t: float) -> float:
        return 0.01 + 0.001 * np.sin(2 * np.pi * 20 * t)

    def volt(t: float) -> float:
        return 40.0 if t < 0.01 else 48.0

    whole = mk.simulate(model, (0.0, 0.05), dt_s=1e-3, gaps_m=gap, voltages_V=volt,
                        initial_currents_A=20.0)
    assert model._use_tables             # the compiled loop ran, not the B-splines
    first = mk.simulate(model, (0.0, 0.023), dt_s=1e-3, gaps_m=gap, voltages_V=volt,
                        initial_currents_A=20.0)
    rest = mk.simulate(model, (0.023, 0.05), dt_s=1e-3, gaps_m=gap, voltages_V=volt,
                       initial_state=first.final_state)
    assert first.eddy_currents_A is not None and rest.eddy_currents_A is not None
    # the same steps in the same compiled arithmetic: equal to rounding (measured 3.6e-15
    # A on ~20 A, 1.7e-16 A on branch currents of up to 0.59 A)
    np.testing.assert_allclose(np.concatenate([first.currents_A, rest.currents_A[1:]]),
                               whole.currents_A, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.concatenate([first.eddy_currents_A,
                                               rest.eddy_currents_A[1:]]),
                               whole.eddy_currents_A, rtol=0, atol=1e-12)
    # what the assertion guards: restarting with the branches at 0 moves the current by
    # about 0.5 A (measured 0.53 A)
    st = first.final_state
    dropped = mk.simulate(model, (0.023, 0.05), dt_s=1e-3, gaps_m=gap, voltages_V=volt,
                          initial_state=dataclasses.replace(
                              st, eddy_currents_A=np.zeros_like(st.eddy_currents_A)))
    assert np.max(np.abs(dropped.currents_A - rest.currents_A)) > 0.1
