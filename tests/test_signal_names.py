"""The signals' times, frequency and phase carry their units in their names (issue 22,
item 7); the unit-less names stay as deprecated aliases for one release, and the scenario
files keep their keys."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maglevkit.errors import InputError
from maglevkit.models.signals import Ramp, Sine, Step, Tabulated, parse_signal

T = np.linspace(0.0, 0.2, 41)


def test_unit_named_fields_and_their_values() -> None:
    step, ramp = Step(1.0, 3.0, time_s=0.05), Ramp(0.0, 2.0, start_s=0.05, stop_s=0.15)
    sine, tab = Sine(1.0, 0.5, frequency_Hz=10.0, phase_rad=0.3), Tabulated(times_s=(0.0, 0.2),
                                                                          values=(0.0, 4.0))
    assert step.time_s == 0.05 and step.breakpoints == (0.05,)
    assert np.array_equal(step(T), np.where(T < 0.05, 1.0, 3.0))
    assert (ramp.start_s, ramp.stop_s) == ramp.breakpoints == (0.05, 0.15)
    assert ramp(0.1) == pytest.approx(1.0, rel=1e-15)
    # the sine against its formula evaluated independently with math.sin
    assert sine(T) == pytest.approx([1.0 + 0.5 * math.sin(2 * math.pi * 10.0 * t + 0.3)
                                     for t in T], rel=1e-15, abs=1e-15)
    assert tab.times_s == (0.0, 0.2) and tab(0.1) == pytest.approx(2.0, rel=1e-15)
    with pytest.raises(InputError, match=r"sine signal: frequency_Hz = -1\.0 Hz must be >= 0"):
        Sine(0.0, 1.0, frequency_Hz=-1.0)
    with pytest.raises(InputError, match=r"ramp signal: stop_s = 0\.0 s must be > start_s = "
                                         r"0\.1 s"):
        Ramp(0.0, 1.0, 0.1, 0.0)


@pytest.mark.parametrize(("make", "old", "new", "read"), [
    (lambda: Step(1.0, 3.0, time=0.05), "time", "time_s", 0.05),
    (lambda: Ramp(0.0, 2.0, start=0.05, stop=0.15), "stop", "stop_s", 0.15),
    (lambda: Sine(1.0, 0.5, frequency=10.0, phase=0.3), "frequency", "frequency_Hz", 10.0),
    (lambda: Tabulated(times=(0.0, 0.2), values=(0.0, 4.0)), "times", "times_s", (0.0, 0.2)),
])
def test_old_names_are_deprecated_aliases(make, old: str, new: str, read: object) -> None:
    with pytest.warns(DeprecationWarning, match=rf"{old}= is deprecated, use {new}="):
        sig = make()
    assert getattr(sig, new) == read
    with pytest.warns(DeprecationWarning, match=rf"\.{old} is deprecated, use \.{new}"):
        assert getattr(sig, old) == read


def test_scenario_files_keep_their_keys() -> None:
    """The file keys set the unit-named fields (no warning: the format is unchanged)."""
    assert parse_signal({"type": "step", "initial": 1.0, "final": 3.0, "time": 0.05}) == \
        Step(1.0, 3.0, 0.05)
    assert parse_signal({"type": "sine", "offset": 1.0, "amplitude": 0.5, "frequency": 10.0,
                         "phase": 0.3}) == Sine(1.0, 0.5, 10.0, 0.3)
    assert parse_signal({"type": "ramp", "initial": 0.0, "final": 2.0, "start": 0.05,
                         "stop": 0.15}) == Ramp(0.0, 2.0, 0.05, 0.15)
    assert parse_signal({"type": "tabulated", "times": [0.0, 0.2], "values": [0.0, 4.0]}) == \
        Tabulated((0.0, 0.2), (0.0, 4.0))
