"""Levitation magnets (standard and bow): topology, conservation, symmetry, locality, load."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.magnets import pole_gap_names
from maglevkit.models import coupling_ratios, saturation_knee

from .conftest import paper_tr09, tr09_params

G = 9.81
SECTION_MASS = 57e3          # kg (facts.md: ~57 t section)
HALF_MAGNETS = 32            # 8 magnets per side x 2 sides x 2 halves


# The laws of the lumped "paper" network (topology, counts, Roters' leakage, eddy elements,
# its recorded L and coupling) are tested on that network, loaded explicitly: the bundled
# files use flux_paths = "split" since issue 26 (docs/decisions.md, tr09switch); the split
# network's topology is tests/test_levitation_split.py, the bundled files' load below.
@pytest.fixture(scope="module")
def std() -> mk.Magnet:
    return paper_tr09("tr09-standard")


@pytest.fixture(scope="module")
def bow() -> mk.Magnet:
    return paper_tr09("tr09-bow")


@pytest.fixture(scope="module")
def bundled_std() -> mk.Magnet:
    return mk.load_magnet("tr09-standard")


def _params(name: str) -> dict:
    """The bundled file's parameters on the "paper" network (the network this file tests)."""
    return tr09_params(name, flux_paths="paper")


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
    sol = mk.solve_statics(std, gaps_m=gaps, currents_A=[30.0, 38.0])
    A = std.network.incidence_matrix
    # node sums relative to the largest branch flux: round-off level (loop fluxes are exact)
    assert np.max(np.abs(A @ sol.branch_flux_Wb)) <= 1e-12 * np.max(np.abs(sol.branch_flux_Wb))


def test_half_magnets_symmetric(std: mk.Magnet) -> None:
    sol = mk.solve_statics(std, gaps_m=0.010, currents_A=34.0)
    f = sol.pole_force_N
    front, rear = f[:6].sum(), f[6:].sum()
    # mirror symmetry of the network: equal to solver precision (Newton to 1e-9 scaled residual)
    assert front == pytest.approx(rear, rel=1e-9)
    np.testing.assert_allclose(f[:6], f[::-1][:6], rtol=1e-9)
    L = sol.differential_inductance_H
    assert L[0, 0] == pytest.approx(L[1, 1], rel=1e-9)


def test_locality_of_one_pole_gap(std: mk.Magnet) -> None:
    base = mk.solve_statics(std, gaps_m=0.010, currents_A=34.0).pole_force_N
    for k in (0, 3, 6, 11):
        gaps = np.full(12, 0.010)
        gaps[k] = 0.012
        changed = mk.solve_statics(std, gaps_m=gaps, currents_A=34.0).pole_force_N
        delta = np.abs(changed - base)
        # the pole whose gap opened loses most; every other pole changes less than half as much
        assert np.argmax(delta) == k
        others = np.delete(delta, k)
        assert others.max() < 0.5 * delta[k]
        assert changed[k] < base[k]


def test_total_force_continuous_and_decreasing_in_gap(std: mk.Magnet) -> None:
    gaps = np.linspace(0.004, 0.025, 85)
    sol = mk.solve_statics(std, gaps_m=gaps, currents_A=np.array([20.0, 34.0, 60.0]), grid=True)
    F = sol.force_N  # (gaps, currents)
    assert np.all(np.diff(F, axis=0) < 0.0)
    # continuity: the step between neighbouring gaps (0.25 mm) is bounded by the exact
    # derivative times the step (within 50 %, the derivative varies along the step)
    dF = sol.dforce_dgap_N_per_m.sum(axis=(-2, -1))
    step = gaps[1] - gaps[0]
    assert np.all(np.abs(np.diff(F, axis=0)) <= 1.5 * np.abs(dF[:-1]) * step)


@pytest.mark.parametrize("which", ["bundled_std", "std"])
def test_half_magnet_carries_section_share(which: str, request: pytest.FixtureRequest) -> None:
    # the bundled (split) file at its 31.7 A and the "paper" network at its former 33.5 A
    std = request.getfixturevalue(which)
    share = SECTION_MASS * G / HALF_MAGNETS
    s0, i0 = std.nominal_gap, std.nominal_current
    assert s0 == pytest.approx(0.010)
    sol = mk.solve_statics(std, gaps_m=s0, currents_A=i0)
    half = sol.pole_force_N[:6].sum()
    # margin 5 %: room for the control loop and a heavier load; the file's nominal current
    # (31.7 A, split) is chosen for ~8 % (computed 18.80 kN = 1.076 x 17.47 kN; "paper" at
    # 33.5 A: 18.99 kN = 1.087 x)
    assert half >= 1.05 * share
    # "with margin": the knee lies above nominal and the force there exceeds 1.5 x the share
    knee = saturation_knee(std)
    assert knee > 1.2 * i0
    at_knee = mk.solve_statics(std, gaps_m=s0, currents_A=knee).pole_force_N[:6].sum()
    assert at_knee > 1.5 * share


def test_coupling_of_the_two_circuits_is_small(std: mk.Magnet) -> None:
    c = coupling_ratios(std)
    # each half magnet has an even number of alternating poles, so its net flux into the
    # pole back and stator is ~0 and only the leakage/iron paths at the p06-p07 junction
    # couple the halves: the ratio is < 2 % (computed ~0.7 %); the paper: "hardly couple"
    assert 0.0 < c.max_ratio < 0.02
    # the differential inductance matrix against central differences of the solved flux
    # linkages, one circuit current at a time (h = 1e-4 I: truncation ~1e-9, measured
    # 8e-10 for L_11 and 1.1e-9 for the coupling ratio; bound 1e-7)
    i0 = std.nominal_current
    h = 1e-4 * i0
    psi = mk.solve_statics(std, gaps_m=std.nominal_gap,
                           currents_A=[[i0 + h, i0], [i0 - h, i0], [i0, i0 + h],
                                     [i0, i0 - h]]).flux_linkage_Wb
    l_fd = np.column_stack([psi[0] - psi[1], psi[2] - psi[3]]) / (2 * h)   # [i, j] = dpsi_i/dI_j
    np.testing.assert_allclose(c.inductance_H, l_fd, rtol=1e-7)
    assert c.max_ratio == pytest.approx(abs(l_fd[0, 1]) / np.sqrt(l_fd[0, 0] * l_fd[1, 1]),
                                        rel=1e-7)
    # Half-magnet inductance: the only public figure is an estimate, "~0.5 H" [E] given to
    # one significant digit (facts.md), i.e. 0.45 ... 0.55 H; the model gives 0.5401 H at
    # the nominal point (the earlier centre value 0.52 H had no source).  Regression bound
    # on the model value: +-1 % (any change of the TR09 network, iron or leakage that
    # moves it more must re-measure it).
    assert 0.45 <= c.inductance_H[0, 0] < 0.55
    assert c.inductance_H[0, 0] == pytest.approx(0.5401, rel=0.01)


def test_coupling_time_response_is_small(std: mk.Magnet) -> None:
    """Voltage step +20 % on 'front' (detailed flux model with eddy currents): the largest
    current change of 'rear' is 0.42 % of the stepped circuit's (computed); bound 1 %,
    the paper's "the circuits hardly couple".  The static ratio is computed 0.72 %."""
    from maglevkit.figures import coupling_response

    r = coupling_response(std)
    assert 0.0 < r.other_peak_ratio < 0.01
    # the static ratio reported with the response is the matrix checked against finite
    # differences in test_coupling_of_the_two_circuits_is_small (measured 0.007234)
    assert r.mutual_ratio == pytest.approx(0.007234, rel=1e-3)
    # the stepped circuit really responded: it approaches +20 % within three time constants
    assert r.relative_current_change[-1, 0] > 0.15


def test_bow_magnet_three_circuits(bow: mk.Magnet) -> None:
    assert bow.circuit_names == ("c1", "c2", "c3")
    assert [len(c.coils) for c in bow.network.circuits] == [4, 4, 4]
    c = coupling_ratios(bow)
    assert c.max_ratio < 0.02
    # resistance scales with the poles of each circuit
    np.testing.assert_allclose(bow.network.resistances, 4 * 0.2167)
    # same iron and gaps as the standard magnet: equal total force at equal currents
    std = paper_tr09("tr09-standard")
    f_bow = mk.solve_statics(bow, gaps_m=0.01, currents_A=30.0).force_N
    f_std = mk.solve_statics(std, gaps_m=0.01, currents_A=30.0).force_N
    assert f_bow == pytest.approx(f_std, rel=1e-9)


def test_provenance_tags_every_value() -> None:
    for name in ("tr09-standard", "tr09-bow", "tr-guidance", "u-magnet"):
        p = tr09_params(name)          # the bundled file as it is (any bundled name)
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
                # a value that rests on an estimate anywhere is an estimate: a tag that
                # mentions [E] must lead with it (was: "[P] LIG windings ...; count [E]")
                assert "[E]" not in tag[3:] or tag[:3] == "[E]", f"{name}: {table}.{key}: {tag!r}"


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


# ----------------------------------------------------------------- element formulas
MU0 = 4e-7 * np.pi


def _carter_by_hand(s: float, tau: float, b: float) -> float:
    """Carter's coefficient from the textbook formula of facts.md sec. 3, written out."""
    x = b / (2.0 * s)
    gamma = 4.0 / np.pi * (x * np.arctan(x) - np.log(np.sqrt(1.0 + x * x)))
    return tau / (tau - gamma * s)


def test_carter_coefficient_against_hand_computation(std: mk.Magnet) -> None:
    from maglevkit.circuit import carter_coefficient

    st = _params("tr09-standard")["stator"]
    tau, b = st["slot_pitch"], st["slot_opening"]
    # hand value at 10 mm: x = 35/20 = 1.75, atan 1.75 = 1.05165, x atan x = 1.84039,
    # ln sqrt(4.0625) = 0.70090, gamma = (4/pi) 1.13949 = 1.4508,
    # k_C = 86 / (86 - 14.508) = 1.2029 (5 digits carried: tolerance 1e-4 relative)
    assert carter_coefficient(0.010, tau, b) == pytest.approx(1.2029, rel=1e-4)
    for s in (0.004, 0.008, 0.010, 0.015, 0.025):
        # same formula, two implementations: agreement to round-off
        assert carter_coefficient(s, tau, b) == pytest.approx(_carter_by_hand(s, tau, b),
                                                              rel=1e-13)
    # the magnet's air-gap elements use exactly this coefficient
    gaps = [e for br in std.network.branches for e in br.elements if isinstance(e, mk.AirGap)]
    assert len(gaps) == 12
    for e in gaps:
        assert e.effective_gap(0.010) == pytest.approx(_carter_by_hand(0.010, tau, b) * 0.010,
                                                       rel=1e-13)
    # limit: a vanishing slot opening gives 1 (gamma ~ (2/pi) x^2, so k_C - 1 ~ b^2/(2 pi s tau);
    # 2e-10 at b = 1 um, bound 1e-8), and k_C falls monotonically towards it
    ks = [carter_coefficient(0.010, tau, bb) for bb in (0.035, 0.01, 1e-3, 1e-4, 1e-6)]
    assert np.all(np.diff(ks) < 0.0)
    assert abs(ks[-1] - 1.0) < 1e-8


def test_lig_grooves_matter(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Without the LIG grooves the pole face is whole: more gap permeance, more force."""
    p = _params("tr09-standard")
    m = p["magnet"]
    with_g = paper_tr09("tr09-standard")
    p["magnet"]["lig_grooves"] = 0
    no_g = mk.load_magnet(_write(tmp_path, p))
    f_with = mk.solve_statics(with_g, gaps_m=0.010, currents_A=33.5).force_N
    f_no = mk.solve_statics(no_g, gaps_m=0.010, currents_A=33.5).force_N
    assert f_no > 1.01 * f_with
    # permeance difference by hand: the groove area A_g faces the gap directly instead of
    # through the groove depth, dG = mu0 A_g (1/s' - 1/(s' + d_g)); exact to round-off
    st = p["stator"]
    sp = _carter_by_hand(0.010, st["slot_pitch"], st["slot_opening"]) * 0.010
    a_g = 2 * m["lig_groove_width"] * m["pole_width"]
    d_expected = MU0 * a_g * (1.0 / sp - 1.0 / (sp + m["lig_groove_depth"]))

    def g(mag: mk.Magnet) -> float:
        e = next(e for br in mag.network.branches for e in br.elements
                 if isinstance(e, mk.AirGap) and e.name == "gap_p01")
        return float(e.permeance(0.010))

    assert g(no_g) - g(with_g) == pytest.approx(d_expected, rel=1e-10)


def test_leakage_permeances_against_roters() -> None:
    """leak_pp and leak_pb equal the Roters formulas of docs/magnets.md, evaluated here."""
    m = _params("tr09-standard")["magnet"]
    net = paper_tr09("tr09-standard").network
    wp, lp, tau = m["pole_width"], m["pole_length"], m["pole_pitch"]
    hc, tc, hf = m["coil_height"], m["coil_thickness"], m["coil_to_face"]
    # pole to pole: parallel faces across the window, energy-equivalent height h_c/3 + flank
    g_pp = MU0 * wp * (hc / 3.0 + hf) / (tau - lp)
    # pole to pole back: half hollow cylinder mu0 l ln(1 + t/r_i)/pi, r_i = h_c/2
    per_m = MU0 * np.log(1.0 + tc / (hc / 2.0)) / np.pi
    g_pb_inner = per_m * 2.0 * (lp + 2.0 * tc)
    g_pb_end = per_m * (2.0 * (lp + 2.0 * tc) + (wp + 2.0 * tc))
    leak = {e.name: e.value_H for br in net.branches for e in br.elements
            if isinstance(e, mk.LeakagePermeance)}
    pp = {k: v for k, v in leak.items() if k.startswith("leak_pp_")}
    pb = {k: v for k, v in leak.items() if k.startswith("leak_pb_")}
    assert len(pp) == 11 and len(pb) == 12 and len(leak) == 23
    for v in pp.values():
        assert v == pytest.approx(g_pp, rel=1e-12)     # same formula: round-off only
    for name, v in pb.items():
        end = name in ("leak_pb_p01", "leak_pb_p12")
        assert v == pytest.approx(g_pb_end if end else g_pb_inner, rel=1e-12)
    # sanity of the magnitudes against the gap: each leakage is a few % of a pole's gap
    # permeance at 10 mm (~2.3e-6 H), so the leakage factor stays realistic (< 1.3)
    assert g_pp < 0.1 * 2.3e-6 and g_pb_end < 0.1 * 2.3e-6


def test_iron_is_saturable_and_teeth_are_loaded(std: mk.Magnet) -> None:
    net = std.network
    irons = [e for br in net.branches for e in br.elements if isinstance(e, mk.IronPath)]
    # 12 cores + 12 tooth groups + 11 back + 11 stator segments, all with a B-H curve
    assert len(irons) == 46
    assert all(e.material.saturates for e in irons)
    sol = mk.solve_statics(std, gaps_m=std.nominal_gap, currents_A=std.nominal_current)
    b_teeth = []
    for br, phi in zip(net.branches, sol.branch_flux_Wb, strict=True):
        for e in br.elements:
            if isinstance(e, mk.IronPath) and e.name.startswith("iron_teeth_"):
                b_teeth.append(abs(phi) / e.cross_section_m2)
    b_teeth = np.array(b_teeth)
    assert b_teeth.size == 12
    # computed at (10 mm, 33.5 A): 1.00 .. 1.24 T.  Every tooth carries > 0.95 T and the
    # most loaded ones exceed B_mymax = 1.2 T of M700-100A (facts.md sec. 4), where its
    # permeability is already falling: the teeth matter for the knee.
    assert b_teeth.min() > 0.95
    assert b_teeth.max() > 1.2


def test_eddy_elements_in_pole_cores_and_back_only(std: mk.Magnet) -> None:
    """Solid parts (pole cores, pole back) carry eddy elements; the laminated stator packs
    and teeth, the gaps and the leakage paths do not (docs/magnets.md, element table)."""
    with_eddy = {br.name for br in std.network.branches
                 if any(isinstance(e, mk.EddyCurrent) for e in br.elements)}
    gaps = pole_gap_names(12)
    cores = {f"core_{p}" for p in gaps}
    backs = {f"back_{a}_{b}" for a, b in zip(gaps[:-1], gaps[1:], strict=True)}
    assert with_eddy == cores | backs
    n_eddy = sum(isinstance(e, mk.EddyCurrent) for br in std.network.branches for e in br.elements)
    assert n_eddy == 23       # exactly one per solid part
    assert not std.with_options(eddy_currents=False).network.has_eddy_currents


@pytest.mark.parametrize("assignment", [
    [1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3],          # 2-8-2
    [1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3],          # interleaved
])
def test_bow_magnet_other_assignment(tmp_path, assignment) -> None:  # type: ignore[no-untyped-def]
    p = _params("tr09-bow")
    p["circuits"]["assignment"] = assignment
    mag = mk.load_magnet(_write(tmp_path, p))
    assert mag.circuit_names == ("c1", "c2", "c3")
    r_pole = p["magnet"]["resistance_per_pole"]
    for i, c in enumerate(mag.network.circuits):
        poles = [k for k, a in enumerate(assignment) if a == i + 1]
        assert [coil.branch for coil in c.coils] == [f"core_p{k + 1:02d}" for k in poles]
        # polarity alternates along the magnet whatever circuit feeds the pole
        assert [coil.polarity for coil in c.coils] == [1 if k % 2 == 0 else -1 for k in poles]
        assert c.resistance_ohm == pytest.approx(len(poles) * r_pole, rel=1e-12)
    # same iron and gaps: with all circuits at the same current the MMF pattern is that of
    # the standard magnet, so the total force is equal (solver precision, Newton 1e-9)
    f = mk.solve_statics(mag, gaps_m=0.010, currents_A=30.0).force_N
    f_std = mk.solve_statics(paper_tr09("tr09-standard"), gaps_m=0.010, currents_A=30.0).force_N
    assert f == pytest.approx(f_std, rel=1e-9)
