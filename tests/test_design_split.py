"""Design optimisation on the TR09's FEM-checked ``flux_paths = "split"`` network (the
bundled tr-09 file's own, 231 loops with the eddy elements left out): the two-variable
optimum against a brute-force grid search, the active constraints, the written file's
statics re-solved independently, exact design derivatives, and the variables the split
network's geometry does not admit."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from maglevkit import design as design_mod
from maglevkit.design import DesignSpecError, design_magnet, read_design_spec

from .test_design import check_active_constraints, check_design_gradients, check_written_design
from .test_design_tr09 import (
    bundled_doc,
    check_front_force,
    check_grid_search_optimum,
    tr09_mass,
)

#: pole width and pole-back height, bounds around the optimum (126.1 mm, 45.9 mm) so that
#: the brute-force grid below stays short (every grid point is a statics solve of the
#: 231-loop network for its nominal current)
WP, HB = (0.09, 0.17), (0.03, 0.07)


def split_two_variable_doc() -> dict[str, Any]:
    doc = bundled_doc()
    doc["variables"] = {"pole_width": list(WP), "back_height": list(HB)}
    return doc


@pytest.fixture(scope="module")
def two_variable() -> tuple[Any, Any]:
    spec = read_design_spec(split_two_variable_doc())
    assert spec.magnet.parameters["magnet"]["flux_paths"] == "split"
    return spec, design_magnet(spec)


@pytest.mark.slow       # ~100 s: ~60 designs' statics on the 231-loop network
def test_two_variable_optimum_matches_grid_search(two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    assert res.success and res.status == "Solve_Succeeded" and not res.crossed
    wp_o, hb_o = res.values["pole_width"], res.values["back_height"]
    assert res.mass_kg == pytest.approx(tr09_mass(spec, wp_o, hb_o), rel=1e-12)
    assert not any(c.active for c in res.constraints.values() if c.detail == "variable bound")
    check_grid_search_optimum(spec, res, np.linspace(*WP, 9), np.linspace(*HB, 9))


def test_active_constraints_are_reported(two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    assert set(res.active) == {"force_nominal", "current_density", "flux_density"}
    assert res.constraints["flux_density"].detail.startswith("iron_back_")
    check_active_constraints(spec, res)


def test_written_design_meets_the_constraints_resolved(tmp_path: Path,
                                                        two_variable: tuple[Any, Any]) -> None:
    spec, res = two_variable
    # the loaded file's numeric split network (Python's min, max, <) reproduces the
    # optimiser's symbolic one (check_written_design: to 1e-7 relative)
    mag, ev = check_written_design(spec, res, tmp_path / "tr09-split-optimised.toml")
    assert mag.parameters["magnet"]["flux_paths"] == "split"
    check_front_force(spec, mag, ev)


def test_design_gradients_match_central_differences() -> None:
    spec = read_design_spec(bundled_doc())
    values = {"pole_width": 0.15, "core_height": 0.14, "coil_height": 0.10,
              "coil_thickness": 0.04, "back_height": 0.06}
    check_design_gradients(spec, values, 0.009, 40.0)


def test_without_end_effects(tmp_path: Path) -> None:
    """A file with ``end_effects = false`` (the 2-D slab: no across-track terms) designs on
    its own network, and its optimum re-solves to meet the constraints."""
    import tomllib

    from maglevkit import load_magnet
    from maglevkit.parameter_files import toml_text

    params = dict(load_magnet("tr09-standard").parameters)
    params = {k: dict(v) if isinstance(v, dict) else v for k, v in params.items()}
    params["magnet"]["end_effects"] = False
    params["provenance"]["magnet.end_effects"] = "[E] test: the 2-D cut"
    path = tmp_path / "tr09-2d.toml"
    path.write_text(toml_text(params))
    doc = split_two_variable_doc()
    doc["design"]["magnet"] = str(path)
    spec = read_design_spec(doc)
    assert spec.magnet.parameters["magnet"]["end_effects"] is False
    res = design_magnet(spec)
    assert res.success
    check_written_design(spec, res, tmp_path / "out.toml")
    assert tomllib.loads((tmp_path / "out.toml").read_text())["magnet"]["end_effects"] is False


@pytest.mark.parametrize(("kind", "variable", "unit", "base", "needle"), [
    # the split network chooses deep or shallow LIG grooves on their depth (a choice of
    # structure, not a smooth law)
    ("levitation_magnet", "lig_groove_depth", "m", 0.020,
     "decides its structure on this value"),
    # the U-magnet's air-cell margin belongs to the grid discretisation: the lumped
    # network and the winding's laws do not depend on it
    ("u_magnet", "air_margin", "m", 0.2, "do not depend on it"),
])
def test_a_variable_the_network_geometry_does_not_admit_is_refused(
        monkeypatch: pytest.MonkeyPatch, kind: str, variable: str, unit: str, base: float,
        needle: str) -> None:
    from .test_design import example_doc

    kinds = {k: dict(v) for k, v in design_mod.KIND_VARIABLES.items()}
    kinds[kind][variable] = unit
    monkeypatch.setattr(design_mod, "KIND_VARIABLES", kinds)
    doc = split_two_variable_doc() if kind == "levitation_magnet" else example_doc()
    if kind == "u_magnet":
        doc["design"]["flux_paths"] = "split"
    doc["variables"][variable] = [0.5 * base, 1.5 * base]
    with pytest.raises(DesignSpecError, match=rf"\[variables\] \['{variable}'\]: .*{needle}"):
        read_design_spec(doc)
