"""Which public callables of maglevkit leave a parameter undocumented (numpy-style docstrings).

Used by ``tests/test_docstrings.py``; run as a script to list the gaps:
``python tools/docstring_audit.py``.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import re
from collections.abc import Callable, Iterator

PUBLIC_MODULES = ("maglevkit", "maglevkit.materials", "maglevkit.circuit", "maglevkit.magnets",
                  "maglevkit.models", "maglevkit.reduction", "maglevkit.control",
                  "maglevkit.vehicle", "maglevkit.export", "maglevkit.sweep")

_SECTION = re.compile(r"^\s*(Parameters|Other Parameters|Attributes)\s*\n\s*-{3,}\s*$", re.M)
_ANY_SECTION = re.compile(r"^\s*[A-Z][A-Za-z ]+\s*\n\s*-{3,}\s*$", re.M)
_ENTRY = re.compile(r"^\s*(\*{0,2}[A-Za-z_][\w]*(?:\s*,\s*\*{0,2}[A-Za-z_][\w]*)*)\s*(?::|$)")


def documented_names(doc: str | None) -> set[str]:
    """Parameter names listed in a docstring's Parameters / Other Parameters / Attributes."""
    if not doc:
        return set()
    doc = inspect.cleandoc(doc)
    names: set[str] = set()
    for match in _SECTION.finditer(doc):
        body = doc[match.end():]
        nxt = _ANY_SECTION.search(body)
        body = body[: nxt.start()] if nxt else body
        for line in body.splitlines():
            if line and not line.startswith((" ", "\t")):
                m = _ENTRY.match(line)
                if m:
                    names.update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return names


def _parameters(func: Callable[..., object]) -> list[str]:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return []
    return [p.name for p in sig.parameters.values()
            if p.name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


def _public_objects(modules: tuple[str, ...] = PUBLIC_MODULES) -> Iterator[tuple[str, object]]:
    seen: set[int] = set()
    for module_name in modules:
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if id(obj) in seen or not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            seen.add(id(obj))
            yield f"{obj.__module__}.{obj.__qualname__}", obj


def public_callables(modules: tuple[str, ...] = PUBLIC_MODULES
                     ) -> Iterator[tuple[str, Callable[..., object]]]:
    """``(qualified name, callable)`` over the ``__all__`` of ``modules``: exported
    functions, the constructors of exported classes (the class itself; a dataclass's fields
    are its parameters) and their public methods (also used by ``tools/unit_name_audit.py``)."""
    for qualname, obj in _public_objects(modules):
        if inspect.isfunction(obj):
            yield qualname, obj
            continue
        assert inspect.isclass(obj)
        if issubclass(obj, BaseException):
            continue
        if obj.__dict__.get("__init__") is not None or dataclasses.is_dataclass(obj):
            yield qualname, obj
        for name, member in vars(obj).items():
            if name.startswith("_"):
                continue
            func = member.__func__ if isinstance(member, (classmethod, staticmethod)) else member
            if inspect.isfunction(func):
                yield f"{qualname}.{name}", func


def parameters(func: Callable[..., object]) -> list[str]:
    """The named parameters of ``func`` (``self``/``cls``, ``*args``, ``**kwargs`` left out)."""
    return _parameters(func)


def gaps() -> dict[str, list[str]]:
    """``qualified name -> undocumented parameters`` over the public API."""
    out: dict[str, list[str]] = {}
    for qualname, obj in public_callables():
        if inspect.isclass(obj):
            # the constructor: documented in the class docstring (or __init__'s)
            init = obj.__dict__.get("__init__")
            doc = documented_names(obj.__doc__) | documented_names(getattr(init, "__doc__", None))
        else:
            doc = documented_names(obj.__doc__)
        missing = [p for p in _parameters(obj) if p not in doc]
        if missing:
            out[qualname] = missing
    return out


if __name__ == "__main__":
    found = gaps()
    for key in sorted(found):
        print(f"{key}: {', '.join(found[key])}")
    print(f"{len(found)} public callables with undocumented parameters")
