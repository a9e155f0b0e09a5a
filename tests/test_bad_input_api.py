"""Bad input to the Python API and to parameter files (issue 10, API half).

Every public entry point validates numbers and switches through one path
(``maglevkit.validation``): bools, strings and other non-numbers are refused, switches
must be True/False, time spans follow one rule in ``simulate`` and in scenario files,
inputs far outside a magnet's physical range warn, and wrong types give a specific
``MaglevkitError`` instead of a TypeError/AttributeError/CasADi traceback.
"""

from __future__ import annotations

import copy
import math
import sys
import warnings
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit import carter_coefficient
from maglevkit.magnets.base import MAX_CURRENT_DENSITY_A_PER_M2, Schema, take
from maglevkit.models import parse_scenario

from .conftest import build_u, loop_network, u_params

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _params(name: str) -> dict[str, Any]:
    text = (resources.files("maglevkit") / "data" / f"{name}.toml").read_text()
    return copy.deepcopy(tomllib.loads(text))


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _write(tmp_path: Path, params: dict[str, Any], name: str = "m.toml") -> Path:
    lines = []
    for table, values in params.items():
        lines.append(f"[{table}]")
        lines += [f'"{k}" = {_toml(v)}' for k, v in values.items()]
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def u_lin() -> mk.Magnet:
    """The bundled U-magnet without eddy currents (cheap transients)."""
    return mk.load_magnet("u-magnet", eddy_currents=False)


# ----------------------------------------------------------------- 1. schema checks
def test_negative_integer_count_is_refused(tmp_path: Path) -> None:
    # was: integer values skipped the "nonnegative" check (+26 % force from -2 grooves)
    p = _params("tr09-standard")
    p["magnet"]["lig_grooves"] = -2
    with pytest.raises(mk.ParameterFileError, match=r"\[magnet\] lig_grooves = -2: must be >= 0"):
        mk.load_magnet(_write(tmp_path, p))


@pytest.mark.parametrize(("key", "value", "msg"), [
    ("poles", 0, r"poles = 0: must be > 0"),
    ("poles", True, r"poles = True: expected a whole number"),
    ("poles", 12.5, r"poles = 12.5: must be a whole number"),
    ("lig_grooves", 1.5, r"lig_grooves = 1.5: must be a whole number"),
    ("pole_width", -0.17, r"pole_width = -0.17 m: must be > 0"),
    ("pole_width", math.inf, r"pole_width = inf: must be finite"),
    ("pole_width", True, r"pole_width = True: expected a number \[m\]"),
])
def test_schema_checks_apply_to_every_number_type(key: str, value: Any, msg: str) -> None:
    p = _params("tr09-standard")
    p["magnet"][key] = value
    with pytest.raises(mk.ParameterFileError, match=msg):
        mk.build_magnet(p)


def test_whole_float_is_accepted_for_a_count() -> None:
    # "poles = 12.0" means 12: the same network (its repr covers every element) as 12
    p = _params("tr09-standard")
    p["magnet"]["poles"] = 12.0
    assert repr(mk.build_magnet(p).network) == repr(mk.load_magnet("tr09-standard").network)


def test_schema_with_an_unknown_check_is_a_programming_error() -> None:
    with pytest.raises(TypeError, match="nonnegativ"):
        Schema(int, check="nonnegativ")
    with pytest.raises(mk.ParameterFileError, match=r"\[t\] n = -1: must be >= 0"):
        take({"n": -1}, {"n": Schema(int, check="nonnegative")}, "t")


# ----------------------------------------------------------------- 2. one validation path
@pytest.mark.parametrize(("gaps", "currents", "msg"), [
    (True, 20.0, r"gaps \[m\] = True \(bool\) is a bool"),
    (0.01, True, r"circuit currents \[A\] = True \(bool\) is a bool"),
    ("0.01", 20.0, r"gaps \[m\] = '0.01' \(str\) is a string"),
    ([0.01, "0.01"], 20.0, r"contains a string \('0.01'\)"),
    (0.01, np.array([True]), r"is an array of bool values"),
    (0.01, 1 + 2j, r"is a complex"),
    (None, 20.0, r"is a NoneType"),
    ({"left": 0.01, "right": False}, 20.0, r"gap 'right' \[m\] = False \(bool\) is a bool"),
])
def test_statics_refuses_non_numbers(u_magnet: mk.Magnet, gaps: Any, currents: Any,
                                     msg: str) -> None:
    # was: gaps=True computed a 1 m gap, currents=True 1 A, gaps="0.01" was parsed
    with pytest.raises(mk.InputError, match=msg):
        mk.solve_statics(u_magnet, gaps_m=gaps, currents_A=currents)


def test_statics_grid_switch_and_grid_values(u_magnet: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match=r"grid = 'no' \(str\): expected True or False"):
        mk.solve_statics(u_magnet, gaps_m=0.01, currents_A=20.0, grid="no")
    with pytest.raises(mk.InputError, match=r"currents \[A\] = \['0', '10'\] \(list\) contains a "
                                            r"string"):
        mk.solve_statics(u_magnet, gaps_m=[0.01, 0.02], currents_A=["0", "10"], grid=True)


@pytest.mark.parametrize("value", ["no", "false", 0, 1, None, "True"])
def test_physics_switches_must_be_bools(u_magnet: mk.Magnet, value: Any) -> None:
    # was: with_options(saturation="no") and load_magnet(saturation="no") switched it ON
    msg = r"saturation = .*: expected True or False"
    with pytest.raises(mk.InputError, match=msg):
        u_magnet.with_options(saturation=value)
    with pytest.raises(mk.InputError, match=msg):
        mk.load_magnet("u-magnet", saturation=value)
    with pytest.raises(mk.InputError, match=msg):
        mk.ModelOptions(saturation=value)
    if value is not None:  # None means "as built" for FluxModel
        with pytest.raises(mk.InputError, match=msg):
            mk.FluxModel(u_magnet, saturation=value)


def test_numpy_bool_switch_is_a_bool(u_magnet: mk.Magnet) -> None:
    lin = u_magnet.with_options(saturation=np.False_)
    assert lin.options.saturation is False
    assert lin.network == u_magnet.with_options(saturation=False).network


def test_simulate_refuses_bool_initial_currents(u_lin: mk.Magnet) -> None:
    # was: initial_currents=True ran at 1 A
    with pytest.raises(mk.InputError, match=r"initial_currents \[A\] = True \(bool\) is a bool"):
        mk.simulate(u_lin, (0.0, 1e-3), dt_s=1e-4, gaps_m=0.01, voltages_V=1.0, initial_currents_A=True)


@pytest.fixture(scope="module")
def small_maps() -> Any:
    # 4 x 4 maps of the ideal-iron U-magnet: ~1 s, enough to construct a CurrentModel
    return mk.build_maps(build_u(material="ideal", fringing=False, leakage=False),
                         gaps_m=np.linspace(0.004, 0.02, 4), currents_A=np.linspace(0.0, 80.0, 4),
                         progress=False)


def test_simulate_refuses_bool_initial_currents_for_the_reduced_model(small_maps: Any) -> None:
    cm = mk.CurrentModel(small_maps)
    with pytest.raises(mk.InputError, match=r"initial_currents \[A\] = True \(bool\) is a bool"):
        mk.simulate(cm, (0.0, 1e-3), dt_s=1e-4, gaps_m=0.01, voltages_V=1.0, initial_currents_A=True)


@pytest.mark.parametrize(("kwargs", "msg"), [
    ({"gaps_m": "0.01"}, r"gaps \[m\] = '0.01' \(str\) is a string"),
    ({"voltages_V": ["1.0"]}, r"voltages \[V\] = \['1.0'\] \(list\) contains a string"),
    ({"voltages_V": lambda t: "1.0"}, r"the callable must return numbers \[V\].*is a string"),
    ({"gaps_m": lambda t: True}, r"the callable must return numbers \[m\].*is a bool"),
    ({"gap_rate_tolerance": "0.1", "gap_rates_m_per_s": 0.0}, r"gap_rate_tolerance = '0.1' \(str\)"),
])
def test_simulate_refuses_non_numbers(u_lin: mk.Magnet, kwargs: dict[str, Any], msg: str) -> None:
    args: dict[str, Any] = {"gaps_m": 0.01, "voltages_V": 1.0, **kwargs}
    with pytest.raises(mk.InputError, match=msg):
        mk.simulate(u_lin, (0.0, 1e-3), dt_s=1e-4, **args)


def test_simulate_refuses_string_times(u_lin: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match=r"t \[s\] = \('0', '0.001'\) \(tuple\) contains a "
                                            r"string"):
        mk.simulate(u_lin, ("0", "0.001"), dt_s=1e-4, gaps_m=0.01, voltages_V=1.0)


@pytest.mark.parametrize(("kwargs", "msg"), [
    ({"max_num_steps": True}, r"max_num_steps = True \(bool\)"),
    ({"max_num_steps": 10.5}, r"max_num_steps = 10.5: must be a whole number"),
    ({"radau_elements": 0}, r"radau_elements = 0: must be a whole number >= 1"),
    ({"rtol": "1e-6"}, r"rtol = '1e-6' \(str\)"),
    ({"method": 1}, r"method = 1; use 'idas'"),
])
def test_flux_model_options(u_lin: mk.Magnet, kwargs: dict[str, Any], msg: str) -> None:
    with pytest.raises(mk.InputError, match=msg):
        mk.FluxModel(u_lin, **kwargs)


def test_flux_model_step_and_state_inputs(u_lin: mk.Magnet) -> None:
    fm = mk.FluxModel(u_lin)
    with pytest.raises(mk.InputError, match=r"time \[s\] = '0' \(str\)"):
        fm.initial_state(gaps_m=0.01, currents_A=10.0, time_s="0")
    st = fm.initial_state(gaps_m=0.01, currents_A=10.0)
    with pytest.raises(mk.InputError, match=r"voltages \[V\] = '20' \(str\) is a string"):
        fm.step(st, 1e-4, "20")
    with pytest.raises(mk.InputError, match=r"gaps \[m\] = True \(bool\) is a bool"):
        fm.step(st, 1e-4, 20.0, gaps_m=True)
    with pytest.raises(mk.InputError, match=r"dt \[s\] = True \(bool\)"):
        fm.step(st, True, 20.0)


# ----------------------------------------------------------------- 3. one time-span rule
def test_dt_longer_than_the_span_is_refused_like_in_scenario_files(u_lin: mk.Magnet) -> None:
    # was: dt = 1 s over a 0.01 s span silently returned the 2 samples [0, 0.01]
    msg = r"dt = 1 s exceeds the simulated span tf - t0 = 0.01 s"
    with pytest.raises(mk.InputError, match=msg):
        mk.simulate(u_lin, (0.0, 0.01), dt_s=1.0, gaps_m=0.01, voltages_V=1.0)
    scenario = {"scenario": {"duration": 0.01, "dt": 1.0}, "voltages": {"all": 1.0},
                "gaps": {"all": 0.01}}
    with pytest.raises(mk.ParameterFileError, match=r"\[scenario\] " + msg):
        parse_scenario(scenario, "s.toml")


def test_dt_equal_to_the_span_is_a_two_point_grid(u_lin: mk.Magnet) -> None:
    # the boundary of the rule: allowed in both places
    res = mk.simulate(u_lin, (0.0, 1e-3), dt_s=1e-3, gaps_m=0.01, voltages_V=1.0)
    np.testing.assert_array_equal(res.time_s, [0.0, 1e-3])
    sc = parse_scenario({"scenario": {"duration": 1e-3, "dt": 1e-3}, "voltages": {"all": 1.0},
                         "gaps": {"all": 0.01}}, "s.toml")
    assert sc.dt_s == sc.duration_s == 1e-3


def test_scenario_numbers_must_be_finite() -> None:
    with pytest.raises(mk.ParameterFileError, match=r"\[scenario\] duration = inf: must be finite"):
        parse_scenario({"scenario": {"duration": math.inf, "dt": 1e-3},
                        "voltages": {"all": 1.0}, "gaps": {"all": 0.01}}, "s.toml")


# ----------------------------------------------------------------- 4. plausibility
def test_plausible_range_from_the_geometry() -> None:
    # bounds recomputed here from the file values (not from the code's formulas' output)
    p = u_params()["magnet"]
    u = mk.load_magnet("u-magnet").plausible_range
    assert u is not None
    assert u.max_gap_m == p["pole_width"] == 0.030
    # 100 A/mm^2 on one leg's coil: 1e8 * 0.050 m * 0.015 m / 300 turns = 250 A
    assert MAX_CURRENT_DENSITY_A_PER_M2 == 100e6
    assert u.max_current_A == pytest.approx(250.0, rel=1e-12)
    t = mk.load_magnet("tr09-standard").plausible_range
    assert t is not None
    assert t.max_gap_m == 0.12                                # pole length < width 0.17
    assert t.max_current_A == pytest.approx(1e8 * 0.10 * 0.045 / 190, rel=1e-12)  # 2368 A
    g = mk.load_magnet("tr-guidance").plausible_range
    assert g is not None
    assert g.max_gap_m == 0.06                                # pole-bar height
    assert g.max_current_A == pytest.approx(1e8 * 0.12 * 0.06 / 300, rel=1e-12)   # 2400 A


def test_gap_in_millimetres_warns(u_magnet: mk.Magnet) -> None:
    # "--gaps 10" meant 10 mm: a 10 m gap on a 30 mm pole
    with pytest.warns(mk.PlausibilityWarning, match=r"gap 10 m is larger than the pole width "
                                                    r"\(0.03 m\)"):
        sol = mk.solve_statics(u_magnet, gaps_m=10.0, currents_A=20.0)
    assert np.isfinite(sol.force_N)          # warned, not refused: the result is still there


def test_current_no_coil_carries_warns(u_magnet: mk.Magnet) -> None:
    with pytest.warns(mk.PlausibilityWarning, match=r"current 1e\+06 A exceeds 250 A, i.e. "
                                                    r"100 A/mm\^2 in the coil of one leg"):
        mk.solve_statics(u_magnet, gaps_m=0.01, currents_A=1e6)
    with pytest.warns(mk.PlausibilityWarning, match=r"current 1e\+06 A exceeds"):
        mk.solve_statics(u_magnet, gaps_m=0.01, currents_A=-1e6)     # magnitude counts


def test_documented_grids_do_not_warn(u_magnet: mk.Magnet) -> None:
    # the README's and demo's grids (4-20 mm, 0-80 A) stay silent on every bundled magnet
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in mk.bundled_magnets():
            m = mk.load_magnet(name)
            mk.solve_statics(m, gaps_m=np.linspace(0.004, 0.02, 2),
                             currents_A=np.linspace(0.0, 80.0, 2), grid=True)
        # the bound itself is allowed (rounding allowance 1e-9)
        mk.solve_statics(u_magnet, gaps_m=0.030, currents_A=250.0)


def test_flux_model_and_simulate_warn(u_lin: mk.Magnet) -> None:
    fm = mk.FluxModel(u_lin)
    with pytest.warns(mk.PlausibilityWarning, match=r"FluxModel.initial_state: current 1000 A"):
        fm.initial_state(gaps_m=0.01, currents_A=1000.0)
    st = fm.initial_state(gaps_m=0.01, currents_A=10.0)
    with pytest.warns(mk.PlausibilityWarning, match=r"FluxModel.step: gap 5 m"):
        fm.step(st, 1e-4, 20.0, gaps_m=5.0)
    with pytest.warns(mk.PlausibilityWarning, match=r"simulate: gap 10 m"):
        mk.simulate(fm.with_options(rtol=1e-5), (0.0, 1e-3), dt_s=1e-3, gaps_m=10.0, voltages_V=1.0)
    # the voltages drive the currents: 1e4 V on 2 ohm is 5 kA at steady state; after
    # 1 ms (tau = L/R ~ 30 ms) the current is far above 250 A already
    with pytest.warns(mk.PlausibilityWarning, match=r"the currents the voltages drive"):
        mk.simulate(fm, (0.0, 1e-3), dt_s=1e-3, gaps_m=0.01, voltages_V=1e4, initial_currents_A=240.0)


def test_bare_network_has_no_range() -> None:
    # a hand-built Network has no geometry to judge by: no warning, documented
    net = loop_network(eddy=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mk.solve_statics(net, gaps_m=10.0, currents_A=1e6)


# ----------------------------------------------------------------- 5. turns, provenance
@pytest.mark.parametrize(("name", "key", "value", "msg"), [
    ("u-magnet", "turns", 600.5, r"turns = 600.5: must be a whole number"),
    ("tr09-standard", "turns_per_pole", 190.5, r"turns_per_pole = 190.5: must be a whole"),
    ("tr-guidance", "turns_per_yoke", 299.9, r"turns_per_yoke = 299.9: must be a whole"),
])
def test_turns_must_be_whole(tmp_path: Path, name: str, key: str, value: Any, msg: str) -> None:
    p = _params(name)
    p["magnet"][key] = value
    with pytest.raises(mk.ParameterFileError, match=msg):
        mk.load_magnet(_write(tmp_path, p))


def test_missing_provenance_table_warns(tmp_path: Path) -> None:
    p = _params("u-magnet")
    del p["provenance"]
    path = _write(tmp_path, p)
    with pytest.warns(mk.ProvenanceWarning, match=r"m.toml: no \[provenance\] table"):
        m = mk.load_magnet(path)
    assert m.provenance == {}


def test_missing_provenance_entries_are_named(tmp_path: Path) -> None:
    p = _params("tr09-standard")
    del p["provenance"]["magnet.turns_per_pole"]
    del p["provenance"]["stator.width"]
    with pytest.warns(mk.ProvenanceWarning,
                      match=r"no entry for magnet.turns_per_pole, stator.width"):
        mk.load_magnet(_write(tmp_path, p))


def test_malformed_provenance_tag_warns() -> None:
    p = _params("u-magnet")
    p["provenance"]["magnet.turns"] = "estimate"
    with pytest.warns(mk.ProvenanceWarning, match=r"tag\(s\) of magnet.turns do not start with "
                                                  r"\[P\], \[R\], \[E\]"):
        mk.build_magnet(p)


def test_bundled_magnets_load_without_warnings() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in mk.bundled_magnets():
            m = mk.load_magnet(name)
            m.with_options(saturation=False)      # a rebuild does not warn again either


# ----------------------------------------------------------------- 6. no tracebacks
def test_absurd_dimension_is_a_named_error_not_a_casadi_traceback() -> None:
    # was: RuntimeError "Evaluation failed" from CasADi, then a SolverError at the first
    # solve; since tidy26 a length beyond the physical limits (10 nm ... 10 km) is refused
    # when the file is read, naming the key (test_plausible_files)
    p = _params("tr09-standard")
    p["magnet"]["pole_pitch"] = 1e30
    with pytest.raises(mk.ParameterFileError, match=r"\[magnet\] pole_pitch = 1e\+30 m cannot "
                                                    r"be physical"):
        mk.build_magnet(p)


def test_a_name_instead_of_a_magnet() -> None:
    msg = r"model = 'u-magnet' is a name or path, not a magnet; load it first: .*load_magnet"
    with pytest.raises(mk.InputError, match=msg):
        mk.solve_statics("u-magnet", gaps_m=0.01, currents_A=20.0)
    with pytest.raises(mk.InputError, match=msg):
        mk.build_maps("u-magnet", gaps_m=np.linspace(0.005, 0.01, 4),
                      currents_A=np.linspace(0, 10, 4))
    with pytest.raises(mk.InputError, match=r"model = 'u-magnet.toml' is a name or path"):
        mk.FluxModel(Path("u-magnet.toml"))
    with pytest.raises(mk.InputError, match=msg):
        mk.simulate("u-magnet", (0.0, 1e-3), gaps_m=0.01, voltages_V=1.0)


@pytest.mark.parametrize("call", [
    lambda: mk.load_magnet(None),  # type: ignore[arg-type]
    lambda: mk.load_magnet(42),  # type: ignore[arg-type]
    lambda: mk.load_magnet(""),
    lambda: mk.load_scenario(None),  # type: ignore[arg-type]
    lambda: mk.solve_statics(None, gaps_m=0.01, currents_A=1.0),
    lambda: mk.coenergy(42, gaps_m=0.01, currents_A=1.0),
    lambda: mk.magnetic_energy(mk.load_magnet("u-magnet"), "x", 0.01),
    lambda: mk.FluxModel({"magnet": {}}),
    lambda: mk.pole_force_eq6(1e-3, "4e-4"),
    lambda: mk.pole_force_eq6(1e-3, 4e-4, mu_r=0.5),
    lambda: mk.build_magnet(_params("u-magnet"), options={"saturation": False}),  # type: ignore[arg-type]
])
def test_wrong_types_give_input_errors(call: Any) -> None:
    with pytest.raises(mk.InputError, match=r"expected|must|not a magnet"):
        call()


def test_with_options_unknown_switch(u_magnet: mk.Magnet) -> None:
    # was: TypeError from ModelOptions.__init__
    with pytest.raises(mk.InputError, match=r"unknown switch\(es\) \['bogus'\]; the physics "
                                            r"switches are saturation, fringing, leakage, "
                                            r"eddy_currents"):
        u_magnet.with_options(bogus=1)


def test_circuit_constructors_refuse_bools_and_strings() -> None:
    with pytest.raises(mk.ParameterError, match=r"turns = True must be > 0"):
        mk.Coil("core", True)
    with pytest.raises(mk.ParameterError, match=r"polarity must be \+1 or -1"):
        mk.Coil("core", 10, polarity=True)
    with pytest.raises(mk.ParameterError, match=r"resistance_ohm = True must be"):
        mk.Circuit("c", True, (mk.Coil("core", 10),))
    with pytest.raises(mk.TopologyError, match=r"network branches must be a sequence of Branch "
                                               r"objects, got str"):
        mk.Network("abc", ())  # type: ignore[arg-type]
    with pytest.raises(mk.TopologyError, match=r"network circuits: 'coil' is not a Circuit"):
        mk.Network(loop_network(eddy=False).branches, ("coil",))  # type: ignore[arg-type]
    with pytest.raises(mk.InputError, match=r"gap_m \[m\] = '0.01' \(str\) is a string"):
        carter_coefficient("0.01", 0.086, 0.035)
    with pytest.raises(mk.ParameterError, match=r"slot_opening_m = 0.1 m must be smaller "
                                                r"than slot_pitch_m"):
        carter_coefficient(0.01, 0.086, 0.1)


def test_step_experiment_arguments(u_lin: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match=r"circuit = True must be an index"):
        mk.differential_inductance_from_step(u_lin, gap_m=0.01, current_A=10.0, circuit=True)
    with pytest.raises(mk.InputError, match=r"samples_per_tau = 'many'"):
        mk.differential_inductance_from_step(u_lin, gap_m=0.01, current_A=10.0,
                                             samples_per_tau="many")
    with pytest.raises(mk.InputError, match=r"gap \[m\]|gaps \[m\] = '0.01'"):
        mk.voltage_step_response(u_lin, gap_m="0.01", voltage_V=1.0, duration_s=1e-3, dt_s=1e-4)


def test_vehicle_and_controller_arguments(u_lin: mk.Magnet) -> None:
    from maglevkit.control import closed_loop, design_gap_controller
    from maglevkit.vehicle import HeaveMass, HeaveState

    with pytest.raises(mk.ParameterError, match=r"mass_kg \[kg\] = '1000' \(str\)"):
        HeaveMass("1000")  # type: ignore[arg-type]
    with pytest.raises(mk.ParameterError, match=r"mass_kg \[kg\] = True \(bool\)"):
        HeaveMass(True)
    mass = HeaveMass(100.0)
    with pytest.raises(mk.InputError, match=r"dt \[s\] = True \(bool\)"):
        mass.step(HeaveState(0.01, 0.0), True, 0.0)
    with pytest.raises(mk.InputError, match=r"damping = 'high' \(str\)"):
        design_gap_controller(u_lin, mass_kg=100.0, gap_m=0.01, current_A=10.0, damping="high")
    ctl = design_gap_controller(u_lin, mass_kg=100.0, gap_m=0.01, current_A=10.0)
    fm = mk.FluxModel(u_lin)
    common: dict[str, Any] = {"initial_gap_m": 0.01, "initial_current_A": 10.0}
    # was: 0.5 s at 0.3 s steps silently ran 0.6 s
    with pytest.raises(mk.InputError, match=r"duration_s = 0.5 s is not a whole number of steps "
                                            r"dt_s = 0.3 s"):
        closed_loop(fm, mass, ctl, duration_s=0.5, dt_s=0.3, **common)
    with pytest.raises(mk.InputError, match=r"dt = 1 s exceeds the simulated span"):
        closed_loop(fm, mass, ctl, duration_s=0.01, dt_s=1.0, **common)
    with pytest.raises(mk.InputError, match=r"initial_current_A \[A\] = True \(bool\)"):
        closed_loop(fm, mass, ctl, duration_s=0.01, dt_s=1e-3, initial_gap_m=0.01,
                    initial_current_A=True)


def test_unknown_flux_model_options(u_lin: mk.Magnet) -> None:
    # was: TypeError from FluxModel.__init__
    msg = r"unknown option\(s\) \['bogus'\]; the FluxModel options are saturation, eddy_currents"
    with pytest.raises(mk.InputError, match=r"simulate: " + msg):
        mk.simulate(u_lin, (0.0, 1e-3), gaps_m=0.01, voltages_V=1.0, bogus=1)
    with pytest.raises(mk.InputError, match=r"FluxModel.with_options: " + msg):
        mk.FluxModel(u_lin).with_options(bogus=1)
    with pytest.raises(mk.InputError, match=msg):
        mk.voltage_step_response(u_lin, gap_m=0.01, voltage_V=1.0, duration_s=1e-3, dt_s=1e-4, bogus=1)
