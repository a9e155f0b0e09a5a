"""BankStepper: the bank's in-place co-simulation loop equals MagnetBank.step bit for bit,
keeps its state on a failed step, and refuses bad input as step does."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError
from maglevkit.reduced.bank import MagnetBank

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


@pytest.fixture(scope="module")
def guidance_maps() -> mk.CharacteristicMaps:
    # the lumped eddy elements by name (the file's is the ladder since guideswitch): a
    # cheap two-circuit network with eq. 8's jump resistance
    return mk.build_maps(mk.load_magnet("tr-guidance", eddy_model="lumped"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


def _drive(bank: MagnetBank, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Random voltages, gaps (every 5th step set anew, else continued) and gap rates."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        u = bank.resistance_ohm * rng.uniform(18.0, 26.0, bank.n_circuits)
        g = rng.uniform(0.008, 0.012, bank.n_gaps) if k % 5 == 0 else None
        r = rng.uniform(-0.05, 0.05, bank.n_gaps)
        out.append((u, g, r))
    return out


def _same_run(bank: MagnetBank, n: int = 40, seed: int = 3) -> None:
    """The stepper and ``bank.step`` on the same inputs give identical arrays (the same
    compiled function on the same numbers: bit for bit, no tolerance)."""
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    stepper = bank.stepper(state, 1e-3)
    for u, g, r in _drive(bank, n, seed):
        state, out = bank.step(state, 1e-3, u, gaps_m=g, gap_rates_m_per_s=r, pole_forces=True)
        stepper.advance(voltages_V=u, gaps_m=g, gap_rates_m_per_s=r)
        assert stepper.time_s == state.time_s
        np.testing.assert_array_equal(stepper.currents_A, out.currents_A)
        np.testing.assert_array_equal(stepper.inductor_currents_A, out.inductor_currents_A)
        np.testing.assert_array_equal(stepper.circuit_force_N, out.circuit_force_N)
        np.testing.assert_array_equal(stepper.member_force_N, out.member_force_N)
        np.testing.assert_array_equal(stepper.gaps_m, state.gaps_m)
        assert out.pole_force_N is not None
        np.testing.assert_array_equal(stepper.pole_force_N, out.pole_force_N)
    # the stepper's state continues with step exactly as the step-built state does
    s1, o1 = bank.step(stepper.state, 1e-3, 40.0)
    s2, o2 = bank.step(state, 1e-3, 40.0)
    np.testing.assert_array_equal(o1.currents_A, o2.currents_A)
    assert s1.time_s == s2.time_s


@pytest.mark.parametrize("compiled, codegen", [("auto", "lanes"), ("auto", "casadi"),
                                               ("never", "lanes")])
def test_stepper_equals_step_bit_for_bit(u_maps, guidance_maps, compiled: str,
                                         codegen: str) -> None:
    bank = MagnetBank({"a": u_maps, "g": guidance_maps, "b": u_maps}, compiled=compiled,
                      codegen=codegen)
    _same_run(bank)


def test_stepper_of_banks_without_fast_path_runs_step(u_magnet, u_maps) -> None:
    """Detailed members and per-pole gaps: the stepper runs ``bank.step`` behind the same
    interface (same numbers)."""
    detailed = MagnetBank({"d": mk.FluxModel(u_magnet, eddy_currents=False), "r": u_maps},
                          gap_inputs="pole")
    _same_run(detailed, n=6)
    _same_run(MagnetBank({"a": u_maps, "b": u_maps}, gap_inputs="pole"), n=10)


def test_stepper_equals_single_current_model(u_maps) -> None:
    """Independent of the bank's step: a bank of one through the stepper against the
    single CurrentModel (bound 1e-12 as tests/test_bank.py: tables vs B-spline ~4e-14)."""
    bank = MagnetBank({"m": u_maps})
    single = mk.CurrentModel(u_maps)
    stepper = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3)
    ss = single.initial_state(gaps_m=0.010, currents_A=20.0)
    seen = []
    for k in range(100):
        u = 40.0 + 10.0 * np.sin(0.1 * k)
        g = 0.010 + 0.001 * np.sin(0.05 * k)
        rate = 0.001 * 0.05 / 1e-3 * np.cos(0.05 * k)
        stepper.advance(voltages_V=u, gaps_m=g, gap_rates_m_per_s=rate)
        ss, os_ = single.step(ss, 1e-3, u, gaps_m=g, gap_rates_m_per_s=rate)
        seen.append(stepper.currents_A[0])
    assert stepper.currents_A[0] == pytest.approx(os_.currents_A[0], rel=1e-12)
    assert stepper.circuit_force_N[0] == pytest.approx(os_.force_N, rel=1e-12)
    assert np.ptp(seen) > 1.0                 # the run moved the current


def test_failed_step_leaves_the_stepper_at_the_last_good_step(u_maps) -> None:
    bank = MagnetBank({"front": u_maps, "rear": u_maps})
    stepper = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3)
    stepper.advance(voltages_V=45.0)
    before = (stepper.time_s, stepper.inductor_currents_A.copy(), stepper.currents_A.copy(),
              stepper.circuit_force_N.copy(), stepper.gaps_m.copy())
    with pytest.raises(OutOfRangeError, match=r"member 'rear'.*RK4 sub-step.*currents 0\.\.60 A"):
        stepper.advance(voltages_V=np.array([45.0, 1e6]))
    after = (stepper.time_s, stepper.inductor_currents_A, stepper.currents_A,
             stepper.circuit_force_N, stepper.gaps_m)
    assert after[0] == before[0]
    for a, b in zip(after[1:], before[1:], strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(OutOfRangeError, match=r"member 'front'.*gap 0\.05 m"):
        stepper.advance(voltages_V=45.0, gaps_m=np.array([0.05, 0.010]))
    with pytest.raises(InputError, match=r"voltages must be finite.*'rear/coil'"):
        stepper.advance(voltages_V=np.array([45.0, np.nan]), gaps_m=0.010)
    # after the refusals it goes on from where it was
    stepper.advance(voltages_V=45.0, gaps_m=0.010)
    assert stepper.time_s == pytest.approx(2e-3, abs=1e-15)


def test_stepper_bad_input(u_maps) -> None:
    bank = MagnetBank({"m": u_maps, "n": u_maps})
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match="BankState"):
        bank.stepper(object(), 1e-3)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="dt"):
        bank.stepper(state, -1e-3)
    other = MagnetBank({"m": u_maps})
    with pytest.raises(InputError, match="BankState of this bank"):
        other.stepper(state, 1e-3)
    stepper = bank.stepper(state, 1e-3)
    with pytest.raises(InputError, match=r"voltages: expected 2 values"):
        stepper.advance(voltages_V=[1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="bool"):
        stepper.advance(gap_rates_m_per_s=True)
    with pytest.raises(InputError, match=r"gaps must be numbers"):
        stepper.advance(gaps_m="10 mm")
    # outputs are the stepper's own buffers: read-only
    with pytest.raises(ValueError, match="read-only"):
        stepper.currents_A[0] = 1.0
    assert stepper.time_s == 0.0                      # nothing was stepped
    assert "2 circuits" in repr(stepper)


def test_simulate_in_place_equals_a_loop_of_steps(u_maps, guidance_maps) -> None:
    """simulate() of a reduced bank runs through the stepper; it equals one step() per
    interval bit for bit, on a grid whose intervals differ in the last bits (linspace),
    and on a grid with two sub-step counts (which takes the step() loop)."""
    bank = MagnetBank({"a": u_maps, "g": guidance_maps})
    for times in (np.linspace(0.0, 0.05, 51), np.concatenate([np.arange(0.0, 0.01, 1e-3),
                                                             0.01 + 1.5e-3 * np.arange(6)])):
        gaps = 0.010 + 0.001 * np.sin(2 * np.pi * 10 * times)[:, None] * np.ones(bank.n_gaps)
        volts = np.outer(1.0 + 0.1 * np.cos(2 * np.pi * 7 * times), bank.resistance_ohm * 20.0)
        res = bank.simulate(times, gaps_m=gaps, voltages_V=volts)
        state = bank.initial_state(gaps_m=gaps[0], currents_A=volts[0] / bank.resistance_ohm,
                                   time_s=float(times[0]))
        rates = (gaps[1:] - gaps[:-1]) / np.diff(times)[:, None]
        for k in range(times.size - 1):
            state, out = bank.step(state, float(times[k + 1] - times[k]), volts[k],
                                   gaps_m=gaps[k], gap_rates_m_per_s=rates[k], pole_forces=True)
            np.testing.assert_array_equal(res.currents_A[k + 1], out.currents_A)
            np.testing.assert_array_equal(res.circuit_force_N[k + 1], out.circuit_force_N)
            assert out.pole_force_N is not None
            np.testing.assert_array_equal(res.pole_force_N[k + 1], out.pole_force_N)
        assert res.final_state.time_s == state.time_s
        np.testing.assert_array_equal(res.final_state.inductor_currents_A,
                                      state.inductor_currents_A)
        np.testing.assert_array_equal(res.final_state.gaps_m, state.gaps_m)


def test_arrays_keep_their_identity_and_bound_references_see_every_step(u_maps) -> None:
    """A co-simulation binds the stepper's arrays once: writes into a kept gaps_m are used
    at every step and a kept output view shows every step's values (review finding)."""
    bank = MagnetBank({"a": u_maps, "b": u_maps})
    st0 = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    bound, ref = bank.stepper(st0, 1e-3), bank.stepper(st0, 1e-3)
    gaps, volts, rates = bound.gaps_m, bound.voltages_V, bound.gap_rates_m_per_s
    force, current = bound.circuit_force_N, bound.currents_A
    for k in range(6):
        gaps[:] = 0.0105 + 0.0005 * k
        volts[:] = 45.0 + k
        rates[:] = 0.01 * (-1) ** k
        bound.advance()
        ref.advance(voltages_V=45.0 + k, gaps_m=0.0105 + 0.0005 * k, gap_rates_m_per_s=0.01 * (-1) ** k)
        np.testing.assert_array_equal(force, ref.circuit_force_N)
        np.testing.assert_array_equal(current, ref.currents_A)
    assert bound.gaps_m is gaps and bound.voltages_V is volts and bound.circuit_force_N is force


def test_assignment_copies_into_the_inputs_and_typos_are_refused(u_maps) -> None:
    bank = MagnetBank({"a": u_maps, "b": u_maps})
    st0 = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    by_attr, by_arg = bank.stepper(st0, 1e-3), bank.stepper(st0, 1e-3)
    volts = by_attr.voltages_V
    by_attr.voltages_V = np.array([60.0, 60.0])      # assignment copies into the buffer
    by_attr.gap_rates_m_per_s = 0.01
    by_attr.gaps_m = [0.011, 0.011]
    assert by_attr.voltages_V is volts and volts[0] == 60.0
    by_attr.advance()
    by_arg.advance(voltages_V=60.0, gaps_m=0.011, gap_rates_m_per_s=0.01)
    np.testing.assert_array_equal(by_attr.inductor_currents_A, by_arg.inductor_currents_A)
    assert by_attr.inductor_currents_A[0] > 20.1      # the 60 V step took effect
    with pytest.raises(AttributeError):
        by_attr.dt_s = 2e-3  # type: ignore[misc]
    with pytest.raises(AttributeError):
        by_attr.voltage_V = 1.0  # type: ignore[attr-defined]
    with pytest.raises(InputError, match=r"voltages: expected 2 values"):
        by_attr.voltages_V = [1.0, 2.0, 3.0]


def test_refused_or_failed_advance_changes_nothing_of_the_state(u_maps) -> None:
    bank = MagnetBank({"a": u_maps, "b": u_maps})
    sp = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3)
    sp.advance(voltages_V=45.0)
    good_gaps = sp.gaps_m.copy()
    with pytest.raises(InputError, match="gaps must be numbers"):
        sp.advance(voltages_V=50.0, gaps_m="x")
    assert sp.voltages_V[0] == 45.0                  # nothing of a refused call is written
    with pytest.raises(OutOfRangeError, match=r"member 'a'.*gap 0\.05 m"):
        sp.advance(gaps_m=np.array([0.05, 0.010]))
    np.testing.assert_array_equal(sp.gaps_m, good_gaps)      # reset to the last good state
    np.testing.assert_array_equal(sp.state.gaps_m, good_gaps)
    sp.advance()                                     # and it goes on without new gaps
    s2, _ = bank.step(sp.state, 1e-3, 45.0)          # the state continues with step
    assert s2.time_s == pytest.approx(3e-3, abs=1e-15)


def test_non_fast_path_failure_and_initial_voltages(u_magnet, u_maps) -> None:
    """Detailed members: the start voltages are the steady state R_el I of every circuit
    (a detailed magnet then holds its current), and a failed step keeps the state."""
    bank = MagnetBank({"d": mk.FluxModel(u_magnet, eddy_currents=False), "r": u_maps})
    sp = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3)
    np.testing.assert_allclose(sp.voltages_V, bank.resistance_ohm * 20.0, rtol=1e-9)
    for _ in range(5):
        sp.advance()
    # steady state held: the detailed model's own consistency (IDAS tolerance ~1e-6)
    np.testing.assert_allclose(sp.currents_A, 20.0, rtol=1e-5)
    before = (sp.time_s, sp.currents_A.copy(), sp.gaps_m.copy())
    with pytest.raises(OutOfRangeError, match=r"member 'r'"):
        sp.advance(gaps_m=np.array([0.010, 0.05]))
    assert sp.time_s == before[0]
    np.testing.assert_array_equal(sp.currents_A, before[1])
    np.testing.assert_array_equal(sp.gaps_m, before[2])


def test_messages_match_step_and_several_sub_steps(u_maps) -> None:
    bank = MagnetBank({"a": u_maps, "b": u_maps}, max_step_s=4e-4)
    st0 = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    sp = bank.stepper(st0, 1e-3)                     # 3 RK4 sub-steps per step
    msgs = []
    for call in (lambda: bank.step(st0, 1e-3, np.array([40.0, np.nan])),
                 lambda: sp.advance(voltages_V=np.array([40.0, np.nan]))):
        with pytest.raises(InputError) as err:
            call()
        msgs.append(str(err.value))
    assert msgs[0] == msgs[1] and "circuit 'b/coil' = nan V" in msgs[0]
    sp.voltages_V[:] = 45.0
    sp.voltages_V[1] = np.inf                        # written directly into the array
    with pytest.raises(InputError, match=r"voltages must be finite.*'b/coil'"):
        sp.advance()
    # ints, float32, lists and scalars are converted; 3 sub-steps equal step bit for bit
    state = st0
    sp2 = bank.stepper(st0, 1e-3)
    for volts in ([45, 46], np.array([45.0, 47.0], dtype=np.float32), 44):
        state, out = bank.step(state, 1e-3, np.asarray(volts, dtype=float) * np.ones(2))
        sp2.advance(voltages_V=volts)
        np.testing.assert_array_equal(sp2.inductor_currents_A, out.inductor_currents_A)


def test_bad_states_copies_and_pickling(u_maps) -> None:
    import copy
    import pickle

    from maglevkit.reduced.bank import BankState

    bank = MagnetBank({"a": u_maps, "b": u_maps})
    bad = BankState(0.0, np.array([20.0]), np.array([0.01, 0.01]), ())
    with pytest.raises(InputError, match="BankState of this bank"):
        bank.stepper(bad, 1e-3)
    with pytest.raises(InputError, match="BankState of this bank"):
        bank.step(bad, 1e-3, 40.0)
    sp = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), 1e-3)
    sp.advance(voltages_V=45.0)
    twin = copy.copy(sp)
    deep = copy.deepcopy(sp)
    sp.advance(voltages_V=60.0)                        # the copies do not move with it
    twin.advance()
    deep.advance()
    np.testing.assert_array_equal(twin.inductor_currents_A, deep.inductor_currents_A)
    assert twin.inductor_currents_A[0] < sp.inductor_currents_A[0]
    with pytest.raises(InputError, match="cannot be pickled"):
        pickle.dumps(sp)


def test_extrapolation_is_reported_once_per_circuit(u_maps) -> None:
    bank = MagnetBank({"a": u_maps, "b": u_maps}, extrapolate=True)
    sp = bank.stepper(bank.initial_state(gaps_m=0.0155, currents_A=20.0), 1e-3)
    import warnings

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        for _ in range(20):
            sp.advance(voltages_V=40.0, gaps_m=0.0165)
    texts = [str(w.message) for w in seen]
    assert len(texts) == 2 and all("reported once per circuit" in t for t in texts)
    with pytest.raises(OutOfRangeError) as err:
        sp.advance(gaps_m=0.030)
    assert "extrapolate=True" not in str(err.value)


def test_the_public_parts_the_stepper_uses(u_maps: mk.CharacteristicMaps) -> None:
    """What the stepper takes from the bank is public (no private name crosses the two
    modules): the state check, the fast path, the pole forces, the diagnosis of the
    kernel's reason codes (raise_step_flags), and a step length of the same sub-step
    count."""
    bank = MagnetBank({"front": u_maps, "rear": u_maps})
    assert bank.compiled_fast_path
    state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    bank.check_state(state)
    with pytest.raises(InputError, match="state must be a BankState of this bank"):
        bank.check_state(MagnetBank({"m": u_maps}).initial_state(gaps_m=0.01, currents_A=1.0))
    # pole forces: each pole an equal share of its circuit's force, as step gives them
    _, out = bank.step(state, 1e-3, 40.0, pole_forces=True)
    np.testing.assert_array_equal(bank.pole_forces(out.circuit_force_N), out.pole_force_N)
    np.testing.assert_array_equal(bank.pole_forces(np.stack([out.circuit_force_N] * 2))[1],
                                  out.pole_force_N)
    # the kernel's codes turned into step's message (a current leaving in a sub-step)
    f = bank.step_kernel(1e-3)
    i, s, u = np.array([20.0, 58.0]), np.full(2, 0.01), np.array([40.0, 400.0])
    res = f.call({"I_L": i, "s": s, "U": u, "sdot": np.zeros(2), "h": 1e-3})
    with pytest.raises(OutOfRangeError) as direct:
        bank.raise_step_flags(np.asarray(res["flags"]).ravel(), gaps_m=s,
                              gap_rates_m_per_s=np.zeros(2), inductor_currents_A=i,
                              voltages_V=u, current_min_A=np.asarray(res["I_L_min"]).ravel(),
                              current_max_A=np.asarray(res["I_L_max"]).ravel(), start_s=0.0,
                              end_s=1e-3)
    with pytest.raises(OutOfRangeError) as stepped:
        bank.step(bank.initial_state(gaps_m=0.01, currents_A=i), 1e-3, u)
    assert str(direct.value) == str(stepped.value)
    assert "member 'rear', circuit 'coil' in an RK4 sub-step" in str(direct.value)
    # another length of the same sub-step count is taken; one of another count is refused
    stepper = bank.stepper(state, 1e-3)
    stepper.set_step_length(0.9e-3)
    stepper.advance(40.0)
    assert stepper.dt_s == 0.9e-3 and stepper.time_s == pytest.approx(0.9e-3, rel=1e-15)
    with pytest.raises(InputError, match=r"set_step_length: dt_s = 0\.0015 s takes 2 RK4 "
                                         r"sub-steps, this stepper's step of 0\.0009 s takes 1"):
        stepper.set_step_length(1.5e-3)
