"""Reading the TOML parameter files (magnets, guideways, vehicles, sweeps): one reader.

Every kind of parameter file is found the same way: a bundled name (a ``.toml`` file
shipped in ``maglevkit/data/<folder>``) or the path of a ``.toml`` file, and fails the
same way, with a :class:`~maglevkit.errors.ParameterFileError` that names the file and
what is allowed.  The files' contents are checked by each kind's own parser.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Collection, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from .errors import InputError, ParameterFileError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["bundled_files", "parse_provenance", "read_parameter_file", "toml_text"]


def _folder(folder: str) -> Any:
    base = resources.files("maglevkit") / "data"
    return base / folder if folder else base


def bundled_files(folder: str = "", *, table: str | None = None) -> list[str]:
    """Names (without ``.toml``) of the files bundled in ``maglevkit/data/<folder>``.

    Parameters
    ----------
    folder : str
        Sub-folder of the package data ("" for the magnets).
    table : str, optional
        Only files with this top-level table (e.g. ``"guideway"``), for folders that hold
        files of several kinds.
    """
    names = []
    for p in _folder(folder).iterdir():
        if not p.name.endswith(".toml"):
            continue
        if table is not None and table not in tomllib.loads(p.read_text()):
            continue
        names.append(p.name[:-5])
    return sorted(names)


def read_parameter_file(source: str | os.PathLike[str], *, what: str, folder: str = "",
                        table: str | None = None) -> tuple[dict[str, Any], str]:
    """The parsed TOML of a bundled file or a path, and a label for messages.

    Parameters
    ----------
    source : str or path
        A bundled name (:func:`bundled_files` of ``folder`` and ``table``) or a ``.toml``
        file path.
    what : str
        The kind of file, for messages ("magnet", "guideway", ...).
    folder, table : str
        Where bundled files of this kind live and the table they must have (see
        :func:`bundled_files`).

    Returns
    -------
    (dict, str)
        The TOML contents and the label (the bundled name or the path).

    Raises
    ------
    InputError
        ``source`` is neither a name nor a path.
    ParameterFileError
        No such bundled name or file, or not valid TOML.
    """
    if not isinstance(source, (str, os.PathLike)) or not str(source):
        names = ", ".join(bundled_files(folder, table=table))
        raise InputError(f"source = {source!r}: expected a bundled {what} name ({names}) or "
                         "the path of a .toml file")
    path = Path(source)
    if path.suffix != ".toml" and not path.exists():
        names_list = bundled_files(folder, table=table)
        if str(source) not in names_list:
            raise ParameterFileError(f"no {what} file {str(source)!r} and no bundled {what} of "
                                     f"that name; bundled {what}s: {', '.join(names_list)}")
        text = (_folder(folder) / f"{source}.toml").read_text()
        label = str(source)
    else:
        if not path.is_file():
            raise ParameterFileError(f"{what} file {str(path)!r} does not exist")
        text = path.read_text()
        label = str(path)
    try:
        return tomllib.loads(text), label
    except tomllib.TOMLDecodeError as exc:
        raise ParameterFileError(f"{label}: not valid TOML: {exc}") from None


def parse_provenance(parameters: Mapping[str, Any], tables: Collection[str],
                     source: str) -> dict[str, str]:
    """The ``[provenance]`` table of a parameter file: ``"table.key" -> tag``.

    Every entry must name a value of one of ``tables`` present in ``parameters`` and
    carry a string; otherwise :class:`~maglevkit.errors.ParameterFileError`.

    Parameters
    ----------
    parameters : mapping
        The parsed file; its optional ``provenance`` table is read.
    tables : collection of str
        Tables whose values may carry a provenance tag (an entry naming one that
        ``parameters`` lacks raises :class:`~maglevkit.errors.ParameterFileError`).
    source : str
        File label for error messages.

    Returns
    -------
    dict of str to str
        ``"table.key" -> tag``.
    """
    raw = parameters.get("provenance", {})
    if not isinstance(raw, Mapping):
        raise ParameterFileError(f"{source}: [provenance] must map 'table.key' to a tag string")
    prov: dict[str, str] = {}
    for key, tag in raw.items():
        table, _, sub = str(key).partition(".")
        values = parameters.get(table) if table in tables else None
        if not isinstance(values, Mapping) or sub not in values:
            lacks = (f"; the file has no [{table}] table" if table in tables
                     and not isinstance(values, Mapping) else "")
            raise ParameterFileError(f"{source}: [provenance] {key!r} names no value of this "
                                     f"file{lacks} (allowed: 'table.key' of the tables "
                                     f"{', '.join(sorted(tables))})")
        if not isinstance(tag, str):
            raise ParameterFileError(f"{source}: [provenance] {key!r} must be a string")
        prov[str(key)] = tag
    return prov


# ---------------------------------------------------------------------------- writing
def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise InputError(f"cannot write {v!r} to TOML")


def _toml(tables: Mapping[str, Any], prefix: str = "") -> list[str]:
    lines: list[str] = []
    scalars = {k: v for k, v in tables.items() if not isinstance(v, Mapping)}
    subs = {k: v for k, v in tables.items() if isinstance(v, Mapping)}
    if prefix and scalars:
        lines.append(f"[{prefix}]")
    for k, v in scalars.items():
        key = k if k.replace("_", "").isalnum() else _toml_value(k)
        lines.append(f"{key} = {_toml_value(v)}")
    if scalars:
        lines.append("")
    for k, v in subs.items():
        name = k if k.replace("_", "").replace("-", "").isalnum() else _toml_value(k)
        lines += _toml(v, f"{prefix}.{name}" if prefix else name)
    return lines


def toml_text(tables: Mapping[str, Any]) -> str:
    """TOML text of nested tables of numbers, strings, bools and lists: the one writer of
    the parameter files maglevkit writes (calibrated and optimised magnets).

    Parameters
    ----------
    tables : mapping
        Top-level scalars and (nested) tables; values are numbers, strings, bools or lists
        of them.

    Returns
    -------
    str
        The TOML text (ends with a newline).

    Raises
    ------
    InputError
        A value TOML cannot hold here (e.g. None).
    """
    return "\n".join(_toml(tables)) + "\n"
