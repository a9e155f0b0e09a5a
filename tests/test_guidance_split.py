"""``flux_paths = "split"`` of the guidance magnet (issue 26, guidance26).

The paths (src/maglevkit/magnets/guidance.py): the air behind the yoke (the yoke's back face
as a thin plate, Joukowski + Schwarz, plus the coil's back side), the legs' window leakage
at mid-length, the legs' top fringe to the rail and the air through the coil's cross-section
beside the yoke; since guide26 the yoke-leg bend from its conformal map
(``bend_reduction``), the bars' flanks as branches of their own (conformal edge law) landing
on the rail beside the face, the face in two strips and the rail beside it in pieces.  The
FEM comparison is tests/test_fem_guidance.py.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.magnets.guidance import bend_reduction, plate_flux


def _params(**magnet: object) -> dict:
    p = copy.deepcopy(mk.load_magnet("tr-guidance").parameters)
    p["magnet"].update(magnet)
    for k in magnet:
        p["provenance"][f"magnet.{k}"] = "[E] test"
    return p


def _series_plate_flux(a: float, b: float, xi: float, n_terms: int = 2001) -> float:
    """Second method: the plate's potential as a Fourier series on the unit circle,
    ``V = sum c_n rho^-n cos(n phi)``, and the flux across ``phi = pi/2`` from ``rho`` to
    infinity ``sum c_n sin(n pi/2) rho^-n`` (Cauchy-Riemann on the circle's exterior)."""
    phi = np.linspace(-np.pi, np.pi, 40001)[:-1]
    f = 0.5 * np.clip(b * np.cos(phi) / a, -1.0, 1.0)
    t = xi / b
    rho = t + np.sqrt(t * t + 1.0)
    n = np.arange(1, n_terms, 2)
    c = 2.0 * (f[None, :] * np.cos(n[:, None] * phi[None, :])).mean(axis=1)
    return float(abs(np.sum(c * np.sin(n * np.pi / 2) * rho ** -n.astype(float))))


@pytest.mark.parametrize("a,b,xi", [(0.06, 0.135, 0.03), (0.06, 0.135, 0.2), (0.02, 0.1, 0.01)])
def test_plate_flux_against_series(a: float, b: float, xi: float) -> None:
    # quadrature of Schwarz's integral vs the Fourier series: both converge to ~1e-6 here
    # (the kinks of the plate's potential: second order for the midpoint rule, c_n ~ n^-2
    # for the series' tail beyond 2000 odd terms)
    assert plate_flux(a, b, xi) == pytest.approx(_series_plate_flux(a, b, xi), rel=2e-5)


def test_plate_flux_limits() -> None:
    # a coil over the whole plate (a = b): the potential is linear, cos(phi)/2 on the
    # circle, so V = cos(phi)/(2 rho) and the flux beyond rho is 1/(2 rho); at xi = 0
    # (rho = 1): 1/2
    assert plate_flux(0.1, 0.1, 0.0) == pytest.approx(0.5, rel=1e-6)
    xi, b = 0.07, 0.1
    rho = xi / b + np.hypot(xi / b, 1.0)
    assert plate_flux(0.1, 0.1, xi) == pytest.approx(0.5 / rho, rel=1e-6)
    # more coil-free plate (smaller a) drives more flux; farther out less crosses
    assert plate_flux(0.05, 0.1, 0.0) > plate_flux(0.1, 0.1, 0.0)
    assert plate_flux(0.05, 0.1, 0.2) < plate_flux(0.05, 0.1, 0.02)


def test_paper_network_unchanged_by_coil_thickness() -> None:
    """The bundled file gained coil_thickness (for "split", its flux_paths since the switch);
    the "paper" network ignores it."""
    with_key = mk.build_magnet(_params(flux_paths="paper"))
    p = copy.deepcopy(with_key.parameters)
    del p["magnet"]["coil_thickness"]
    del p["provenance"]["magnet.coil_thickness"]
    without = mk.build_magnet(p)
    assert with_key.network == without.network


def test_split_network_conserves_and_links() -> None:
    mag = mk.build_magnet(_params(flux_paths="split"), options=mk.ModelOptions(eddy_currents=False))
    sol = mk.solve_statics(mag, gaps_m=[0.009, 0.011], currents_A=[32.0, 25.0])
    A = mag.network.incidence_matrix
    assert np.max(np.abs(A @ sol.branch_flux_Wb)) <= 1e-12 * np.max(np.abs(sol.branch_flux_Wb))
    # one winding of 300 turns per section on two parallel branches (iron and the coil's
    # air): the linkage is n x (the sum of their fluxes)
    for i in (1, 2):
        phi = sol.branch_flux(f"yoke_{i}") + sol.branch_flux(f"coil_air_{i}")
        assert np.ravel(sol.flux_linkage_Wb)[i - 1] == pytest.approx(300.0 * phi, rel=1e-12)
    # the eddy elements (node EY) do not change the statics
    eddy = mk.build_magnet(_params(flux_paths="split"))
    sol_e = mk.solve_statics(eddy, gaps_m=[0.009, 0.011], currents_A=[32.0, 25.0])
    np.testing.assert_allclose(sol_e.force_N, sol.force_N, rtol=1e-10)
    np.testing.assert_allclose(sol_e.flux_linkage_Wb, sol.flux_linkage_Wb, rtol=1e-10)


def test_split_end_effects_depths() -> None:
    """Without end effects every air path has the cut's depth (the section length); with
    them the legs', yoke's and coil's paths exist over the yokes (smaller): less leakage,
    so less flux linkage at the same gap flux density, same structure."""
    cut = mk.build_magnet(_params(flux_paths="split", end_effects=False),
                          options=mk.ModelOptions(eddy_currents=False))
    full = mk.build_magnet(_params(flux_paths="split"), options=mk.ModelOptions(eddy_currents=False))
    assert [b.name for b in cut.network.branches] == [b.name for b in full.network.branches]
    g = {b.name: b.elements[0] for b in cut.network.branches}
    h = {b.name: b.elements[0] for b in full.network.branches}
    for name in ("back_1", "leak_leg_1", "leak_coil_1", "coil_air_1"):
        assert h[name].value_H < g[name].value_H, name
    assert h["leak_1"].value_H == g["leak_1"].value_H          # the bars run through
    a = mk.solve_statics(cut, gaps_m=0.010, currents_A=[32.0, 32.0])
    b = mk.solve_statics(full, gaps_m=0.010, currents_A=[32.0, 32.0])
    assert np.ravel(b.flux_linkage_Wb)[0] < np.ravel(a.flux_linkage_Wb)[0]


def test_flux_paths_and_coil_thickness_keys() -> None:
    with pytest.raises(mk.ParameterFileError, match=r"flux_paths = 'fem': expected one of "
                                                    r"'paper', 'split'"):
        mk.build_magnet(_params(flux_paths="fem"))
    p = _params(flux_paths="split")
    del p["magnet"]["coil_thickness"]
    with pytest.raises(mk.ParameterFileError, match=r"flux_paths = \"split\" needs coil_thickness"):
        mk.build_magnet(p)
    with pytest.raises(mk.ParameterFileError,
                       match=r"coil_thickness = 0.07 m: .* < leg_length = 0.06 m"):
        mk.build_magnet(_params(flux_paths="split", coil_thickness=0.07))


def test_split_maps_build() -> None:
    """Maps (with the eddy elements after the yoke and its coil air, node EY) build, with
    a finite positive eddy resistance per circuit, and their statics are the network's."""
    from maglevkit.reduction.maps import build_maps

    # the lumped eddy elements by name (the file's is the ladder since guideswitch, whose
    # maps have no current jump: R_ec = inf)
    mag = mk.build_magnet(_params(flux_paths="split", eddy_model="lumped"))
    maps = build_maps(mag, gaps_m=np.linspace(0.006, 0.012, 4), currents_A=[0.0, 20.0, 40.0, 60.0],
                      executor=None, progress=False)
    r_ec = maps.dataset["eddy_resistance_ohm"].values
    assert np.all(np.isfinite(r_ec)) and np.all(r_ec > 0.0)
    ref = mk.solve_statics(mag.with_options(eddy_currents=False), gaps_m=0.008,
                           currents_A=[40.0, 40.0])
    force = maps.dataset["force_N"].sel(gap=0.008, current=40.0).values
    # the map's force per circuit at equal currents is the network's per-gap force
    np.testing.assert_allclose(force, np.ravel(ref.pole_force_N), rtol=1e-9)


def _bend_squares(a: float, b: float, h: float, length: float) -> float:
    """Second method for the bend: finite volumes (square cells of side ``h``) on the
    L-shaped strip, a horizontal arm of width ``a`` and a vertical one of width ``b``, both
    ``length`` along their outer edges from the outer corner, potential 0 at the end of one
    and 1 at the other, insulated elsewhere; returns the resistance in squares."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    nxa, nya, nxb, nyb = (round(v / h) for v in (length, a, b, length))
    inside = np.zeros((max(nxa, nxb), max(nya, nyb)), bool)
    inside[:nxa, :nya] = True
    inside[:nxb, :nyb] = True
    idx = -np.ones(inside.shape, int)
    idx[inside] = np.arange(inside.sum())
    n = int(inside.sum())
    i, j = np.nonzero(inside)
    rows, cols, diag, rhs = [], [], np.zeros(n), np.zeros(n)
    for di, dj in ((1, 0), (0, 1)):
        ok = (i + di < inside.shape[0]) & (j + dj < inside.shape[1])
        i2, j2 = i[ok], j[ok]
        nb = inside[i2 + di, j2 + dj]
        p, q = idx[i2[nb], j2[nb]], idx[i2[nb] + di, j2[nb] + dj]
        rows += [p, q]
        cols += [q, p]
        np.add.at(diag, p, 1.0)
        np.add.at(diag, q, 1.0)
    east, north = idx[nxa - 1, :nya], idx[:nxb, nyb - 1]     # the two ends (half cells)
    np.add.at(diag, east, 2.0)
    np.add.at(diag, north, 2.0)
    rhs[north] = 2.0
    r, c = np.concatenate([*rows, np.arange(n)]), np.concatenate([*cols, np.arange(n)])
    v = np.concatenate([-np.ones(r.size - n), diag])
    phi = spla.spsolve(sp.csc_matrix((v, (r, c)), shape=(n, n)), rhs)
    return 1.0 / float(np.sum(2.0 * phi[east]))


@pytest.mark.parametrize("a,b", [(1.0, 1.0), (1.0, 2.0), (1.0, 3.0)])
def test_bend_reduction_against_finite_volumes(a: float, b: float) -> None:
    """The conformal map's bend against a finite-volume solution of the same Laplace
    problem (0.1 s): the arms 5 max(a, b) long, so that the bend's disturbance has decayed
    (``exp(-5 pi)``) at their ends.  Measured error 0.0025 / 0.0018 / 0.0017 squares at
    ``h = 1/40`` (0.0063 / 0.0046 / 0.0042 at 1/20: first order, from the re-entrant
    corner), so 0.005 squares; the mean quarter circle used before guide26 is 0.23 squares
    off for equal widths."""
    length = 5.0 * max(a, b)
    got = _bend_squares(a, b, 1.0 / 40.0, length)
    want = (length - bend_reduction(a, b)) / a + (length - bend_reduction(b, a)) / b
    assert got == pytest.approx(want, abs=5e-3)
    # equal widths: the corner square counts 0.559 of a square (the conformal map's value)
    if a == b:
        assert 2.0 - 2.0 * bend_reduction(a, b) / a == pytest.approx(0.5587, abs=1e-4)
