"""The many-magnet bank: equality with single-model runs, range checks, compilation, tables."""

from __future__ import annotations

import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import maglevkit as mk
from maglevkit.compare import standard_scenarios
from maglevkit.errors import CompilationWarning, InputError, OutOfRangeError, SolverError
from maglevkit.models import compiled as compiled_mod
from maglevkit.reduced.bank import MagnetBank, StepFlag
from maglevkit.reduced.tables import cell_table

from .conftest import u_params

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)
# Equality with separate runs: the bank evaluates the same eq. 8 expression with the same
# RK4 arithmetic; the only difference is the map evaluation (per-cell polynomial instead of
# CasADi's B-spline, equal to ~4e-14 relative).  Measured largest difference over these
# tests: 3e-14 relative; bound 1e-12 (the criterion).
REL = 1e-12


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


@pytest.fixture(scope="module")
def u_variant_maps() -> mk.CharacteristicMaps:
    """A U-magnet with 20 % more turns: different maps of the same topology."""
    p = u_params()
    p["magnet"]["turns"] = int(round(p["magnet"]["turns"] * 1.2))
    return mk.build_maps(mk.build_magnet(p), gaps_m=GAPS, currents_A=CURRENTS, progress=False)


@pytest.fixture(scope="module")
def guidance_maps() -> mk.CharacteristicMaps:
    # the lumped eddy elements by name (the file's is the ladder since guideswitch): a
    # cheap two-circuit network with eq. 8's jump resistance
    return mk.build_maps(mk.load_magnet("tr-guidance", eddy_model="lumped"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


@pytest.fixture(scope="module")
def tr09_maps() -> mk.CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("tr09-standard"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _open_scenarios(magnet: mk.Magnet, gap: float, current: float) -> list:
    out = [sc for sc in standard_scenarios(magnet, gap_m=gap, current_A=current)
           if sc.kind == "open"]
    assert len(out) >= 3
    return out


def _check_members_vs_single(bank: MagnetBank, members: dict, scenario, dt: float,
                             r_scenario: float) -> None:
    """Each member of ``bank`` equals its own CurrentModel run.  The scenario's voltages
    (of a magnet with resistance ``r_scenario``) are scaled to every circuit's resistance
    and by a per-member factor, so that every circuit gets its own inputs."""
    from maglevkit.models.inputs import sample_input

    times = np.arange(0.0, min(scenario.duration_s, 0.2) + dt / 2, dt)
    u_ref = sample_input(scenario.voltages_V, times, ("coil",), "voltages", "V")[:, 0]
    gap = sample_input(scenario.gaps_m, times, ("left", "right"), "gaps", "m").mean(axis=1)
    factor = np.concatenate([np.full(len(m.circuits), 1.0 + 0.03 * k)
                             for k, m in enumerate(members.values())])
    volt = u_ref[:, None] / r_scenario * bank.resistance_ohm[None, :] * factor[None, :]
    res = bank.simulate(times, gaps_m=np.repeat(gap[:, None], bank.n_gaps, axis=1), voltages_V=volt)
    sl = bank.circuit_slices
    for name, maps in members.items():
        single = mk.CurrentModel(maps)
        ref = single.simulate(times, gaps_m=np.repeat(gap[:, None], len(single.gap_names), axis=1),
                              voltages_V=volt[:, sl[name]])
        assert _rel(res.currents_A[:, sl[name]], ref.currents_A) <= REL, name
        assert _rel(res.inductor_currents_A[:, sl[name]], ref.inductor_currents_A) <= REL, name
        assert _rel(res.circuit_force_N[:, sl[name]], ref.circuit_force_N) <= REL, name
        assert np.ptp(ref.currents_A) > 0.05         # the scenario moves the current


def test_bank_of_identical_magnets_equals_single_runs(u_magnet, u_maps) -> None:
    members = {f"m{k}": u_maps for k in range(5)}
    bank = MagnetBank(members, compiled="never")
    assert bank.n_distinct_maps == 1            # shared, stored once
    for sc in _open_scenarios(u_magnet, 0.010, 20.0):
        _check_members_vs_single(bank, members, sc, 1e-3, u_magnet.network.resistances[0])


def test_mixed_bank_equals_single_runs(u_magnet, u_maps, u_variant_maps, guidance_maps,
                                       tr09_maps) -> None:
    members = {"u": u_maps, "u_big": u_variant_maps, "guide": guidance_maps,
               "tr09": tr09_maps, "u2": u_maps}
    bank = MagnetBank(members)                 # compiled (falls back with a warning)
    # u and u2 share; tr09 and guidance have 2 circuits each with their own maps
    assert bank.n_distinct_maps == 1 + 1 + 2 + 2
    assert bank.n_circuits == 1 + 1 + 2 + 2 + 1
    for sc in _open_scenarios(u_magnet, 0.010, 20.0):
        _check_members_vs_single(bank, members, sc, 1e-3, u_magnet.network.resistances[0])


def test_compiled_equals_interpreted(u_maps, guidance_maps) -> None:
    members = {"a": u_maps, "b": guidance_maps}
    fast = MagnetBank(members, compiled="auto")
    slow = MagnetBank(members, compiled="never")
    rng = np.random.default_rng(1)
    sf = fast.initial_state(gaps_m=0.010, currents_A=rng.uniform(10, 40, 3))
    ss = slow.initial_state(gaps_m=0.010, currents_A=sf.inductor_currents_A)
    for _ in range(50):
        u = rng.uniform(5, 60, 3)
        rate = rng.uniform(-0.02, 0.02, 3)
        sf, of = fast.step(sf, 1e-3, u, gap_rates_m_per_s=rate)
        ss, os_ = slow.step(ss, 1e-3, u, gap_rates_m_per_s=rate)
    # same IEEE arithmetic (no -ffast-math); bound for FMA contraction on other CPUs
    assert _rel(of.inductor_currents_A, os_.inductor_currents_A) <= REL
    assert _rel(of.circuit_force_N, os_.circuit_force_N) <= REL


def test_detailed_members_equal_their_own_steps(u_magnet, u_maps) -> None:
    fm1 = mk.FluxModel(u_magnet, eddy_currents=False)
    fm2 = mk.FluxModel(u_magnet, eddy_currents=False)
    bank = MagnetBank({"d1": fm1, "r": u_maps, "d2": fm2}, gap_inputs="pole")
    assert bank.circuit_names == ("d1/coil", "r/coil", "d2/coil")
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    s1 = fm1.initial_state(gaps_m=0.010, currents_A=20.0)
    s2 = fm2.initial_state(gaps_m=0.010, currents_A=20.0)
    single = mk.CurrentModel(u_maps)
    sr = single.initial_state(gaps_m=0.010, currents_A=20.0)
    rate = np.array([0.01, 0.01, -0.005, -0.005, 0.0, 0.0])
    for k in range(20):
        u = np.array([25.0, 30.0, 35.0]) + k
        state, out = bank.step(state, 1e-3, u, gap_rates_m_per_s=rate, pole_forces=True)
        s1, o1 = fm1.step(s1, 1e-3, u[0], gap_rates_m_per_s=rate[:2])
        sr, orr = single.step(sr, 1e-3, u[1], gap_rates_m_per_s=rate[2:4])
        s2, o2 = fm2.step(s2, 1e-3, u[2], gap_rates_m_per_s=rate[4:])
    assert _rel(out.currents_A, np.array([o1.currents_A[0], orr.currents_A[0],
                                          o2.currents_A[0]])) <= REL
    assert out.pole_force_N is not None
    assert _rel(out.pole_force_N[:2], o1.pole_force_N) <= REL
    assert _rel(out.pole_force_N[4:], o2.pole_force_N) <= REL
    assert out.circuit_force_N[0] == pytest.approx(o1.force_N, rel=REL)
    assert out.circuit_force_N[1] == pytest.approx(orr.force_N, rel=REL)
    assert np.isnan(out.inductor_currents_A[[0, 2]]).all()   # no I_L in a detailed member
    # per-member totals and pole shares add up
    assert out.member_force_N == pytest.approx(out.circuit_force_N, rel=1e-15)
    assert out.pole_force_N[2:4].sum() == pytest.approx(out.circuit_force_N[1], rel=1e-14)


def test_gap_inputs_pole_mode_averages_like_the_single_model(tr09_maps) -> None:
    bank = MagnetBank({"a": tr09_maps}, gap_inputs="pole", compiled="never")
    single = mk.CurrentModel(tr09_maps)
    assert bank.n_gaps == 12
    g = np.linspace(0.009, 0.011, 12)
    sb = bank.initial_state(gaps_m=g, currents_A=30.0)
    ss = single.initial_state(gaps_m=g, currents_A=30.0)
    sb, ob = bank.step(sb, 1e-3, 40.0, gap_rates_m_per_s=np.full(12, 0.01), pole_forces=True)
    ss, os_ = single.step(ss, 1e-3, 40.0, gap_rates_m_per_s=0.01)
    assert _rel(ob.circuit_force_N, os_.circuit_force_N) <= REL
    assert ob.pole_force_N is not None
    assert _rel(ob.pole_force_N, os_.pole_force_N) <= REL


def test_range_checked_before_integrating_names_member_and_range(u_maps) -> None:
    bank = MagnetBank({"front": u_maps, "rear": u_maps})
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    # far outside: 50 mm on 6-16 mm maps, and a gap rate that leaves the maps in the step
    with pytest.raises(OutOfRangeError, match=r"member 'rear', circuit 'coil'.*gap 0\.05 m.*"
                                              r"maps cover gaps 0\.006\.\.0\.016 m"):
        bank.step(state, 1e-3, 20.0, gaps_m=np.array([0.010, 0.05]))
    with pytest.raises(OutOfRangeError, match=r"member 'front'.*over the step"):
        bank.step(state, 1e-3, 20.0, gap_rates_m_per_s=np.array([1e3, 0.0]))
    # a current that leaves the maps inside the step (huge voltage)
    with pytest.raises(OutOfRangeError, match=r"RK4 sub-step.*currents 0\.\.60 A"):
        bank.step(state, 1e-3, np.array([20.0, 1e6]))
    with pytest.raises(OutOfRangeError, match=r"member 'front'.*current 70 A"):
        bank.initial_state(gaps_m=0.010, currents_A=np.array([70.0, 20.0]))


def test_extrapolation_warns_within_three_cells(u_maps) -> None:
    bank = MagnetBank({"m": u_maps}, extrapolate=True, compiled="never")
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.warns(UserWarning, match="extrapolating"):
        bank.step(state, 1e-3, 20.0, gaps_m=0.017)
    with pytest.raises(OutOfRangeError, match="three|3 grid cells"):
        bank.step(state, 1e-3, 20.0, gaps_m=0.030)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_inputs_name_the_magnet(u_maps, bad: float) -> None:
    bank = MagnetBank({"left": u_maps, "right": u_maps})
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match=r"voltages must be finite.*'right/coil'"):
        bank.step(state, 1e-3, np.array([20.0, bad]))
    with pytest.raises(InputError, match=r"gaps must be finite.*'left/coil'"):
        bank.step(state, 1e-3, 20.0, gaps_m=np.array([bad, 0.01]))
    with pytest.raises(InputError, match=r"gap_rates must be finite.*'left/coil'"):
        bank.step(state, 1e-3, 20.0, gap_rates_m_per_s=np.array([bad, 0.0]))
    with pytest.raises(InputError, match=r"gaps must be finite.*'right/coil'"):
        bank.initial_state(gaps_m=np.array([0.01, bad]), currents_A=20.0)


def test_bad_construction_and_inputs(u_maps) -> None:
    with pytest.raises(InputError, match="CharacteristicMaps, a CurrentModel or a FluxModel"):
        MagnetBank({"m": "maps.nc"})
    with pytest.raises(InputError, match="unique"):
        MagnetBank([("m", u_maps), ("m", u_maps)])
    with pytest.raises(InputError, match="without '/'"):
        MagnetBank({"a/b": u_maps})
    with pytest.raises(InputError, match="at least one member"):
        MagnetBank({})
    with pytest.raises(InputError, match="interpolation = 'cubic'.*bicubic"):
        MagnetBank({"m": u_maps}, interpolation="cubic")
    with pytest.raises(InputError, match="gap_inputs"):
        MagnetBank({"m": u_maps}, gap_inputs="poles")
    with pytest.raises(InputError, match="compiled = 'yes'"):
        MagnetBank({"m": u_maps}, compiled="yes").step(
            MagnetBank({"m": u_maps}).initial_state(gaps_m=0.01, currents_A=10.0), 1e-3, 10.0)
    bank = MagnetBank({"m": u_maps, "n": u_maps})
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match=r"voltages: expected 2 values"):
        bank.step(state, 1e-3, [1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="bool"):
        bank.step(state, 1e-3, True)
    with pytest.raises(InputError, match="dt"):
        bank.step(state, 0.0, 20.0)
    with pytest.raises(InputError, match="BankState"):
        bank.step(object(), 1e-3, 20.0)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"gaps must stay > 0 m"):
        MagnetBank({"m": u_maps}, gap_inputs="pole").step(
            MagnetBank({"m": u_maps}, gap_inputs="pole").initial_state(gaps_m=0.01, currents_A=10.0),
            1e-3, 10.0, gap_rates_m_per_s=-20.0)


def test_solver_error_on_non_finite_state_carries_time_and_state(u_maps, monkeypatch) -> None:
    bank = MagnetBank({"m": u_maps}, compiled="never")
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0, time_s=0.5)
    real = bank._kernel

    class Poisoned:
        """The real compiled step, with a NaN current put into its result and the
        kernel's reason code for it (the diagnosis reads the codes)."""

        def __init__(self, call) -> None:  # type: ignore[no-untyped-def]
            self.call = call
            self.res = call.res

        def __call__(self, *args):  # type: ignore[no-untyped-def]
            x, c, f, mf, _, s_next = self.call(*args)
            x[:] = np.nan
            self.res[8][:] = StepFlag.RESULT_NOT_FINITE
            return x, c, f, mf, 1.0, s_next

    def poisoned(dt: float) -> Poisoned:
        return Poisoned(real(dt))

    monkeypatch.setattr(bank, "_kernel", poisoned)
    with pytest.raises(SolverError, match=r"non-finite.*'m/coil'.*t = 0\.5 s.*I_L_A=20"):
        bank.step(state, 1e-3, 20.0)


def test_ode_function_matches_current_model_and_differentiates(u_maps, tr09_maps) -> None:
    bank = MagnetBank({"u": u_maps, "t": tr09_maps}, compiled="never")
    f = bank.ode_function
    rng = np.random.default_rng(3)
    for _ in range(5):
        i = rng.uniform(1, 55, 3)
        u = rng.uniform(5, 80, 3)
        s = rng.uniform(0.007, 0.015, 3)
        sd = rng.uniform(-0.05, 0.05, 3)
        got = np.asarray(f(i, u, s, sd)).ravel()
        ref = np.concatenate([np.asarray(mk.CurrentModel(m).ode(i[sl], u[sl], s[sl], sd[sl])).ravel()
                              for m, sl in ((u_maps, slice(0, 1)), (tr09_maps, slice(1, 3)))])
        assert _rel(got, ref) <= REL
    # AD through the table lookup against central differences of the same function
    x = ca.MX.sym("x", 3)
    jac = ca.Function("j", [x], [ca.jacobian(f(x, u, s, sd), x)])
    jad = np.asarray(jac(i))
    h = 1e-4
    jfd = np.column_stack([(np.asarray(f(i + h * e, u, s, sd)) - np.asarray(f(i - h * e, u, s, sd)))
                           .ravel() / (2 * h) for e in np.eye(3)])
    # central differences of a C2 bicubic: truncation ~h^2 f''' ~ 1e-7 relative here
    assert np.allclose(jad, jfd, rtol=1e-5, atol=1e-9 * np.abs(jad).max())
    assert np.count_nonzero(jad - np.diag(np.diag(jad))) == 0   # circuits are independent
    outs = bank.output_function(i, u, s)
    ref_f = np.concatenate([np.asarray(mk.CurrentModel(m).outputs_fun(i[sl], u[sl], s[sl])[1])
                            .ravel() for m, sl in ((u_maps, slice(0, 1)),
                                                   (tr09_maps, slice(1, 3)))])
    assert _rel(np.asarray(outs[1]).ravel(), ref_f) <= REL


def test_compiled_kernel_is_cached_on_disk(u_maps, tmp_path: Path) -> None:
    if compiled_mod.find_compiler() is None:
        pytest.skip("no C compiler on this machine")
    b1 = MagnetBank({"m": u_maps}, compiled="always", cache_dir=tmp_path)
    st = b1.initial_state(gaps_m=0.01, currents_A=20.0)
    _, o1 = b1.step(st, 1e-3, 25.0)
    libs = sorted(tmp_path.glob("*.so"))
    assert len(libs) == 1 and b1.compiled is True
    mtime = libs[0].stat().st_mtime_ns
    b2 = MagnetBank({"m": u_maps}, compiled="always", cache_dir=tmp_path)
    _, o2 = b2.step(st, 1e-3, 25.0)
    assert sorted(tmp_path.glob("*.so")) == libs and libs[0].stat().st_mtime_ns == mtime
    assert np.array_equal(o1.currents_A, o2.currents_A)
    # a bank of other maps is another library
    MagnetBank({"m": u_maps, "n": u_maps}, compiled="always", cache_dir=tmp_path).step(
        MagnetBank({"m": u_maps, "n": u_maps}).initial_state(gaps_m=0.01, currents_A=20.0), 1e-3, 25.0)
    assert len(list(tmp_path.glob("*.so"))) == 2


def test_without_compiler_falls_back_with_a_warning(u_maps, monkeypatch, tmp_path) -> None:
    monkeypatch.setattr(compiled_mod, "find_compiler", lambda: None)
    bank = MagnetBank({"m": u_maps}, cache_dir=tmp_path)
    st = bank.initial_state(gaps_m=0.01, currents_A=20.0)
    with pytest.warns(CompilationWarning, match="virtual machine"):
        _, out = bank.step(st, 1e-3, 25.0)
    assert bank.compiled is False
    ref = MagnetBank({"m": u_maps}, compiled="never").step(st, 1e-3, 25.0)[1]
    assert np.array_equal(out.currents_A, ref.currents_A)
    strict = MagnetBank({"m": u_maps}, compiled="always", cache_dir=tmp_path)
    with pytest.raises(SolverError, match="compiling .* failed.*no C compiler"):
        strict.step(st, 1e-3, 25.0)


# ---------------------------------------------------------------- per-cell tables
def test_bicubic_table_equals_casadi_bspline(tr09_maps) -> None:
    rng = np.random.default_rng(5)
    s = rng.uniform(0.006, 0.016, 500)
    i = rng.uniform(0.0, 60.0, 500)
    v = np.stack([tr09_maps.variable(n, "front") for n in ("inductance_H", "dL_ds_H_per_m",
                                                            "force_N")])
    tab = cell_table(GAPS, CURRENTS, v, method="bicubic")
    data = np.stack([x.ravel(order="F") for x in v], axis=1).ravel()
    ref = np.asarray(ca.interpolant("r", "bspline", [GAPS, CURRENTS], data)(np.vstack([s, i]))).T
    # measured 3e-14 relative (two exact representations of the same spline)
    assert _rel(tab.evaluate(s, i), ref) <= 1e-12


@pytest.mark.parametrize("method", ["bicubic", "monotone", "bilinear"])
def test_tables_reproduce_grid_values(tr09_maps, method: str) -> None:
    v = tr09_maps.variable("force_N", "rear")[None]
    tab = cell_table(GAPS, CURRENTS, v, method=method)
    G, II = np.meshgrid(GAPS, CURRENTS, indexing="ij")
    assert _rel(tab.evaluate(G, II)[..., 0], v[0]) <= 1e-13


def test_monotone_table_does_not_overshoot_along_grid_lines() -> None:
    # a saturating curve with a sharp knee: the not-a-knot spline overshoots, PCHIP not
    s = np.linspace(0.0, 1.0, 6)
    i = np.linspace(0.0, 10.0, 11)
    f = np.minimum(i, 3.0)[None, :] * (1 + s[:, None])
    fine = np.linspace(0.0, 10.0, 1001)
    for k, sv in enumerate(s):
        mono = cell_table(s, i, f[None], method="monotone").evaluate(np.full_like(fine, sv), fine)
        cub = cell_table(s, i, f[None], method="bicubic").evaluate(np.full_like(fine, sv), fine)
        top = f[k].max()
        assert mono.max() <= top * (1 + 1e-12)
        assert np.all(np.diff(mono[..., 0]) >= -1e-12 * top)
        assert cub.max() > top * (1 + 1e-3)          # the contrast the option exists for


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=16, max_size=16), st.lists(st.floats(-2, 2),
                                                                       min_size=4, max_size=4))
def test_tables_reproduce_their_polynomial_class(cubic: list[float], bilin: list[float]) -> None:
    """Not-a-knot bicubic splines reproduce bicubic polynomials, bilinear ones bilinear
    functions, everywhere (not only at the nodes)."""
    s = np.linspace(0.004, 0.02, 7)
    i = np.linspace(-5.0, 80.0, 9)
    c = np.array(cubic).reshape(4, 4)
    b = np.array(bilin).reshape(2, 2)

    def poly(cc: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        xn, yn = (x - 0.012) / 0.008, (y - 37.5) / 42.5
        return sum(cc[p, q] * xn**p * yn**q for p in range(cc.shape[0]) for q in range(cc.shape[1]))

    G, II = np.meshgrid(s, i, indexing="ij")
    rng = np.random.default_rng(0)
    xs, ys = rng.uniform(0.004, 0.02, 200), rng.uniform(-5.0, 80.0, 200)
    scale = 1.0 + np.abs(c).sum()
    got = cell_table(s, i, poly(c, G, II)[None], method="bicubic").evaluate(xs, ys)[..., 0]
    assert np.max(np.abs(got - poly(c, xs, ys))) <= 1e-11 * scale
    scale_b = 1.0 + np.abs(b).sum()
    got_b = cell_table(s, i, poly(b, G, II)[None], method="bilinear").evaluate(xs, ys)[..., 0]
    assert np.max(np.abs(got_b - poly(b, xs, ys))) <= 1e-12 * scale_b


def test_table_input_errors() -> None:
    with pytest.raises(InputError, match="regular"):
        cell_table(np.array([0.0, 1.0, 3.0, 4.0]), np.arange(5.0), np.zeros((1, 4, 5)))
    with pytest.raises(InputError, match="at least 4 points"):
        cell_table(np.arange(3.0), np.arange(5.0), np.zeros((1, 3, 5)))
    with pytest.raises(InputError, match="non-finite"):
        cell_table(np.arange(4.0), np.arange(5.0), np.full((1, 4, 5), np.nan))
    with pytest.raises(InputError, match="interpolation = 'spline'"):
        cell_table(np.arange(4.0), np.arange(5.0), np.zeros((1, 4, 5)), method="spline")


def test_interpolation_options_change_results_by_little(u_maps) -> None:
    """All three interpolations give close trajectories on the U-magnet's maps (the
    accuracy of each against finer maps is measured in BENCHMARKS.md)."""
    ref = None
    for method in ("bicubic", "monotone", "bilinear"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", CompilationWarning)
            bank = MagnetBank({"m": u_maps}, interpolation=method)
            res = bank.simulate((0.0, 0.1), dt_s=1e-3, gaps_m=0.010,
                                voltages_V=lambda t: 30.0 if t > 0.01 else 20.0)
        if ref is None:
            ref = res
        else:
            # bilinear on a 2 mm x 10 A grid: ~1-3 % map error (BENCHMARKS.md)
            assert _rel(res.currents_A, ref.currents_A) <= 0.05
            assert _rel(res.currents_A, ref.currents_A) > 0.0


def test_circuit_expressions_with_the_table_as_input_equal_ode_function(u_maps,
                                                                       tr09_maps) -> None:
    bank = MagnetBank({"u": u_maps, "t": tr09_maps}, compiled="never")
    tab = ca.MX.sym("table", bank.table.size)
    x, u, s, sd = (ca.MX.sym(n, 3) for n in ("x", "u", "s", "sd"))
    rhs = ca.vertcat(*[bank.circuit_expressions(k, x[k], s[k], u[k], sd[k], tab)[0]
                       for k in range(3)])
    f = ca.Function("f", [x, u, s, sd, tab], [rhs])
    args = ([20.0, 30.0, 35.0], [30.0, 40.0, 45.0], [0.009, 0.011, 0.012], [0.01, -0.02, 0.0])
    assert _rel(np.asarray(f(*args, bank.table)), np.asarray(bank.ode_function(*args))) == 0.0
    assert not bank.table.flags.writeable
    assert bank.map_ranges.shape == (4, 3) and bank.members[1][:2] == ("t", "reduced")


def test_moving_gap_converges_with_rk4_order(u_maps) -> None:
    """Independent of any second path (CurrentModel steps on the same kernel now): under
    a gap ramp the bank's step must converge with RK4's order.  The stage gaps enter at
    the sub-step's start, middle and end; taking the middle stages' gap at the start
    (a mutation that the comparison with CurrentModel no longer sees) drops the order
    to about 1.  Halving the step three times: errors e(h)/e(h/2) ~ 2^4 = 16; bound
    2^3 leaves room for the tables' piecewise cubic cells."""
    bank = MagnetBank({"u": u_maps}, compiled="never", max_step_s=1.0)   # 1 sub-step
    r = float(u_maps.dataset["resistance_ohm"].values[0])
    duration, rate, s0, i0 = 0.02, 0.15, 0.008, 20.0     # gap 8 -> 11 mm

    def final_current(n: int) -> float:
        dt = duration / n
        state = bank.initial_state(gaps_m=s0, currents_A=i0)
        for k in range(n):
            state, _ = bank.step(state, dt, r * i0, s0 + rate * k * dt, rate)
        return float(state.inductor_currents_A[0])

    x = [final_current(n) for n in (10, 20, 40, 80)]
    e = np.abs(np.diff(x))
    ratios = e[:-1] / e[1:]
    assert np.all(ratios > 8.0), ratios
    assert abs(x[-1] - i0) > 1.0                        # the ramp moves the current
    assert e[-1] > 1e-12                                # above round-off
