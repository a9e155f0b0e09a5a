"""U-magnet EMC against the independent 2-D FEM of benchmarks/fem_u_magnet.py (issue 2).

The errors asserted here are the ones *measured* (docs/validation_fem.md) plus a margin.
Over the whole grid (4-20 mm, 5-80 A) the EMC is within -7.6 ... +3.9 % in force and
-7.9 ... +0.1 % in flux linkage; the points tested here:

    s [mm]  I [A]   err F [%]   err psi [%]      (EMC - FEM)/FEM, AISI 1008
      4       5       -1.14        -0.37
      8      40       -7.59        -5.51     (default run: the knee, largest force error)
     20      80       -1.4         -7.9
    linear iron mu_r = 200, I = 10 A, s = 8 mm:  err F -6.43 %, err psi -3.48 %

(before the flank-leakage and distributed-coil model of docs/equations.md sec. 6 these were
up to +48 % in force and -25 % in flux linkage).  The FEM itself is accurate to < 0.1 %
(h/2 mesh study, virtual work vs Maxwell stress).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk

from .conftest import HAVE_SKFEM, SKIP_FEM_VAR, load_script

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fem_u_magnet.py"

# Without scikit-fem (the "validation" extra, which `make test` installs) the FEM checks
# cannot run.  That is a failure, not a silent skip, unless it is asked for explicitly
# with MAGLEVKIT_SKIP_FEM=1; the pytest header states which (tests/conftest.py).
needs_fem = pytest.mark.skipif(not HAVE_SKFEM, reason="scikit-fem not installed and "
                               f"{SKIP_FEM_VAR}=1: FEM validation skipped on request")


def test_fem_extra_is_installed() -> None:
    if not HAVE_SKFEM and os.environ.get(SKIP_FEM_VAR) == "1":
        pytest.skip(f"scikit-fem not installed; FEM validation skipped ({SKIP_FEM_VAR}=1)")
    assert HAVE_SKFEM, ("scikit-fem is not installed, so the FEM validation cannot run: "
                        "pip install -e '.[validation]' (make test does), or set "
                        f"{SKIP_FEM_VAR}=1 to skip it explicitly")


def _fem():  # type: ignore[no-untyped-def]
    return load_script(_PATH)


def _emc(s: float, current: float, **opts: bool) -> tuple[float, float]:
    mag = mk.load_magnet("u-magnet", eddy_currents=False, **opts)
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    return float(np.ravel(sol.force_N)[0]), float(np.ravel(sol.flux_linkage_Wb)[0])


def _err(emc: float, fem: float) -> float:
    return 100.0 * (emc - fem) / fem


# Signed windows: the EMC error must stay within MARGIN percentage points of its measured
# value, on either side.  The EMC is deterministic (Newton to ~1e-15) and the FEM value
# itself is checked to 0.5 % (regression), so 0.5 pp covers both; an error that moves
# it by more fails, whichever direction it goes (the former symmetric abs() windows
# accepted anything within +-7.9 % / +-5.0 %, e.g. a +14 % air-gap permeance error).
MARGIN = 0.5


def _within(err: float, measured: float) -> bool:
    return measured - MARGIN <= err <= measured + MARGIN


@needs_fem
def test_fem_linear_point_against_textbook_and_emc() -> None:
    """Fast: linear iron only (one direct solve each)."""
    fem = _fem()
    # nearly ideal iron, small gap: force -> textbook (measured 1.036 at 1 mm, fringing)
    s, current, n, area = 0.001, 10.0, 600.0, 0.030 * 0.100
    r = fem.solve_full(s, current, mu_r=1e5)
    f_tb = fem.MU0 * (n * current) ** 2 * area / (4 * s**2)
    assert 1.0 < r.force_N / f_tb < 1.05
    assert math.isclose(r.coenergy_J, 0.5 * r.psi_Wb * current, rel_tol=1e-9)
    # linear iron mu_i = 200 at 8 mm against the EMC without saturation
    s = 0.008
    r = fem.solve_full(s, current, mu_r=200.0)
    f_emc, psi_emc = _emc(s, current, saturation=False)
    assert math.isclose(r.force_N, 466.8, rel_tol=5e-3)        # FEM regression
    assert math.isclose(r.psi_Wb, 1.3539, rel_tol=5e-3)
    assert _within(_err(f_emc, r.force_N), -6.43), _err(f_emc, r.force_N)
    assert _within(_err(psi_emc, r.psi_Wb), -3.48), _err(psi_emc, r.psi_Wb)


SATURABLE = [
    # the knee point runs by default (one nonlinear FEM solve, ~8 s on an idle 2-core
    # machine, measured 75 s with 8 processes sharing the 2 cores); the others are slow
    (0.008, 40.0, 3913.4, 3.8614, -7.59, -5.51),
    pytest.param(0.004, 5.0, 566.5, 1.2531, -1.14, -0.37, marks=pytest.mark.slow),
    pytest.param(0.020, 80.0, 2409.6, 4.2676, -1.4, -7.9, marks=pytest.mark.slow),
]


@needs_fem
@pytest.mark.parametrize(("s", "current", "f_fem", "psi_fem", "err_f", "err_psi"), SATURABLE)
def test_emc_against_fem_saturable(s: float, current: float, f_fem: float, psi_fem: float,
                                   err_f: float, err_psi: float) -> None:
    fem = _fem()
    force, psi = fem.solve_fem(s, current)
    assert math.isclose(force, f_fem, rel_tol=5e-3)              # FEM regression
    assert math.isclose(psi, psi_fem, rel_tol=5e-3)
    f_emc, psi_emc = _emc(s, current)
    assert _within(_err(f_emc, force), err_f), _err(f_emc, force)
    assert _within(_err(psi_emc, psi), err_psi), _err(psi_emc, psi)
