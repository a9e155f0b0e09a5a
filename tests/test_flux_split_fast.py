"""The TR09 split network's detailed model made affordable (issue 26, part 2): a loop basis of
short loops for large networks (:attr:`maglevkit.circuit.network.Network.loop_matrix`) and the
sparse form of the flux DAE.  Both are a change of formulation only: the same DAE, so the
same solution as the fundamental loops on the dense form (docs/decisions.md, splitfast)."""

from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit import network as network_mod
from maglevkit.models import compiled as compiled_mod
from maglevkit.models import flux

from .conftest import paper_tr09

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _split() -> mk.Magnet:
    p = tomllib.loads((resources.files("maglevkit") / "data" / "tr09-standard.toml").read_text())
    p["magnet"]["flux_paths"] = "split"
    p["provenance"]["magnet.flux_paths"] = "[E] modelling choice: the FEM-checked paths"
    # the split network's lumped eddy elements (the file's ladder since switch26m has 526
    # loops; the numbers below are the lumped network's)
    p["magnet"]["eddy_model"] = "lumped"
    return mk.build_magnet(p)


@pytest.fixture(scope="module")
def split() -> mk.Magnet:
    return _split()


def _pattern_nnz(C: np.ndarray) -> int:
    """Nonzeros of the loop Jacobian's pattern ``|C| |C|^T`` (C diag(dV/dphi) C^T)."""
    return int(np.count_nonzero(np.abs(C) @ np.abs(C).T))


def test_short_loops_are_a_sparse_basis_of_the_same_loop_space(split: mk.Magnet) -> None:
    net = split.network
    C, F = net.loop_matrix, net._fundamental_loops()
    # 231 loops since fringe26 (one flank strip per inner flank instead of two; was 253)
    assert net.n_loops == 231 > network_mod.SHORT_LOOP_SIZE
    assert C.shape == F.shape
    assert set(np.unique(C)) <= {-1.0, 0.0, 1.0}
    # closed loops (node law, exact in integer arithmetic), independent, and spanning the
    # fundamental loops' space: together they have no more rank than either
    A = net.incidence_matrix
    assert np.array_equal(A @ C.T, np.zeros((A.shape[0], C.shape[0])))
    assert np.linalg.matrix_rank(C) == net.n_loops
    assert np.linalg.matrix_rank(np.vstack((C, F))) == net.n_loops
    # the point of it: measured 922 vs 2990 entries of C, 1537 vs 23455 of the loop
    # Jacobian's pattern; bounds with room for ties broken otherwise
    assert np.count_nonzero(C) < 0.4 * np.count_nonzero(F)
    assert _pattern_nnz(C) < 0.1 * _pattern_nnz(F)


def test_small_networks_keep_their_fundamental_loops() -> None:
    """The lumped networks (recorded results) are solved in the loops of earlier versions."""
    # the TR09 files' lumped "paper" network, loaded explicitly (the bundled files are split
    # since issue 26: 231 loops since fringe26, 253 before)
    for net in (paper_tr09("tr09-standard").network, paper_tr09("tr09-bow").network,
                mk.load_magnet("u-magnet").network):
        assert net.n_loops <= network_mod.SHORT_LOOP_SIZE
        np.testing.assert_array_equal(net.loop_matrix, net._fundamental_loops())


def test_short_loops_fall_back_to_fundamental_loops_where_needed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Two squares sharing an edge plus a branch parallel to one: the shortest loops (the
    pair, the two squares) taken, repeats left out; closed, independent and complete."""
    from maglevkit.circuit import Branch, Circuit, Coil, LeakagePermeance, Network

    def br(name: str, a: str, b: str) -> Branch:
        return Branch(name, a, b, (LeakagePermeance(f"r_{name}", value_H=1e-7),))

    branches = [br("a", "1", "2"), br("b", "2", "3"), br("c", "3", "4"), br("d", "4", "1"),
                br("e", "2", "5"), br("f", "5", "6"), br("g", "6", "3"), br("p", "1", "2")]
    monkeypatch.setattr(network_mod, "SHORT_LOOP_SIZE", 0)
    net = Network(branches, [Circuit("c", 1.0, (Coil("a", 100.0),))])
    C = net.loop_matrix
    assert C.shape == (3, 8)
    assert np.array_equal(net.incidence_matrix @ C.T, np.zeros((6, 3)))
    assert np.linalg.matrix_rank(C) == 3
    # the shortest loop through a (and p): a, p (2 branches); then the two squares (4 each)
    assert sorted(np.count_nonzero(C, axis=1).tolist()) == [2, 4, 4]


def _dae_in(monkeypatch: pytest.MonkeyPatch, basis: str, form: str) -> mk.Magnet:
    monkeypatch.setattr(network_mod, "SHORT_LOOP_SIZE", 0 if basis == "short" else 10**9)
    monkeypatch.setattr(flux, "SPARSE_FORM_SIZE", 0 if form == "sparse" else 10**9)
    return mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=4)


def _two_runs(fm: mk.FluxModel) -> np.ndarray:
    """A saturating voltage step at a fixed gap and a 50 Hz gap sine at constant voltage
    (20 ms each, 1 ms outputs): currents [A], force [N], flux linkage [Wb] as columns."""
    t = np.linspace(0.0, 0.02, 21)
    u = float(fm.resistances[0])
    a = mk.simulate(fm, t, gaps_m=0.008, voltages_V=u * 45.0, initial_currents_A=20.0)
    b = mk.simulate(fm, t, gaps_m=lambda tt: 0.010 + 1e-3 * np.sin(2 * np.pi * 50.0 * tt),
                    voltages_V=u * 20.0, initial_currents_A=20.0)
    return np.vstack([np.column_stack((r.currents_A, r.force_N, r.flux_linkage_Wb))
                      for r in (a, b)])


def test_short_loops_and_sparse_form_give_the_fundamental_dense_solution(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The U-magnet's ladder n = 4 (59 loops, diffusing eddy currents, saturable iron) in
    short loops on the sparse form (the split network's formulation) against the
    fundamental loops on the dense form (its formulation before), both at rtol 1e-9: the
    same DAE, so equal to the integrator's tolerance: measured 3.3e-8 (current), 1.3e-8
    (force), 2.9e-9 (flux linkage) of each column's largest value; bound 1e-6, 30x above."""
    runs = {}
    for basis, form in (("short", "sparse"), ("fundamental", "dense")):
        mag = _dae_in(monkeypatch, basis, form)
        fm = mk.FluxModel(mag.network, rtol=1e-9, compiled="never")
        assert fm.dae.form == form
        runs[basis] = _two_runs(fm)
    a, b = runs["short"], runs["fundamental"]
    err = (np.abs(a - b) / np.abs(b).max(axis=0)).max(axis=0)
    assert err.max() < 1e-6, err


@pytest.mark.slow
def test_split_model_equals_the_formulation_before(monkeypatch: pytest.MonkeyPatch) -> None:
    """The TR09 split network (231 loops; 253 before fringe26): short loops on the sparse
    form against the fundamental loops on the dense form (27.5 s CPU per simulated second
    interpreted before),
    a voltage step and a gap sine at rtol 1e-9.  Measured over 1 s at rtol 1e-10: currents
    1.6e-9, forces 3.1e-9 of their largest values; bound 1e-6."""
    runs = []
    for short, form in ((0, 0), (10**9, 10**9)):
        monkeypatch.setattr(network_mod, "SHORT_LOOP_SIZE", short)
        monkeypatch.setattr(flux, "SPARSE_FORM_SIZE", form)
        mag = _split()
        fm = mk.FluxModel(mag.network, rtol=1e-9, compiled="never")
        t = np.linspace(0.0, 0.02, 21)
        u = fm.resistances * 33.5
        a = mk.simulate(fm, t, gaps_m=0.010, voltages_V=lambda tt, u=u: u * (1.2 if tt >= 0.005 else 1.0),
                        initial_currents_A=33.5)
        b = mk.simulate(fm, t, gaps_m=lambda tt: 0.010 + 1e-3 * np.sin(2 * np.pi * 50.0 * tt),
                        voltages_V=u, initial_currents_A=33.5)
        runs.append(np.vstack([np.column_stack((r.currents_A, r.force_N)) for r in (a, b)]))
    err = (np.abs(runs[0] - runs[1]) / np.abs(runs[1]).max(axis=0)).max(axis=0)
    assert err.max() < 1e-6, err


@pytest.mark.slow
def test_split_model_compiles_under_auto_within_a_minute(split: mk.Magnet, tmp_path: Path) -> None:
    """compiled="auto" compiles the split network (255 unknowns <= AUTO_COMPILE_SIZE): the
    sparse form in short loops, 11 s of gcc -O1 measured (the dense form in the fundamental
    loops had not compiled after 600 s); the compiled run is the interpreted one."""
    if compiled_mod.find_compiler() is None:
        pytest.skip("no C compiler on this machine")
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    fm = mk.FluxModel(split, compiled="auto", cache_dir=tmp_path)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert fm.compiled and fm.dae.form == "sparse"
    # the compiler's CPU time: 11 s measured on a shared core; 60 s is the aim
    assert (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime) < 60.0
    t = np.linspace(0.0, 0.05, 51)
    runs = [mk.simulate(m, t, gaps_m=lambda tt: 0.010 + 1e-3 * np.sin(2 * np.pi * 5.0 * tt),
                        voltages_V=m.resistances * 33.5, initial_currents_A=33.5)
            for m in (fm, mk.FluxModel(split, compiled="never"))]
    # the same expressions in the same order: bit-identical measured, bound 1e-9 of 35 A
    np.testing.assert_allclose(runs[0].currents_A, runs[1].currents_A, rtol=0.0, atol=35e-9)
