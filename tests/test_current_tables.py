"""CurrentModel on the bank's compiled cell tables vs its B-spline path (issue 22, item 2)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.compare import standard_scenarios
from maglevkit.errors import InputError, MaglevkitError, OutOfRangeError
from maglevkit.models.inputs import sample_input
from maglevkit.reduced.current import CurrentModel

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)
# The tables hold the same bicubic function as CasADi's B-spline (docs/bank.md: 4e-14
# relative); the two paths differ only in rounding (map evaluation, and the bank's RK4
# stage gaps s + sdot t against the B-spline path's gap state).  Measured largest
# difference over the full standard scenarios of every bundled magnet: 3.7e-14 relative
# (docs/decisions.md); bound 1e-12, the bank's own bound against CurrentModel.
REL = 1e-12
MAGNETS = ("u-magnet", "tr09-standard", "tr09-bow", "tr-guidance")    # every bundled one


@pytest.fixture(scope="module")
def all_maps() -> dict[str, tuple[mk.Magnet, mk.CharacteristicMaps]]:
    out = {}
    for name in MAGNETS:
        mag = mk.load_magnet(name)
        out[name] = (mag, mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False))
    return out


def rel_difference(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def forbid_bspline(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make the B-spline RK4 path fail, so that a passing call ran on the tables."""
    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("the B-spline path ran")

    monkeypatch.setattr(CurrentModel, "_integrate", fail)
    monkeypatch.setattr(CurrentModel, "_step_call", fail)


def _nominal(mag: mk.Magnet) -> tuple[float, float]:
    """The magnet file's operating point; the U-magnet has none: 10 mm, 20 A (compare's)."""
    s0, i0 = getattr(mag, "nominal_gap", None), getattr(mag, "nominal_current", None)
    return (0.010, 20.0) if s0 is None or i0 is None else (float(s0), float(i0))


@pytest.mark.parametrize("name", MAGNETS)
def test_tables_equal_bspline_on_the_standard_scenarios(all_maps, name: str,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    mag, maps = all_maps[name]
    s0, i0 = _nominal(mag)
    spline = CurrentModel(maps, lookup="bspline")
    tables = CurrentModel(maps)
    scenarios = [sc for sc in standard_scenarios(mag, gap_m=s0, current_A=i0) if sc.kind == "open"]
    assert len(scenarios) >= 6
    refs = []
    for sc in scenarios:
        span = (0.0, min(sc.duration_s, 0.3))
        refs.append((sc, span, mk.simulate(spline, span, dt_s=sc.dt_s, gaps_m=sc.gaps_m,
                                           voltages_V=sc.voltages_V, initial_currents_A=i0)))
    forbid_bspline(monkeypatch)
    for sc, span, ref in refs:
        res = mk.simulate(tables, span, dt_s=sc.dt_s, gaps_m=sc.gaps_m, voltages_V=sc.voltages_V,
                          initial_currents_A=i0)
        for field in ("currents_A", "inductor_currents_A", "circuit_force_N", "pole_force_N",
                      "force_N"):
            assert rel_difference(getattr(res, field), getattr(ref, field)) <= REL, (sc.name, field)
        assert np.ptp(ref.currents_A) > 1e-3 * np.max(np.abs(ref.currents_A)), sc.name
        assert res.final_state.time_s == ref.final_state.time_s
        assert rel_difference(res.final_state.inductor_currents_A,
                    ref.final_state.inductor_currents_A) <= REL


@pytest.mark.parametrize("name", ["u-magnet", "tr09-standard"])
def test_step_on_tables_equals_bspline_step(all_maps, name: str,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    mag, maps = all_maps[name]
    s0, i0 = _nominal(mag)
    spline = CurrentModel(maps, lookup="bspline")
    tables = CurrentModel(maps)
    sc = standard_scenarios(mag, gap_m=s0, current_A=i0)[3]          # gap sine 5 Hz
    t = np.arange(0.0, 0.2 + 1e-9, 1e-3)
    g = sample_input(sc.gaps_m, t, spline.gap_names, "gaps", "m")
    u = mag.network.resistances * i0 * 1.1
    refs = []
    st = spline.initial_state(gaps_m=g[0], currents_A=i0)
    for k in range(t.size - 1):
        st, out = spline.step(st, 1e-3, u, gaps_m=g[k], gap_rates_m_per_s=(g[k + 1] - g[k]) / 1e-3)
        refs.append(out)
    forbid_bspline(monkeypatch)
    st = tables.initial_state(gaps_m=g[0], currents_A=i0)
    for k in range(t.size - 1):
        st, out = tables.step(st, 1e-3, u, gaps_m=g[k], gap_rates_m_per_s=(g[k + 1] - g[k]) / 1e-3)
        ref = refs[k]
        assert out.time_s == ref.time_s
        assert rel_difference(out.currents_A, ref.currents_A) <= REL
        assert rel_difference(out.circuit_force_N, ref.circuit_force_N) <= REL
        assert rel_difference(out.pole_force_N, ref.pole_force_N) <= REL
        assert out.force_N == pytest.approx(ref.force_N, rel=REL)
    # the step's state and outputs are separate arrays
    assert st.inductor_currents_A is not out.inductor_currents_A
    assert np.array_equal(st.inductor_currents_A, out.inductor_currents_A)
    assert st.gaps_m == pytest.approx(g[-1], rel=1e-12)


def test_leaving_the_maps_gives_the_bspline_messages(all_maps) -> None:
    _, maps = all_maps["u-magnet"]
    tables, spline = CurrentModel(maps), CurrentModel(maps, lookup="bspline")
    messages = []
    for model in (tables, spline):
        st = model.initial_state(gaps_m=0.010, currents_A=20.0)
        with pytest.raises(MaglevkitError) as step_err:     # the current leaves the maps
            model.step(model.initial_state(gaps_m=0.010, currents_A=58.0), 1e-3, 300.0)
        with pytest.raises(OutOfRangeError) as sim_err:
            model.simulate(np.linspace(0.0, 0.05, 51), gaps_m=0.010,
                           voltages_V=lambda t, r=model.resistance_ohm: 20.0 * r * (1 + 400 * t))
        with pytest.raises(InputError) as nan_err:
            model.step(st, 1e-3, np.array([np.nan]))
        with pytest.raises(InputError) as neg_err:
            model.step(st, 1e-3, 20.0, gaps_m=np.array([0.010, -0.001]))
        messages.append([(type(e.value), str(e.value))
                         for e in (step_err, sim_err, nan_err, neg_err)])
    # simulate: the tables name the flagged step of the compiled loop (its reason code: an
    # RK4 sub-step end), the B-spline path the end of that interval; the rest is the same
    tab_sim, spl_sim = messages[0].pop(1), messages[1].pop(1)
    assert tab_sim[0] is spl_sim[0] is OutOfRangeError
    assert tab_sim[1] == spl_sim[1].replace(" at t = 0.017 s",
                                            " in an RK4 sub-step within t = 0.016..0.017 s")
    assert messages[0] == messages[1]
    assert messages[0][0][0] is OutOfRangeError and "currents 0..60 A" in messages[0][0][1]
    # a step so steep that the B-spline RK4 leaves the splines' extension (it then
    # integrates step-wise to the time the current leaves): the tables report the kernel's
    # reason code, the sub-step, as the bank does for the same step
    with pytest.raises(OutOfRangeError, match=r"circuit 'coil' in an RK4 sub-step within "
                                              r"t = 0\.\.0\.001 s") as steep:
        tables.step(tables.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3, 1e4)
    bank = mk.MagnetBank({"m": maps})
    with pytest.raises(OutOfRangeError) as banked:
        bank.step(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3, 1e4)
    assert str(steep.value).split(" (")[0] == str(banked.value).split(" (")[0].replace(
        "member 'm', circuit 'coil'", "circuit 'coil'")


def test_extrapolation_falls_back_to_the_bspline_path(all_maps) -> None:
    _, maps = all_maps["u-magnet"]
    tables = CurrentModel(maps, extrapolate=True)
    spline = CurrentModel(maps, extrapolate=True, lookup="bspline")
    res = []
    for model in (tables, spline):
        with pytest.warns(UserWarning, match="extrapolating"):
            res.append(model.simulate(np.linspace(0.0, 0.02, 21), gaps_m=0.0165, voltages_V=20.0,
                                      initial_currents_A=20.0))
    assert np.array_equal(res[0].circuit_force_N, res[1].circuit_force_N)


def test_tables_need_rk4_without_eddy_modes_and_a_known_lookup(all_maps) -> None:
    _, maps = all_maps["u-magnet"]
    with pytest.raises(InputError, match="lookup = 'fast'.*'tables'.*'bspline'"):
        CurrentModel(maps, lookup="fast")
    with pytest.raises(InputError, match="compiled = 'yes'"):
        CurrentModel(maps, compiled="yes")
    # CVODES keeps its own path and still agrees with RK4 on the tables
    cv = CurrentModel(maps, method="cvodes")
    rk = CurrentModel(maps)
    a = cv.simulate(np.linspace(0.0, 0.05, 51), gaps_m=0.010, voltages_V=25.0, initial_currents_A=20.0)
    b = rk.simulate(np.linspace(0.0, 0.05, 51), gaps_m=0.010, voltages_V=25.0, initial_currents_A=20.0)
    # RK4 at 1 ms sub-steps stays within 3e-6 of CVODES (CurrentModel docstring)
    assert rel_difference(b.currents_A, a.currents_A) <= 1e-5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        CurrentModel(maps, compiled="never").simulate(np.linspace(0.0, 0.01, 11), gaps_m=0.010,
                                                      voltages_V=25.0, initial_currents_A=20.0)


@pytest.mark.parametrize("codegen", ["lanes", "casadi"])
def test_bank_run_steps_equals_its_stepper_bit_for_bit(all_maps, codegen: str) -> None:
    from maglevkit.reduced.bank import RUN_CHUNK, MagnetBank

    maps = {"a": all_maps["tr09-standard"][1], "b": all_maps["u-magnet"][1]}
    bank = MagnetBank(maps, codegen=codegen)
    n = RUN_CHUNK + 300                     # two calls of the compiled loop
    rng = np.random.default_rng(3)
    t = np.arange(n + 1) * 1e-3
    g = 0.010 + 1e-3 * np.sin(2 * np.pi * 5 * t)[:, None] * rng.uniform(0.5, 1.0, 3)
    u = bank.resistance_ohm * rng.uniform(18.0, 30.0, (n, 3))
    rates = np.diff(g, axis=0) / 1e-3
    i0 = np.full(3, 20.0)
    run = bank.run_steps(i0, g[:-1], u, rates, np.full(n, 1e-3))
    stepper = bank.stepper(bank.initial_state(gaps_m=g[0], currents_A=i0), 1e-3)
    for k in range(n):
        stepper.advance(u[k], g[k], rates[k])
        assert np.array_equal(run.inductor_currents_A[k], stepper.inductor_currents_A)
        assert np.array_equal(run.currents_A[k], stepper.currents_A)
        assert np.array_equal(run.circuit_force_N[k], stepper.circuit_force_N)
    assert run.n_good == n
    # a run of one compiled call (at most RUN_CHUNK steps of one sub-step: the short path
    # of run_steps) gives the same rows as the long run
    short = bank.run_steps(i0, g[:300], u[:300], rates[:300], np.full(300, 1e-3))
    for a, b in ((short.inductor_currents_A, run.inductor_currents_A),
                 (short.currents_A, run.currents_A), (short.circuit_force_N, run.circuit_force_N)):
        assert np.array_equal(a, b[:300])
    # steps of 2 ms take two RK4 sub-steps: a run of mixed lengths equals step() per step
    h = np.where(np.arange(n) % 500 < 250, 1e-3, 2e-3)[:600]
    mixed = bank.run_steps(i0, g[:600], u[:600], rates[:600] * 0.5, h)
    state = bank.initial_state(gaps_m=g[0], currents_A=i0)
    for k in range(600):
        state, out = bank.step(state, float(h[k]), u[k], gaps_m=g[k], gap_rates_m_per_s=rates[k] * 0.5)
        assert np.array_equal(mixed.circuit_force_N[k], out.circuit_force_N)
    # a step that leaves the maps: step()'s diagnosis, or a stop at it
    u_bad = u[:20].copy()
    u_bad[12, 1] = 1e5
    with pytest.raises(OutOfRangeError, match=r"member 'a', circuit .*RK4 sub-step within "
                                              r"t = 0\.012\.\.0\.013 s"):
        bank.run_steps(i0, g[:20], u_bad, rates[:20], np.full(20, 1e-3))
    stop = bank.run_steps(i0, g[:20], u_bad, rates[:20], np.full(20, 1e-3), stop_at_flag=True)
    assert stop.n_good == 12
    assert np.array_equal(stop.circuit_force_N[:12], run.circuit_force_N[:12])
    assert np.isnan(stop.circuit_force_N[12:]).all()
    with pytest.raises(InputError, match=r"run_steps: expected I_L \(3,\)"):
        bank.run_steps(i0, g[:20, :2], u[:20], rates[:20], np.full(20, 1e-3))


def test_kernel_reason_codes_name_each_reason(all_maps) -> None:
    from maglevkit.reduced.bank import MagnetBank, StepFlag

    maps = all_maps["u-magnet"][1]
    bank = MagnetBank({"a": maps, "b": maps, "c": maps, "d": maps})
    f = bank.step_kernel(1e-3)
    i = np.array([20.0, 20.0, 70.0, 20.0])          # c starts above the maps' 60 A
    s = np.array([0.010, 0.030, 0.010, 0.010])      # b outside the 6-16 mm maps
    u = bank.resistance_ohm * np.array([20.0, 20.0, 20.0, np.nan])    # d: NaN voltage
    res = f.call({"I_L": i, "s": s, "U": u, "sdot": np.zeros(4), "h": 1e-3})
    flags = np.asarray(res["flags"]).ravel()
    assert flags[0] == 0
    assert flags[1] == StepFlag.GAP_OUT_OF_RANGE
    assert flags[2] == StepFlag.CURRENT_OUT_OF_RANGE
    assert int(flags[3]) & StepFlag.INPUT_NOT_FINITE
    assert float(res["n_bad"]) == 3                 # a count of circuits, not of reasons
    # the step turns the codes into messages, inputs first
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match=r"voltages must be finite: circuit 'd/coil'"):
        bank.step(state, 1e-3, u)
    with pytest.raises(OutOfRangeError, match=r"member 'b'.*over the step.*gap 0\.03 m"):
        bank.step(state, 1e-3, u[0], gaps_m=s)
    assert [int(r) for r in StepFlag.by_priority()] == [4, 1, 8, 2]


def test_current_model_step_reads_the_kernels_reason_codes(all_maps) -> None:
    """A flagged table step of CurrentModel is diagnosed from the kernel's reason codes
    (no range check of its own: the checks are made to fail) and says what the B-spline
    path says, character for character, and what the bank says of its circuit."""
    from maglevkit.reduced.bank import MagnetBank

    maps = all_maps["u-magnet"][1]                  # 6-16 mm, 0-60 A
    tables, spline = mk.CurrentModel(maps), mk.CurrentModel(maps, lookup="bspline")

    def no_check(*args: object, **kwargs: object) -> None:
        raise AssertionError("a range check of CurrentModel's own ran")

    tables._check_range = no_check                  # type: ignore[method-assign]
    tables._check_substeps = no_check               # type: ignore[method-assign]
    r = float(tables.core.resistance_ohm[0])
    cases = [  # (start current [A], voltages, gaps, gap rates, error, message)
        (20.0, np.array([20.0 * r]), 0.030, 0.0, OutOfRangeError,
         r"circuit 'coil' over the step t = 0\.\.0\.001 s: substitute gap 0\.03 m"),
        (20.0, np.array([20.0 * r]), 0.015, 2.0, OutOfRangeError,
         r"over the step.*gap 0\.017 m"),
        (58.0, np.array([300.0]), 0.010, 0.0, OutOfRangeError,
         r"circuit 'coil' in an RK4 sub-step within t = 0\.\.0\.001 s: substitute gap 0\.01 m "
         r"and current [\d.]+ A; its maps cover gaps 0\.006\.\.0\.016 m and currents 0\.\.60 A"),
        (20.0, np.array([np.nan]), 0.010, 0.0, InputError,
         r"voltages must be finite: circuit 'coil' = nan V"),
    ]
    # simulate: the compiled time loop stops at the flagged step, whose codes say why
    # (a gap ramp out of the 6-16 mm maps between 20 and 21 ms)
    with pytest.raises(OutOfRangeError, match=r"circuit 'coil' over the step t = 0\.02\.\.0\.021 "
                                              r"s: substitute gap 0\.0161 m"):
        tables.simulate(np.linspace(0.0, 0.05, 51), gaps_m=lambda t: 0.014 + 0.1 * t,
                        voltages_V=20.0 * r, initial_currents_A=20.0)
    bank = MagnetBank({"m": maps})
    for i0, u, g, gd, err, pattern in cases:
        msgs = []
        state = spline.initial_state(gaps_m=0.010, currents_A=i0)   # (checks the range)
        for model in (tables, spline):
            with pytest.raises(err, match=pattern) as info:
                model.step(state, 1e-3, u, gaps_m=np.full(len(model.gap_names), g),
                           gap_rates_m_per_s=np.full(len(model.gap_names), gd))
            msgs.append(str(info.value))
        assert msgs[0] == msgs[1]
        bst = bank.initial_state(gaps_m=0.010, currents_A=i0)
        with pytest.raises(err) as info:
            bank.step(bst, 1e-3, u, gaps_m=g, gap_rates_m_per_s=gd)
        # the bank names member and circuit; its own advice has no command-line hint
        bank_msg = str(info.value).replace("member 'm', circuit 'coil'", "circuit 'coil'")
        bank_msg = bank_msg.replace("'m/coil'", "'coil'")
        assert msgs[0].startswith(bank_msg.removesuffix(")"))


def test_maps_the_tables_cannot_hold_stay_on_the_bsplines() -> None:
    import dataclasses

    mag = mk.load_magnet("u-magnet")
    regular = mk.build_maps(mag, gaps_m=np.linspace(0.006, 0.016, 5), currents_A=CURRENTS,
                            progress=False)
    # as an old maps file on a grid that is not equidistant would load (build_maps refuses
    # such grids now; load_maps does not check)
    ds = regular.dataset.assign_coords(gap=[0.006, 0.008, 0.011, 0.013, 0.016])
    maps = dataclasses.replace(regular, dataset=ds)
    with pytest.raises(InputError, match="regular"):
        mk.MagnetBank({"m": maps})
    tables, spline = CurrentModel(maps), CurrentModel(maps, lookup="bspline")
    runs = [m.simulate(np.linspace(0.0, 0.05, 51), gaps_m=0.010, voltages_V=25.0,
                       initial_currents_A=20.0) for m in (tables, spline)]
    assert np.array_equal(runs[0].currents_A, runs[1].currents_A)
    st = tables.initial_state(gaps_m=0.010, currents_A=20.0)
    st, out = tables.step(st, 1e-3, 25.0)
    assert out.currents_A[0] == pytest.approx(runs[1].currents_A[1, 0], rel=1e-12)


def test_step_wrapper_compiled_at_the_first_step_is_bit_identical(all_maps) -> None:
    """CurrentModel.step's wrapper around the bank's lane step is C linked against the
    lane library from the first step of a step length on (no compile pause later in a
    run), and gives the same bits as the same wrapper on CasADi's virtual machine (12
    different pole gaps and rates, voltages varying, 60 steps; on the module's TR09 maps:
    the run stays within 9-11 mm and 0-60 A)."""
    from maglevkit.reduced import current as cur

    maps = all_maps["tr09-standard"][1]
    model = mk.CurrentModel(maps)
    st = model.initial_state(gaps_m=0.01, currents_A=34.0)
    model.step(st, 1e-3, 40.0)
    compiled = model._table_steps[1e-3]
    if compiled.library is None:
        pytest.skip("no lane library (no C compiler)")
    assert compiled.bound.function.class_name() != "MXFunction"       # compiled at once
    lanes = model._bank.compiled_step_library(1e-3)
    vm = cur._TableStep(lanes[0], model._avg, model._share, 1e-3)      # no library: the VM
    assert vm.bound.function.class_name() == "MXFunction"

    def run(call: cur._TableStep) -> np.ndarray:
        i = np.array([34.0, 34.0])
        rng = np.random.default_rng(0)
        rows = []
        for k in range(60):
            g = 0.01 + 1e-3 * np.sin(0.03 * k) + 1e-5 * rng.standard_normal(12)
            u = np.array([40.0, 42.0]) * (1 + 0.2 * np.sin(0.1 * k))
            out = call(i, g, u, 1e-3 * rng.standard_normal(12), 1e-3 * (k + 1))
            assert out is not None
            state, outs = out
            i = state.inductor_currents_A
            rows.append(np.concatenate([state.inductor_currents_A, state.gaps_m, outs.currents_A,
                                        outs.inductor_currents_A, outs.circuit_force_N,
                                        outs.pole_force_N, [outs.force_N]]))
        return np.array(rows)

    assert np.array_equal(run(compiled), run(vm))


def test_row_sums_equal_numpy_sum_bit_for_bit() -> None:
    from maglevkit.reduced.current import row_sums

    rng = np.random.default_rng(5)
    for m in range(0, 11):
        a = rng.standard_normal((257, m)) * 10.0 ** rng.integers(-4, 6, (257, m))
        assert np.array_equal(row_sums(a), a.sum(axis=1))


def test_kernel_lookup_equals_the_cell_table_reference() -> None:
    """The kernel's table lookup (power sums, gap half first) against the NumPy evaluation
    of the same per-cell polynomials (einsum), inside and outside the grid (the edge cell
    continued).  The two sum the same terms in different orders: rounding only; bound
    1e-13 relative to the map's largest value (measured 1e-15)."""
    import casadi as ca

    from maglevkit.reduced.tables import N_TABLE_MAPS, cell_lookup, cell_table, gap_cell_part

    s_ax, i_ax = np.linspace(0.005, 0.016, 12), np.linspace(0.0, 80.0, 17)
    G, II = np.meshgrid(s_ax, i_ax, indexing="ij")
    maps = np.stack([1e-2 / (G + 0.002) * (1 + II / 40.0) ** -1.3, -G * II ** 0.5 - G,
                     1e3 * II ** 2 / (G * 1e3) ** 1.7])
    assert maps.shape[0] == N_TABLE_MAPS
    for method, degree in (("bicubic", 3), ("bilinear", 1)):
        tab = cell_table(s_ax, i_ax, maps, method=method)
        ns, ni = tab.n_cells
        p = ca.DM([tab.s0_m, 1.0 / tab.ds_m, ns, tab.i0_A, 1.0 / tab.di_A, ni, 0.0])
        s, i = ca.MX.sym("s"), ca.MX.sym("i")
        table = ca.MX(ca.DM(tab.coefficients.reshape(-1)))
        vals, k = cell_lookup(gap_cell_part(s, p, degree), i, p, table, degree)
        # a lookup with a guess of the current's cell: the same values for any guess
        guess = ca.MX.sym("guess")
        hinted, _ = cell_lookup(gap_cell_part(s, p, degree), i, p, table, degree, hint=guess)
        f = ca.Function("f", [s, i], vals)
        fh = ca.Function("fh", [s, i, guess], hinted)
        rng = np.random.default_rng(7)
        pts = np.column_stack([rng.uniform(0.0045, 0.0165, 400), rng.uniform(-3.0, 83.0, 400)])
        got = np.array([np.array(f(a, b)).ravel() for a, b in pts], dtype=float).reshape(-1, 3)
        ref = tab.evaluate(pts[:, 0], pts[:, 1])
        scale = np.max(np.abs(ref), axis=0)
        assert np.max(np.abs(got - ref) / scale) <= 1e-13, method
        for a, b in pts[:40]:
            for g in (0.0, 5.0, 16.0, np.nan):
                assert np.array_equal(np.array(fh(a, b, g), dtype=float).ravel(),
                                      np.array(f(a, b), dtype=float).ravel())


def test_fast_built_results_carry_every_field(all_maps) -> None:
    """``step`` and ``simulate`` build their frozen results without the dataclass
    ``__init__`` (``current._new``, speed22); every field must be set, as the ``__init__``
    would require (review3: a field added later would otherwise be missing silently)."""
    import dataclasses

    from maglevkit.reduced.current import CurrentModelState, CurrentOutputs, ReducedSimulation

    mag, maps = all_maps["u-magnet"]
    model = CurrentModel(maps)
    st = model.initial_state(gaps_m=0.010, currents_A=20.0)
    st1, out = model.step(st, 1e-3, mag.network.resistances * 20.0, gaps_m=0.010)
    sim = model.simulate((0.0, 0.01), dt_s=1e-3, gaps_m=0.010,
                         voltages_V=mag.network.resistances * 20.0, initial_currents_A=20.0)
    for obj, cls in ((st1, CurrentModelState), (out, CurrentOutputs), (sim, ReducedSimulation),
                     (sim.final_state, CurrentModelState)):
        assert type(obj) is cls
        assert set(vars(obj)) == {f.name for f in dataclasses.fields(cls)}, cls.__name__
        cls(**vars(obj))                   # what the dataclass __init__ accepts


def test_step_fast_path_and_converted_inputs_give_the_same_bits(all_maps) -> None:
    """The table ``step`` takes float64 arrays of the right shape as they are and sends
    every other form through the converters (cmstep22): lists, mappings, a float64 dtype
    that is equal but not NumPy's singleton (metadata), and a NumPy float ``dt`` must give
    exactly the results of the plain arrays (the converters only copy float64 values, so
    the bits must match, not merely be close)."""
    mag, maps = all_maps["tr09-standard"]
    model = CurrentModel(maps)
    names, gap_names = model.circuit_names, model.gap_names
    u = mag.network.resistances * 34.0 * np.array([1.1, 0.9])
    g = 0.010 + 1e-4 * np.arange(len(gap_names))
    gd = 1e-3 * np.cos(np.arange(len(gap_names)))
    st = model.initial_state(gaps_m=g, currents_A=34.0)

    def fields(res: tuple) -> np.ndarray:
        s, o = res
        assert s.eddy_currents_A is None
        return np.concatenate([[s.time_s], s.inductor_currents_A, s.gaps_m, [o.time_s],
                               o.currents_A, o.inductor_currents_A, o.circuit_force_N,
                               o.pole_force_N, [o.force_N]])

    ref = fields(model.step(st, 1e-3, u, gaps_m=g, gap_rates_m_per_s=gd))
    meta = np.dtype(np.float64, metadata={"unit": "V"})
    assert meta == np.float64 and u.astype(meta).dtype is not np.dtype(np.float64)
    forms = [
        (1e-3, u.tolist(), g.tolist(), gd.tolist()),
        (np.float64(1e-3), dict(zip(names, u, strict=True)),
         dict(zip(gap_names, g, strict=True)), dict(zip(gap_names, gd, strict=True))),
        (1e-3, u.astype(meta), g.astype(meta), gd.astype(meta)),
    ]
    for dt, uu, gg, gdd in forms:
        got = fields(model.step(st, dt, uu, gaps_m=gg, gap_rates_m_per_s=gdd))
        assert np.array_equal(got.view(np.uint64), ref.view(np.uint64))
    # the kept per-input checks still name the input (wrong count, here one value short)
    with pytest.raises(InputError, match="voltages"):
        model.step(st, 1e-3, u[:1].copy())
