"""Cached maps are keyed on the code of the laws too, not only on the network's data.

``network_hash`` covers elements and parameters; a maglevkit whose permeance or statics
code changed would otherwise read maps an older version cached under the same name.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

import maglevkit as mk
from maglevkit.reduction import maps as maps_module
from maglevkit.reduction.maps import LAW_PACKAGES, law_hash
from maglevkit.vehicle import mapcache

PKG = Path(mk.__file__).resolve().parent


def _copy_laws(dest: Path) -> Path:
    dest.mkdir()
    for name in LAW_PACKAGES:
        if (PKG / name).is_file():
            shutil.copy2(PKG / name, dest / name)
        else:
            shutil.copytree(PKG / name, dest / name, ignore=shutil.ignore_patterns("__pycache__"))
    return dest


def test_law_hash_follows_the_law_code_and_nothing_else(tmp_path: Path) -> None:
    root = _copy_laws(tmp_path / "pkg")
    before = law_hash.__wrapped__(root)
    assert before == law_hash.__wrapped__(root)          # deterministic
    assert before == law_hash()                          # the copy is the installed code
    # a file outside the law packages changes nothing
    (root / "cli").mkdir()
    (root / "cli" / "x.py").write_text("A = 1\n")
    assert law_hash.__wrapped__(root) == before
    # one character of a law changes it (a package's file, and the materials module)
    materials = root / "materials.py"
    materials.write_text(materials.read_text() + "\n")
    after_materials = law_hash.__wrapped__(root)
    assert after_materials != before
    elements = root / "circuit" / "elements.py"
    elements.write_text(elements.read_text().replace("return gamma * gap", "return 1.0 * gamma * gap"))
    assert law_hash.__wrapped__(root) not in (before, after_materials)


def test_vehicle_maps_cache_path_changes_with_the_law_code(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    magnet = mk.load_magnet("tr09-standard")
    g, c = np.array([0.008, 0.012]), np.array([0.0, 40.0])
    path = mapcache.maps_path(magnet, g, c, "/tmp/cache")
    assert path == mapcache.maps_path(magnet, g, c, "/tmp/cache")
    monkeypatch.setattr(maps_module, "law_hash", lambda: "another version of the laws")
    assert mapcache.maps_path(magnet, g, c, "/tmp/cache") != path
