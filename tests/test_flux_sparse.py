"""The flux model's sparse IDAS form (``K y' = h``, large networks) against its dense form
(``y' = K^+ v``, ``Q v = 0``, every network up to :data:`SPARSE_FORM_SIZE` unknowns), and
the incremental row selection against the rank test per row it replaced.

Both forms are built from the same network here; the dense form is the one every earlier
result of the flux model came from.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit.assembly import assemble
from maglevkit.magnets.base import ModelOptions, build_magnet
from maglevkit.models import compiled as compiled_mod
from maglevkit.models import flux
from maglevkit.models.flux import FluxDAE, _independent_rows


def _grid(**options: object) -> mk.Magnet:
    params = copy.deepcopy(mk.load_magnet("u-magnet").parameters)
    params["magnet"]["discretisation"] = "grid"
    params["provenance"]["magnet.discretisation"] = "[E] test variant"
    return build_magnet(params, options=ModelOptions(**options))  # type: ignore[arg-type]


NETWORKS = {
    # 54 differential states from 56 eddy branches: dependent rows in the selection
    "u-magnet ladder n = 4": lambda: mk.load_magnet("u-magnet", eddy_model="ladder",
                                                    eddy_layers=4).network,
    # two circuits (two flux-linkage rows, S_psi with two rows); its lumped eddy elements
    # (the file's ladder since switch26m has 1011 branches: the dense form's pseudo-inverse
    # took ~8 min of this module on a loaded machine for nothing the two rows need)
    "tr09-standard": lambda: mk.load_magnet("tr09-standard", eddy_model="lumped").network,
    # the cell network (tubes) with its placeholder eddy elements: 132 eddy branches
    "u-magnet grid": lambda: _grid(eddy_model="lumped").network,
}


def _old_rows(A: np.ndarray) -> list[int]:
    """The selection as the flux model made it before: a rank test (SVD) per row."""
    rows: list[np.ndarray] = []
    out = []
    for k, row in enumerate(A):
        cand = np.array([*rows, row])
        scaled = cand / np.maximum(np.abs(cand).max(axis=1, keepdims=True), 1e-300)
        if np.linalg.matrix_rank(scaled, tol=1e-9) == len(cand):
            rows.append(row)
            out.append(k)
    return out


@pytest.fixture(scope="module", params=sorted(NETWORKS))
def pair(request: pytest.FixtureRequest) -> tuple[FluxDAE, FluxDAE]:
    net = NETWORKS[request.param]()
    args = (net, "idas", 1e-6, 1e-8, 20000, 2, 3, "never", None)
    return FluxDAE(*args, form="dense"), FluxDAE(*args, form="sparse")


def test_incremental_row_selection_is_the_rank_test_per_row(
        pair: tuple[FluxDAE, FluxDAE]) -> None:
    dense, _ = pair
    eq = assemble(dense.network)
    a_psi = eq.N.T @ eq.C.T
    A = np.vstack((a_psi, eq.C.T[dense.eddy_idx]))
    assert _independent_rows(A) == _old_rows(A)
    assert len(_old_rows(A)) == dense.n_diff


def test_sparse_form_matrices_equal_the_dense_ones(pair: tuple[FluxDAE, FluxDAE]) -> None:
    dense, sparse = pair
    assert dense.form == "dense" and sparse.form == "sparse"
    assert dense.diff_names == sparse.diff_names
    np.testing.assert_array_equal(dense.D, sparse.D)
    # K = M D^+ (dense, by a pseudo-inverse) vs K = [a_e^T G_e S_e; S_psi] (sparse, its
    # entries G_ec and the node/loop law coefficients of S): equal to rounding of the
    # pseudo-inverse, 1e-12 of the largest entry
    for a, b in ((dense.K, sparse.K), (dense.T, sparse.T), (dense.M, sparse.M)):
        assert a.shape == b.shape
        np.testing.assert_allclose(b, a, rtol=0.0, atol=1e-12 * max(1.0, np.abs(a).max()))
    np.testing.assert_allclose(sparse.K_sparse.toarray(), sparse.K, rtol=0.0, atol=0.0)
    # the sparse K really is sparse (the point of the form): a few entries per column
    assert sparse.K_sparse.nnz <= 0.2 * sparse.K.size + 2 * sparse.K.shape[1]
    # the same left null space (as a projector: the bases may differ by a rotation)
    pd, ps = dense.Q.T @ dense.Q, sparse.Q.T @ sparse.Q
    np.testing.assert_allclose(ps, pd, rtol=0.0, atol=1e-10)
    assert np.isfinite(sparse.index1_condition) and sparse.index1_condition >= 1.0


def test_sparse_form_functions_equal_the_dense_ones(pair: tuple[FluxDAE, FluxDAE]) -> None:
    """Outputs, initial balance and the energy quadrature at random states: the dense form's
    ``v`` and the sparse form's ``y' = K^+ v`` give the same values to rounding."""
    dense, sparse = pair
    rng = np.random.default_rng(7)
    nl, nc, ng, r = dense.n_loops, dense.n_circuits, dense.n_gaps, dense.n_diff
    for _ in range(3):
        x = rng.normal(scale=1e-4, size=nl)
        cur = rng.uniform(5.0, 40.0, size=nc)
        s = rng.uniform(0.006, 0.014, size=ng)
        y = dense.D @ x
        U = rng.uniform(-50.0, 50.0, size=nc)
        rate = rng.uniform(-0.1, 0.1, size=ng)
        w = np.concatenate((y, s, x, cur))
        od = np.asarray(dense.output_fun(w, U, rate)).ravel()
        os_ = np.asarray(sparse.output_fun(w, U, rate)).ravel()
        np.testing.assert_allclose(os_, od, rtol=1e-12, atol=1e-12 * np.abs(od).max())
        v = np.asarray(dense._balance(np.concatenate((x, cur)), s, U)).ravel()
        yd = np.asarray(sparse._balance(np.concatenate((x, cur)), s, U)).ravel()
        np.testing.assert_allclose(yd, np.linalg.pinv(dense.K) @ v, rtol=1e-10,
                                   atol=1e-12 * np.abs(yd).max())
        u = np.concatenate(((1e-3,), s, rate, (0.0,)))
        qd = dense._oracle(t=0.0, x=y, z=np.concatenate((x, cur, v)), p=U, u=u)
        qs = sparse._oracle(t=0.0, x=y, z=np.concatenate((x, cur, yd)), p=U, u=u)
        for key in ("ode", "quad"):
            a, b = np.asarray(qd[key]).ravel(), np.asarray(qs[key]).ravel()
            np.testing.assert_allclose(b, a, rtol=1e-10, atol=1e-12 * max(np.abs(a).max(), 1e-30))
        # the dense form's algebraic part is zero at v = h(x, I, s, U) exactly when the
        # sparse one is at y' = K^+ v: both leave the part of v outside range(K), Q v
        ad = np.asarray(qd["alg"]).ravel()
        as_ = np.asarray(qs["alg"]).ravel()
        np.testing.assert_allclose(as_[:r], ad[:r], rtol=0.0, atol=0.0)
        out_of_range = -dense.Q.T @ ad[r:r + dense.Q.shape[0]]
        np.testing.assert_allclose(as_[r:], out_of_range, rtol=0.0,
                                   atol=1e-9 * max(np.abs(v).max(), 1.0))


def test_sparse_form_trajectory_equals_the_dense_one(monkeypatch: pytest.MonkeyPatch) -> None:
    """A saturating voltage step with diffusing eddy currents: the two forms are the same
    DAE, so the currents agree to the integrator's tolerance (rtol = 1e-9 here; the forms
    differ only in which algebraic unknowns IDAS's error test weighs)."""
    mag = mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=4)
    times = np.linspace(0.0, 0.03, 31)

    def run() -> mk.SimulationResult:
        fm = mk.FluxModel(mag.network, rtol=1e-9, compiled="never")
        return mk.simulate(fm, times, gaps_m=0.008, voltages_V=fm.resistances[0] * 45.0,
                           initial_currents_A=20.0)

    dense = run()
    monkeypatch.setattr(flux, "SPARSE_FORM_SIZE", 0)   # the cache key holds the form
    sparse = run()
    assert flux.flux_dae(mag.network, "idas", 1e-9, flux.DEFAULT_ATOL, 20000, 2, 3,
                     "never").form == "sparse"
    step = 25.0
    err = np.abs(sparse.currents_A - dense.currents_A).max() / step
    assert err < 1e-6, err
    np.testing.assert_allclose(sparse.eddy_loss_J, dense.eddy_loss_J, rtol=1e-5,
                               atol=1e-6 * dense.eddy_loss_J[-1])


@pytest.mark.slow
def test_air_cell_network_builds_in_the_sparse_form() -> None:
    """The air-cell grid (2812 branches, 1385 loops) takes the sparse form; without eddy
    currents its flux model starts at the statics and stays there at U = R I."""
    params = copy.deepcopy(mk.load_magnet("u-magnet", eddy_currents=False).parameters)
    params["magnet"]["discretisation"] = "grid"
    params["magnet"]["air_model"] = "cells"
    params["provenance"]["magnet.discretisation"] = "[E] test variant"
    params["provenance"]["magnet.air_model"] = "[E] test variant"
    mag = build_magnet(params, options=ModelOptions(eddy_currents=False))
    fm = mk.FluxModel(mag, compiled="never")
    assert fm.dae.form == "sparse"
    res = mk.simulate(fm, np.linspace(0.0, 0.004, 5), gaps_m=0.010,
                      voltages_V=fm.resistances[0] * 20.0, initial_currents_A=20.0)
    np.testing.assert_allclose(res.currents_A[:, 0], 20.0, rtol=1e-6)
    sol = mk.solve_statics(mag, gaps_m=0.010, currents_A=20.0)
    np.testing.assert_allclose(res.flux_linkage_Wb[-1], sol.flux_linkage_Wb, rtol=1e-6)


def test_sparse_form_compiles_to_the_same_trajectory(monkeypatch: pytest.MonkeyPatch,
                                                     tmp_path: Path) -> None:
    """The sparse form's IDAS functions compiled to C run the interpreted trajectory (the
    same expressions in the same order)."""
    if compiled_mod.find_compiler() is None:
        pytest.skip("no C compiler on this machine")
    monkeypatch.setattr(flux, "SPARSE_FORM_SIZE", 0)
    mag = mk.load_magnet("u-magnet", eddy_currents=False)
    runs = []
    for mode in ("always", "never"):
        fm = mk.FluxModel(mag, compiled=mode, cache_dir=tmp_path)
        assert fm.dae.form == "sparse" and fm.compiled == (mode == "always")
        runs.append(mk.simulate(fm, np.linspace(0.0, 0.05, 51), gaps_m=0.010,
                                voltages_V=fm.resistances[0] * 30.0, initial_currents_A=10.0))
    # as the dense form's compiled test: bit-identical measured, bound 1e-9 of the range
    np.testing.assert_allclose(runs[0].currents_A, runs[1].currents_A, rtol=0.0,
                               atol=1e-9 * 20.0)


def test_auto_does_not_compile_large_networks(monkeypatch: pytest.MonkeyPatch,
                                              tmp_path: Path) -> None:
    """compiled="auto" interprets networks above AUTO_COMPILE_SIZE (compiling the grid's
    eddy ladders took many minutes); "always" still compiles them."""
    if compiled_mod.find_compiler() is None:
        pytest.skip("no C compiler on this machine")
    mag = mk.load_magnet("u-magnet", eddy_currents=False)
    size = mag.network.n_loops + len(mag.network.circuits)
    monkeypatch.setattr(flux, "AUTO_COMPILE_SIZE", size - 1)
    assert mk.FluxModel(mag, compiled="auto", cache_dir=tmp_path).compiled is False
    assert mk.FluxModel(mag, compiled="always", cache_dir=tmp_path).compiled is True
    monkeypatch.setattr(flux, "AUTO_COMPILE_SIZE", size)
    assert mk.FluxModel(mag, compiled="auto", cache_dir=tmp_path).compiled is True
