"""The car body's coupled lateral-roll ("lower sway") mode of the cross-section vehicle is
damped as its file says (20 %): from the eigenvalues of the linearised model, and in a
closed-loop run from the decay of the swing after a step force.  And why it was not with
the lateral dampers at the air springs' height (docs/cross_section.md)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from maglevkit.vehicle.crosssection import CrossSectionData, CrossSectionMechanics, load_cross_section

G0 = 9.80665


def _sway_modes(data: CrossSectionData) -> list[tuple[float, float]]:
    """(frequency [Hz], damping ratio) of the two car-body sway modes (lateral and roll of
    the car body dominant) of the linearised model, lowest first.

    The magnets with their gap controllers are stood in for by spring-dampers of the
    controllers' design (5 Hz, 0.7, each magnet moving half the slice's mass); the
    stiffness includes the static preloads (``linearised_stiffness``)."""
    mech = CrossSectionMechanics(data)
    m, w, zeta = 0.5 * data.total_mass_kg, 2 * math.pi * 5.0, 0.7
    k, c = m * w * w, 2 * zeta * w * m
    s = mech.with_magnet_springs(k, k, levitation_damping_N_s_per_m=c,
                                 guidance_damping_N_s_per_m=c)
    a, _ = s.state_matrices()
    n = s.n_dof
    a[n:, :n] -= np.linalg.solve(s.M, mech.linearised_stiffness([0.0, G0]) - mech.system.K)
    lam, vec = np.linalg.eig(a)
    iy, iphi = s.dof_names.index("car_body.y"), s.dof_names.index("car_body.phi")
    out = []
    for lk, v in zip(lam, vec.T, strict=True):
        q = np.abs(v[:n])
        if lk.imag > 0 and q.argmax() in (iy, iphi):
            out.append((abs(lk) / (2 * math.pi), -lk.real / abs(lk)))
    return sorted(out)


def test_lower_sway_mode_is_damped_20_percent() -> None:
    modes = _sway_modes(load_cross_section())
    assert len(modes) == 2
    (f1, z1), (f2, z2) = modes
    # the file's lateral damping is derived for 20 % (4 digits of the damping: +-0.1 %)
    assert 0.45 < f1 < 0.6 and z1 == pytest.approx(0.20, abs=2e-3)
    # the upper sway mode is damped about as much (measured 21.5 %)
    assert 1.0 < f2 < 1.2 and 0.18 < z2 < 0.25


def test_dampers_at_the_air_springs_height_cannot_reach_20_percent() -> None:
    """With the dampers on the air springs' line (0.95 m below the car body's centre of
    mass), the lower sway mode moves them little; more damping locks them and the mode
    becomes a roll about them: the damping ratio peaks below 20 % whatever the damping."""
    d = load_cross_section()
    best = 0.0
    for c in np.geomspace(2e3, 1e5, 15):
        low = dataclasses.replace(d, lateral_damper_z_m=None,
                                  spring_lateral_damping_N_s_per_m=float(c))
        best = max(best, _sway_modes(low)[0][1])
    # measured maximum 19.5 % near 2.5e4 N s/m per damper; 5.7e3 N s/m (the old file) 13 %
    assert 0.15 < best < 0.197
    old = dataclasses.replace(d, lateral_damper_z_m=None, spring_lateral_damping_N_s_per_m=5.7e3)
    assert _sway_modes(old)[0][1] == pytest.approx(0.132, abs=5e-3)


def test_the_swing_decays_at_about_20_percent_in_a_closed_loop_run() -> None:
    """A 5 kN step force on the car body (magnets through the bank, gap controllers): the
    decay of its lateral swing about the final position over four half-periods gives
    the damping ratio, ``delta = ln(a_k / a_k+1)`` per half-period, ``zeta = delta /
    sqrt(pi^2 + delta^2)``."""
    from scipy.signal import find_peaks

    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind

    run = CrossSectionModel().run(speed_m_per_s=0.0, duration_s=8.0,
                                  crosswind=Crosswind(5000.0, start_s=0.2, shape="step"))
    t, y = run.dataset.time.values, run.dataset.car_body_y.values
    swing = np.abs(y - y[-1])
    peaks, _ = find_peaks(swing)
    peaks = peaks[t[peaks] > 0.3][:5]
    delta = math.log(swing[peaks[0]] / swing[peaks[-1]]) / (len(peaks) - 1)
    zeta = delta / math.sqrt(math.pi ** 2 + delta ** 2)
    # measured 19 % (the linear stand-in: 20 %; the old file 11 %); the controllers are
    # not the stand-in's springs, so +-5 points
    assert 0.15 < zeta < 0.25
