"""Levitation magnets (standard and bow): topology, conservation, symmetry, locality, load."""

from __future__ import annotations

import sys
from importlib import resources

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.magnets import coupling_ratios, pole_gap_names, saturation_knee

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

G = 9.81
SECTION_MASS = 57e3          # kg (facts.md: ~57 t section)
HALF_MAGNETS = 32            # 8 magnets per side x 2 sides x 2 halves


@pytest.fixture(scope="module")
def std() -> mk.Magnet:
    return mk.load_magnet("tr09-standard")


@pytest.fixture(scope="module")
def bow() -> mk.Magnet:
    return mk.load_magnet("tr09-bow")


def _params(name: str) -> dict:
    text = (resources.files("maglevkit") / "data" / f"{name}.toml").read_text()
    return tomllib.loads(text)


def test_network_shape_and_names(std: mk.Magnet) -> None:
    net = std.network
    assert net.gap_names == pole_gap_names(12)
    assert net.circuit_names == ("front", "rear")
    # 12 cores + 12 gaps + 12 pole-back leakages + 3 x 11 links; 3 nodes per pole
    assert len(net.branches) == 69 and len(net.nodes) == 36 and net.n_loops == 34
    # each circuit drives 6 poles with alternating polarity
    N = net.turns_matrix
    for c in net.circuits:
        assert len(c.coils) == 6
        signs = [coil.polarity for coil in c.coils]
        assert signs == [1, -1, 1, -1, 1, -1]
    assert np.count_nonzero(N) == 12
    assert std.network.has_eddy_currents


def test_loop_matrix_is_a_cycle_basis(std: mk.Magnet) -> None:
    """Every fundamental loop is closed: incidence @ C^T = 0 (exactly, integer arithmetic)."""
    A = std.network.incidence_matrix
    C = std.network.loop_matrix
    assert np.array_equal(A @ C.T, np.zeros((A.shape[0], C.shape[0])))
    assert np.linalg.matrix_rank(C) == C.shape[0]


def test_flux_conservation(std: mk.Magnet) -> None:
    gaps = np.linspace(0.008, 0.013, 12)
    sol = mk.solve_statics(std, gaps=gaps, currents=[30.0, 38.0])
    A = std.network.incidence_matrix
    # node sums relative to the largest branch flux: round-off level (loop fluxes are exact)
    assert np.max(np.abs(A @ sol.branch_flux_Wb)) <= 1e-12 * np.max(np.abs(sol.branch_flux_Wb))


def test_half_magnets_symmetric(std: mk.Magnet) -> None:
    sol = mk.solve_statics(std, gaps=0.010, currents=34.0)
    f = sol.pole_force_N
    front, rear = f[:6].sum(), f[6:].sum()
    # mirror symmetry of the network: equal to solver precision (Newton to 1e-9 scaled residual)
    assert front == pytest.approx(rear, rel=1e-9)
    np.testing.assert_allclose(f[:6], f[::-1][:6], rtol=1e-9)
    L = sol.differential_inductance_H
    assert L[0, 0] == pytest.approx(L[1, 1], rel=1e-9)


def test_locality_of_one_pole_gap(std: mk.Magnet) -> None:
    base = mk.solve_statics(std, gaps=0.010, currents=34.0).pole_force_N
    for k in (0, 3, 6, 11):
        gaps = np.full(12, 0.010)
        gaps[k] = 0.012
        changed = mk.solve_statics(std, gaps=gaps, currents=34.0).pole_force_N
        delta = np.abs(changed - base)
        # the pole whose gap opened loses most; every other pole changes less than half as much
        assert np.argmax(delta) == k
        others = np.delete(delta, k)
        assert others.max() < 0.5 * delta[k]
        assert changed[k] < base[k]


def test_total_force_continuous_and_decreasing_in_gap(std: mk.Magnet) -> None:
    gaps = np.linspace(0.004, 0.025, 85)
    sol = mk.solve_statics(std, gaps=gaps, currents=np.array([20.0, 34.0, 60.0]), grid=True)
    F = sol.force_N  # (gaps, currents)
    assert np.all(np.diff(F, axis=0) < 0.0)
    # continuity: the step between neighbouring gaps (0.25 mm) is bounded by the exact
    # derivative times the step (within 50 %, the derivative varies along the step)
    dF = sol.dforce_dgap_N_per_m.sum(axis=(-2, -1))
    step = gaps[1] - gaps[0]
    assert np.all(np.abs(np.diff(F, axis=0)) <= 1.5 * np.abs(dF[:-1]) * step)


def test_half_magnet_carries_section_share(std: mk.Magnet) -> None:
    share = SECTION_MASS * G / HALF_MAGNETS
    s0, i0 = std.nominal_gap, std.nominal_current
    assert s0 == pytest.approx(0.010)
    sol = mk.solve_statics(std, gaps=s0, currents=i0)
    half = sol.pole_force_N[:6].sum()
    assert half >= share
    # "with margin": the knee lies above nominal and the force there exceeds 1.5 x the share
    knee = saturation_knee(std)
    assert knee > 1.2 * i0
    at_knee = mk.solve_statics(std, gaps=s0, currents=knee).pole_force_N[:6].sum()
    assert at_knee > 1.5 * share


def test_coupling_of_the_two_circuits_is_small(std: mk.Magnet) -> None:
    c = coupling_ratios(std)
    # each half magnet has an even number of alternating poles, so its net flux into the
    # pole back and stator is ~0 and only the leakage/iron paths at the p06-p07 junction
    # couple the halves: the ratio is < 2 % (computed ~0.7 %); the paper: "hardly couple"
    assert 0.0 < c.max_ratio < 0.02
    assert c.inductance_H[0, 0] == pytest.approx(0.52, rel=0.1)  # facts.md: L ~ 0.5 H [E]


def test_bow_magnet_three_circuits(bow: mk.Magnet) -> None:
    assert bow.circuit_names == ("c1", "c2", "c3")
    assert [len(c.coils) for c in bow.network.circuits] == [4, 4, 4]
    c = coupling_ratios(bow)
    assert c.max_ratio < 0.02
    # resistance scales with the poles of each circuit
    np.testing.assert_allclose(bow.network.resistances, 4 * 0.2167)
    # same iron and gaps as the standard magnet: equal total force at equal currents
    std = mk.load_magnet("tr09-standard")
    f_bow = mk.solve_statics(bow, gaps=0.01, currents=30.0).force_N
    f_std = mk.solve_statics(std, gaps=0.01, currents=30.0).force_N
    assert f_bow == pytest.approx(f_std, rel=1e-9)


def test_provenance_tags_every_value() -> None:
    for name in ("tr09-standard", "tr09-bow", "tr-guidance"):
        p = _params(name)
        prov = p["provenance"]
        for table, values in p.items():
            if table in ("provenance",):
                continue
            for key in values:
                if table == "magnet" and key in ("kind", "name"):
                    continue
                tag = prov.get(f"{table}.{key}")
                assert tag is not None, f"{name}: {table}.{key} has no provenance"
                assert tag[:3] in ("[P]", "[R]", "[E]"), f"{name}: {table}.{key}: {tag!r}"


# ----------------------------------------------------------------- bad parameter files
def _write(tmp_path, params: dict) -> str:  # type: ignore[no-untyped-def]
    def val(v):  # type: ignore[no-untyped-def]
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)

    lines = []
    for table, values in params.items():
        lines.append(f"[{table}]")
        lines += [f'"{k}" = {val(v)}' for k, v in values.items()]
    path = tmp_path / "m.toml"
    path.write_text("\n".join(lines))
    return str(path)


def test_unknown_key_is_an_error(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-standard")
    p["magnet"]["pole_lenght"] = 0.1
    with pytest.raises(mk.ParameterFileError, match=r"\[magnet\]: unknown key.*pole_lenght"):
        mk.load_magnet(_write(tmp_path, p))


def test_missing_key_is_an_error(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-standard")
    del p["stator"]["slot_pitch"]
    del p["provenance"]["stator.slot_pitch"]
    msg = r"\[stator\]: missing required key 'slot_pitch'"
    with pytest.raises(mk.ParameterFileError, match=msg):
        mk.load_magnet(_write(tmp_path, p))


@pytest.mark.parametrize("assignment, message", [
    ([1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3], r"11 entries but the magnet has 12 poles"),
    ([1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 4],
     r"pole 12 -> 4 is not a circuit number; allowed are 1..3"),
    ([1, 1, 1, 1, 1, 1, 3, 3, 3, 3, 3, 3], r"circuit\(s\) \['c2'\] feed no pole"),
    ([1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, "x"], r"pole 12 -> 'x' is not a circuit number"),
])
def test_bad_bow_circuit_assignment(tmp_path, assignment, message) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-bow")
    p["circuits"]["assignment"] = assignment
    with pytest.raises(mk.ParameterFileError, match=message):
        mk.load_magnet(_write(tmp_path, p))


def test_bad_operating_table(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-standard")
    p["operating"]["nominal_gap"] = -0.01
    msg = r"\[operating\] nominal_gap = -0.01 m: must be > 0"
    with pytest.raises(mk.ParameterFileError, match=msg):
        mk.load_magnet(_write(tmp_path, p))


def test_geometry_checks(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-standard")
    p["magnet"]["coil_thickness"] = 0.08
    with pytest.raises(mk.ParameterFileError, match="do not fit between neighbouring pole cores"):
        mk.load_magnet(_write(tmp_path, p))
