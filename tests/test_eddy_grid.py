"""Diffusing eddy currents of the U-magnet, part 2: the rail split under and between the
poles (``eddy_model = "ladder_split"``) and the ladders on the cell network
(``discretisation = "grid"``, ``eddy_model = "ladder"``), docs/equations.md section 1b.

Independent references: the lumped network's statics, the ladder's own coefficients
(:func:`maglevkit.circuit.ladder.ladder_parameters`), and the transient 2-D FEM recorded by
``benchmarks/fem_u_magnet_transient.py`` in ``benchmarks/results/fem_transient_cases.json``
(its rail and core eddy powers separately).
"""

from __future__ import annotations

import copy
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit.elements import EddyCurrent, IronPath
from maglevkit.circuit.ladder import LADDER_COEFFICIENTS
from maglevkit.errors import ParameterFileError
from maglevkit.magnets.base import ModelOptions, build_magnet

ROOT = Path(__file__).resolve().parents[1]
FEM_CASES = ROOT / "benchmarks" / "results" / "fem_transient_cases.json"


def _grid(**options: object) -> mk.Magnet:
    params = copy.deepcopy(mk.load_magnet("u-magnet").parameters)
    params["magnet"]["discretisation"] = "grid"
    params["provenance"]["magnet.discretisation"] = "[E] test variant"
    return build_magnet(params, options=ModelOptions(**options))  # type: ignore[arg-type]


def _fem_case(label: str) -> dict:
    return next(r for r in json.loads(FEM_CASES.read_text())["runs"] if r["label"] == label)


def _fem_energy(ref: dict, key: str) -> float:
    t, p = np.asarray(ref["time_s"]), np.asarray(ref[key])
    return float(np.sum(np.diff(t) * p[1:]))


def _run(mag: mk.Magnet, ref: dict) -> tuple[dict, float]:
    """Metrics of the flux model against ``ref`` and the model's rail eddy energy [J]."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from fem_u_magnet_transient import body_energies, metrics

    fm = mk.FluxModel(mag, rtol=1e-7, compiled="never")
    res = mk.simulate(fm, np.asarray(ref["time_s"]), gaps_m=ref["gap_m"],
                      voltages_V=mag.network.resistances[0] * ref["i1_A"],
                      initial_currents_A=ref["i0_A"])
    return metrics(res.time_s, res.currents_A[:, 0], res.eddy_loss_J, ref), \
        body_energies(res)[1]


def test_rail_split_scales_only_the_rail_conductances() -> None:
    a = mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=4).network
    b = mk.load_magnet("u-magnet", eddy_model="ladder_split", eddy_layers=4).network
    assert a.branch_names == b.branch_names
    ga, gb = a.eddy_conductances, b.eddy_conductances
    rail = np.array([n.split(":")[0] == "rail" for n in a.branch_names])
    # eddy length w_w + 2 w_p/3 = 60 + 20 mm of the rail's iron path w_w + w_p + t = 120 mm
    np.testing.assert_allclose(gb[rail], ga[rail] * (0.060 + 0.020) / 0.120, rtol=1e-12)
    np.testing.assert_array_equal(gb[~rail], ga[~rail])
    assert (ga[rail] > 0).sum() == 4          # the 4 eddy elements of the rail ladder
    # statics: parallel tubes of one material carry one B whatever the eddy conductances
    s0 = mk.solve_statics(mk.load_magnet("u-magnet"), gaps_m=0.006, currents_A=50.0)
    s1 = mk.solve_statics(mk.load_magnet("u-magnet", eddy_model="ladder_split",
                                         eddy_layers=4), gaps_m=0.006, currents_A=50.0)
    # measured 1e-11 relative (the Newton tolerance)
    assert float(s1.force_N) == pytest.approx(float(s0.force_N), rel=1e-8)


def test_grid_ladders_are_the_parts_slab_on_each_link() -> None:
    lumped = _grid()
    ladder = _grid(eddy_model="ladder", eddy_layers=3)
    a, w = LADDER_COEFFICIENTS[3]
    rho = 1.5e-7                      # ohm m, AISI 1008 of the bundled magnet
    checked = {"leg": 0, "yoke": 0, "rail": 0}
    for br in lumped.network.branches:
        if not any(isinstance(el, EddyCurrent) for el in br.elements):
            continue
        (iron,) = [el for el in br.elements if isinstance(el, IronPath)]
        part = {"frame_v": "leg", "frame_h": "yoke", "rail_h": "rail"}[
            "_".join(br.name.split("_")[:2])]
        # pole width, yoke thickness, rail thickness of the bundled magnet: all 30 mm
        thick = {"leg": 0.030, "yoke": 0.030, "rail": 0.030}[part]
        tubes = [ladder.network.branch(f"{br.name}:tube{k + 1}").elements[0] for k in range(3)]
        # the tubes are the link's own section in the fitted fractions, same length
        np.testing.assert_allclose([t.cross_section_m2 for t in tubes],
                                   np.array(a) * iron.cross_section_m2, rtol=1e-12)
        assert all(t.length_m == iron.length_m for t in tubes)
        # conductances of the part's 2-D slab (thickness t, half-thickness b) on the
        # link's section: m links in parallel are the part's ladder (docs/equations.md 1b)
        g = [ladder.network.branch(br.name).elements[0].conductance_S] + [
            ladder.network.branch(f"{br.name}:eddy{k + 1}").elements[0].conductance_S
            for k in (1, 2)]
        scale = iron.length_m * thick * 0.5 * thick / (2.0 * rho * iron.cross_section_m2)
        np.testing.assert_allclose(g, np.array(w) * scale, rtol=1e-12)
        checked[part] += 1
    # every eddy link of the grid became a ladder (measured: 54 leg, 33 yoke, 45 rail
    # links on the bundled grid, 132 in all)
    assert checked == {"leg": 54, "yoke": 33, "rail": 45}


def test_grid_refuses_the_rail_split() -> None:
    with pytest.raises(ParameterFileError, match="ladder_split"):
        _grid(eddy_model="ladder_split")


def test_rail_split_brings_the_rail_eddy_energy_to_the_fem() -> None:
    ref = _fem_case("10 mm, 10 -> 20 A")
    m, rail = _run(mk.load_magnet("u-magnet", eddy_model="ladder_split", eddy_layers=6), ref)
    fem_rail = _fem_energy(ref, "eddy_power_rail_W")
    # measured: rail 0.238 J vs the FEM's 0.199 J (+20 %; the two-sided slab over the whole
    # rail path, eddy_model="ladder": 0.334 J, +68 %); bound 25 %
    assert abs(rail / fem_rail - 1.0) < 0.25
    # whole response: measured +0.2 % of the step at 1 ms, max 2.5 % for t >= 1 ms
    # (ladder: 2.8 %), eddy energy +12 % (ladder: +18 %); bounds 1 %, 3 %, 15 %
    assert abs(m["err_1ms"]) < 0.01
    assert m["err_max"] < 0.03
    assert abs(m["e_eddy_J"] / m["e_eddy_fem_J"] - 1.0) < 0.15


@pytest.mark.slow
def test_rail_split_all_recorded_steps() -> None:
    """All four recorded steps (docs/validation_fem.md section 5)."""
    for ref in json.loads(FEM_CASES.read_text())["runs"]:
        m, rail = _run(mk.load_magnet("u-magnet", eddy_model="ladder_split", eddy_layers=6),
                       ref)
        # measured: at 1 ms +0.2 ... +3.0 % of the step, max (t >= 1 ms) 2.5 / 3.4 / 6.2 /
        # 5.3 %, E_eddy -2 ... +12 %, rail -15 ... +20 %, t63 -13.2 ... +0.3 %: the aims
        # (5 % / 5 % / 20 %) are met for the energy everywhere and for the current below
        # the knee, not in saturation and not for t63 (the static network, see the docs)
        assert abs(m["err_1ms"]) < 0.035
        assert m["err_max"] < 0.07
        assert abs(m["e_eddy_J"] / m["e_eddy_fem_J"] - 1.0) < 0.15
        assert abs(rail / _fem_energy(ref, "eddy_power_rail_W") - 1.0) < 0.25
        assert abs(m["t63_s"] / m["t63_fem_s"] - 1.0) < 0.15


@pytest.mark.slow
def test_grid_ladder_statics_are_the_grid_statics() -> None:
    a = mk.solve_statics(_grid(), gaps_m=0.006, currents_A=50.0)
    b = mk.solve_statics(_grid(eddy_model="ladder", eddy_layers=2), gaps_m=0.006, currents_A=50.0)
    # parallel tubes of one material and length carry one B: measured 7e-11 relative in
    # force and 4e-11 in flux linkage (the Newton tolerance); bound 1e-8
    assert float(b.force_N) == pytest.approx(float(a.force_N), rel=1e-8)
    assert float(b.flux_linkage_Wb[0]) == pytest.approx(float(a.flux_linkage_Wb[0]), rel=1e-8)


@pytest.mark.slow
def test_air_cells_without_eddy_currents_rise_with_the_fem() -> None:
    """The air-cell network (``air_model = "cells"``, statics within 3 % of the FEM) in the
    transient: a saturating step without eddy currents against the FEM with sigma = 0
    (``benchmarks/results/fem_transient_noeddy.json``); its flux model runs on the sparse
    IDAS form (1386 loop and circuit unknowns)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from fem_u_magnet_transient import CELLS, model_magnet, rise_time

    noeddy = ROOT / "benchmarks" / "results" / "fem_transient_noeddy.json"
    ref = next(r for r in json.loads(noeddy.read_text())["runs"]
               if r["label"] == "10 mm, 20 -> 50 A")
    mag = model_magnet(**CELLS, eddy_currents=False)
    fm = mk.FluxModel(mag, rtol=1e-7, compiled="never")
    tf, i_f = np.asarray(ref["time_s"]), np.asarray(ref["current_A"])
    res = mk.simulate(fm, tf, gaps_m=ref["gap_m"], voltages_V=fm.resistances[0] * ref["i1_A"],
                      initial_currents_A=ref["i0_A"])
    i = res.currents_A[:, 0]
    t63 = rise_time(tf, i, ref["i0_A"], ref["i1_A"])
    t63_fem = rise_time(tf, i_f, ref["i0_A"], ref["i1_A"])
    err = np.max(np.abs(i - i_f)[tf >= 1e-3 - 1e-12]) / (ref["i1_A"] - ref["i0_A"])
    # measured: t63 26.23 vs 25.66 ms (+2.2 %; the grid with Roters tubes -9.8 %), max
    # current error 1.3 % of the step (grid 6.3 %); bounds 3 % (the statics' aim) and 2 %
    assert abs(t63 / t63_fem - 1.0) < 0.03
    assert err < 0.02


@pytest.mark.slow
def test_air_cells_with_the_ladder_meet_the_rise_time_aim_below_the_knee() -> None:
    """The step with the smallest margin (6 mm, 10 -> 20 A): the air-cell network with the
    slab ladder n = 8 on every eddy link against the transient FEM."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from fem_u_magnet_transient import CELLS, model_magnet

    ref = _fem_case("6 mm, 10 -> 20 A")
    m, rail = _run(model_magnet(**CELLS, eddy_model="ladder", eddy_layers=8), ref)
    # measured: t63 68.07 vs 65.38 ms (+4.1 %; n = 4: +12.3 %, n = 6: +6.5 %), max current
    # error 1.5 % of the step, eddy energy -8 %, rail -27 %; bounds: the 5 % for
    # t63 and current, 15 % for the energy (aim 20 %), the rail's deficit below 35 %
    assert abs(m["t63_s"] / m["t63_fem_s"] - 1.0) < 0.05
    assert m["err_max"] < 0.05
    assert abs(m["e_eddy_J"] / m["e_eddy_fem_J"] - 1.0) < 0.15
    assert 0.65 < rail / _fem_energy(ref, "eddy_power_rail_W") < 1.0
