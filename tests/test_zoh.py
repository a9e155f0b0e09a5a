"""The one exact zero-order-hold step (``maglevkit.vehicle.zoh``) against closed forms."""

from __future__ import annotations

import math

import numpy as np

from maglevkit.vehicle.zoh import exact_zoh_step


def test_first_order_lag_and_undamped_oscillator_closed_forms() -> None:
    # x' = -x/T + u: Ad = exp(-dt/T), Bd = T (1 - exp(-dt/T))
    tau, dt = 0.3, 0.01
    ad, bd = exact_zoh_step([[-1 / tau]], [[1.0]], dt)
    # expm (scaled Pade) agrees with the closed form to a few ulp of order-1 numbers
    assert abs(ad[0, 0] - math.exp(-dt / tau)) < 1e-15
    assert abs(bd[0, 0] - tau * (1 - math.exp(-dt / tau))) < 1e-15
    # q'' = -w^2 q + f: Ad = [[cos, sin/w], [-w sin, cos]], Bd = [(1-cos)/w^2, sin/w]
    w, dt = 2 * math.pi * 3.0, 0.02
    ad, bd = exact_zoh_step([[0.0, 1.0], [-w * w, 0.0]], [[0.0], [1.0]], dt)
    c, s = math.cos(w * dt), math.sin(w * dt)
    np.testing.assert_allclose(ad, [[c, s / w], [-w * s, c]], rtol=0, atol=1e-13)
    np.testing.assert_allclose(bd[:, 0], [(1 - c) / w**2, s / w], rtol=0, atol=1e-13)
    ad[0, 0] = 0.0          # writable copies
