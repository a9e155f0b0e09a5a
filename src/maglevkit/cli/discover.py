"""``maglevkit list`` and ``maglevkit template``: what is bundled, and a file to start from."""

from __future__ import annotations

import sys
from enum import Enum
from typing import Annotated, Any

import typer

from ._app import app, console, fail, info


class Kind(str, Enum):
    """The kinds of parameter file."""

    magnets = "magnets"
    vehicles = "vehicles"
    guideways = "guideways"
    scenarios = "scenarios"
    sweeps = "sweeps"
    designs = "designs"


#: kind -> (folder under maglevkit/data, top-level table that marks the kind, title key)
_KINDS: dict[str, tuple[str, str | None, tuple[str, str] | None]] = {
    "magnets": ("", "magnet", ("magnet", "name")),
    "vehicles": ("vehicle", "vehicle", ("vehicle", "name")),
    "guideways": ("vehicle", "guideway", None),
    "scenarios": ("scenarios", None, None),
    "sweeps": ("sweeps", None, ("sweep", "name")),
    "designs": ("designs", "design", None),
}
#: further top-level tables that mark a kind (the cross-section vehicles are vehicles too)
_MORE_TABLES: dict[str, tuple[str, ...]] = {"vehicles": ("cross_section",)}
#: the commands that take each kind (the next step after listing)
_USE = {"magnets": "maglevkit statics NAME", "vehicles": "maglevkit vehicle run NAME",
        "guideways": "maglevkit vehicle run --guideway NAME",
        "scenarios": "maglevkit simulate MAGNET --scenario NAME",
        "sweeps": "maglevkit sweep NAME -o sweep.nc",
        "designs": "maglevkit design NAME -o design.toml"}
#: magnet kinds ([magnet] kind) -> the bundled file a template is made from
MAGNET_KIND_EXAMPLES = {"u_magnet": "u-magnet", "levitation_magnet": "tr09-standard",
                        "guidance_magnet": "tr-guidance"}


def _text(folder: str, name: str) -> str:
    from importlib import resources

    base = resources.files("maglevkit") / "data"
    return (base / folder / f"{name}.toml" if folder else base / f"{name}.toml").read_text()


#: Options of a magnet kind that its bundled example leaves at the default, offered in its
#: template commented out: the [magnet] lines and the [provenance] line that goes with them
#: (a file setting the key without a tag warns about the missing provenance).
_TEMPLATE_OPTIONS: dict[str, tuple[str, str]] = {
    "u_magnet": (
        '# flux_paths = "window"    # air paths of the lumped network: "standard" (default,\n'
        '#                          # Roters\' tubes), "split" or "window" (the edges by a\n'
        '#                          # conformal map, end_effects = false; the network the FEM\n'
        '#                          # calibration meets 2 % with; docs/magnets.md).  Uncomment\n'
        '#                          # it with its [provenance] line.\n',
        '# "magnet.flux_paths" = "[E] modelling choice: the lumped network\'s air paths '
        '(docs/magnets.md)"\n'),
    **{kind: (
        '# end_effects = false      # true (default): the magnet with its terms across the\n'
        '#                          # cut (3-D); false: its 2-D cut, the like-for-like\n'
        '#                          # partner of a 2-D FEM (docs/magnets.md).  Uncomment it\n'
        '#                          # with its [provenance] line.\n',
        '# "magnet.end_effects" = "[E] modelling choice: the 2-D cut, for a 2-D FEM '
        '(docs/magnets.md)"\n') for kind in ("levitation_magnet", "guidance_magnet")},
}


def _with_options(text: str) -> str:
    """A magnet file's text with its kind's :data:`_TEMPLATE_OPTIONS` inserted, commented
    out: the option at the end of ``[magnet]``, its tag at the end of ``[provenance]``
    (each only if the file does not set the key and has the table)."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    doc = tomllib.loads(text)
    kind = doc.get("magnet", {}).get("kind")
    if kind not in _TEMPLATE_OPTIONS or "provenance" not in doc:
        return text
    option, tag = _TEMPLATE_OPTIONS[kind]
    key = option.split("=")[0].lstrip("# ").strip()
    if key in doc["magnet"]:
        return text
    lines = text.splitlines(keepends=True)

    def table_end(name: str) -> int:
        """Index after the last non-blank line of table ``[name]``."""
        start = next(k for k, ln in enumerate(lines) if ln.strip() == f"[{name}]")
        end = next((k for k in range(start + 1, len(lines))
                    if lines[k].lstrip().startswith("[")), len(lines))
        while end > start + 1 and not lines[end - 1].strip():
            end -= 1
        return end

    for name, block in (("provenance", tag), ("magnet", option)):   # the later table first
        at = table_end(name)
        if not lines[at - 1].endswith("\n"):
            lines[at - 1] += "\n"
        lines[at:at] = [block]
    return "".join(lines)


def _names(kind: str) -> list[str]:
    from ..parameter_files import bundled_files

    folder, table, _ = _KINDS[kind]
    names = set(bundled_files(folder, table=table))
    for more in _MORE_TABLES.get(kind, ()):
        names.update(bundled_files(folder, table=more))
    return sorted(names)


def _title(kind: str, name: str) -> str:
    """A one-line description: the file's name key, else its first comment line."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    folder, _, key = _KINDS[kind]
    text = _text(folder, name)
    if key is not None:
        doc = tomllib.loads(text)
        for table in (key[0], *_MORE_TABLES.get(kind, ())):
            value: Any = doc.get(table, {}).get(key[1])
            if isinstance(value, str) and value:
                return value
    for line in text.splitlines():
        if line.startswith("#"):     # its first phrase
            return line.lstrip("# ").split(": ")[0].split(". ")[0].rstrip(".:")
    return ""


@app.command("list", short_help="List the bundled magnets, vehicles, guideways, scenarios, "
                                "sweeps.")
def list_files(
    kind: Annotated[Kind | None, typer.Argument(metavar="KIND",
        help="Which kind to list (default: all).", case_sensitive=False)] = None,
) -> None:
    """List the parameter files bundled with maglevkit (name and description, on stdout).

    A name can be given wherever a file is expected; `maglevkit template` writes a
    commented copy to start your own from.

    \b
    Example:
      maglevkit list magnets
    """
    kinds = [kind.value] if kind is not None else list(_KINDS)
    # one column as wide as the longest name (a fixed 16 cut tr09-cross-section's row)
    width = max((len(n) for k in kinds for n in _names(k)), default=0)
    for k in kinds:
        if len(kinds) > 1:
            console.print(f"{k}:")
        for name in _names(k):
            title = _title(k, name)
            console.print(f"  {name:<{width}}  {title}" if title else f"  {name}")
    if len(kinds) == 1:
        info(f"next: {_USE[kinds[0]]}, or maglevkit template {kinds[0][:-1]} NAME > my.toml")


@app.command("template", short_help="Print a commented parameter file to start from.")
def template(
    kind: Annotated[str, typer.Argument(metavar="KIND",
        help="magnet, vehicle, guideway, scenario, sweep or design.")],
    name: Annotated[str | None, typer.Argument(metavar="NAME",
        help="For a magnet: its kind (u_magnet, levitation_magnet, guidance_magnet) or a "
             "bundled name; otherwise a bundled name (default: the first).")] = None,
) -> None:
    """Print a commented parameter file of KIND on stdout (SI units, every key with its
    unit and provenance tag), made from a bundled example: redirect it into a file and
    edit the values.

    \b
    Example:
      maglevkit template magnet u_magnet > my-magnet.toml
    """
    kinds = {k[:-1]: k for k in _KINDS}
    plural = kinds.get(kind.lower().rstrip("s")) if kind else None
    if plural is None:
        raise fail(f"KIND {kind!r}: use one of {', '.join(kinds)}")
    names = _names(plural)
    source = name if name is not None else names[0]
    if plural == "magnets" and source in MAGNET_KIND_EXAMPLES:
        source = MAGNET_KIND_EXAMPLES[source]
    if source not in names:
        extra = (f"a magnet kind ({', '.join(MAGNET_KIND_EXAMPLES)}) or "
                 if plural == "magnets" else "")
        raise fail(f"NAME {source!r}: use {extra}a bundled {plural[:-1]} "
                   f"({', '.join(names)})")
    folder = _KINDS[plural][0]
    header = (f"# maglevkit {plural[:-1]} template, made from the bundled {source!r} "
              "(maglevkit template).\n"
              "# Edit the values (SI units: m, kg, s, A, V, ohm, m/s)")
    if plural in ("magnets", "vehicles", "guideways"):
        header += (" and their [provenance] tags\n# ([P] published, [R] widely quoted, [E] "
                   "estimate); values outside a plausible range\n# warn with the key's unit "
                   "and the likely unit slip.\n")
    else:
        header += ".\n"
    body = _text(folder, source)
    sys.stdout.write(header + (_with_options(body) if plural == "magnets" else body))
    sys.stdout.flush()
    use = _USE[plural].replace("NAME", "FILE")
    info(f"next: save it (maglevkit template {plural[:-1]} {source} > my.toml), edit it, "
         f"then {use}")
