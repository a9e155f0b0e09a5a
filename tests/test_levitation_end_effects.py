"""Levitation magnets: the ``end_effects`` switch (across-track terms on/off, issue 26).

``end_effects = false`` must give exactly the longitudinal-cut network: the default
network with the two along-track fringing edges of every pole face removed and the
pole-back leakage cut down to the end poles' outer side over the depth ``pole_width``.
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from importlib import resources

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit import Branch, Network

from .conftest import paper_tr09, tr09_params

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

MU0 = 4e-7 * math.pi


def _params(name: str) -> dict:
    return tomllib.loads((resources.files("maglevkit") / "data" / f"{name}.toml").read_text())


@pytest.fixture(scope="module")
def pair() -> tuple[mk.Magnet, mk.Magnet]:
    # the lumped "paper" network, loaded explicitly (the bundled file is split since issue 26;
    # the split network's cut is checked below)
    full = paper_tr09("tr09-standard", eddy_currents=False)
    return full, full.with_options(end_effects=False)


def _by_hand(full: mk.Magnet) -> Network:
    """The longitudinal cut built from the full network by hand."""
    m = full.parameters["magnet"]
    lp, wp, hc, tc = m["pole_length"], m["pole_width"], m["coil_height"], m["coil_thickness"]
    # the end poles' outer side only, over the cut's depth: half hollow cylinder
    g_end = MU0 * wp * math.log(1.0 + tc / (0.5 * hc)) / math.pi
    out: list[Branch] = []
    for br in full.network.branches:
        if br.name.startswith("leak_pb_"):
            if br.name not in ("leak_pb_p01", "leak_pb_p12"):
                continue
            (el,) = br.elements
            out.append(replace(br, elements=(replace(el, value_H=g_end),)))
        elif br.name.startswith("gap_"):
            gap, teeth = br.elements
            assert isinstance(gap, mk.AirGap)
            # the fringing edges of length pole_length run along the track: dropped
            edges = tuple(e for e in gap.fringe_edges if e[0] != lp)
            assert len(edges) == 2 and all(w == wp for w, _ in edges)
            out.append(replace(br, elements=(replace(gap, fringe_edges=edges), teeth)))
        else:
            out.append(br)
    return Network(tuple(out), full.network.circuits, name="by hand")


def test_cut_equals_the_hand_built_network(pair: tuple[mk.Magnet, mk.Magnet]) -> None:
    full, cut = pair
    hand = _by_hand(full)
    assert sorted(b.name for b in cut.network.branches) == sorted(b.name for b in hand.branches)
    gaps, cur = np.array([0.008, 0.010, 0.016]), np.array([10.0, 33.5, 80.0])
    a = mk.solve_statics(cut, gaps_m=gaps, currents_A=cur, grid=True)
    b = mk.solve_statics(hand, gaps_m=gaps, currents_A=cur, grid=True)
    # the same equations in another branch order: agreement to the Newton tolerance
    np.testing.assert_allclose(a.force_N, b.force_N, rtol=1e-9)
    np.testing.assert_allclose(a.flux_linkage_Wb, b.flux_linkage_Wb, rtol=1e-9)


def test_cut_has_less_force_and_flux(pair: tuple[mk.Magnet, mk.Magnet]) -> None:
    """Fewer parallel permeances: less flux linkage everywhere.  Below the knee also less
    force (the dropped fringing tubes carry force; the dropped leakage, a few % of a
    pole's gap permeance, cannot outweigh them).  In deep saturation the core flux is
    limited by the iron, and without the pole-back leakage more of it crosses the gap:
    the force then rises."""
    full, cut = pair
    gaps, cur = np.array([0.006, 0.010, 0.020]), np.array([10.0, 33.5, 100.0])
    a = mk.solve_statics(full, gaps_m=gaps, currents_A=cur, grid=True)
    b = mk.solve_statics(cut, gaps_m=gaps, currents_A=cur, grid=True)
    assert np.all(b.flux_linkage_Wb < a.flux_linkage_Wb)
    assert np.all(b.force_N[:, :2] < a.force_N[:, :2])
    assert np.all(b.force_N[:2, 2] > a.force_N[:2, 2])
    # at 10 mm / 10 A (linear iron) the force falls by about the dropped fringing
    # permeance's share of the gap permeance: a few %, bounded by 10 %
    rel = b.force_N[1, 0] / a.force_N[1, 0] - 1.0
    assert -0.10 < rel < -0.005


def test_file_key_equals_with_options(tmp_path, pair) -> None:  # type: ignore[no-untyped-def]
    full, cut = pair
    p = tr09_params("tr09-standard", flux_paths="paper")       # the pair's network
    p["magnet"]["end_effects"] = False
    # a file value needs its provenance tag (the switch adds none to the parameters)
    with pytest.warns(mk.ProvenanceWarning, match="magnet.end_effects"):
        from_file = mk.build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
    assert from_file.parameter_hash == cut.parameter_hash
    assert cut.parameter_hash != full.parameter_hash
    sa = mk.solve_statics(from_file, gaps_m=0.010, currents_A=40.0)
    sb = mk.solve_statics(cut, gaps_m=0.010, currents_A=40.0)
    np.testing.assert_array_equal(sa.force_N, sb.force_N)
    # true is the default: the file key and the switch give back the full network
    back = cut.with_options(end_effects=True)
    assert mk.solve_statics(back, gaps_m=0.010, currents_A=40.0).force_N == pytest.approx(
        mk.solve_statics(full, gaps_m=0.010, currents_A=40.0).force_N, rel=1e-12)


def test_bad_end_effects_values() -> None:
    p = _params("tr09-standard")
    p["magnet"]["end_effects"] = "no"
    with pytest.raises(mk.ParameterFileError, match=r"end_effects = 'no': expected true or false"):
        mk.build_magnet(p)
    std = mk.load_magnet("tr09-standard")
    with pytest.raises(mk.InputError, match=r"end_effects = 0 \(int\): expected True or False"):
        std.with_options(end_effects=0)
    # every bundled kind has the key now (the guidance magnet's: tests/test_guidance_end_effects.py)
    guid = mk.load_magnet("tr-guidance")
    assert guid.with_options(end_effects=False).parameters["magnet"]["end_effects"] is False
    with pytest.raises(mk.InputError, match=r"unknown switch\(es\) \['end_effect'\]"):
        std.with_options(end_effect=False)


def test_coil_segments_key() -> None:
    """``flux_paths = "split"``: ``coil_segments`` splits each core along its coil; the
    turns of a pole add up to ``turns_per_pole`` whatever K, and a finer split changes the statics little (the
    leakage's MMF profile along the coil converges): 10 mm / 33.5 A, K = 3 vs 6 within 1 %
    (measured 0.1 % force, 0.5 % flux linkage).  Bad values name the key and the range."""
    p = _params("tr09-standard")
    p["magnet"]["flux_paths"] = "split"
    p["provenance"]["magnet.flux_paths"] = "[E] modelling choice: the FEM-checked paths"
    mags = {}
    for k in (1, 3, 6):
        p["magnet"]["coil_segments"] = k
        with pytest.warns(mk.ProvenanceWarning, match="magnet.coil_segments"):
            mags[k] = mk.build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
        for c in mags[k].network.circuits:
            # K + 1 core segments, each with the coil-air branch beside it (same turns)
            core = [coil for coil in c.coils if coil.branch.startswith("core_")]
            assert len(c.coils) == 2 * len(core) == 2 * 6 * (k + 1)
            assert sum(coil.turns for coil in core) == pytest.approx(6 * 190.0, rel=1e-12)
    s3 = mk.solve_statics(mags[3], gaps_m=0.010, currents_A=33.5)
    s6 = mk.solve_statics(mags[6], gaps_m=0.010, currents_A=33.5)
    assert float(s6.force_N) == pytest.approx(float(s3.force_N), rel=0.01)
    np.testing.assert_allclose(s6.flux_linkage_Wb, s3.flux_linkage_Wb, rtol=0.01)
    p["magnet"]["coil_segments"] = 0
    with pytest.raises(mk.ParameterFileError, match=r"coil_segments = 0: must be > 0"):
        mk.build_magnet(p)
    p["magnet"]["coil_segments"] = 13
    with pytest.raises(mk.ParameterFileError, match=r"coil_segments = 13: allowed are 1 \.\.\. 12"):
        mk.build_magnet(p)


def test_flux_paths_key() -> None:
    """Bad values name the key and what is allowed; coil_segments needs "split"."""
    p = _params("tr09-standard")
    p["magnet"]["flux_paths"] = "fem"
    with pytest.raises(mk.ParameterFileError,
                       match=r"flux_paths = 'fem': expected one of 'paper', 'split'"):
        mk.build_magnet(p)
    p["magnet"]["flux_paths"] = "paper"
    p["magnet"]["coil_segments"] = 3
    with pytest.raises(mk.ParameterFileError, match=r"coil_segments applies to flux_paths"):
        mk.build_magnet(p)
