"""Design optimisation (issue 25, part 3): maglevkit.design and ``maglevkit design``."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

from maglevkit import load_magnet
from maglevkit.cli import app
from maglevkit.design import (
    DesignSpecError,
    design_magnet,
    design_sensitivities,
    evaluate_design,
    read_design_spec,
    write_design_toml,
)
from maglevkit.models.statics import solve_statics

runner = CliRunner()


def example_doc() -> dict[str, Any]:
    text = (resources.files("maglevkit") / "data" / "designs" / "u-magnet-design.toml").read_text()
    return tomllib.loads(text)


def two_variable_doc() -> dict[str, Any]:
    """Pole width and coil height of the bundled U-magnet (coil thickness 15 mm, leg 70 mm
    fixed); 10 A/mm^2 continuous makes the optimum interior: the iron's 1.5 T fixes the pole
    width, the current density the coil height.  A current ramp of 100 A/s puts L~ into the
    (inactive) voltage bound, which the re-solved statics check."""
    doc = example_doc()
    doc["requirements"]["current_density_A_per_m2"] = 10e6
    doc["requirements"]["current_rate_A_per_s"] = 100.0     # L~ enters the voltage bound
    doc["variables"] = {"pole_width": [0.015, 0.040], "coil_height": [0.020, 0.060]}
    return doc


@pytest.fixture(scope="module")
def two_variable() -> tuple[Any, Any]:
    spec = read_design_spec(two_variable_doc())
    return spec, design_magnet(spec)


def lazy_grid_min(spec: Any, names: tuple[str, str], xa: np.ndarray, xb: np.ndarray,
                  mass: Callable[[Any, float, float], float]) -> tuple[float, tuple[float, float]]:
    """The lightest feasible point of the grid ``xa x xb`` of the variables ``names``
    (brute force; the mass is explicit in the geometry, so the points are checked in the
    order of their mass and the first feasible one is the grid's optimum -- the same
    answer as checking every point; shared with tests/test_design_tr09.py)."""
    pts = [(a, b) for a in xa for b in xb]
    masses = [mass(spec, a, b) for a, b in pts]
    for k in np.argsort(masses):
        a, b = pts[k]
        ev = evaluate_design(spec, dict(zip(names, (a, b), strict=True)))
        if ev["feasible"]:
            return ev["mass_kg"], (a, b)
    return math.inf, (math.nan, math.nan)


def _lazy_grid_min(spec: Any, wp: np.ndarray, hc: np.ndarray) -> tuple[float, tuple[float, float]]:
    return lazy_grid_min(spec, ("pole_width", "coil_height"), wp, hc, evaluate_mass)


def evaluate_mass(spec: Any, wp: float, hc: float) -> float:
    # magnet mass from the geometry, as the spec defines it (docs/design.md)
    m = spec.magnet.parameters["magnet"]
    c = spec.coil
    d, hl, ty, ww, tc = (m[k] for k in ("depth", "leg_height", "yoke_thickness",
                                        "window_width", "coil_thickness"))
    iron = (2 * wp * hl + (ww + 2 * wp) * ty) * d * c["iron_density_kg_per_m3"]
    turn = 2 * (wp + d) + math.pi * tc
    copper = 2 * c["fill_factor"] * hc * tc * turn * c["conductor_density_kg_per_m3"]
    return float(iron + copper)


def test_two_variable_optimum_matches_grid_search(two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    assert res.success and res.status == "Solve_Succeeded"
    assert res.mass_kg == pytest.approx(evaluate_mass(spec, res.values["pole_width"],
                                                      res.values["coil_height"]), rel=1e-12)
    # coarse grid over the bounds, then a grid a quarter as fine over the coarse optimum's
    # neighbouring cells
    wp = np.linspace(0.015, 0.040, 9)
    hc = np.linspace(0.020, 0.060, 9)
    _, (a, b) = _lazy_grid_min(spec, wp, hc)
    h_wp, h_hc = (wp[1] - wp[0]) / 4, (hc[1] - hc[0]) / 4
    fine_wp = a + h_wp * np.arange(-4, 5)
    fine_hc = b + h_hc * np.arange(-4, 5)
    m_grid, (a, b) = _lazy_grid_min(spec, fine_wp, fine_hc)
    # no grid point is lighter than the optimum (feasibility checked to 1e-6 relative,
    # the same order as IPOPT's constraint tolerance here)
    assert m_grid >= res.mass_kg * (1 - 1e-6)
    # ... and the grid's best lies within one fine cell up and right of the optimum: a wider
    # pole lowers B, a taller coil lowers J, so the corner (wp* + h, hc* + h) is feasible and
    # the grid optimum is at most one cell's mass increment above the true one
    dm = (evaluate_mass(spec, res.values["pole_width"] + h_wp, res.values["coil_height"] + h_hc)
          - res.mass_kg)
    assert m_grid - res.mass_kg <= dm
    assert abs(a - res.values["pole_width"]) <= h_wp
    assert abs(b - res.values["coil_height"]) <= h_hc


def check_active_constraints(spec: Any, res: Any) -> None:
    """Every reported-active constraint sits at its bound, every other has slack, and,
    independently (statics re-solved by solve_statics), a constraint is at its bound
    exactly when it is reported active (shared with tests/test_design_tr09.py)."""
    for c in res.constraints.values():
        if c.active:
            assert abs(c.slack) <= 1e-6 * max(abs(c.bound), 1.0), c
        else:
            assert c.slack > 1e-4 * max(abs(c.bound), 1e-3), c
    ev = evaluate_design(spec, res.values)
    req = spec.requirements
    at_bound = {
        "current_density": ev["current_density_A_per_m2"] / req["current_density_A_per_m2"],
        "flux_density": ev["flux_density_T"] / req["max_flux_density_T"],
        "voltage": ev["voltage_V"] / req["supply_voltage_V"],
        "force_reserve": req["reserve_factor"] * req["force_N"] / ev["force_reserve_N"]}
    for name, ratio in at_bound.items():
        assert (abs(ratio - 1.0) <= 1e-6) == (name in res.active), (name, ratio)


def check_written_design(spec: Any, res: Any, path: Path) -> tuple[Any, dict[str, Any]]:
    """Write the optimum, load it as any magnet file (no warning: complete and tagged), and
    re-solve its statics independently: it meets every constraint and reproduces the
    optimiser's values (shared with tests/test_design_tr09.py).  Returns the magnet and
    :func:`evaluate_design`'s values."""
    path = write_design_toml(res, path)
    assert "[E] optimised: maglevkit design" in path.read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("error")        # a complete, tagged parameter file
        mag = load_magnet(path)
    ev = evaluate_design(spec, magnet=mag)
    assert ev["feasible"]
    req = spec.requirements
    # the re-solved statics (solve_statics on the loaded file) reproduce the optimiser's
    # values: the same network law, solved to ~1e-12 relative by both
    assert ev["nominal_current_A"] == pytest.approx(res.nominal_current_A, rel=1e-7)
    assert ev["flux_density_T"] <= req["max_flux_density_T"] * (1 + 1e-6)
    assert ev["flux_density_T"] == pytest.approx(res.constraints["flux_density"].value,
                                                 rel=1e-7)
    assert ev["current_density_A_per_m2"] <= req["current_density_A_per_m2"] * (1 + 1e-6)
    assert ev["force_reserve_N"] >= req["reserve_factor"] * req["force_N"]
    assert ev["voltage_V"] <= req["supply_voltage_V"]
    assert ev["voltage_V"] == pytest.approx(res.constraints["voltage"].value, rel=1e-7)
    assert ev["power_W"] == pytest.approx(res.power_W, rel=1e-7)
    return mag, ev


def test_active_constraints_are_reported(two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    assert set(res.active) == {"force_nominal", "current_density", "flux_density"}
    check_active_constraints(spec, res)


def test_written_design_meets_the_constraints_resolved(tmp_path: Path,
                                                        two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    mag, ev = check_written_design(spec, res, tmp_path / "design.toml")
    req = spec.requirements
    sol = solve_statics(mag, gaps_m=req["nominal_gap_m"], currents_A=ev["nominal_current_A"])
    assert float(np.asarray(sol.force_N)) == pytest.approx(req["force_N"], rel=1e-9)


def test_design_gradients_match_central_differences() -> None:
    spec = read_design_spec(example_doc())
    values = {"pole_width": 0.027, "coil_height": 0.045, "coil_thickness": 0.014,
              "leg_height": 0.068}
    gap, cur = 0.008, 14.0
    check_design_gradients(spec, values, gap, cur)


def check_design_gradients(spec: Any, values: dict[str, float], gap: float, cur: float) -> None:
    """``design_sensitivities`` at (gap, current) equals the statics of the magnet built
    from the parameter file and its derivatives their central differences (shared with
    tests/test_design_tr09.py)."""
    from maglevkit.design import design_parameters
    from maglevkit.magnets import build_magnet

    sens = design_sensitivities(spec, values, gap_m=gap, current_A=cur)

    def statics(v: dict[str, float]) -> tuple[float, float]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mag = build_magnet(design_parameters(spec, v))
            sol = solve_statics(mag, gaps_m=gap, currents_A=cur)
        # per circuit: the magnet's force over its circuits; circuit 1's flux linkage
        return (float(np.asarray(sol.force_N)) / len(mag.network.circuits),
                float(np.asarray(sol.flux_linkage_Wb).ravel()[0]))

    f0, psi0 = statics(values)
    # the symbolic network equals the numeric one built from the parameter file
    assert sens["force_N"] == pytest.approx(f0, rel=1e-10)
    assert sens["flux_linkage_Wb"] == pytest.approx(psi0, rel=1e-10)
    for name, v in values.items():
        h = 1e-5 * v        # truncation ~h^2 f''' ~1e-10 relative; rounding of the
        #                     statics (~1e-13) / h ~1e-8: 1e-6 relative holds with margin
        fp, pp = statics({**values, name: v + h})
        fm, pm = statics({**values, name: v - h})
        assert sens["dforce_dp"][name] == pytest.approx((fp - fm) / (2 * h), rel=1e-6,
                                                        abs=1e-6 * abs(f0) / v), name
        assert sens["dpsi_dp"][name] == pytest.approx((pp - pm) / (2 * h), rel=1e-6,
                                                      abs=1e-6 * abs(psi0) / v), name


def test_turns_derivative_from_ampere_turns() -> None:
    # F depends on N I only and psi = N phi(N I): dF/dN = (I/N) dF/dI and
    # dpsi/dN = psi/N + (I/N) dpsi/dI, with dF/dI, dpsi/dI from solve_statics
    doc = example_doc()
    doc["variables"]["turns"] = [100, 1200]
    spec = read_design_spec(doc)
    values = {"pole_width": 0.03, "coil_height": 0.05, "coil_thickness": 0.015,
              "leg_height": 0.07, "turns": 600.0}
    check_turns_derivative(spec, values, "turns", 0.01, 12.0)


def check_turns_derivative(spec: Any, values: dict[str, float], key: str, gap: float,
                           cur: float) -> None:
    """The turns' design derivatives from the ampere-turns relations, with dF/dI and
    dpsi/dI (every circuit at ``cur``) of the base magnet's solve_statics, whose turns
    ``values[key]`` must be (shared with tests/test_design_tr09.py)."""
    n = values[key]
    sens = design_sensitivities(spec, values, gap_m=gap, current_A=cur)
    sol = solve_statics(spec.magnet, gaps_m=gap, currents_A=cur)
    circuits = len(spec.magnet.network.circuits)
    dfdi = float(np.sum(np.asarray(sol.dforce_dcurrent_N_per_A))) / circuits
    ldiff = float(np.asarray(sol.common_differential_inductance_H).ravel()[0])
    psi = float(np.asarray(sol.flux_linkage_Wb).ravel()[0])
    assert sens["dforce_dp"][key] == pytest.approx(cur / n * dfdi, rel=1e-8)
    assert sens["dpsi_dp"][key] == pytest.approx(psi / n + cur / n * ldiff, rel=1e-8)


@pytest.mark.parametrize(("edit", "needle"), [
    (lambda d: d["variables"].update(bogus=[0.01, 0.02]),
     "[variables] unknown design variable 'bogus'"),
    (lambda d: d["variables"].update(pole_width=[0.05, 0.02]),
     "[variables] pole_width = [0.05, 0.02]: expected 0 < lower < upper"),
    (lambda d: d["variables"].update(pole_width=0.03), "[variables] pole_width = 0.03"),
    (lambda d: d["requirements"].pop("force_N"), "[requirements] missing required key "
                                                 "'force_N' [N]"),
    (lambda d: d["requirements"].update(force_N="800"), "[requirements] force_N = '800'"),
    (lambda d: d["requirements"].update(nominal_gap_m=-0.01),
     "[requirements] nominal_gap_m = -0.01 [m]: must be > 0"),
    (lambda d: d["requirements"].update(force_kN=1.0), "[requirements] unknown key(s) "
                                                       "['force_kN']"),
    (lambda d: d["design"].update(objective="cost"), "[design] objective = 'cost'"),
    (lambda d: d["design"].update(magnet="tr09-standard", flux_paths="paper"), "[variables] unknown design "
     "variable 'leg_height' for a levitation_magnet"),
    (lambda d: d["design"].update(magnet="nope"), "[design] magnet = 'nope'"),
    (lambda d: d["coil"].update(fill_factor=1.5), "[coil] fill_factor = 1.5"),
    (lambda d: d.update(extra={}), "unknown table(s) ['extra']"),
    (lambda d: d["provenance"].update({"coil.fill_factor": "guess"}),
     "[provenance] 'coil.fill_factor' = 'guess'"),
])
def test_bad_spec_names_the_key(edit: Any, needle: str) -> None:
    doc = example_doc()
    edit(doc)
    with pytest.raises(DesignSpecError) as info:
        read_design_spec(doc)
    assert needle in str(info.value)


def test_cli_design_writes_file_and_pareto(tmp_path: Path) -> None:
    out = tmp_path / "design.toml"
    png = tmp_path / "front.png"
    res = runner.invoke(app, ["design", "u-magnet-design", "-o", str(out), "--pareto",
                              str(png), "--pareto-points", "2", "--format", "json"])
    assert res.exit_code == 0, res.output
    import json

    payload = json.loads(res.stdout)
    assert payload["status"] == "Solve_Succeeded"
    assert set(payload["active"]) >= {"force_nominal", "current_density"}
    assert "wrote" in res.stderr and out.is_file() and png.read_bytes()[:4] == b"\x89PNG"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_magnet(out)
    # an existing output is refused without --force, before the computation
    again = runner.invoke(app, ["design", "u-magnet-design", "-o", str(out)])
    assert again.exit_code == 2 and "exists; add --force" in again.stderr


def test_cli_design_bad_spec_is_one_line(tmp_path: Path) -> None:
    spec = tmp_path / "spec.toml"
    doc = example_doc()
    text = (resources.files("maglevkit") / "data" / "designs" / "u-magnet-design.toml").read_text()
    spec.write_text(text.replace("coil_height = [0.020, 0.080]", "coil_hight = [0.020, 0.080]"))
    assert "coil_hight" not in doc["variables"]
    res = runner.invoke(app, ["design", str(spec), "-o", str(tmp_path / "d.toml")])
    assert res.exit_code == 2
    assert "error: [variables] unknown design variable 'coil_hight'" in res.stderr
    assert "Traceback" not in res.output


def test_pareto_front_trades_mass_for_power() -> None:
    from maglevkit.design import pareto_front

    spec = read_design_spec(example_doc())
    front = pareto_front(spec, points=3)
    assert all(r.success for r in front)
    power = [r.power_W for r in front]
    mass = [r.mass_kg for r in front]
    # from the minimum-power end to the minimum-mass end: power rises, mass falls
    assert power == sorted(power) and mass == sorted(mass, reverse=True)
    assert front[0].constraints["max_power"].active


def test_bundled_spec_is_listed_and_its_template_reads(tmp_path: Path) -> None:
    res = runner.invoke(app, ["list", "designs"])
    assert res.exit_code == 0 and "u-magnet-design" in res.stdout
    res = runner.invoke(app, ["template", "design"])
    assert res.exit_code == 0, res.output
    path = tmp_path / "spec.toml"
    path.write_text(res.stdout)
    spec = read_design_spec(path)
    assert spec.objective == "mass" and "pole_width" in spec.variables
    assert spec.provenance["requirements.force_N"].startswith("[E]")


def test_spec_magnet_path_is_relative_to_the_spec_and_infeasible_is_refused(
        tmp_path: Path) -> None:
    from maglevkit.parameter_files import toml_text

    (tmp_path / "sub").mkdir()
    mag = load_magnet("u-magnet")
    (tmp_path / "sub" / "mine.toml").write_text(toml_text(dict(mag.parameters)))
    doc = example_doc()
    doc["design"]["magnet"] = "mine.toml"
    doc["requirements"]["force_N"] = 50000.0        # far beyond what the bounds allow
    (tmp_path / "sub" / "spec.toml").write_text(toml_text(doc))
    spec = read_design_spec(tmp_path / "sub" / "spec.toml")
    assert spec.magnet.parameters["magnet"] == mag.parameters["magnet"]
    out = tmp_path / "d.toml"
    res = runner.invoke(app, ["design", str(tmp_path / "sub" / "spec.toml"), "-o", str(out)])
    assert res.exit_code == 2 and "IPOPT did not converge" in res.stderr
    assert not out.exists() and "Traceback" not in res.output


@pytest.mark.parametrize(("name", "key"), [
    ("current_density", "current_density_A_per_m2"),
    pytest.param("flux_density", "max_flux_density_T", marks=pytest.mark.slow)])
def test_shadow_prices_match_re_solved_optima(two_variable: tuple[Any, Any], name: str,
                                              key: str) -> None:
    # the reported d(mass)/d(bound) of an active constraint (from IPOPT's multipliers, i.e.
    # the NLP's exact derivatives) against re-solving with the bound moved by +-0.5 %:
    # central difference, curvature error ~(5e-3)^2 relative, IPOPT's 1e-10 negligible
    spec, res = two_variable
    c = res.constraints[name]
    assert c.active and c.sensitivity < 0.0          # a looser limit: a lighter magnet
    masses = []
    for f in (1.005, 0.995):
        doc = two_variable_doc()
        doc["requirements"][key] *= f
        masses.append(design_magnet(read_design_spec(doc)).mass_kg)
    fd = (masses[0] - masses[1]) / (0.01 * c.bound)
    assert c.sensitivity == pytest.approx(fd, rel=1e-3), name
    # an inactive constraint costs nothing: its elasticity (d ln m / d ln bound) is ~0
    for other in ("voltage", "force_reserve"):
        o = res.constraints[other]
        assert not o.active and abs(o.sensitivity * o.bound / res.mass_kg) < 1e-6, other


@pytest.mark.parametrize(("initial", "match"), [
    ({"pole_widht": 0.02}, r"initial pole_widht = 0.02: not a design variable of the spec; "
                           r"its variables: \['pole_width', 'coil_height'\]"),
    ({"pole_width": 0.02, "coil_height": "0.03"}, r"initial coil_height \[m\] = '0.03' \(str\): "
                                                  r"expected a real number"),
    ({"pole_width": 20.0}, r"initial pole_width = 20.0 \[m\]: outside its bounds \[0.015, 0.04\]"),
])
def test_bad_initial_point_names_the_variable_and_what_is_allowed(initial: dict, match: str
                                                                  ) -> None:
    """review3: an unknown name was reported with "bounds None", a string raised numpy's
    TypeError from the bound comparison."""
    from maglevkit.errors import InputError

    with pytest.raises(InputError, match=match):
        design_magnet(read_design_spec(two_variable_doc()), initial=initial)


def test_split_u_magnet_design_written_file_reproduces_the_optimum(tmp_path: Path) -> None:
    """The U-magnet's ``flux_paths = "split"`` network (ulumped25) is accepted as a design
    base (lumped, symbolic builder): its optimum, written and loaded as a numeric file,
    meets the constraints and reproduces the optimiser's symbolic statics (review3: the
    path was reachable but untested)."""
    from maglevkit.parameter_files import toml_text

    params = {k: (dict(v) if isinstance(v, dict) else v)
              for k, v in load_magnet("u-magnet").parameters.items()}
    params["magnet"]["flux_paths"] = "split"
    params["provenance"]["magnet.flux_paths"] = "[E] the 2-D FEM's paths (test)"
    (tmp_path / "split.toml").write_text(toml_text(params))
    doc = two_variable_doc()
    doc["design"]["magnet"] = str(tmp_path / "split.toml")
    spec = read_design_spec(doc)
    res = design_magnet(spec)
    assert res.success
    mag, ev = check_written_design(spec, res, tmp_path / "design.toml")
    assert mag.parameters["magnet"]["flux_paths"] == "split"
    sol = solve_statics(mag, gaps_m=spec.requirements["nominal_gap_m"],
                        currents_A=ev["nominal_current_A"])
    # the same network law solved by both routes (~1e-12); 1e-9 as in the standard test
    assert float(np.asarray(sol.force_N)) == pytest.approx(spec.requirements["force_N"], rel=1e-9)
    # the split network's optimum differs from the standard one's (another network)
    std = design_magnet(read_design_spec(two_variable_doc()))
    assert abs(res.mass_kg / std.mass_kg - 1.0) > 1e-3
