"""Irregularities on the vehicle's paths: the phasor evaluation of the random profile
equals the direct sum of cosines (the same sum, different rounding of the phases)."""

from __future__ import annotations

import numpy as np
import pytest

from maglevkit.vehicle.irregularities import RandomProfile, SpanSag
from maglevkit.vehicle.simulation import parse_irregularity


def _paths(n_steps: int, step: float) -> tuple[np.ndarray, np.ndarray]:
    start = np.linspace(60.0, 135.0, 13)
    return start, start[None, :] + step * np.arange(n_steps)[:, None]


@pytest.mark.parametrize("n_steps,step", [(700, 0.111), (300, 0.0), (5, 0.05)])
def test_random_profile_on_paths_equals_direct_sum(n_steps: int, step: float) -> None:
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:4", span_length_m=24.768)
    start, x = _paths(n_steps, step)
    r, rx = prof.on_paths(x, start_m=start, step_m=step)
    r_ref = prof.elevation_m(x.ravel()).reshape(x.shape)
    rx_ref = prof.slope(x.ravel()).reshape(x.shape)
    # measured 2e-14 (elevation) and 1.3e-13 (slope) relative to the largest value on
    # 2000-step paths; the phases Omega x (|Omega| <= ~6 rad/m, x <= 400 m) round
    # differently, |Omega x| eps ~ 5e-13 rad; bound 1e-11
    assert np.max(np.abs(r - r_ref)) <= 1e-11 * np.max(np.abs(r_ref))
    assert np.max(np.abs(rx - rx_ref)) <= 1e-11 * np.max(np.abs(rx_ref))
    assert np.ptp(r_ref) > 0                       # the profile is not flat


def test_default_on_paths_is_the_pointwise_evaluation() -> None:
    sag = SpanSag(amplitude_m=0.5e-3, span_length_m=24.768)
    start, x = _paths(50, 0.3)
    r, rx = sag.on_paths(x, start_m=start, step_m=0.3)
    np.testing.assert_array_equal(r, sag.elevation_m(x.ravel()).reshape(x.shape))
    np.testing.assert_array_equal(rx, sag.slope(x.ravel()).reshape(x.shape))


def test_random_profile_block_boundaries() -> None:
    """Paths longer than one block of 256 steps: every block starts from exact phasors."""
    prof = RandomProfile(psd=lambda om: 1e-8 / (1 + om ** 2), omega_min_rad_per_m=0.05,
                         omega_max_rad_per_m=6.0, n_components=200, seed=2)
    start, x = _paths(1030, 0.2)
    r, _ = prof.on_paths(x, start_m=start, step_m=0.2)
    ref = prof.elevation_m(x.ravel()).reshape(x.shape)
    err = np.abs(r - ref).max(axis=1) / np.abs(ref).max()
    assert err.max() <= 1e-11                      # measured ~1e-14, no growth over blocks


def test_track_synthesis_equals_the_sums_on_each_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """The train's case (50 points over 75 m, 3000 steps of 0.111 m): the profile is
    synthesised once on the track grid and interpolated; it agrees with the sums on each
    point's own path (the previous method) to the interpolation bound."""
    prof = parse_irregularity("random:0.3e-3:1", span_length_m=24.768)
    assert isinstance(prof, RandomProfile)
    start = 500.0 - np.sort(np.random.default_rng(0).uniform(0.0, 75.0, 50))
    step = 400 / 3.6 * 1e-3
    x = start[None, :] + step * np.arange(3000)[:, None]
    calls = []
    monkeypatch.setattr(RandomProfile, "_on_paths_phasors",
                        lambda self, *a: calls.append(1))    # type: ignore[func-returns-value]
    r, rx = prof.on_paths(x, start_m=start, step_m=step)
    assert not calls                                    # the track grid was used
    monkeypatch.undo()
    r_ref, rx_ref = prof._on_paths_phasors(x, start, step)
    # interpolation remainder bound 1e-13 of the RMS (TRACK_TOLERANCE); measured 6e-14
    # (elevation) and 3e-13 (slope: the phases' rounding) of the largest value
    assert np.max(np.abs(r - r_ref)) <= 1e-12 * np.max(np.abs(r_ref))
    assert np.max(np.abs(rx - rx_ref)) <= 2e-12 * np.max(np.abs(rx_ref))
    assert prof.track_spacing_m() > step                 # one grid node per step here


@pytest.mark.parametrize("offset", [1e-12, 1e-6])
def test_track_synthesis_at_positions_rounded_off_the_paths(offset: float) -> None:
    """Positions a little off ``start + k step`` (a run's ``x0 + v t`` rounds to ~1e-13 m
    off them): within 1e-12 m plus their rounding the elevation is corrected by slope x offset,
    further off they are evaluated where they are; either way the direct sums at the
    positions themselves are reproduced."""
    prof = parse_irregularity("random:0.3e-3:2", span_length_m=24.768)
    start = 300.0 - np.linspace(0.0, 75.0, 40)
    step = 0.12
    x = start[None, :] + step * np.arange(2000)[:, None]
    x = x + np.random.default_rng(3).uniform(-offset, offset, x.shape)
    r, rx = prof.on_paths(x, start_m=start, step_m=step)
    sub = x[::37]
    ref = prof.elevation_m(sub.ravel()).reshape(sub.shape)
    ref_x = prof.slope(sub.ravel()).reshape(sub.shape)
    # uncorrected, the 1e-6 m offsets would be |r'| 1e-6 ~ 3e-10 m, 1e-6 of the largest
    # elevation; the bounds are those of the exact paths
    assert np.max(np.abs(r[::37] - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert np.max(np.abs(rx[::37] - ref_x)) <= 2e-12 * np.max(np.abs(ref_x))


def test_phasor_powers_equal_the_exact_phasors() -> None:
    """exp(i j angle) by doubling (products of <= log2(n) directly evaluated powers, each
    at an exact power-of-two multiple of the angle) against the phasors at the exact
    phases j angle (long double, 64-bit mantissa), every j and column."""
    from maglevkit.vehicle.irregularities import _phasor_powers

    angle = np.array([1e-3, 0.0141, 0.7, 2.9, -1.3])
    n = 300
    got = _phasor_powers(angle, n)
    ph = np.arange(n).astype(np.longdouble)[:, None] * angle.astype(np.longdouble)
    exact = (np.cos(ph) + 1j * np.sin(ph)).astype(complex)
    # <= 9 factors of ~1 ulp each: bound 2e-15 on unit phasors (measured 3.4e-16; the
    # direct exp(1j * (j * angle)) in double is 5e-14 off, the rounding of j angle)
    assert np.max(np.abs(got - exact)) <= 2e-15
    assert np.array_equal(got[0], np.ones(angle.size))


def test_span_coordinate_equals_np_mod() -> None:
    """SpanSag's span coordinate u - floor(u) is np.mod(u, 1) bit for bit, also behind the
    origin and a rounding below a pier (where both give 1.0)."""
    sag = SpanSag(amplitude_m=0.5e-3, span_length_m=24.768, origin_m=3.0)
    x = np.concatenate([np.random.default_rng(2).uniform(-5e3, 5e4, 20000),
                        [3.0, 3.0 - 1e-15, 3.0 + 24.768, -21.768, 3.0 - 1e-300]])
    np.testing.assert_array_equal(sag._xi(x), np.mod((x - 3.0) / 24.768, 1.0))
