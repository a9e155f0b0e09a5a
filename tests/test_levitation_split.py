"""Levitation magnets with ``flux_paths = "split"``: the paths checked against the 2-D FEM
(issue 26, docs/validation_fem.md): the cores split along the coil, the LIG grooves as slots
of the face, the flank fringing through the window's teeth.  Topology and element formulas;
the statics against the FEM are tests/test_fem_tr09.py."""

from __future__ import annotations

import sys
from importlib import resources

import numpy as np
import pytest
from scipy.optimize import brentq

import maglevkit as mk
from maglevkit.circuit import FringePermeance
from maglevkit.magnets import pole_gap_names

from .test_magnets_levitation import _carter_by_hand, _write

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

MU0 = 4e-7 * np.pi


def _params(name: str) -> dict:
    p = tomllib.loads((resources.files("maglevkit") / "data" / f"{name}.toml").read_text())
    p["magnet"]["flux_paths"] = "split"
    p["provenance"]["magnet.flux_paths"] = "[E] modelling choice: the FEM-checked paths"
    # the split network's lumped eddy elements (the file names the ladder since switch26m;
    # the ladder's tubes: tests/test_eddy_ladder*.py, tests/test_fem_tr09_transient.py)
    p["magnet"]["eddy_model"] = "lumped"
    return p


def _split(name: str = "tr09-standard") -> mk.Magnet:
    return mk.build_magnet(_params(name))


@pytest.fixture(scope="module")
def std() -> mk.Magnet:
    return _split()


def test_network_shape_and_names(std: mk.Magnet) -> None:
    net = std.network
    assert net.gap_names == pole_gap_names(12)
    assert net.circuit_names == ("front", "rear")
    # per pole: K + 1 = 4 core segments (coil_segments K = 3) and beside each the air
    # through the coil's cross-section, gap, teeth and their slots' air under the face,
    # the stator yoke over the two half faces, per side (l, r) window teeth and their
    # slots' air, flank fringe, 1 flank strip (the strips start below window/pi = 43.9
    # mm, where the tube's arc pi y/2 reaches half the window: y0 = 15 mm; the second
    # strip starts at 48.3 mm; until fringe26 it was window/2 = 69 mm and 2 strips), one
    # pole-back leakage; the two end poles' back end face and back underside to the stator
    # beyond and two more flank strips on their outer side (no neighbour: strips along the
    # whole coil); per
    # neighbour pair: pole back, stator (over the window), leakage between the heads and
    # per coil strip (3); nodes per pole: head, 3 coil nodes, pole back, stator at the
    # centre and at the two face edges, the two sides' window teeth, tooth tips
    # (with eddy currents, the default, each segment's eddy element is a branch of its
    # own in series with iron and coil air, through a node E per segment)
    # and per side the slot at the face edge between the face's teeth and the window's
    per_pole, per_pair = 3 * 4 + 1 + 2 + 2 + 2 * (2 + 1 + 1 + 1) + 1, 1 + 1 + 1 + 3
    assert len(net.branches) == 12 * per_pole + 2 * 4 + 11 * per_pair == 410
    assert len(net.nodes) == 12 * (11 + 4) and net.n_loops == 410 - 180 + 1
    # each circuit drives 6 poles with alternating polarity; every pole's winding is
    # spread over its 4 core segments, whose turns add up to turns_per_pole, and the air
    # beside each segment carries that segment's turns (its MMF cancels the coil's, so it
    # sees the iron's drop); the pole's winding keeps n = turns_per_pole (pole_turns)
    N = net.turns_matrix
    for c in net.circuits:
        assert len(c.coils) == 6 * 8
        poles = sorted({coil.pole for coil in c.coils})
        assert len(poles) == 6
        for k, pole in enumerate(poles):
            coils = [coil for coil in c.coils if coil.pole == pole]
            assert {coil.polarity for coil in coils} == {1 if k % 2 == 0 else -1}
            assert {coil.pole_turns for coil in coils} == {190.0}
            core = {coil.branch: coil.turns for coil in coils if coil.branch.startswith("core")}
            air = {coil.branch: coil.turns for coil in coils if coil.branch.startswith("coil_air")}
            assert sum(core.values()) == pytest.approx(190.0, rel=1e-12)
            assert sorted(air.values()) == pytest.approx(sorted(core.values()), rel=1e-12)
    assert np.count_nonzero(N) == 96
    assert std.network.has_eddy_currents


def test_lig_grooves_matter(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Without the LIG grooves the pole face is whole: more gap permeance, more force."""
    p = _params("tr09-standard")
    m = p["magnet"]
    with_g = _split()
    p["magnet"]["lig_grooves"] = 0
    no_g = mk.load_magnet(_write(tmp_path, p))
    f_with = mk.solve_statics(with_g, gaps_m=0.010, currents_A=33.5).force_N
    f_no = mk.solve_statics(no_g, gaps_m=0.010, currents_A=33.5).force_N
    assert f_no > 1.01 * f_with
    # the grooves (20 mm deep, 10 mm wide: deeper than half their width) are slots in the
    # face: each takes Carter's slot loss gamma(b/(2s)) s off the face length (at the true
    # gap s; docs/magnets.md), dG = mu0 n_g w_p gamma s / s'; exact to round-off
    st = p["stator"]
    s = 0.010
    sp = _carter_by_hand(s, st["slot_pitch"], st["slot_opening"]) * s
    x = m["lig_groove_width"] / (2.0 * s)
    gamma = 4.0 / np.pi * (x * np.arctan(x) - np.log(np.sqrt(1.0 + x * x)))
    d_expected = MU0 * 2 * m["pole_width"] * gamma * s / sp

    def g(mag: mk.Magnet) -> float:
        e = next(e for br in mag.network.branches for e in br.elements
                 if isinstance(e, mk.AirGap) and e.name == "gap_p01")
        return float(e.permeance(s))

    assert g(no_g) - g(with_g) == pytest.approx(d_expected, rel=1e-10)
    # a shallow groove (depth < width/2) is the groove bottom in series with the gap
    p["magnet"]["lig_grooves"] = 2
    p["magnet"]["lig_groove_depth"] = 0.004
    shallow = mk.load_magnet(_write(tmp_path, p))
    a_g = 2 * m["lig_groove_width"] * m["pole_width"]
    d_shallow = MU0 * a_g * (1.0 / sp - 1.0 / (sp + 0.004))
    assert g(no_g) - g(shallow) == pytest.approx(d_shallow, rel=1e-10)


def test_leakage_permeances_against_roters() -> None:
    """leak_pp, leak_pb and the flank strips equal the Roters formulas of docs/magnets.md,
    evaluated here."""
    m = _params("tr09-standard")["magnet"]
    st = _params("tr09-standard")["stator"]
    net = _split().network
    wp, lp, tau = m["pole_width"], m["pole_length"], m["pole_pitch"]
    hc, tc, hf = m["coil_height"], m["coil_thickness"], m["coil_to_face"]
    window, h = tau - lp, hc / 3.0                     # coil_segments = 3 (default)
    # pole to pole: parallel faces across the window, the flank below the coil between the
    # heads and one coil strip between the coil nodes
    g_pp_face, g_pp_strip = MU0 * wp * hf / window, MU0 * wp * h / window
    # pole to pole back: half hollow cylinder mu0 l ln(1 + t/r_i)/pi, r_i = h_c/2
    per_m = MU0 * np.log(1.0 + tc / (hc / 2.0)) / np.pi
    g_pb_inner = per_m * 2.0 * (lp + 2.0 * tc)
    g_pb_end = per_m * (2.0 * (lp + 2.0 * tc) + (wp + 2.0 * tc))
    leak = {e.name: e.value_H for br in net.branches for e in br.elements
            if isinstance(e, mk.LeakagePermeance)}
    pp = {k: v for k, v in leak.items() if k.startswith("leak_pp_")}
    pb = {k: v for k, v in leak.items() if k.startswith("leak_pb_")}
    slots = {k: v for k, v in leak.items() if "slots_" in k}
    air = {k: v for k, v in leak.items() if k.startswith("coil_air_")}
    across = {k: v for k, v in leak.items() if k.startswith("across_")}
    assert len(pp) == 11 * 4 and len(pb) == 12 and len(slots) == 36 and len(air) == 12 * 4
    assert len(across) == 24 and len(leak) == 44 + 12 + 36 + 48 + 24
    # across the slot at each face edge (face teeth T -> that side's window teeth W): the
    # potential difference falls linearly from the tips to the roots, so the slot of
    # opening b and depth d carries mu0 wp dV d/(2 b): int_0^d mu0 wp (1 - y/d)/b dy
    y = np.linspace(0.0, st["slot_depth"], 20001)
    g_across = float(np.trapezoid(MU0 * wp * (1 - y / st["slot_depth"]) / st["slot_opening"], y))
    for name, v in across.items():
        assert v == pytest.approx(g_across, rel=1e-8), name
    # the air through the coil's cross-section beside each core segment: linked width per
    # flank int_0^tc (1 - x/a)(1 - x/tc) dx (a = window/2; an end pole's outer flank
    # a -> oo: tc/2), here evaluated by the trapezoidal rule, over the segment's length
    # (face to the first coil node, coil strips, last coil node to the back's underside)
    x = np.linspace(0.0, tc, 20001)
    w_in = float(np.trapezoid((1 - x / (0.5 * window)) * (1 - x / tc), x))
    w_out = float(np.trapezoid(1 - x / tc, x))
    seg = [hf + 0.5 * h, h, h, m["core_height"] - hf - hc + 0.5 * h]
    for name, v in air.items():
        pole, j = int(name[10:12]), int(name[-1])
        width = w_in + (w_out if pole in (1, 12) else w_in)
        assert v == pytest.approx(MU0 * wp * width / seg[j], rel=1e-8), name
    # the slots' air beside the teeth: mu0 (footprint x wp x b/tau_s) / slot depth, the
    # footprint being the pole length under the face and each side's half window
    share = st["slot_opening"] / st["slot_pitch"]
    for name, v in slots.items():
        footprint = 0.5 * window if name.startswith("window_") else lp
        assert v == pytest.approx(MU0 * footprint * wp * share / st["slot_depth"], rel=1e-12)
    for name, v in pp.items():
        strip = name.count("_") == 4                   # leak_pp_pXX_pYY_j
        assert v == pytest.approx(g_pp_strip if strip else g_pp_face, rel=1e-12)
    for name, v in pb.items():
        end = name in ("leak_pb_p01", "leak_pb_p12")
        assert v == pytest.approx(g_pb_end if end else g_pb_inner, rel=1e-12)
    # the flank strips of an inner pole (each flank, wp, lands on its own side's window
    # teeth): the field of the pole edge over the stator plane at Carter's s' (conformal
    # map: the flank point at height y has v - atan v = pi y/(2 s'), the strip carries
    # (mu0 wp/pi) ln((1 + v1^2)/(1 + v0^2)); v found here by a bracketing root finder),
    # one strip 15-43.9 mm (window/pi, where the tube's arc is half the window long); the
    # end pole's outer flank (pole 1, side l) has no neighbour: three strips along the
    # coil, 15-48.3, 48.3-81.7, 81.7-115 mm; the flank below the coil (fringe_) the same
    # law over 0-15 mm
    sp = _carter_by_hand(0.010, st["slot_pitch"], st["slot_opening"]) * 0.010
    inner = [(hf, window / np.pi)]
    outer = [(hf + j * h, hf + (j + 1) * h) for j in range(3)]
    fringe = {e.name: e for br in net.branches for e in br.elements
              if isinstance(e, FringePermeance)}
    flank = {k: e for k, e in fringe.items() if k.startswith(("flank_p02_", "flank_p01_"))}
    assert sorted(flank) == ["flank_p01_1_l", "flank_p01_1_r", "flank_p01_2_l",
                             "flank_p01_3_l", "flank_p02_1_l", "flank_p02_1_r"]

    def ln_1v2(y: float) -> float:
        q = np.pi * y / (2 * sp)
        v = brentq(lambda v: v - np.arctan(v) - q, 0.0, q + 2.0, xtol=1e-15)
        return float(np.log(1 + v * v))

    def conformal(y0: float, y1: float) -> float:
        return MU0 * wp / np.pi * (ln_1v2(y1) - (ln_1v2(y0) if y0 > 0 else 0.0))

    def roters(y0: float, y1: float) -> float:
        return 2 * MU0 * wp / np.pi * np.log((sp + np.pi * y1 / 2) / (sp + np.pi * y0 / 2))

    for j, (y0, y1) in enumerate(inner, start=1):
        for name in (f"flank_p02_{j}_l", f"flank_p02_{j}_r", f"flank_p01_{j}_r"):
            assert float(flank[name].permeance(0.010)) == pytest.approx(conformal(y0, y1),
                                                                        rel=1e-10)
    for j, (y0, y1) in enumerate(outer, start=1):
        assert float(flank[f"flank_p01_{j}_l"].permeance(0.010)) == pytest.approx(
            conformal(y0, y1), rel=1e-10)
    for k in ("fringe_p01_l", "fringe_p02_r"):
        assert float(fringe[k].permeance(0.010)) == pytest.approx(conformal(0.0, hf),
                                                                  rel=1e-10)
    # the end poles' back end face (depth 130 ... 210 mm below the face; the quarter
    # circles clear the coil's outer corner at hypot(115, 45) = 123.5 mm < 130 mm) to the
    # stator beyond the magnet, one flank of width wp
    y0, y1 = m["core_height"], m["core_height"] + m["back_height"]
    assert np.hypot(hf + hc, tc) < y0
    end = roters(y0, y1)
    assert sorted(k for k in fringe if k.startswith("end_")) == ["end_p01", "end_p12"]
    for k in ("end_p01", "end_p12"):
        assert float(fringe[k].permeance(0.010)) == pytest.approx(end, rel=1e-12)
    # and the back's underside from its end to the window centre (u <= lp/2 + tau/2): half
    # circles about the bottom corner, up beside the end (D = 210 mm) and across the gap,
    # (mu0 wp/pi) ln((s' + D + pi u)/(s' + D))
    depth, u = y1, 0.5 * lp + 0.5 * tau
    under = MU0 * wp / np.pi * np.log((sp + depth + np.pi * u) / (sp + depth))
    assert sorted(k for k in fringe if k.startswith("under_")) == ["under_p01", "under_p12"]
    for k in ("under_p01", "under_p12"):
        assert float(fringe[k].permeance(0.010)) == pytest.approx(under, rel=1e-12)
    # sanity of the magnitudes against the gap: each leakage is a few % of a pole's gap
    # permeance at 10 mm (~2.3e-6 H), so the leakage factor stays realistic (< 1.3)
    assert g_pp_strip < 0.1 * 2.3e-6 and g_pb_end < 0.1 * 2.3e-6


def test_iron_is_saturable_and_teeth_are_loaded(std: mk.Magnet) -> None:
    net = std.network
    irons = [e for br in net.branches for e in br.elements if isinstance(e, mk.IronPath)]
    # 12 x 4 core segments + 12 tooth groups under the faces + 2 x 12 in the windows
    # + 2 x 12 yoke halves over the faces + 11 back + 11 stator segments, all with a B-H curve
    assert len(irons) == 48 + 12 + 24 + 24 + 11 + 11
    assert all(e.material.saturates for e in irons)
    # at 33.5 A, the files' nominal current before issue 26 (at today's 31.7 A: 0.89 .. 1.12 T)
    sol = mk.solve_statics(std, gaps_m=std.nominal_gap, currents_A=33.5)
    b_teeth = []
    for br, phi in zip(net.branches, sol.branch_flux_Wb, strict=True):
        for e in br.elements:
            if isinstance(e, mk.IronPath) and e.name.startswith("iron_teeth_"):
                b_teeth.append(abs(phi) / e.cross_section_m2)
    b_teeth = np.array(b_teeth)
    assert b_teeth.size == 12
    # computed at (10 mm, 33.5 A): 0.93 .. 1.17 T in the teeth under the faces (the flank
    # fringing rises in the window's teeth, issue 26).  Every tooth carries > 0.9 T and the
    # most loaded ones approach B_mymax = 1.2 T of M700-100A, where its permeability
    # starts to fall: the teeth matter for the knee.
    assert b_teeth.min() > 0.9
    assert b_teeth.max() > 1.1


def test_eddy_elements_in_pole_cores_and_back_only(std: mk.Magnet) -> None:
    """Solid parts (pole cores, pole back) carry eddy elements; the laminated stator packs
    and teeth, the gaps and the leakage paths do not (docs/magnets.md, element table)."""
    with_eddy = {br.name for br in std.network.branches
                 if any(isinstance(e, mk.EddyCurrent) for e in br.elements)}
    gaps = pole_gap_names(12)
    # a core segment's eddy element is a branch of its own (eddy_core_...), in series with
    # the segment's iron and the coil air beside it
    cores = {f"eddy_core_{p}_{j}" for p in gaps for j in range(4)}
    backs = {f"back_{a}_{b}" for a, b in zip(gaps[:-1], gaps[1:], strict=True)}
    assert with_eddy == cores | backs
    n_eddy = sum(isinstance(e, mk.EddyCurrent) for br in std.network.branches for e in br.elements)
    assert n_eddy == 12 * 4 + 11       # exactly one per core segment and pole-back segment
    # the segments of a core carry, together, the eddy conductance of the whole core (the
    # element's conductance is proportional to its length), from the face to the pole
    # back's underside (the junction belongs to the pole back's path)
    m = std.parameters["magnet"]
    whole = mk.EddyCurrent.solid_rectangular("c", m["pole_length"], m["pole_width"],
                                             m["core_height"], 9.0e-8)
    parts = [mk.EddyCurrent.solid_rectangular("c", m["pole_length"], m["pole_width"],
                                              e.length_m, 9.0e-8)
             for br in std.network.branches if br.name.startswith("core_p01_")
             for e in br.elements if isinstance(e, mk.IronPath)]
    assert sum(e.conductance_S for e in parts) == pytest.approx(whole.conductance_S, rel=1e-12)
    assert not std.with_options(eddy_currents=False).network.has_eddy_currents


def test_teeth_and_slot_air_share_one_mmf_deep_in_saturation(std: mk.Magnet) -> None:
    """At 10 mm / 100 A (teeth ~2.1 T, where M700-100A's differential permeability is
    ~2 mu0) the face flux splits between the teeth and the air of their slots at one
    magnetic potential drop: the apparent tooth flux density of machine design,
    ``phi = A_t B(H) + mu0 H A_slot`` with ``H`` the teeth's field (closed form, from
    the material's B-H law alone); the tooth-tip node conserves flux (with the slots at
    the face edges to the window's teeth); and the core's
    length is the core height (the junction counted once, in the pole back)."""
    mag = std.with_options(eddy_currents=False)
    net = mag.network
    sol = mk.solve_statics(mag, gaps_m=0.010, currents_A=[100.0, 100.0])
    flux = dict(zip(sol.branch_names, np.ravel(sol.branch_flux_Wb), strict=True))
    st = mag.parameters["stator"]
    el = {e.name: e for br in net.branches for e in br.elements}
    for p in pole_gap_names(12):
        teeth, slot = el[f"iron_teeth_{p}"], el[f"slots_{p}"]
        # Kirchhoff at the tooth tips: gap = teeth + slots + the slots at the face edges
        # to the window's teeth (the solver's loop fluxes)
        assert flux[f"gap_{p}"] == pytest.approx(
            flux[f"teeth_{p}"] + flux[f"slots_{p}"] + flux[f"across_{p}_l"]
            + flux[f"across_{p}_r"], rel=1e-9)
        b = flux[f"teeth_{p}"] / teeth.cross_section_m2
        h = float(teeth.material.field_strength(abs(b)))
        # the slots' air at the teeth's field: B_air = mu0 H over the slots' area
        a_slot = slot.value_H * st["slot_depth"] / MU0
        assert abs(flux[f"slots_{p}"]) == pytest.approx(MU0 * h * a_slot, rel=1e-9)
    # deep in saturation the slots carry a few % of the face flux, far more of its
    # increment: mu0 A_slot against mu_diff(2.1 T) A_t ~ 2 mu0 A_t
    share = abs(flux["slots_p09"] / flux["gap_p09"])
    assert 0.01 < share < 0.1
    m = mag.parameters["magnet"]
    lengths = sum(e.length_m for br in net.branches if br.name.startswith("core_p01_")
                  for e in br.elements if isinstance(e, mk.IronPath))
    assert lengths == pytest.approx(m["core_height"], rel=1e-12)


def test_split_network_reciprocity_by_ad_in_saturation(std: mk.Magnet) -> None:
    """Co-energy reciprocity ``dF_k/dI_j = -dpsi_j/ds_k`` (both from CasADi's AD of the
    network) at a knee point and deep in saturation, per pole and circuit: a check that
    the new parallel branches enter the co-energy consistently."""
    mag = std.with_options(eddy_currents=False)
    for s, i in ((0.010, 50.0), (0.006, 100.0)):
        sol = mk.solve_statics(mag, gaps_m=s, currents_A=[i, 0.8 * i])
        df_di = np.asarray(sol.dforce_dcurrent_N_per_A)        # (gaps, circuits)
        dpsi_ds = np.asarray(sol.dpsi_dgap_Wb_per_m)           # (circuits, gaps)
        scale = np.max(np.abs(df_di))
        # round-off of the Newton solution (1e-12) and of the AD Jacobians
        assert np.max(np.abs(df_di + dpsi_ds.T)) < 1e-7 * scale


def test_coil_air_sees_the_iron_drop() -> None:
    """The air beside a core segment carries the segment's turns, so its MMF cancels the
    coil's and its flux is its permeance times the iron's own potential drop (tangential H
    continuous at the flank), in deep saturation and below the knee alike.  Its share of the
    core's flux grows with saturation (measured 0.07 % at 10 mm / 10 A, 0.74 % at 100 A):
    a term of the increment in deep saturation, not of the statics below the knee."""
    mag = mk.build_magnet(_params("tr09-standard"), options=mk.ModelOptions(eddy_currents=False))
    leak = {e.name: e.value_H for br in mag.network.branches for e in br.elements
            if isinstance(e, mk.LeakagePermeance)}
    shares = {}
    for i in (10.0, 100.0):
        sol = mk.solve_statics(mag, gaps_m=0.010, currents_A=[i, i])
        flux = dict(zip(sol.branch_names, np.ravel(sol.branch_flux_Wb), strict=True))
        for j in range(4):
            iron = next(e for br in mag.network.branches if br.name == f"core_p09_{j}"
                        for e in br.elements if isinstance(e, mk.IronPath))
            drop = float(iron.mmf_drop(flux[f"core_p09_{j}"], 0.010))
            # Newton to ~1e-10 relative; the drop is a difference of O(1e4) A potentials
            assert flux[f"coil_air_p09_{j}"] == pytest.approx(leak[f"coil_air_p09_{j}"] * drop,
                                                              rel=1e-6, abs=1e-12)
        shares[i] = abs(flux["coil_air_p09_2"] / flux["core_p09_2"])
    assert shares[10.0] < 0.001 and 5 * shares[10.0] < shares[100.0] < 0.02, shares
