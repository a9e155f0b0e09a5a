"""The ``end_effects`` switch of the guidance and bow magnets (issue 26).

The guidance magnet's ``"paper"`` network is already the 2-D cross-section (no term across
the cut: the bars and the rail run through the sections, the magnet's two ends are
neglected), so ``end_effects = false`` must build exactly the same network and ``true`` the
same again.  (The bundled file's ``"split"`` paths take their depth from the switch; that
cut is tested in tests/test_guidance_split.py.)  The bow
magnet shares the levitation builder: its cut removes exactly the along-track fringing edges
of every face and the across-track share of the pole-back leakage, as the standard magnet's.
"""

from __future__ import annotations

import copy
import math

import numpy as np

import maglevkit as mk

MU0 = 4e-7 * math.pi


def _paper_guidance(eddy: bool) -> mk.Magnet:
    """The bundled guidance magnet with the ``"paper"`` paths (the file sets ``"split"``)."""
    p = copy.deepcopy(mk.load_magnet("tr-guidance").parameters)
    p["magnet"]["flux_paths"] = "paper"
    return mk.build_magnet(p, options=mk.ModelOptions(eddy_currents=eddy))


def test_guidance_cut_is_todays_network() -> None:
    for eddy in (False, True):
        today = _paper_guidance(eddy)
        cut, on = today.with_options(end_effects=False), today.with_options(end_effects=True)
        assert cut.parameters["magnet"]["end_effects"] is False
        assert on.parameters["magnet"]["end_effects"] is True
        # the key is in the parameters (and so in the hash), the network is unchanged:
        # element by element (frozen dataclasses compare by value)
        assert cut.parameter_hash != today.parameter_hash
        assert cut.network == today.network and on.network == today.network
    gaps, cur = np.array([0.006, 0.010, 0.020]), np.array([10.0, 32.0, 60.0])
    a = mk.solve_statics(today.with_options(eddy_currents=False), gaps_m=gaps, currents_A=cur,
                         grid=True)
    b = mk.solve_statics(cut.with_options(eddy_currents=False), gaps_m=gaps, currents_A=cur,
                         grid=True)
    # the same equations: bit-identical
    np.testing.assert_array_equal(a.force_N, b.force_N)
    np.testing.assert_array_equal(a.flux_linkage_Wb, b.flux_linkage_Wb)


def test_bow_cut_removes_exactly_the_across_track_terms() -> None:
    full = mk.load_magnet("tr09-bow", eddy_currents=False)
    cut = full.with_options(end_effects=False)
    on = full.with_options(end_effects=True)
    assert on.network == full.network                        # true: today's network
    m = full.parameters["magnet"]
    lp, wp, hc, tc = m["pole_length"], m["pole_width"], m["coil_height"], m["coil_thickness"]
    ln = math.log(1.0 + tc / (0.5 * hc)) / math.pi
    a = {b.name: b for b in full.network.branches}
    b = {br.name: br for br in cut.network.branches}
    # the cut loses the inner poles' pole-back leakage (across-track sides only)
    assert set(a) - set(b) == {f"leak_pb_p{k:02d}" for k in range(2, 12)}
    assert set(b) <= set(a)
    for name, br in b.items():
        if name.startswith("leak_pb_"):                      # end poles: outer side, depth wp
            (el,) = br.elements
            (full_el,) = a[name].elements
            assert math.isclose(el.value_H, MU0 * wp * ln, rel_tol=1e-12)
            assert math.isclose(full_el.value_H,
                                MU0 * (2 * (lp + 2 * tc) + wp + 2 * tc) * ln, rel_tol=1e-12)
        elif name.startswith("gap_"):                        # along-track edges dropped
            gap, full_gap = br.elements[0], a[name].elements[0]
            assert isinstance(gap, mk.AirGap)
            assert [e for e in full_gap.fringe_edges if e not in gap.fringe_edges] == \
                [e for e in full_gap.fringe_edges if e[0] == lp]
            assert all(e[0] == wp for e in gap.fringe_edges)
            assert len(full_gap.fringe_edges) == len(gap.fringe_edges) + 2
        else:
            assert br == a[name], name
