"""The two-quadrant chopper's ``I >= 0`` in the controllers' own laws (issue 23): the
single-magnet cascade does not command below 0 V where the measured current is at zero,
and the NMPC's plan keeps the predicted coil currents >= 0 (a hard constraint)."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

import maglevkit as mk
from maglevkit.control import closed_loop, design_gap_controller
from maglevkit.control.cascade import ZERO_CURRENT_A, GapController
from maglevkit.control.model import MagnetHeaveModel
from maglevkit.control.realtime import RealTimeMPC
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

S0 = 0.010
START_GAP = 0.007        # 3 mm below the reference at the design current: far too much force


@pytest.fixture(scope="module")
def plant(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    maps = mk.build_maps(u_magnet, gaps=np.linspace(0.004, 0.02, 17),
                         currents=np.linspace(0, 80, 33), progress=False)
    f0 = float(mk.solve_statics(u_magnet, gaps=S0, currents=20.0).force_N)
    return maps, f0, HeaveMass(f0 / STANDARD_GRAVITY)


def _cascade_run(u_magnet, maps, veh, design, freewheel):  # type: ignore[no-untyped-def]
    psi = np.atleast_1d(mk.solve_statics(u_magnet, gaps=START_GAP, currents=20.0)
                        .flux_linkage_Wb)
    return closed_loop(mk.CurrentModel(maps, freewheel=freewheel), veh, design,
                       duration_s=0.1, dt_s=1e-3, initial_gap_m=START_GAP,
                       initial_current_A=20.0, initial_flux_Wb=psi)


def test_cascade_does_not_command_below_zero_at_zero_current(u_magnet, plant) -> None:  # type: ignore[no-untyped-def]
    """Starting 3 mm low at the design current, the cascade cuts the flux at the voltage
    limit and the current reaches zero.  A four-quadrant law then commands a negative
    voltage at zero current (about -140 V: on a plant without diodes the current goes to
    -1.2 A), the two-quadrant law (the default) does not command below 0 V there."""
    maps, _, veh = plant
    design = design_gap_controller(u_magnet, mass_kg=veh.mass_kg, gap_m=S0, current_A=20.0)
    assert design.two_quadrant
    four = dataclasses.replace(design, two_quadrant=False)
    for fw in (True, False):
        two_q = _cascade_run(u_magnet, maps, veh, design, fw)
        four_q = _cascade_run(u_magnet, maps, veh, four, fw)
        at_zero = two_q.currents_A[:-1, 0] <= ZERO_CURRENT_A
        at_zero4 = four_q.currents_A[:-1, 0] <= ZERO_CURRENT_A
        print("freewheel", fw, "zero-current samples", at_zero.sum(), at_zero4.sum(),
              "commands there", two_q.voltages_V[:-1, 0][at_zero],
              four_q.voltages_V[:-1, 0][at_zero4], "min I", four_q.currents_A.min())
        assert at_zero.any() and at_zero4.any()          # the scenario reaches I = 0
        assert np.all(two_q.voltages_V[:-1, 0][at_zero] >= 0.0)
        # the scenario would drive the current negative: measured -137/-140 V
        assert four_q.voltages_V[:-1, 0][at_zero4].min() < -100.0
        if not fw:
            assert four_q.currents_A.min() < -0.5           # measured -1.2 A
    with pytest.raises(mk.ParameterError, match="two_quadrant"):
        GapController(**{**dataclasses.asdict(design), "two_quadrant": "yes"})


def test_mpc_plan_keeps_the_coil_current_nonnegative(plant) -> None:  # type: ignore[no-untyped-def]
    """From states that call for a fast flux reduction (gap below the reference, current
    at or above the trim), the NMPC's plan holds the predicted coil currents at zero
    (U = -R_ec I_L, the chopper's floor) instead of the -440 V its cost would choose: the
    hard ``I >= 0`` rows are active; the coil currents never below zero."""
    maps, f0, veh = plant
    model = MagnetHeaveModel(maps, mass_kg=veh.mass_kg)
    x, u, d = ca.MX.sym("x", model.nx), ca.MX.sym("u", model.nu), ca.MX.sym("d", model.nd)
    coil = ca.Function("coil", [x, u, d], [model.coil_currents(x, u, d)])
    ctl = RealTimeMPC(model, gap_ref_m=S0, sample_time_s=1e-3, horizon=5, interval_s=2e-3)
    for x0 in ([22.0, START_GAP, 0.0], [10.0, 0.009, -0.1]):
        plan = ctl.solve_ocp(x0, [0.0, 0.0])
        i_coil = np.array([float(coil(plan["states"][k], plan["inputs_V"][k], [0.0, 0.0]))
                           for k in range(ctl.horizon)])
        print(x0, plan["inputs_V"].ravel(), i_coil)
        # the constraint rows are linear in (I_L, U), so the QP's plan meets them exactly
        # (measured 0 to 1e-15 A); 1e-9 A allows rounding
        assert i_coil.min() >= -1e-9
        assert abs(i_coil[0]) < 1e-9                       # active at the first interval
        assert plan["inputs_V"][0, 0] > -ctl.voltage_limit_V + 1.0  # not the voltage limit
