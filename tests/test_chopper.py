"""The chopper bound ``U >= -R_ec I_L`` written once (``plant.chopper_floor``).

Independent reference: the coil current of eq. 8's circuit, ``I = (U + R_ec I_L) /
(R_el + R_ec)``, must come out >= 0 for the bounded voltage and exactly 0 where the
bound acts; NumPy and CasADi give the same values, NaN included.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from maglevkit.plant import chopper_floor


def test_bound_makes_the_coil_current_non_negative_and_leaves_allowed_commands() -> None:
    r_el, r_ec = np.array([1.3, 1.3, 0.8]), np.array([5.75, 5.75, 2.0])
    i_l = np.array([30.0, 30.0, -2.0])
    u = np.array([-440.0, 10.0, -1.0])
    out = chopper_floor(u, i_l, r_ec)
    coil = (out + r_ec * i_l) / (r_el + r_ec)
    assert coil[0] == 0.0                       # -440 V would reverse it: held at I = 0
    assert out[1] == 10.0 and coil[1] > 0.0     # allowed commands pass unchanged
    assert out[2] == 4.0 and coil[2] == 0.0     # I_L < 0: the bound is positive
    assert np.all(coil >= 0.0)


def test_numpy_and_casadi_agree_and_keep_nan() -> None:
    u = np.array([-440.0, 10.0, np.nan])
    i_l, r_ec = np.array([30.0, 30.0, 30.0]), np.array([5.75, 5.75, 5.75])
    us, ils = ca.SX.sym("u", 3), ca.SX.sym("i", 3)
    f = ca.Function("f", [us, ils], [chopper_floor(us, ils, ca.DM(r_ec))])
    np.testing.assert_array_equal(np.asarray(f(u, i_l)).ravel(), chopper_floor(u, i_l, r_ec))
    assert np.isnan(chopper_floor(u, i_l, r_ec)[2])


def test_a_circuit_without_eddy_path_at_zero_current_has_no_bound_and_no_warning() -> None:
    """R_ec = inf (no eddy path) at I_L = 0: the bound -R_ec I_L is inf * 0, undefined; the
    command passes unchanged, in NumPy without a RuntimeWarning (pytest turns none into an
    error here: the filter below), and CasADi gives the same."""
    import warnings

    u = np.array([-5.0, 3.0])
    i_l, r_ec = np.array([0.0, 1.0]), np.array([np.inf, np.inf])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = chopper_floor(u, i_l, r_ec)
    np.testing.assert_array_equal(out, u)
    us, ils = ca.SX.sym("u", 2), ca.SX.sym("i", 2)
    f = ca.Function("f", [us, ils], [chopper_floor(us, ils, ca.DM(r_ec))])
    np.testing.assert_array_equal(np.asarray(f(u, i_l)).ravel(), u)
