"""Fuzzing every bundled parameter file (issue 27, "Must show").

Each example changes one or two dimensional values of a bundled magnet, vehicle,
guideway, cross-section or design-spec file: a unit slip (times 1000 or 1/1000) or a
plausible change (times 0.5 ... 2).
Every outcome must be one of

* a documented error (a :class:`~maglevkit.MaglevkitError`, naming what is wrong),
* a :class:`~maglevkit.PlausibilityWarning` naming every slipped key,
* a plausible result: the magnet's force at its operating point finite, positive and
  within a factor 100 of the bundled file's (vehicles, cross-sections: the derived masses
  finite and positive; guideways: the span positive; design specs: every requirement and
  bound finite, every bound pair ordered).

A slipped key must always be warned about (an error alone is not enough: the user should
learn which value is off).  The examples are bounded so that the default suite stays fast;
``MAGLEVKIT_FUZZ_EXAMPLES=400`` runs more and ``MAGLEVKIT_FUZZ_REPORT=1`` prints the
outcome counts (docs/decisions.md has those of a 400-example run).
"""

from __future__ import annotations

import copy
import math
import os
import warnings
from collections import Counter
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import maglevkit as mk
from maglevkit.design import DESIGN_PLAUSIBLE, read_design_spec
from maglevkit.magnets.base import MAGNET_PLAUSIBLE
from maglevkit.vehicle.crosssection import CROSS_SECTION_PLAUSIBLE, parse_cross_section
from maglevkit.vehicle.data import GUIDEWAY_PLAUSIBLE, parse_guideway
from maglevkit.vehicle.train import VEHICLE_PLAUSIBLE, parse_vehicle

from .test_plausible_files import (
    CROSS_SECTIONS,
    DESIGNS,
    GUIDEWAYS,
    MAGNETS,
    VEHICLES,
    dimensional_keys,
    scaled,
)

EXAMPLES = int(os.environ.get("MAGLEVKIT_FUZZ_EXAMPLES", "40"))
OUTCOMES: Counter[str] = Counter()
FILES = ([("magnet", n, p, MAGNET_PLAUSIBLE) for n, p in MAGNETS.items()]
         + [("vehicle", n, p, VEHICLE_PLAUSIBLE) for n, p in VEHICLES.items()]
         + [("guideway", n, p, GUIDEWAY_PLAUSIBLE) for n, p in GUIDEWAYS.items()]
         + [("cross-section", n, p, CROSS_SECTION_PLAUSIBLE) for n, p in CROSS_SECTIONS.items()]
         + [("design", n, p, DESIGN_PLAUSIBLE) for n, p in DESIGNS.items()])
BUILD = {"magnet": lambda p, name: mk.build_magnet(p, source=name),
         "vehicle": parse_vehicle,
         "guideway": parse_guideway,
         "cross-section": parse_cross_section,
         "design": lambda p, name: read_design_spec(p)}
SLIPS = (1e3, 1e-3)


def _operating_point(params: dict[str, Any]) -> tuple[float, float]:
    op = params.get("operating", {})
    return float(op.get("nominal_gap", 0.010)), float(op.get("nominal_current", 20.0))


_REFERENCE: dict[str, float] = {}


def _force(params: dict[str, Any]) -> float:
    m = mk.build_magnet(params, options=mk.ModelOptions(eddy_currents=False))
    gap, current = _operating_point(params)
    return float(mk.solve_statics(m, gaps_m=gap, currents_A=current).force_N)


def _reference_force(name: str) -> float:
    if name not in _REFERENCE:
        _REFERENCE[name] = _force(copy.deepcopy(MAGNETS[name]))
    return _REFERENCE[name]


def _plausible_result(kind: str, name: str, params: dict[str, Any]) -> None:
    """Assert that an unwarned, accepted file gives a plausible result."""
    if kind == "magnet":
        f, f0 = _force(params), _reference_force(name)
        assert math.isfinite(f) and f > 0 and f0 / 100 < f < f0 * 100, (name, f, f0)
    elif kind == "vehicle":
        t = parse_vehicle(params, name)
        assert math.isfinite(t.total_mass_kg) and t.total_mass_kg > 0
    elif kind == "cross-section":
        x = parse_cross_section(params, name)
        masses = (x.empty_train_mass_kg, x.car_body_mass_kg, x.chassis_mass_kg)
        assert all(math.isfinite(m) and m > 0 for m in masses), masses
    elif kind == "design":
        spec = read_design_spec(params)
        assert all(math.isfinite(v) for v in spec.requirements.values()), spec.requirements
        assert all(math.isfinite(lo) and lo < hi for lo, hi in spec.variables.values())
    else:
        span = parse_guideway(params, name).span
        assert span.length_m > 0


@st.composite
def mutations(draw: st.DrawFn) -> tuple[str, str, dict[str, Any], list[str], list[str]]:
    kind, name, params, ranges = draw(st.sampled_from(FILES))
    keys = dimensional_keys(params, ranges)
    chosen = draw(st.lists(st.sampled_from(keys), min_size=1, max_size=2, unique=True))
    slipped = []
    p = params
    for key in chosen:
        if draw(st.booleans()):
            factor = draw(st.sampled_from(SLIPS))
            slipped.append(key)
        else:
            factor = draw(st.floats(0.5, 2.0))
        p = scaled(p, key, factor)
    return kind, name, p, chosen, slipped


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(mutations())
def test_every_mutated_bundled_file_gives_a_documented_outcome(
        case: tuple[str, str, dict[str, Any], list[str], list[str]]) -> None:
    kind, name, params, chosen, slipped = case
    build = BUILD[kind]
    error: Exception | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            build(copy.deepcopy(params), name)
        except mk.MaglevkitError as exc:      # documented; anything else fails the test
            error = exc
    texts = [str(w.message) for w in caught if w.category is mk.PlausibilityWarning]
    for key in slipped:                       # a slip is always named, error or not
        table, _, sub = key.partition(".")
        assert any(f"[{table}] {sub} = " in t for t in texts), (name, key, texts, error)
    if error is not None:
        assert str(error), "an error without a message"
        OUTCOMES["documented error" + (" after a warning" if texts else "")] += 1
    elif texts:
        OUTCOMES["plausibility warning naming the key"] += 1
    else:
        _plausible_result(kind, name, copy.deepcopy(params))
        OUTCOMES["plausible result"] += 1


@pytest.fixture(scope="module", autouse=True)
def _report() -> Any:
    yield
    if os.environ.get("MAGLEVKIT_FUZZ_REPORT"):
        print("\nfuzz outcomes:", dict(OUTCOMES), "total", sum(OUTCOMES.values()))
