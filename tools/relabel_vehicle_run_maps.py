"""Relabel the stored vehicle-run maps after a value-neutral change of the networks' repr.

The maps in ``tests/data/vehicle_run_maps`` are named and tagged by the network hash of the
magnet they belong to (``<magnet name>-<network hash>.nc``, attribute ``magnet_hash``; see
``tools/record_vehicle_runs.py``).  A rename of an element, circuit or material field
(e.g. the circuits' ``resistance`` -> ``resistance_ohm``) changes every hash without
changing one number of the maps; rebuilding them on another processor would move the recorded runs at the
solvers' tolerance (about 4e-6 of a value), so instead this script carries each stored file
over to the new hash: it computes the hashes of the recorded runs' magnets under the old
code (``--old-src``, a checkout's ``src`` before the rename, run in a subprocess) and under
this code, and rewrites every stored file of an old hash under the new one (the arrays
read and written by maglevkit's own ``load_maps``/``to_netcdf``; only ``magnet_hash``
changes).  Files of no recorded magnet are listed and left alone.

Use it only for a change that leaves the maps' values bit-identical -- show that first
(build a map set with the old and the new code and compare), then::

    git archive <old commit> src | tar -x -C /tmp/old
    PYTHONPATH=src python tools/relabel_vehicle_run_maps.py --old-src /tmp/old/src
    PYTHONPATH=src python tools/record_vehicle_runs.py tests/data/vehicle_runs.npz

and check that the re-recorded runs equal the old ones bit for bit.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAPS_DIR = ROOT / "tests" / "data" / "vehicle_run_maps"

#: Prints ``[[file stem, full network hash], ...]`` of the recorded runs' magnets: the
#: bundled TR09 standard and bow magnets, the guidance magnet, and the TR09 magnets on the
#: "paper" network of the reference run (``tests/conftest.py``).
_HASHES = r"""
import json, sys, tempfile
sys.path.insert(0, sys.argv[1])
from tests.conftest import paper_tr09_vehicle
from maglevkit.magnets import load_magnet
from maglevkit.reduction.maps import network_hash
from maglevkit.vehicle.mapcache import VEHICLE_MAP_CURRENTS_A, VEHICLE_MAP_GAPS_M, maps_path
from maglevkit.vehicle.train import load_vehicle

with tempfile.TemporaryDirectory() as tmp:
    paper = load_vehicle(paper_tr09_vehicle(tmp))
    magnets = [load_magnet(n) for n in ("tr09-standard", "tr09-bow", "tr-guidance",
                                         paper.standard_magnet, paper.bow_magnet)]
    out = []
    for m in magnets:
        stem = maps_path(m, VEHICLE_MAP_GAPS_M, VEHICLE_MAP_CURRENTS_A, tmp).stem
        out.append([stem.rsplit("-", 1)[0], network_hash(m.network)])
print(json.dumps(out))
"""


def magnet_hashes(src: str | Path) -> list[list[str]]:
    """``[file stem, network hash]`` of the recorded runs' magnets under the code in ``src``."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    with tempfile.TemporaryDirectory() as cache:
        env["MAGLEVKIT_CACHE_DIR"] = cache
        done = subprocess.run([sys.executable, "-c", _HASHES, str(ROOT)], env=env, cwd=ROOT,
                              capture_output=True, text=True, check=True)
    return [list(pair) for pair in json.loads(done.stdout.strip().splitlines()[-1])]


def main(argv: list[str] | None = None) -> int:
    """Relabel the stored maps of the old hashes; print what was done."""
    from maglevkit.reduction.maps import load_maps

    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--old-src", required=True, help="the src folder of the old code")
    args = parser.parse_args(argv)
    old = magnet_hashes(args.old_src)
    new = magnet_hashes(ROOT / "src")
    for (old_stem, _), (new_stem, _) in zip(old, new, strict=True):
        if old_stem.rsplit("-", 1)[0] != new_stem.rsplit("-", 1)[0]:
            raise SystemExit(f"the magnets differ: {old_stem} vs {new_stem}")
    moved = set()
    for (old_stem, _), (new_stem, new_hash) in zip(old, new, strict=True):
        src = MAPS_DIR / f"{old_stem}.nc"
        if old_stem in moved or not src.is_file():
            continue
        maps = load_maps(src)
        maps.dataset.attrs["magnet_hash"] = new_hash
        maps.to_netcdf(MAPS_DIR / f"{new_stem}.nc")
        if new_stem != old_stem:
            src.unlink()
        moved.add(old_stem)
        print(f"{old_stem}.nc -> {new_stem}.nc")
    left = sorted(f.name for f in MAPS_DIR.glob("*.nc")
                  if f.stem not in {stem for stem, _ in new})
    if left:
        print("not of a recorded magnet (left alone; delete if stale):", ", ".join(left))
    return 0


if __name__ == "__main__":
    sys.exit(main())
