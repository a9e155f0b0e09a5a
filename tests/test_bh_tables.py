"""Tabulated B-H curves (issue 12, part 1; issue 10 crash): physics by construction.

The interpolant of :class:`maglevkit.TabulatedBH` must satisfy ``0 < dH/dB <= 1/mu0``
everywhere for every accepted table (docs/equations.md, "Tabulated B-H curves"), be a
CasADi expression with a continuous derivative ("smooth") or the FEM tools' piecewise
linear curve ("linear"), and load from TOML lists or a two-column CSV file.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import PchipInterpolator
from scipy.optimize import brentq

import maglevkit as mk
from maglevkit.materials import CHORD_TOLERANCE, MU0, read_bh_csv

U = 1.0 / MU0
# The bound holds exactly in exact arithmetic; evaluated slopes are sums of a few rounded
# terms of size <= U, so they may exceed U by a few ulps (measured: 0 on the steel table).
# 1e-12 allows ~4500 ulps and is far below any physical violation (the PCHIP tail that
# the old check refused is 6 % above U).
ROUND = 1e-12


def _slope_function(mat: mk.Material) -> ca.Function:
    b = ca.SX.sym("b")
    h = mat.field_strength(b)
    return ca.Function("dh", [b], [ca.jacobian(h, b)])


def _casadi_slopes(mat: mk.Material, b: np.ndarray) -> np.ndarray:
    f = _slope_function(mat).map(b.size)
    return np.asarray(f(ca.DM(b).T)).ravel()


def _sample_points(mat: mk.TabulatedBH, n_uniform: int = 20001) -> np.ndarray:
    """A uniform grid over +-1.2 B_n plus both sides and the middle of every piece."""
    b_end = mat.B[-1]
    x = np.asarray(mat._x)
    eps = 1e-9 * b_end
    near = np.concatenate([x, x + eps, np.maximum(x - eps, 0.0), 0.5 * (x[1:] + x[:-1])])
    return np.unique(np.concatenate([np.linspace(-1.2 * b_end, 1.2 * b_end, n_uniform),
                                     near, -near, [0.0]]))


def _assert_physical(mat: mk.TabulatedBH) -> None:
    """0 < dH/dB <= 1/mu0 from the CasADi derivative and from chords of dense samples."""
    b = _sample_points(mat)
    g = _casadi_slopes(mat, b)
    assert np.all(g > 0.0), f"dH/dB = {g.min():.3g} <= 0 at B = {b[np.argmin(g)]:.6g} T"
    assert np.all(g <= U * (1.0 + ROUND)), \
        f"mu_r,diff = {1.0 / (MU0 * g.max()):.9f} < 1 at B = {b[np.argmax(g)]:.6g} T"
    # Difference quotients of the NumPy evaluation on the uniform grid: chords of a C0
    # function whose slope is in (0, U] are in (0, U] (mean value theorem).  They carry the
    # rounding of H (|H| <= 4e6 A/m, 2 ulp = 1.8e-9 A/m) over steps of 1.2e-4 B_n (B_n >=
    # 1e-5 T here): <= 1.5e-3 A/m per T, 2e-9 U; bound 1e-6 U.
    bu = np.linspace(-1.2 * mat.B[-1], 1.2 * mat.B[-1], 20001)
    h = mat.field_strength(bu)
    chords = np.diff(h) / np.diff(bu)
    assert np.all(chords > 0.0)
    assert np.all(chords <= U * (1.0 + 1e-6))
    pos = bu > 0.0
    mu_r = bu[pos] / (MU0 * h[pos])
    assert mu_r.min() >= 1.0 - ROUND


# ---------------------------------------------------------------- the FEM-library table
# A low-carbon (1010-type) steel table as FEM material libraries ship it, extended with the
# two saturated chords of issue 12: dB/dH = 1.05 mu0, then mu0 to 7 significant digits.
STEEL_H = [0, 150, 250, 400, 600, 800, 1000, 1500, 2000, 3000, 5000, 8000, 12000, 20000,
           40000, 80000, 160000, 1.6e6]
_B = [0, 0.25, 0.55, 0.90, 1.10, 1.20, 1.27, 1.37, 1.43, 1.51, 1.60, 1.68, 1.75, 1.83, 1.94, 2.05]
_B1 = _B[-1] + 1.05 * MU0 * 80000


def steel_table(last_chord_over_mu0: float | None = None) -> list[float]:
    """The table; None: B printed to 7 digits (last chord 0.9999998 mu0), else that chord."""
    b1 = float(f"{_B1:.7g}")
    if last_chord_over_mu0 is None:
        return [*_B, b1, float(f"{_B1 + MU0 * 1.44e6:.7g}")]
    return [*_B, b1, b1 + last_chord_over_mu0 * MU0 * 1.44e6]


@pytest.mark.parametrize("last", [None, 1.0, 1.0 - 2e-7, 1.0 + 2e-7])
@pytest.mark.parametrize("interpolation", ["smooth", "linear"])
def test_fem_library_steel_table_loads_and_is_physical(last: float | None,
                                                       interpolation: str) -> None:
    B = steel_table(last)
    slopes = np.diff(B) / np.diff(STEEL_H) / MU0
    # the table really has the issue's tail (the B values are rounded to 7 digits)
    assert slopes[-2] == pytest.approx(1.05, abs=1e-5)
    assert slopes[-1] == pytest.approx(1.0, abs=1e-6)
    mat = mk.TabulatedBH(tuple(STEEL_H), tuple(B), name="1010", interpolation=interpolation)
    _assert_physical(mat)
    assert mat.initial_relative_permeability >= 1.0
    # passes through the points; only a point after a chord flatter than mu0 moves, by at
    # most CHORD_TOLERANCE of its chord's H increment (measured 0.29 A/m of 1.44e6 A/m for
    # the 7-digit table, 0 for chords >= mu0)
    moved = mat.max_adjustment_A_per_m
    assert moved <= CHORD_TOLERANCE * 1.44e6
    np.testing.assert_allclose(mat.field_strength(np.asarray(B)), STEEL_H, rtol=1e-12,
                               atol=moved + 1e-9)
    # slope mu0 above the last point
    h1, h2 = mat.field_strength(np.array([4.5, 5.0]))
    assert 0.5 / (h2 - h1) == pytest.approx(MU0, rel=1e-12)


def test_the_steel_table_defeats_pchip() -> None:
    # The case is the one the issue reports: a PCHIP of H(B) through these points has
    # mu_r,diff = 0.94 < 1 in the tail (so a test of the new interpolant on it is not vacuous).
    B = steel_table()
    g = PchipInterpolator(B, STEEL_H).derivative()(np.linspace(0.0, B[-1], 100001))
    assert 1.0 / (MU0 * g.max()) < 0.95


def test_smooth_interpolant_is_c1_everywhere() -> None:
    mat = mk.TabulatedBH(tuple(STEEL_H), tuple(steel_table()))
    x = np.asarray(mat._x)
    scale = 1e-10 * x[-1]
    left = _casadi_slopes(mat, np.maximum(x - scale, 0.0))
    right = _casadi_slopes(mat, x + scale)
    # H' is continuous, so over 2e-10 T it changes by H'' * 2e-10 T only: measured at most
    # 6e-3 A/m/T, 1.6e-8 of the slope there; bound 1e-6 (a kink is a jump of order the
    # slopes themselves: 0.5 U for the linear law below)
    assert np.max(np.abs(left - right) / np.maximum(np.abs(right), 1.0)) < 1e-6
    # the odd extension has an even slope: continuous at 0
    g0 = _casadi_slopes(mat, np.array([-scale, 0.0, scale]))
    assert np.ptp(g0) / g0[1] < 1e-6
    # the linear law does have kinks (so the check above can fail)
    lin = mk.TabulatedBH(tuple(STEEL_H), tuple(steel_table()), interpolation="linear")
    xl = np.asarray(lin._x)[1:-1]
    jump = np.abs(_casadi_slopes(lin, xl - scale) - _casadi_slopes(lin, xl + scale))
    assert jump.max() / U > 0.1


# ---------------------------------------------------------------- random physical tables
@st.composite
def physical_tables(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """Random first-magnetisation data: H increasing, M(H) non-decreasing and bounded."""
    n = draw(st.integers(1, 14))
    log_dh = draw(st.lists(st.floats(-1.0, 6.0), min_size=n, max_size=n))
    H = np.concatenate([[0.0], np.cumsum(10.0 ** np.asarray(log_dh))])
    # magnetisation increments >= 0, some exactly 0 (saturated, chord exactly mu0), and
    # any mix of steep and flat chords, in any order (not only convex curves)
    w = draw(st.lists(st.one_of(st.just(0.0), st.floats(1e-9, 1.0)), min_size=n, max_size=n))
    if sum(w) == 0.0:
        w[0] = 1.0
    j_sat = draw(st.floats(0.01, 2.4))  # saturation polarisation mu0 M_s [T]
    M = np.concatenate([[0.0], np.cumsum(w) / sum(w) * j_sat / MU0])
    return H, MU0 * (H + M)


@settings(max_examples=150, deadline=None)
@given(physical_tables(), st.sampled_from(["smooth", "linear"]))
def test_random_physical_tables_never_violate_the_bound(
        table: tuple[np.ndarray, np.ndarray], interpolation: str) -> None:
    H, B = table
    mat = mk.TabulatedBH(tuple(H), tuple(B), interpolation=interpolation)
    _assert_physical(mat)
    # B = mu0 (H + M) rounds, so M-flat chords come out a few ulps flatter or steeper than
    # mu0 and get adjusted or treated as flat: the points move by at most 64 ulp(B_n)/mu0
    # (2.2e-8 A/m at 2.4 T) per such chord, at most 14 chords: atol 1e-6 A/m (plus relative
    # rounding of H, 1e-9)
    np.testing.assert_allclose(mat.field_strength(B), H, rtol=1e-9, atol=1e-6)
    assert 1.0 <= mat.initial_relative_permeability < np.inf


# ---------------------------------------------------------------- accuracy (independent)
@pytest.mark.parametrize("name", ["AISI 1008", "9SMnPb28"])
def test_smooth_curve_reproduces_a_known_curve(name: str) -> None:
    # Sample a smooth Roschke curve at 40 points (geometric in H, up to 2 T, as measured
    # tables are) and compare the interpolants with the curve itself.
    true = mk.get_material(name)
    h_max = float(true.field_strength(2.0))
    Hs = np.concatenate([[0.0], np.geomspace(1e-4 * h_max, h_max, 40)])
    Bs = np.array([0.0, *(brentq(lambda b, h=h: float(true.field_strength(b)) - h, 0.0, 5.0,
                                 xtol=1e-14) for h in Hs[1:])])
    b = np.linspace(0.05, Bs[-2], 20001)  # inside the table, before the last interval
    ht = true.field_strength(b)
    err = {k: np.max(np.abs(mk.TabulatedBH(tuple(Hs), tuple(Bs), interpolation=k)
                            .field_strength(b) - ht) / ht) for k in ("smooth", "linear")}
    # measured: smooth 4.4e-3 / 3.6e-3, linear 2.3e-2 / 2.2e-2 (AISI 1008 / 9SMnPb28)
    assert err["smooth"] < 6e-3
    assert err["linear"] < 3e-2
    assert err["smooth"] < 0.3 * err["linear"]


# ---------------------------------------------------------------- rounding allowance
def test_chords_within_rounding_of_mu0_are_accepted_and_others_refused() -> None:
    H = (0, 1000, 2000, 1e6)
    b2 = 1.5 + MU0 * 998000 * (1.0 - 0.5 * CHORD_TOLERANCE)
    mat = mk.TabulatedBH(H, (0, 1.2, 1.5, b2))
    # the last point moves down by the deficit, 0.5e-3 of 998000 A/m (to within rounding)
    assert mat.max_adjustment_A_per_m == pytest.approx(0.5 * CHORD_TOLERANCE * 998000, rel=1e-3)
    _assert_physical(mat)
    b2_bad = 1.5 + MU0 * 998000 * (1.0 - 2.0 * CHORD_TOLERANCE)
    with pytest.raises(mk.MaterialError, match="between points 2 and 3 .* below mu0 by more"):
        mk.TabulatedBH(H, (0, 1.2, 1.5, b2_bad))


# ---------------------------------------------------------------- issue 10: zero initial slope
ISSUE10_H = (0, 100, 500, 1000, 10000)
ISSUE10_B = (0, 0.8, 1.2, 1.5, 1.6)


def test_issue10_table_has_a_finite_initial_permeability() -> None:
    # PCHIP's end slope of H(B) was 0 here (mu_r(0) = 1/0: ZeroDivisionError); the end
    # slope is now limited to [d0/2, min(2 d0, 1/mu0)] with the first chord d0 = 125 A/m/T.
    mat = mk.TabulatedBH(ISSUE10_H, ISSUE10_B)
    mu0_r = mat.initial_relative_permeability
    chord = 0.8 / (MU0 * 100)
    # here the end formula is negative and the limit d0/2 applies: mu_r(0) = 2 x chord
    assert mu0_r == pytest.approx(2.0 * chord, rel=1e-12)
    assert isinstance(mat.linearized(), mk.ConstantPermeability)
    _assert_physical(mat)


def _u_magnet_with(material: dict) -> dict:
    import sys
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    p = tomllib.loads((Path(mk.__file__).parent / "data" / "u-magnet.toml").read_text())
    p["magnet"]["material"] = "table_steel"
    p["rail"]["material"] = "table_steel"
    p["materials"] = {"table_steel": material}
    p["provenance"]["materials.table_steel"] = "[E] test table"
    return p


def test_issue10_table_solves_statics() -> None:
    p = _u_magnet_with({"H": list(ISSUE10_H), "B": list(ISSUE10_B)})
    mag = mk.build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
    currents = np.array([0.0, 5.0, 20.0, 80.0])
    sol = mk.solve_statics(mag, gaps_m=0.010, currents_A=currents[:, None])
    assert sol.force_N[0] == 0.0
    assert np.all(np.diff(sol.force_N) > 0.0)
    # ideal iron bounds the saturable force from above at every point; at 80 A the table
    # (saturating at 1.6 T) must be well below it (measured ratios 0.99, 0.89, 0.11 at
    # 5, 20, 80 A)
    p_ideal = _u_magnet_with({"H": list(ISSUE10_H), "B": list(ISSUE10_B)})
    p_ideal["magnet"]["material"] = p_ideal["rail"]["material"] = "ideal"
    del p_ideal["materials"], p_ideal["provenance"]["materials.table_steel"]
    ideal = mk.solve_statics(mk.build_magnet(p_ideal, options=mk.ModelOptions(eddy_currents=False)),
                             gaps_m=0.010, currents_A=currents[:, None])
    assert np.all(sol.force_N[1:] < ideal.force_N[1:])
    assert sol.force_N[-1] < 0.5 * ideal.force_N[-1]
    # the unsaturated variant (initial permeability) solves too
    lin = mk.solve_statics(mag.with_options(saturation=False), gaps_m=0.010, currents_A=20.0)
    assert lin.force_N > 0.0


# ---------------------------------------------------------------- CSV files and TOML
def _csv(tmp_path: Path, text: str, name: str = "steel.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("text", [
    "H [A/m], B [T]\n0, 0\n100, 0.8\n500, 1.2\n1000, 1.5\n10000, 1.6\n",
    "# steel, measured\n\nH,B\n0,0\n100,0.8\n500,1.2\n1000,1.5\n10000,1.6\n",
    "0 0\n100\t0.8\n500   1.2\n1000 1.5\n1e4 1.6\n",
    "H (A/m); B (T)\n0;0\n100;0.8\n500;1.2\n1000;1.5\n10000;1.6\n",
    "H [A/m]  B [T]\n0 0\n100 0.8\n500 1.2\n1000 1.5\n10000 1.6\n",
    "0,0,\n100,0.8,\n500,1.2,\n1000,1.5,\n10000,1.6,\n",  # spreadsheet trailing commas
])
def test_csv_reads_the_same_points(tmp_path: Path, text: str) -> None:
    assert read_bh_csv(_csv(tmp_path, text)) == (tuple(map(float, ISSUE10_H)),
                                                 tuple(map(float, ISSUE10_B)))


@pytest.mark.parametrize(("text", "msg"), [
    ("H, B\n0, 0\n100, 0.8, 3\n", "line 3: expected 2 numbers"),
    ("0, 0\n100, x\n", "line 2: .* is not two numbers"),
    ("0, 0\nH, B\n100, 0.8\n", "only the first line may be a header"),
    ("B [T], H [A/m]\n0, 0\n0.8, 100\n", "names the columns B, H"),
    ("H [kA/m], B [T]\n0, 0\n0.1, 0.8\n", "unit 'kA/m'.*A/m"),
    ("H [A/m], B [mT]\n0, 0\n100, 800\n", "unit 'mT'"),
    ("H, B, mu\n0, 0\n", "header must name 2 columns"),
    ("0;0\n100;0,8\n", "expected 2 numbers"),  # decimal comma
    ("# only a comment\n", "at least 2 points"),
    ("0, 0\n100, nan\n", "finite"),
    ("", "at least 2 points"),
])
def test_malformed_csv_raises(tmp_path: Path, text: str, msg: str) -> None:
    with pytest.raises(mk.MaterialError, match=msg):
        read_bh_csv(_csv(tmp_path, text))


def test_csv_file_errors(tmp_path: Path) -> None:
    with pytest.raises(mk.MaterialError, match="does not exist"):
        read_bh_csv(tmp_path / "nope.csv")
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(mk.MaterialError, match="cannot be read as text"):
        read_bh_csv(tmp_path / "bin.csv")
    # B in mT without a header: caught by the polarisation bound
    p = _csv(tmp_path, "0,0\n100,800\n500,1200\n")
    with pytest.raises(mk.MaterialError, match="polarisation .* check the units"):
        mk.TabulatedBH.from_csv(p)
    # swapped columns without a header: also caught
    p = _csv(tmp_path, "0,0\n0.8,100\n1.2,500\n", "swapped.csv")
    with pytest.raises(mk.MaterialError, match="column order"):
        mk.TabulatedBH.from_csv(p)


def test_from_csv_equals_lists(tmp_path: Path) -> None:
    p = _csv(tmp_path, "H,B\n" + "".join(f"{h},{b}\n"
                                          for h, b in zip(ISSUE10_H, ISSUE10_B, strict=True)))
    mat = mk.TabulatedBH.from_csv(p, interpolation="linear")
    assert mat.name == "steel"
    assert mat == mk.TabulatedBH(ISSUE10_H, ISSUE10_B, name="steel", interpolation="linear")


def test_toml_csv_and_interpolation(tmp_path: Path) -> None:
    rows = zip(STEEL_H, steel_table(), strict=True)
    _csv(tmp_path, "H [A/m], B [T]\n" + "".join(f"{h}, {b}\n" for h, b in rows))
    base = (Path(mk.__file__).parent / "data" / "u-magnet.toml").read_text()
    base = base.replace('material = "AISI 1008"', 'material = "steel1010"')
    base = base.replace("[provenance]\n", '[provenance]\n"materials.steel1010" = "[E] test"\n')
    toml = tmp_path / "magnet.toml"
    results = {}
    for key, extra in [("csv", 'csv = "steel.csv"'),
                       ("csv-linear", 'csv = "steel.csv"\ninterpolation = "linear"'),
                       ("lists", f"H = {STEEL_H}\nB = {steel_table()}")]:
        toml.write_text(base + f"\n[materials.steel1010]\n{extra}\n")
        mag = mk.load_magnet(toml, eddy_currents=False)   # csv path relative to the toml
        results[key] = mk.solve_statics(mag, gaps_m=0.008, currents_A=60.0).force_N
    assert results["csv"] == results["lists"]
    # the linear law is a different curve (measured 0.9 % apart here), not a no-op
    assert results["csv-linear"] != pytest.approx(results["csv"], rel=1e-3)
    assert results["csv-linear"] == pytest.approx(results["csv"], rel=0.05)


@pytest.mark.parametrize(("extra", "msg"), [
    ('csv = "missing.csv"', "does not exist"),
    ('csv = "steel.csv"\nH = [0, 1]\nB = [0, 1]', "either as lists"),
    ("H = [0, 100, 200]", "either as lists"),
    ("", "either as lists"),
    ('H = [0, 100, 200]\nB = [0, 0.5, 0.9]\ninterpolation = "cubic"', "interpolation = 'cubic'"),
    ("H = [0, 100, 200]\nB = [0, 0.5, 0.9]\ninterpolation = 1", "expected a string"),
    ("H = [false, true, true]\nB = [0, 0.5, 0.9]", "list of numbers"),
    ('H = [0, 100, 200]\nB = [0, "0.5", 0.9]', "list of numbers"),
])
def test_toml_material_errors(tmp_path: Path, extra: str, msg: str) -> None:
    _csv(tmp_path, "0,0\n100,0.8\n")
    base = (Path(mk.__file__).parent / "data" / "u-magnet.toml").read_text()
    toml = tmp_path / "magnet.toml"
    toml.write_text(base + f"\n[materials.steel1010]\n{extra}\n")
    with pytest.raises(mk.ParameterFileError, match=msg):
        mk.load_magnet(toml)
