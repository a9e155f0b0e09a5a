"""Unit-carrying field names of the circuit elements (issue 22, item 7, units22).

The old keyword and attribute names stay for one release as deprecated aliases: they give
the same element (so the same network hash) and a warning that names the new keyword.  The
migration script ``tools/rename_element_fields.py`` rewrites callers idempotently, and the
tree holds no caller of an old name any more.
"""
# rename_element_fields: skip   (this file uses the old names on purpose)

from __future__ import annotations

import math
import warnings
from dataclasses import fields
from pathlib import Path
from typing import Any

import pytest

import maglevkit as mk
from maglevkit.circuit.elements import FringePermeance, GapLayerPermeance
from maglevkit.circuit.ladder import ladder_branches, ladder_parameters
from maglevkit.errors import InputError
from maglevkit.materials import MU0
from maglevkit.reduction.maps import network_hash

from .conftest import load_script

ROOT = Path(__file__).resolve().parents[1]

# (class, positional args, old keywords, new keywords): every renamed field of each element,
# values chosen valid (fringe inner radius below the radius, slot opening below the pitch)
CASES: list[tuple[type, tuple[Any, ...], dict[str, float], dict[str, float]]] = [
    (mk.IronPath, ("iron",), {"length": 0.3, "cross_section": 2e-3},
     {"length_m": 0.3, "cross_section_m2": 2e-3}),
    (mk.AirGap, ("gap",), {"pole_area": 3e-3, "slot_pitch": 0.086, "slot_opening": 0.043},
     {"pole_area_m2": 3e-3, "slot_pitch_m": 0.086, "slot_opening_m": 0.043}),
    (mk.LeakagePermeance, ("leak",), {"value": 2e-7}, {"value_H": 2e-7}),
    (mk.GapLeakage, ("gl",), {"width": 0.1, "radius": 0.02}, {"width_m": 0.1, "radius_m": 0.02}),
    (FringePermeance, ("fr",), {"width": 0.1, "radius": 0.03, "inner_radius": 0.01,
                                   "slot_pitch": 0.086, "slot_opening": 0.043},
     {"width_m": 0.1, "radius_m": 0.03, "inner_radius_m": 0.01, "slot_pitch_m": 0.086,
      "slot_opening_m": 0.043}),
    (GapLayerPermeance, ("lay",), {"width": 0.1, "length": 0.005},
     {"width_m": 0.1, "length_m": 0.005}),
    (mk.EddyCurrent, ("eddy",), {"conductance": 12.5}, {"conductance_S": 12.5}),
]
IDS = [case[0].__name__ for case in CASES]


def _script() -> Any:
    return load_script(ROOT / "tools" / "rename_element_fields.py")


def _network(element: mk.Element) -> mk.Network:
    """One element on a loop with a coil: enough for network_hash (repr of the branches)."""
    return mk.Network(
        branches=(mk.Branch("b", "A", "B", (element,)),
                  mk.Branch("back", "B", "A", (mk.IronPath("yoke", length_m=0.5,
                                                             cross_section_m2=1e-3),))),
        circuits=(mk.Circuit("coil", resistance_ohm=1.0, coils=(mk.Coil("b", 100.0),)),))


@pytest.mark.parametrize(("cls", "args", "old", "new"), CASES, ids=IDS)
def test_old_keywords_give_the_equal_element_and_network_hash(cls: type, args: tuple,
                                                               old: dict, new: dict) -> None:
    made_new = cls(*args, **new)
    for (key, value), new_key in zip(old.items(), new, strict=True):
        kwargs = {**new, key: value}        # each old keyword on its own names its new one
        del kwargs[new_key]
        with pytest.warns(DeprecationWarning, match=rf"{cls.__name__}: {key}= is deprecated, "
                                                    rf"use {new_key}="):
            one = cls(*args, **kwargs)
        assert one == made_new
    with pytest.warns(DeprecationWarning) as record:
        made_old = cls(*args, **old)
    assert len(record) == 1                 # one warning per call, naming every old keyword
    for key in new:
        assert f"use {key}=" in str(record[0].message)
    assert made_old == made_new
    assert repr(made_old) == repr(made_new)
    assert network_hash(_network(made_old)) == network_hash(_network(made_new))


@pytest.mark.parametrize(("cls", "args", "old", "new"), CASES, ids=IDS)
def test_old_attribute_names_read_the_new_fields_with_a_warning(cls: type, args: tuple,
                                                                old: dict, new: dict) -> None:
    element = cls(*args, **new)
    for (key, value), new_key in zip(old.items(), new, strict=True):
        assert getattr(element, new_key) == value
        with pytest.warns(DeprecationWarning, match=rf"\.{key} is deprecated, use \.{new_key}"):
            assert getattr(element, key) == value


# (callable, positional args, old keywords, new keywords) of the factories and ladder helpers
FACTORY_CASES: list[tuple[Any, tuple[Any, ...], dict[str, float], dict[str, float]]] = [
    (mk.LeakagePermeance.parallel_plates, ("p",), {"area": 2e-3, "distance": 0.01},
     {"area_m2": 2e-3, "distance_m": 0.01}),
    (mk.LeakagePermeance.half_cylinder, ("c",), {"length": 0.1}, {"length_m": 0.1}),
    (mk.LeakagePermeance.quarter_cylinder, ("c",), {"length": 0.1}, {"length_m": 0.1}),
    (mk.LeakagePermeance.half_hollow_cylinder, ("h",),
     {"length": 0.1, "inner_radius": 0.01, "thickness": 0.02},
     {"length_m": 0.1, "inner_radius_m": 0.01, "thickness_m": 0.02}),
    (mk.LeakagePermeance.quarter_hollow_cylinder, ("h",),
     {"length": 0.1, "inner_radius": 0.01, "thickness": 0.02},
     {"length_m": 0.1, "inner_radius_m": 0.01, "thickness_m": 0.02}),
    (mk.LeakagePermeance.quarter_sphere, ("s",), {"radius": 0.01}, {"radius_m": 0.01}),
    (mk.LeakagePermeance.eighth_sphere, ("s",), {"radius": 0.01}, {"radius_m": 0.01}),
    (mk.LeakagePermeance.quarter_hollow_sphere, ("s",), {"thickness": 0.01},
     {"thickness_m": 0.01}),
    # (resistivity -> resistivity_ohm_m since units22b)
    (mk.EddyCurrent.one_turn, ("e",), {"path_area": 1e-4, "path_length": 0.3,
                                       "resistivity": 1.7e-8},
     {"path_area_m2": 1e-4, "path_length_m": 0.3, "resistivity_ohm_m": 1.7e-8}),
    (mk.EddyCurrent.solid_rectangular, ("e",), {"width": 0.03, "height": 0.1, "length": 0.2,
                                                "resistivity": 1.5e-7},
     {"width_m": 0.03, "height_m": 0.1, "length_m": 0.2, "resistivity_ohm_m": 1.5e-7}),
    (mk.EddyCurrent.laminated, ("e",), {"area": 2e-3, "length": 0.2, "sheet_thickness": 5e-4,
                                        "resistivity": 4e-7},
     {"area_m2": 2e-3, "length_m": 0.2, "sheet_thickness_m": 5e-4, "resistivity_ohm_m": 4e-7}),
    (ladder_parameters, (), {"length": 0.2, "area": 2e-3, "thickness": 0.03,
                             "resistivity": 1.5e-7},
     {"length_m": 0.2, "area_m2": 2e-3, "thickness_m": 0.03, "resistivity_ohm_m": 1.5e-7}),
    (ladder_branches, ("b", "A", "B", mk.IronPath("i", length_m=0.2, cross_section_m2=2e-3)),
     {"thickness": 0.03, "resistivity": 1.5e-7}, {"thickness_m": 0.03, "resistivity_ohm_m": 1.5e-7}),
]
# the ladder helpers need a tube count
EXTRA = {"ladder_parameters": {"layers": 3}, "ladder_branches": {"layers": 3}}


@pytest.mark.parametrize(("fn", "args", "old", "new"), FACTORY_CASES,
                         ids=[case[0].__name__ for case in FACTORY_CASES])
def test_factories_and_ladder_helpers_take_the_old_keywords_with_a_warning(
        fn: Any, args: tuple, old: dict, new: dict) -> None:
    extra = EXTRA.get(fn.__name__, {})
    expected = fn(*args, **new, **extra)
    with pytest.warns(DeprecationWarning) as record:
        got = fn(*args, **old, **extra)
    assert len(record) == 1
    for key, new_key in zip(old, new, strict=True):
        assert f"{key}= is deprecated, use {new_key}=" in str(record[0].message)
    assert got == expected and repr(got) == repr(expected)


def test_old_and_new_name_together_are_refused() -> None:
    with pytest.raises(InputError, match=r"give length_m= only \(length= is its deprecated"):
        mk.IronPath("iron", length=0.3, length_m=0.3, cross_section_m2=1e-3)


def test_the_law_is_unchanged_by_the_names() -> None:
    # permeance through the old and the new keywords at two gaps, against the formula
    # mu0 w/pi ln(1 + pi r/s) (exact: the same float operations)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        old = mk.GapLeakage("g", gap_input="s", width=0.1, radius=0.02)
    new = mk.GapLeakage("g", gap_input="s", width_m=0.1, radius_m=0.02)
    for s in (0.005, 0.02):
        expected = MU0 * 0.1 / math.pi * math.log(1.0 + math.pi * 0.02 / s)
        assert old.permeance(s) == new.permeance(s) == pytest.approx(expected, rel=1e-14)


def test_the_field_names_carry_their_units() -> None:
    # the dataclass fields are the new names only; the class lists the renames
    for cls, _, old, new in CASES:
        names = {f.name for f in fields(cls)}
        assert set(new) <= names and not set(old) & names, cls.__name__
        assert cls.renamed_keywords == dict(zip(old, new, strict=True))


SAMPLE = '''\
g = AirGap("g", gap_input=p, pole_area=a, fringe_edges=((w, r),), **slots)
f = mk.FringePermeance("f", gap_input="s", width=w(x, radius=1), radius=r,
                       inner_radius=0.0)   # radius= of the inner call stays
e = replace(el, conductance=2.0 * el.conductance)
h = LeakagePermeance.quarter_cylinder("q", length=d).value
v = iron.length * iron.cross_section / gap.pole_area
s = "width=3" if x.width == y else exc.value
t = IronPath("t", length == 1, cross_section=2)
'''
EXPECTED = '''\
g = AirGap("g", gap_input=p, pole_area_m2=a, fringe_edges=((w, r),), **slots)
f = mk.FringePermeance("f", gap_input="s", width_m=w(x, radius=1), radius_m=r,
                       inner_radius_m=0.0)   # radius= of the inner call stays
e = replace(el, conductance_S=2.0 * el.conductance_S)
h = LeakagePermeance.quarter_cylinder("q", length_m=d).value_H
v = iron.length_m * iron.cross_section_m2 / gap.pole_area_m2
s = "width=3" if x.width == y else exc.value
t = IronPath("t", length == 1, cross_section_m2=2)
'''


def test_the_script_rewrites_callers_and_is_idempotent() -> None:
    # only keywords at the element call's own depth; unrelated .width / .value reads and
    # the comparison length == 1 stay
    script = _script()
    assert script.rewrite(SAMPLE, "src/x.py") == EXPECTED
    assert script.rewrite(EXPECTED, "src/x.py") == EXPECTED


def test_the_tree_has_no_caller_of_an_old_name() -> None:
    # the script would change no file: every caller uses the new names (run it after a
    # merge that brings old names back: PYTHONPATH=src python tools/rename_element_fields.py)
    script = _script()
    assert script.main(["--check", "--root", str(ROOT)]) == 0
