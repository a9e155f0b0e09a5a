"""Move callers of the circuit elements to the unit-carrying field names (issue 22, item 7).

The elements of :mod:`maglevkit.circuit.elements` (``IronPath(length_m, cross_section_m2)``,
``AirGap(pole_area_m2, ...)``, ``LeakagePermeance(value_H)``, ``EddyCurrent(conductance_S)``,
...), the circuits (``Circuit(name, resistance_ohm, coils)``) and the materials
(``SoftMagneticMaterial(..., resistivity_ohm_m=...)``, ``TabulatedBH``, ...) keep their old
keyword and attribute names as deprecated aliases for one release.  This script rewrites the
callers in the tree, so that no code of the package, its tests, tools, benchmarks, examples
or docs uses the old names:

1. keywords of element constructor calls: ``IronPath("x", length=0.1)`` ->
   ``IronPath("x", length_m=0.1)`` (only keywords at the call's own bracket depth), of
   circuit and material constructors (``Circuit("c", resistance_ohm=2.0, ...)``,
   ``TabulatedBH(h, b, resistivity_ohm_m=...)``, ``TabulatedBH.from_csv``), of
   the element factories (``LeakagePermeance.half_cylinder(name, length_m=...)``,
   ``EddyCurrent.laminated``, ...) and the ladder helpers (``ladder_branches(...,
   thickness_m=...)``);
2. keywords of ``dataclasses.replace`` calls whose old name only an element has
   (``replace(el, conductance=...)``);
3. attribute reads: the names only elements, circuits and materials have
   (``.cross_section``, ``.pole_area``, ``.conductance``, ``.inner_radius``,
   ``.resistance``, ``.resistivity``) everywhere, ``.length`` on the receivers that hold
   an iron path (:data:`LENGTH_RECEIVERS`), and ``.value`` after a
   ``LeakagePermeance`` factory call; the other ambiguous reads (``.value`` of an element held
   in a variable) through the explicit table :data:`AMBIGUOUS_READS`.

The old -> new names are read from the classes and functions (the ``renamed_keywords``
attribute that :func:`maglevkit.validation.renamed_keywords` sets), so they have one
source.  The rewrite is
idempotent (a new name never matches an old one: each new name is the old one plus a unit
suffix, matched with word boundaries).  Files that hold the line
``# rename_element_fields: skip`` are left alone (the definitions and the tests of the
deprecated names).  Run from the repository root::

    PYTHONPATH=src python tools/rename_element_fields.py           # rewrite, list files
    PYTHONPATH=src python tools/rename_element_fields.py --check   # exit 1 if any file would change

Afterwards the tests show any read the rules missed: pytest turns the deprecation warning
into an error (``filterwarnings`` in pyproject.toml).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from maglevkit import materials
from maglevkit.circuit import elements, ladder, network

#: The classes whose fields were renamed: the elements (units22), the circuit and the
#: materials (units22b).
CLASSES = {name: getattr(elements, name)
           for name in ("IronPath", "AirGap", "LeakagePermeance", "GapLeakage",
                        "FringePermeance", "GapLayerPermeance", "EddyCurrent")}
CLASSES["Circuit"] = network.Circuit
CLASSES.update({name: getattr(materials, name)
                for name in ("SoftMagneticMaterial", "TabulatedBH", "ConstantPermeability",
                             "IdealIron")})
#: The factories (class methods) whose keywords were renamed.
FACTORIES = {"LeakagePermeance": ("parallel_plates", "half_cylinder", "quarter_cylinder",
                                  "half_hollow_cylinder", "quarter_hollow_cylinder",
                                  "quarter_sphere", "eighth_sphere", "quarter_hollow_sphere"),
             "EddyCurrent": ("one_turn", "solid_rectangular", "laminated"),
             "TabulatedBH": ("from_csv",)}
HELPERS = ("ladder_parameters", "ladder_branches")

#: Where the callers live (relative to the repository root), and which files to rewrite.
ROOTS = ("src", "tests", "tools", "benchmarks", "examples", "docs")
FILES = ("README.md",)
SUFFIXES = (".py", ".md")
SKIP_MARK = "# rename_element_fields: skip"
#: Files that record history (their sections are not edited afterwards).
SKIP_FILES = ("docs/decisions.md", "BENCHMARKS.md", "CHANGELOG.md")

#: Attribute names that, in this code base, only elements, circuits and materials have:
#: renamed on any receiver.
UNIQUE_READS = ("cross_section", "pole_area", "conductance", "inner_radius", "resistance",
                "resistivity")

#: ``.length`` is common (a train, a guideway): renamed only on the receivers that hold an
#: iron path in this code base (``iron``, ``iron_l``, ``irons[0]``, ``tube``, ``e``, ``el``,
#: ``t``, ``self`` in the mutation snippets of elements.py lines).
LENGTH_RECEIVERS = r"(?:\b(?:iron\w*|tube\w*|e|el|t|self)|\birons\[\d+\])"

#: Element reads under names other objects have too (``.value`` of an exception info, ...):
#: per file, the regular expressions of the receivers that hold an element.
AMBIGUOUS_READS: dict[str, tuple[str, ...]] = {
    "tests/test_guidance_split.py": (r"\b[gh]\[[^\]]+\]\.value\b",),
    "tests/test_guidance_end_effects.py": (r"\b(?:el|full_el)\.value\b",),
    "tests/test_levitation_split.py": (r"\be\.value(?= for br in)", r"\bslot\.value\b"),
    "tests/test_magnets_levitation.py": (r"\be\.value(?= for br in)",),
    "tests/test_calibration_split.py": (r"\bels\[[^\]]+\]\.value\b", r"\b(?:cyl|air)\.value\b",
                                        r"\.elements\[0\]\.value\b",
                                        r"\[\"coil_air_left_2\"\]\.value\b"),
    "tools/mutation.py": (r"\bself\.radius\b",),             # mutants of elements.py lines
}

#: Old names as dictionary keys unpacked into element constructors (``AirGap(..., **slots)``):
#: per file, (regular expression, replacement).
KEYWORD_DICTS: dict[str, tuple[tuple[str, str], ...]] = {
    "src/maglevkit/magnets/levitation.py": (
        (r'\{"slot_pitch": (st\["slot_pitch"\]), "slot_opening": (st\["slot_opening"\])\}',
         r'{"slot_pitch_m": \1, "slot_opening_m": \2}'),),
}


def renames() -> dict[str, str]:
    """Old -> new field name over all renamed classes (each old name has one new name)."""
    out: dict[str, str] = {}
    for cls in CLASSES.values():
        for old, new in cls.renamed_keywords.items():
            if out.setdefault(old, new) != new:
                raise SystemExit(f"{old} is renamed to both {out[old]} and {new}")
    return out


def _call_end(text: str, open_at: int) -> int:
    """Index of the bracket that closes the one at ``open_at`` (strings skipped roughly)."""
    depth, i, quote = 0, open_at, ""
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\":
                i += 1
            elif text.startswith(quote, i):
                i += len(quote) - 1
                quote = ""
        elif c in "\"'":
            quote = text[i:i + 3] if text[i:i + 3] in ('"""', "'''") else c
            i += len(quote) - 1
        elif c == "#":
            nl = text.find("\n", i)
            i = len(text) if nl < 0 else nl
            continue
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    return len(text) - 1


def _top_level_keywords(args: str, names: dict[str, str]) -> str:
    """Rename ``old=`` keywords at depth 0 of a call's argument text."""
    out, depth, i, quote = [], 0, 0, ""
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")(\s*=)(?!=)")
    while i < len(args):
        c = args[i]
        if quote:
            if c == "\\":
                out.append(args[i:i + 2])
                i += 2
                continue
            if args.startswith(quote, i):
                out.append(quote)
                i += len(quote)
                quote = ""
                continue
        elif c in "\"'":
            quote = args[i:i + 3] if args[i:i + 3] in ('"""', "'''") else c
            out.append(quote)
            i += len(quote)
            continue
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif depth == 0 and (i == 0 or not (args[i - 1].isalnum() or args[i - 1] == "_")):
            m = pattern.match(args, i)
            if m:
                out.append(names[m.group(1)] + m.group(2))
                i = m.end()
                continue
        out.append(c)
        i += 1
    return "".join(out)


def _rename_calls(text: str, callee: str, names: dict[str, str]) -> str:
    """Rename the keywords of every call of ``callee`` (a regular expression)."""
    pos, out = 0, []
    for m in re.finditer(callee, text):
        if m.start() < pos:
            continue
        start = m.end() - 1                              # the "("
        end = _call_end(text, start)
        out.append(text[pos:start + 1])
        out.append(_top_level_keywords(text[start + 1:end], names))
        pos = end
    out.append(text[pos:])
    return "".join(out)


def rewrite(text: str, path: str) -> str:
    """The text of file ``path`` (relative, ``/``-separated) with the new names."""
    names = renames()
    classes = "|".join(CLASSES)
    owners = r"(?:(?:elements|network|materials|mk)\.)?"
    text = _rename_calls(text, rf"(?<![\w.]){owners}(?:{classes})\(", names)
    for owner, methods in FACTORIES.items():
        for method in methods:
            text = _rename_calls(text, rf"(?<![\w.]){owners}{owner}\.{method}\(",
                                 getattr(CLASSES[owner], method).renamed_keywords)
    for helper in HELPERS:
        text = _rename_calls(text, rf"(?<![\w.])(?:ladder\.|mk\.)?{helper}\(",
                             getattr(ladder, helper).renamed_keywords)
    text = _rename_calls(text, r"(?<![\w.])(?:dataclasses\.)?replace\(",
                         {k: v for k, v in names.items() if k in UNIQUE_READS})
    # a LeakagePermeance factory's result read at once: LeakagePermeance.f(...).value
    pos, out = 0, []
    for m in re.finditer(r"(?<![\w.])LeakagePermeance\.\w+\(", text):
        if m.start() < pos:
            continue
        end = _call_end(text, m.end() - 1)
        if text.startswith(".value", end + 1) and not re.match(r"\w", text[end + 7:end + 8]):
            out.append(text[pos:end + 1] + ".value_H")
            pos = end + 7
    out.append(text[pos:])
    text = "".join(out)
    text = re.sub(rf"({LENGTH_RECEIVERS})\.length\b(?!\s*=[^=])", rf"\1.{names['length']}",
                  text)
    for old in UNIQUE_READS:
        # (not the parameter files' keys "magnet.resistance", "rail.resistivity", ...)
        text = re.sub(rf"(?<=[\w\])])(?<!\bmagnet)(?<!\brail)\.{old}\b(?!\s*=[^=])",
                      f".{names[old]}", text)
    for pattern in AMBIGUOUS_READS.get(path, ()):
        text = re.sub(pattern, lambda m: re.sub(r"\.(\w+)$", lambda a: "." + names[a.group(1)],
                                                 m.group(0)), text)
    for pattern, repl in KEYWORD_DICTS.get(path, ()):
        text = re.sub(pattern, repl, text)
    return text


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or with ``--check`` only list) the files that use old element field names."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--check", action="store_true",
                        help="change nothing; exit 1 when a file would change")
    parser.add_argument("--root", type=Path, default=Path("."), help="repository root")
    args = parser.parse_args(argv)
    changed = []
    candidates = [file for top in ROOTS for file in sorted((args.root / top).rglob("*"))]
    for file in candidates + [args.root / name for name in FILES]:
        if file.suffix not in SUFFIXES or not file.is_file():
            continue
        text = file.read_text(encoding="utf-8")
        if SKIP_MARK in text:
            continue
        rel = file.relative_to(args.root).as_posix()
        if rel in SKIP_FILES:
            continue
        new = rewrite(text, rel)
        if new != text:
            changed.append(rel)
            if not args.check:
                file.write_text(new, encoding="utf-8")
    for rel in changed:
        print(("would change " if args.check else "changed ") + rel)
    return 1 if args.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())
