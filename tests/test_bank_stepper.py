"""BankStepper: the bank's in-place co-simulation loop equals MagnetBank.step bit for bit,
keeps its state on a failed step, and refuses bad input as step does."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError
from maglevkit.models.bank import MagnetBank

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, progress=False)


@pytest.fixture(scope="module")
def guidance_maps() -> mk.CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("tr-guidance"), gaps=GAPS, currents=CURRENTS,
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
    state = bank.initial_state(gaps=0.010, currents=20.0)
    stepper = bank.stepper(state, 1e-3)
    for u, g, r in _drive(bank, n, seed):
        state, out = bank.step(state, 1e-3, u, gaps=g, gap_rates=r, pole_forces=True)
        stepper.advance(voltages=u, gaps=g, gap_rates=r)
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
    stepper = bank.stepper(bank.initial_state(gaps=0.010, currents=20.0), 1e-3)
    ss = single.initial_state(gaps=0.010, currents=20.0)
    seen = []
    for k in range(100):
        u = 40.0 + 10.0 * np.sin(0.1 * k)
        g = 0.010 + 0.001 * np.sin(0.05 * k)
        rate = 0.001 * 0.05 / 1e-3 * np.cos(0.05 * k)
        stepper.advance(voltages=u, gaps=g, gap_rates=rate)
        ss, os_ = single.step(ss, 1e-3, u, gaps=g, gap_rates=rate)
        seen.append(stepper.currents_A[0])
    assert stepper.currents_A[0] == pytest.approx(os_.currents_A[0], rel=1e-12)
    assert stepper.circuit_force_N[0] == pytest.approx(os_.force_N, rel=1e-12)
    assert np.ptp(seen) > 1.0                 # the run moved the current


def test_failed_step_leaves_the_stepper_at_the_last_good_step(u_maps) -> None:
    bank = MagnetBank({"front": u_maps, "rear": u_maps})
    stepper = bank.stepper(bank.initial_state(gaps=0.010, currents=20.0), 1e-3)
    stepper.advance(voltages=45.0)
    before = (stepper.time_s, stepper.inductor_currents_A.copy(), stepper.currents_A.copy(),
              stepper.circuit_force_N.copy(), stepper.gaps_m.copy())
    with pytest.raises(OutOfRangeError, match=r"member 'rear'.*RK4 sub-step.*currents 0\.\.60 A"):
        stepper.advance(voltages=np.array([45.0, 1e6]))
    after = (stepper.time_s, stepper.inductor_currents_A, stepper.currents_A,
             stepper.circuit_force_N, stepper.gaps_m)
    assert after[0] == before[0]
    for a, b in zip(after[1:], before[1:], strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(OutOfRangeError, match=r"member 'front'.*gap 0\.05 m"):
        stepper.advance(voltages=45.0, gaps=np.array([0.05, 0.010]))
    with pytest.raises(InputError, match=r"voltages must be finite.*'rear/coil'"):
        stepper.advance(voltages=np.array([45.0, np.nan]), gaps=0.010)
    # after the refusals it goes on from where it was
    stepper.advance(voltages=45.0, gaps=0.010)
    assert stepper.time_s == pytest.approx(2e-3, abs=1e-15)


def test_stepper_bad_input(u_maps) -> None:
    bank = MagnetBank({"m": u_maps, "n": u_maps})
    state = bank.initial_state(gaps=0.010, currents=20.0)
    with pytest.raises(InputError, match="BankState"):
        bank.stepper(object(), 1e-3)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="dt"):
        bank.stepper(state, -1e-3)
    other = MagnetBank({"m": u_maps})
    with pytest.raises(InputError, match="BankState of this bank"):
        other.stepper(state, 1e-3)
    stepper = bank.stepper(state, 1e-3)
    with pytest.raises(InputError, match=r"voltages: expected 2 values"):
        stepper.advance(voltages=[1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="bool"):
        stepper.advance(gap_rates=True)
    with pytest.raises(InputError, match=r"gaps must be numbers"):
        stepper.advance(gaps="10 mm")
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
        res = bank.simulate(times, gaps=gaps, voltages=volts)
        state = bank.initial_state(gaps=gaps[0], currents=volts[0] / bank.resistance_ohm,
                                   time=float(times[0]))
        rates = (gaps[1:] - gaps[:-1]) / np.diff(times)[:, None]
        for k in range(times.size - 1):
            state, out = bank.step(state, float(times[k + 1] - times[k]), volts[k],
                                   gaps=gaps[k], gap_rates=rates[k], pole_forces=True)
            np.testing.assert_array_equal(res.currents_A[k + 1], out.currents_A)
            np.testing.assert_array_equal(res.circuit_force_N[k + 1], out.circuit_force_N)
            assert out.pole_force_N is not None
            np.testing.assert_array_equal(res.pole_force_N[k + 1], out.pole_force_N)
        assert res.final_state.time_s == state.time_s
        np.testing.assert_array_equal(res.final_state.inductor_currents_A,
                                      state.inductor_currents_A)
        np.testing.assert_array_equal(res.final_state.gaps_m, state.gaps_m)
