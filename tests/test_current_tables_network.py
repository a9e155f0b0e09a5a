"""``CurrentModel(maps, eddy_modes=m)`` on the bank's compiled cell tables vs its B-spline
path: the eddy network's branch currents carried through the table step (``step``) and the
compiled time loop (``simulate``), with and without freewheeling diodes.

The maps are ``tr09-standard`` (the diffusing eddy ladder, two circuits: the (circuit,
branch) layout of the state is exercised) on a small grid.
"""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.compare import standard_scenarios
from maglevkit.errors import OutOfRangeError
from maglevkit.reduced.current import CurrentModel

from .test_current_tables import forbid_bspline, rel_difference

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 60.0, 7)
# The tables hold the same bicubic function as the B-splines; the two paths differ only in
# rounding (tests/test_current_tables.py, eq. 8: 3.7e-14 measured).  With the network
# measured 1.5e-13 relative (m = 1) over these scenarios; the bound is eq. 8's, 1e-12.
REL = 1e-12
GAP = 0.010
I0 = 30.0


@pytest.fixture(scope="module")
def tr09() -> tuple[mk.Magnet, mk.CharacteristicMaps]:
    mag = mk.load_magnet("tr09-standard", eddy_model="ladder")
    return mag, mk.build_maps(mag, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


FIELDS = ("currents_A", "inductor_currents_A", "circuit_force_N", "pole_force_N", "force_N")


def _eddy_close(res: mk.ReducedSimulation | np.ndarray, ref: mk.ReducedSimulation | np.ndarray,
                scale_A: float) -> bool:
    """Branch currents equal to rounding at the coil current's scale ``scale_A`` [A]: they
    (0.2 A of 30 A here) are driven by ``U_L``, a difference of terms of the coil
    current's size, so their rounding follows that size (measured 4e-12 A, m = 2: 1.8e-11
    of the branch currents, 1.2e-13 of ``I_L``)."""
    a = getattr(res, "eddy_currents_A", res)
    b = getattr(ref, "eddy_currents_A", ref)
    return bool(np.max(np.abs(np.asarray(a) - np.asarray(b))) <= REL * scale_A)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_network_simulate_and_step_on_tables_equal_bspline(tr09, m: int,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    mag, maps = tr09
    spline = CurrentModel(maps, eddy_modes=m, lookup="bspline")
    tables = CurrentModel(maps, eddy_modes=m)
    scenarios = [sc for sc in standard_scenarios(mag, gap_m=GAP, current_A=I0)
                 if sc.kind == "open"]
    assert len(scenarios) >= 6
    spans = [(0.0, min(sc.duration_s, 0.1)) for sc in scenarios]
    refs = [mk.simulate(spline, span, dt_s=sc.dt_s, gaps_m=sc.gaps_m, voltages_V=sc.voltages_V,
                        initial_currents_A=I0) for sc, span in zip(scenarios, spans, strict=True)]
    # the step loop: +20 % voltage with the gap moving 10 mm/s, 40 steps of 1 ms
    r_el = spline.resistance_ohm
    ng = len(spline.gap_names)
    rates = np.full(ng, 0.01)
    states = [model.initial_state(gaps_m=GAP, currents_A=I0) for model in (spline, tables)]
    ref_steps = []
    for _ in range(40):
        states[0], out = spline.step(states[0], 1e-3, 1.2 * r_el * I0, gap_rates_m_per_s=rates)
        ref_steps.append((states[0], out))
    forbid_bspline(monkeypatch)
    for sc, span, ref in zip(scenarios, spans, refs, strict=True):
        res = mk.simulate(tables, span, dt_s=sc.dt_s, gaps_m=sc.gaps_m,
                          voltages_V=sc.voltages_V, initial_currents_A=I0)
        for field in FIELDS:
            assert rel_difference(getattr(res, field), getattr(ref, field)) <= REL, (sc.name, field)
        assert _eddy_close(res, ref, float(np.max(np.abs(ref.inductor_currents_A)))), sc.name
        assert res.eddy_currents_A.shape == ref.eddy_currents_A.shape == (res.time_s.size, 2, m)
        # the branches carry current (the layout of (circuit, branch) is tested)
        assert np.max(np.abs(ref.eddy_currents_A)) > 1e-3, sc.name
        # the final state is the run's last row (compared above over the whole run: the
        # branch currents decay to mA, so their end alone is no scale for the rounding)
        assert np.array_equal(res.final_state.eddy_currents_A, res.eddy_currents_A[-1])
    st = states[1]
    assert max(float(np.max(np.abs(r.eddy_currents_A))) for r, _ in ref_steps) > 1e-2
    for ref_state, ref_out in ref_steps:
        st, out = tables.step(st, 1e-3, 1.2 * r_el * I0, gap_rates_m_per_s=rates)
        assert rel_difference(out.currents_A, ref_out.currents_A) <= REL
        assert rel_difference(out.force_N, ref_out.force_N) <= REL
        assert st.eddy_currents_A.shape == (2, m)
        assert _eddy_close(st.eddy_currents_A, ref_state.eddy_currents_A,
                           float(np.max(np.abs(ref_out.inductor_currents_A))))
    # a run continued from the table state: the branch currents are read back as given
    more = tables.simulate(np.linspace(st.time_s, st.time_s + 0.01, 11), gaps_m=st.gaps_m,
                           voltages_V=1.2 * r_el * I0, initial_state=st)
    assert np.array_equal(more.eddy_currents_A[0], st.eddy_currents_A)


def test_network_freewheel_on_tables_equals_bspline(tr09, monkeypatch: pytest.MonkeyPatch) -> None:
    """A voltage step down to -300 V: the diodes block (coil current held at 0) and the
    branches relax through ``R_0``; both paths agree there too."""
    _, maps = tr09
    spline = CurrentModel(maps, eddy_modes=2, freewheel=True, lookup="bspline")
    tables = CurrentModel(maps, eddy_modes=2, freewheel=True)
    r_el = spline.resistance_ohm
    t = np.linspace(0.0, 0.06, 601)
    u = np.where(t[:, None] < 0.01 - 1e-12, 1.2 * r_el * I0, -300.0)
    ref = spline.simulate(t, gaps_m=GAP, voltages_V=u, initial_currents_A=I0)
    forbid_bspline(monkeypatch)
    res = tables.simulate(t, gaps_m=GAP, voltages_V=u, initial_currents_A=I0)
    # the clamp acts for a third of the run (the freewheel law is what runs there): the
    # coil current is 0 up to rounding of the ~30 A sums it is formed from
    assert (np.abs(ref.currents_A) < 1e-12).all(axis=1).sum() > 100
    for field in FIELDS:
        # the coil currents are zeros (to rounding) in both where blocked: compared in
        # absolute terms against the largest (30 A) by _rel
        assert rel_difference(getattr(res, field), getattr(ref, field)) <= REL, field
    assert _eddy_close(res, ref, I0)
    st = tables.initial_state(gaps_m=GAP, currents_A=I0)
    for k in range(t.size - 1):
        st, out = tables.step(st, 1e-4, u[k], gap_rates_m_per_s=0.0)
    assert (np.abs(out.currents_A) < 1e-12).all()        # blocked at the end
    assert rel_difference(out.inductor_currents_A, ref.inductor_currents_A[-1]) <= REL
    assert _eddy_close(st.eddy_currents_A, ref.final_state.eddy_currents_A, I0)


def test_network_leaving_the_maps_gives_the_bspline_messages(tr09) -> None:
    """Currents driven past the maps (60 A): the same error from both paths, in
    ``simulate`` and in ``step``."""
    _, maps = tr09
    spline = CurrentModel(maps, eddy_modes=2, lookup="bspline")
    tables = CurrentModel(maps, eddy_modes=2)
    u = 3.0 * spline.resistance_ohm * I0          # steady state 90 A: leaves at 60 A
    msgs = []
    for model in (spline, tables):
        with pytest.raises(OutOfRangeError) as err:
            model.simulate(np.linspace(0.0, 0.5, 501), gaps_m=GAP, voltages_V=u,
                           initial_currents_A=I0)
        msgs.append(str(err.value))
    # as on eq. 8's table path (tests/test_current_tables.py): the tables name the flagged
    # step of the compiled loop (its reason code: an RK4 sub-step end), the B-spline path
    # the end of that interval; the rest is the same
    assert "current 60.0" in msgs[0]
    assert msgs[1] == msgs[0].replace(" at t = 0.311 s",
                                      " in an RK4 sub-step within t = 0.31..0.311 s")
    msgs = []
    for model in (spline, tables):
        st = model.initial_state(gaps_m=GAP, currents_A=I0)
        with pytest.raises(OutOfRangeError) as err:
            for _ in range(500):
                st, _ = model.step(st, 1e-3, u)
        msgs.append(str(err.value))
    assert msgs[0] == msgs[1]
    # with extrapolate=True the table path hands the flagged run to the B-splines: the
    # same numbers and warning as the B-spline model
    runs = []
    for lookup in ("bspline", "tables"):
        model = CurrentModel(maps, eddy_modes=2, lookup=lookup, extrapolate=True)
        with pytest.warns(UserWarning):
            runs.append(model.simulate(np.linspace(0.0, 0.4, 401), gaps_m=GAP, voltages_V=u,
                                       initial_currents_A=I0))
    assert rel_difference(runs[1].currents_A, runs[0].currents_A) <= REL


def test_network_tables_without_a_compiler_equal_the_compiled_ones(tr09) -> None:
    """``compiled="never"``: the same table step and time loop on CasADi's virtual machine
    (no lane library to link against) give the compiled path's numbers to rounding."""
    _, maps = tr09
    t = np.linspace(0.0, 0.02, 21)
    runs, steps = [], []
    for compiled in ("auto", "never"):
        model = CurrentModel(maps, eddy_modes=2, compiled=compiled)
        u = 1.2 * model.resistance_ohm * I0
        runs.append(model.simulate(t, gaps_m=GAP, voltages_V=u, initial_currents_A=I0))
        st = model.initial_state(gaps_m=GAP, currents_A=I0)
        for _ in range(20):
            st, _ = model.step(st, 1e-3, u, gap_rates_m_per_s=0.01)
        steps.append(st)
        assert model._use_tables                      # neither fell back to the B-splines
    for field in FIELDS:
        assert rel_difference(getattr(runs[1], field), getattr(runs[0], field)) <= REL, field
    assert _eddy_close(runs[1], runs[0], I0)
    assert rel_difference(steps[1].inductor_currents_A, steps[0].inductor_currents_A) <= REL
    assert _eddy_close(steps[1].eddy_currents_A, steps[0].eddy_currents_A, I0)


def test_network_steps_of_many_sub_steps_stay_on_the_bspline_path(tr09) -> None:
    """A time grid whose steps need more RK4 sub-steps than the compiled network loop takes
    (it unrolls them in C: 500 sub-steps were a 32 MB source compiling for minutes) runs on
    the B-splines, with the same numbers as a B-spline model."""
    _, maps = tr09
    from maglevkit.reduced.current import _NETWORK_MAX_SUBSTEPS

    dt = (_NETWORK_MAX_SUBSTEPS + 1) * 1e-3          # one more sub-step than allowed at 1 ms
    t = np.arange(4) * dt
    model = CurrentModel(maps, eddy_modes=2)
    ref = CurrentModel(maps, eddy_modes=2, lookup="bspline")
    u = 1.2 * model.resistance_ohm * I0
    res = model.simulate(t, gaps_m=GAP, voltages_V=u, initial_currents_A=I0)
    assert not model._network_runs                  # no compiled network loop was built
    want = ref.simulate(t, gaps_m=GAP, voltages_V=u, initial_currents_A=I0)
    for field in FIELDS:
        assert rel_difference(getattr(res, field), getattr(want, field)) <= REL, field
