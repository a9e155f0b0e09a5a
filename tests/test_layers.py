"""The house's layers and private names, checked from the source (no import-linter needed).

The layers are read from import-linter's contract in ``pyproject.toml`` (one list; ``make lint``
runs the tool on the same contract).  Every import counts: module level, inside functions and
under ``TYPE_CHECKING``.
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

import maglevkit

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

PACKAGE = Path(maglevkit.__file__).parent
PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"

#: Private names still imported across modules (none since the reduced-circuit core,
#: issue 22 item 1, holds the map-extension helpers).
KNOWN_PRIVATE: set[tuple[str, str]] = set()


@dataclass(frozen=True)
class Import:
    """``importer`` imports ``target`` (a module) or a name ``target.name`` from it."""

    importer: str
    target: str
    name: str | None
    line: int


def modules(root: Path = PACKAGE) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package) for every module of the package."""
    out = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def imports_of(module: str, source: str, is_package: bool, known: set[str]) -> list[Import]:
    """The package-internal imports in ``source`` (of ``module``)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [Import(module, a.name, None, node.lineno) for a in node.names
                      if a.name.split(".")[0] == "maglevkit"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")[:None if is_package else -1]
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "maglevkit":
                continue
            for a in node.names:
                sub = f"{target}.{a.name}"
                found.append(Import(module, sub, None, node.lineno) if sub in known
                             else Import(module, target, a.name, node.lineno))
    return found


def all_imports() -> list[Import]:
    mods = modules()
    known = set(mods)
    out: list[Import] = []
    for name, (path, is_package) in sorted(mods.items()):
        out += imports_of(name, path.read_text(encoding="utf-8"), is_package, known)
    return out


def contract() -> tuple[list[list[str]], set[tuple[str, str]]]:
    """(layers top to bottom, each a list of sibling names; ignored (importer, imported))."""
    cfg = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))["tool"]["importlinter"]
    (c,) = [c for c in cfg["contracts"] if c["id"] == "layers"]
    assert c["containers"] == ["maglevkit"]
    layers = [[s.strip().strip("()") for s in raw.replace(":", "|").split("|")]
              for raw in c["layers"]]
    ignores = {tuple(s.strip() for s in raw.split("->")) for raw in c.get("ignore_imports", [])}
    return layers, ignores  # type: ignore[return-value]


def layer_violations(imports: list[Import], layers: list[list[str]],
                     ignores: set[tuple[str, str]]) -> list[str]:
    """Imports that point up (or sideways between independent siblings, or into the
    package ``__init__``, which sits above every layer)."""
    rank = {name: k for k, group in enumerate(layers) for name in group}
    out = []
    for imp in imports:
        src, dst = imp.importer.split("."), imp.target.split(".")
        if (imp.importer, imp.target) in ignores or src[:2] == dst[:2]:
            continue
        where = f"{imp.importer}:{imp.line} imports {imp.target}"
        if len(dst) == 1:
            if len(src) > 1:
                out.append(f"{where} (the package __init__, above every layer)")
            continue
        if len(src) == 1:
            continue                                   # the package __init__ may import all
        a, b = rank.get(src[1]), rank.get(dst[1])
        if a is None or b is None:
            out.append(f"{where}: {src[1] if a is None else dst[1]} is in no layer")
        elif b < a:
            out.append(f"{where}: layer {dst[1]!r} is above {src[1]!r}")
        elif b == a:
            out.append(f"{where}: independent siblings {src[1]!r} and {dst[1]!r}")
    return out


def private_imports(imports: list[Import]) -> list[tuple[str, str]]:
    """(importer, module.name) of every private name imported from another module (private
    modules such as ``_version`` are the package's own and may be imported)."""
    return [(i.importer, f"{i.target}.{i.name}") for i in imports
            if i.name is not None and i.name.startswith("_") and not i.name.startswith("__")]


def test_no_module_imports_from_a_layer_above() -> None:
    layers, ignores = contract()
    assert layer_violations(all_imports(), layers, ignores) == []


def test_every_module_is_in_a_layer() -> None:
    layers, _ = contract()
    named = {n for group in layers for n in group}
    tops = {name.split(".")[1] for name in modules() if name != "maglevkit"}
    assert tops <= named, sorted(tops - named)


def test_the_layer_check_catches_a_back_arrow() -> None:
    """A planted upward import, a sibling import and an import of the package ``__init__``
    are each reported; a downward one is not."""
    layers, ignores = contract()
    planted = [Import("maglevkit.models.flux", "maglevkit.vehicle.train", "load_vehicle", 1),
               Import("maglevkit.sweep.spec", "maglevkit.export.fmu", "export_fmu", 2),
               Import("maglevkit.reduction.maps", "maglevkit", "__version__", 3),
               Import("maglevkit.vehicle.train", "maglevkit.models.flux", "FluxModel", 4)]
    found = layer_violations(planted, layers, ignores)
    assert [f.split(":")[1].split()[0] for f in found] == ["1", "2", "3"]
    assert "'vehicle' is above 'models'" in found[0]


def test_the_import_parser_resolves_relative_and_lazy_imports() -> None:
    known = {"maglevkit.models.flux", "maglevkit.models", "maglevkit.circuit"}
    src = ("from .flux import FluxModel\n"
           "def f():\n    from ..circuit import assemble\n    from . import flux\n")
    got = imports_of("maglevkit.models.bank", src, False, known)
    assert [(i.target, i.name) for i in got] == [
        ("maglevkit.models.flux", "FluxModel"), ("maglevkit.circuit", "assemble"),
        ("maglevkit.models.flux", None)]


def test_no_private_name_is_imported_across_modules() -> None:
    found = set(private_imports(all_imports()))
    assert found <= KNOWN_PRIVATE, sorted(found - KNOWN_PRIVATE)


def test_the_private_check_catches_a_private_import() -> None:
    imps = imports_of("maglevkit.magnets.guidance", "from .levitation import _resistivity\n"
                      "from .._version import __version__\nfrom . import _x as y\n", False,
                      {"maglevkit.magnets.levitation", "maglevkit._version"})
    assert private_imports(imps) == [("maglevkit.magnets.guidance",
                                      "maglevkit.magnets.levitation._resistivity"),
                                     ("maglevkit.magnets.guidance", "maglevkit.magnets._x")]


def test_import_linter_keeps_the_contract() -> None:
    """The tool itself (``make lint`` runs it as ``lint-imports``) on the same contract."""
    pytest.importorskip("importlinter")
    from importlinter import api  # noqa: F401  (configures the tool, as its command line does)
    from importlinter.application.use_cases import lint_imports

    assert lint_imports(config_filename=str(PYPROJECT), cache_dir=None, no_logo=True)


def test_sweep_and_export_are_attributes_of_the_package() -> None:
    import maglevkit as mk

    assert mk.sweep.run_sweep is not None and mk.export.export_fmu is not None
    assert mk.__version__ == maglevkit._version.__version__


# ------------------------------------------------------------------ private attributes
def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_names_defined(tree: ast.AST) -> set[str]:
    """The private names a module defines: functions, classes and assignments (module or
    class level), attributes it stores (``obj._x = ...``) and ``__slots__`` entries."""
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            out.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, (ast.Store, ast.Del)):
            out.add(node.attr)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and node.value.isidentifier():
            out.add(node.value)                                  # __slots__ entries
    return {n for n in out if _private(n)}


def private_attribute_uses(sources: dict[str, str]) -> set[tuple[str, str]]:
    """(module, ``receiver.name``) of every private attribute a module reads that is not
    its own: ``obj._x`` where the module defines no ``_x`` (another module's private name),
    ``self._x`` where it defines none (inherited from another module's class), and
    ``obj._x`` (not ``self``) where another module defines ``_x`` too (which object it
    is, the source alone does not say: each such use is listed and must be justified)."""
    trees = {m: ast.parse(s) for m, s in sources.items()}
    own = {m: private_names_defined(t) for m, t in trees.items()}
    found: set[tuple[str, str]] = set()
    for m, tree in trees.items():
        others = set().union(*(v for k, v in own.items() if k != m))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load)
                    and _private(node.attr)):
                continue
            receiver = ast.unparse(node.value)
            if node.attr not in own[m] or (receiver not in ("self", "cls")
                                           and node.attr in others):
                found.add((m, f"{receiver}.{node.attr}"))
    return found


#: Private attributes read outside the module that defines them, each with its reason.
KNOWN_PRIVATE_ATTRIBUTES: dict[tuple[str, str], str] = {
    ("maglevkit.validation", "sys._getframe"): "the standard library's documented frame access",
    ("maglevkit.cli._app", "self._width"): "rich.Console's own width (the subclass's base)",
    ("maglevkit.models.flux", "fm._dae"): "fm is a FluxModel: the module's own class",
    ("maglevkit.models.flux", "fm._run"): "fm is a FluxModel: the module's own class",
    ("maglevkit.reduced.stepper", "other._u"): "other is a BankStepper: the module's own class",
    ("maglevkit.control.realtime", "batch._k"): "batch is a RealTimeMPCBatch: the module's own",
    **{("maglevkit.control.realtime", f"{r}.{a}"):
       "RealTimeMPC drives its base class OffsetFreeMPC (control.mpc) through its private "
       "members; control/ was another helper's lane in session 22 (not changed there)"
       for r, a in [("self", "_layout"), ("self", "_bounds"), ("self", "_problem"),
                    ("self", "_rows_per_interval"), ("self", "_unpack"), ("self", "_su"),
                    ("self", "_sx"), ("self", "_initial_guess"), ("self", "_ulim"),
                    ("self", "_shift"), ("c", "_u_prev"), ("ctls[int(j)]", "_su")]},
}


def test_no_private_attribute_is_used_outside_its_module() -> None:
    sources = {name: path.read_text(encoding="utf-8")
               for name, (path, _) in modules().items()}
    found = private_attribute_uses(sources)
    assert found <= set(KNOWN_PRIVATE_ATTRIBUTES), sorted(found - set(KNOWN_PRIVATE_ATTRIBUTES))


def test_the_private_attribute_check_catches_a_use() -> None:
    """A module that reads another module's private method, one that inherits a private
    member from another module's class, and one that reads a name both define (on an
    object that is not ``self``) are reported; a module's own private names are not."""
    sources = {
        "pkg.bank": "class Bank:\n    def _kernel(self):\n        return self._cache\n"
                    "    def __init__(self):\n        self._cache = 1\n        self._u = 0\n",
        "pkg.stepper": "def f(bank):\n    return bank._kernel()\n",
        "pkg.sub": "from pkg.bank import Bank\nclass Sub(Bank):\n"
                   "    def g(self):\n        return self._cache\n",
        "pkg.other": "class O:\n    def __init__(self):\n        self._u = 1\n"
                     "    def h(self, bank):\n        return bank._u + self._u\n",
    }
    assert private_attribute_uses(sources) == {("pkg.stepper", "bank._kernel"),
                                               ("pkg.sub", "self._cache"),
                                               ("pkg.other", "bank._u")}
