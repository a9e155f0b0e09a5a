"""The typer application and shared CLI helpers.

Conventions (docs/decisions.md, "Command-line conventions"):

* results and reports (tables, summaries, ``--format csv|json``) go to **stdout**
  (:data:`console`); progress, diagnostics (``wrote ...``) and errors go to **stderr**
  (:data:`err_console`), so ``maglevkit statics ... > f`` captures the result only;
* no rich markup is interpreted in printed text (``gap [mm]`` stays ``gap [mm]``);
* off a terminal the consoles are :data:`LOG_WIDTH` columns wide (unless ``COLUMNS`` is
  set) and table cells fold instead of being cut with an ellipsis;
* bad input is a one-line ``error: ...`` on stderr and exit code 2, checked before the
  computation where possible (output paths, plot formats).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import sys
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console, ConsoleDimensions
from rich.table import Table
from rich.text import Text
from typer.exceptions import TyperException

from .._interrupt import deferred_sigint, recorded_sigint, sigint_received
from ..errors import MaglevkitError

LOG_WIDTH = 200
"""Console width [characters] when the output is not a terminal and ``COLUMNS`` is unset
(rich's default of 80 cut the comparison table's headers and numbers in logs)."""

app = typer.Typer(
    name="maglevkit",
    help="Electromagnet models of EMS maglev vehicles: statics, dynamics, reduced models.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


class _CliConsole(Console):
    """A rich console that is :data:`LOG_WIDTH` wide off a terminal (pipes, logs, CI)."""

    @property
    def size(self) -> ConsoleDimensions:
        dims = Console.size.fget(self)  # type: ignore[attr-defined]
        if (self._width is None and not self.is_terminal
                and not os.environ.get("COLUMNS", "").isdigit()):
            return ConsoleDimensions(LOG_WIDTH, dims.height)
        return dims  # type: ignore[no-any-return]

    @size.setter
    def size(self, new_size: tuple[int, int]) -> None:
        Console.size.fset(self, new_size)  # type: ignore[attr-defined]


# markup and emoji off: printed text (units in brackets, names, paths) is shown verbatim
console = _CliConsole(soft_wrap=True, markup=False, emoji=False)
"""Results and reports (stdout)."""
err_console = _CliConsole(stderr=True, soft_wrap=True, markup=False, emoji=False)
"""Progress, diagnostics and errors (stderr)."""


class OutputFormat(str, Enum):
    """``--format`` of the commands that print tables."""

    table = "table"
    csv = "csv"
    json = "json"


FormatOption = Annotated[OutputFormat, typer.Option(
    "--format", case_sensitive=False,
    help="How the result is printed on stdout: table (for reading), csv or json (for "
         "programs).")]


def _version(value: bool) -> None:
    if value:
        from .._version import __version__

        typer.echo(f"maglevkit {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version and exit.")] = False,
) -> None:
    """Electromagnet models of EMS maglev vehicles: statics, dynamics, reduced models."""


# ---------------------------------------------------------------------------- errors
def fail(exc: Exception | str) -> typer.Exit:
    """Print a one-line error (no traceback) on stderr and return an exit (code 2).

    After a Ctrl-C the failure is the interruption's doing (CasADi makes a SIGINT inside
    an evaluation a failed evaluation, e.g. "flux model failed ... check the magnet's
    dimensions" with pages of solver inputs): reported as ``interrupted``, code 130.
    """
    if sigint_received():
        return (typer.Exit(code=INTERRUPTED_EXIT_CODE) if _INTERRUPT_REPORTED
                else interrupted())
    message = " ".join(str(exc).split()) if isinstance(exc, Exception) else exc
    err_console.print(Text.assemble(("error:", "bold red"), " ", message))
    return typer.Exit(code=2)


INTERRUPTED_EXIT_CODE = 130
"""Exit code after Ctrl-C / SIGINT (128 + SIGINT, the shell convention)."""


_INTERRUPT_REPORTED = False


def interrupted(detail: str = "") -> typer.Exit:
    """Print ``interrupted[: detail]`` on stderr and return the exit with code 130."""
    import signal

    # a second Ctrl-C while reporting gave a traceback: the exit is on its way
    global _INTERRUPT_REPORTED

    with contextlib.suppress(ValueError):   # (not in the main thread)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    err_console.print(f"interrupted{': ' + detail if detail else ''}")
    _INTERRUPT_REPORTED = True
    return typer.Exit(code=INTERRUPTED_EXIT_CODE)


@contextlib.contextmanager
def interruptible(detail: str = "") -> Iterator[None]:
    """A long computation with Ctrl-C deferred to its safe points.

    The first SIGINT is raised at the next :func:`~maglevkit._interrupt.check_interrupt`
    (between map points, cases, chunks of time steps), not inside a CasADi evaluation,
    which would make it a failed evaluation; a second SIGINT raises at once.  Any failure
    after a SIGINT is reported as ``interrupted[: detail]``, code 130.

    Parameters
    ----------
    detail : str
        What the interruption left behind (e.g. ``no maps written to 'm.nc'``).
    """
    with deferred_sigint() as sig:
        try:
            yield
        except typer.Exit:
            raise
        except BaseException as exc:
            if sig.requested or isinstance(exc, KeyboardInterrupt):
                raise interrupted(detail) from None
            raise


def info(message: str) -> None:
    """A diagnostic line (e.g. ``wrote FILE``) on stderr."""
    err_console.print(message)


def load_magnet_or_exit(source: str | Path, **options: Any) -> Any:
    from ..magnets import load_magnet

    try:
        return load_magnet(source, **options)
    except MaglevkitError as exc:
        raise fail(exc) from None


# ---------------------------------------------------------------------------- input values
def parse_values(text: str, what: str, unit: str) -> Any:
    """Parse ``start:stop:count`` or a comma list into a float array."""
    import numpy as np

    text = text.strip()
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
            if count < 1:
                raise ValueError
            return np.linspace(start, stop, count)
        vals = np.array([float(v) for v in text.split(",") if v.strip()])
        if vals.size == 0:
            raise ValueError
        return vals
    except ValueError:
        raise typer.BadParameter(
            f"{what} must be 'start:stop:count' (count >= 1) or a comma list of numbers in {unit}, "
            f"got {text!r}"
        ) from None


# ---------------------------------------------------------------------------- output paths
def plot_formats() -> tuple[str, ...]:
    """File suffixes matplotlib can write (``png``, ``pdf``, ``svg``, ...)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return tuple(sorted(FigureCanvasBase.get_supported_filetypes()))


ForceOption = Annotated[bool, typer.Option(
    "--force", help="Overwrite existing output files (without it an existing file is an "
                    "error, reported before the computation).")]


def _same_file(path: Path, other: str | Path | None) -> bool:
    """True when ``other`` names an existing file that is ``path`` (resolved paths)."""
    if other is None:
        return False
    try:
        return Path(other).is_file() and Path(other).resolve() == path.resolve()
    except OSError:
        return False


def output_file(path: Path | None, option: str, *,
                formats: Sequence[str] | None = None, force: bool = True,
                inputs: Sequence[str | Path | None] = ()) -> Path | None:
    """Check an output file before the computation (None passes through).

    Refuses a directory, a missing parent directory (nothing is created silently), with
    ``formats`` a suffix outside them, the command's own input file (any of ``inputs``
    that is the same file, even with ``--force``) and, with ``force=False``, an existing
    file (the command's ``--force`` overwrites).  Raises the CLI's error exit (code 2).
    """
    if path is None:
        return None
    if path.is_dir():
        raise fail(f"{option} {str(path)!r} is a directory; give a file name")
    for other in inputs:
        if _same_file(path, other):
            raise fail(f"{option} {str(path)!r} is the command's input file {str(other)!r}; "
                       "give another output name (the input is never overwritten, not even "
                       "with --force)")
    if not force and path.exists():
        raise fail(f"{option} {str(path)!r} exists; add --force to overwrite it, or give "
                   "another name (nothing was computed)")
    parent = path.parent
    if not parent.is_dir():
        raise fail(f"{option} {str(path)!r}: the directory {str(parent)!r} does not exist; "
                   "create it first (nothing is created outside an existing directory)")
    if formats is not None:
        suffix = path.suffix.lower().lstrip(".")
        if suffix not in formats:
            got = f"format {suffix!r}" if suffix else "no file suffix"
            raise fail(f"{option} {str(path)!r}: {got}; use one of "
                       f"{', '.join('.' + f for f in formats)}")
    return path


def plot_file(path: Path | None, option: str = "--plot", *, force: bool = True,
              inputs: Sequence[str | Path | None] = ()) -> Path | None:
    """:func:`output_file` for a figure: the suffix must be a matplotlib format."""
    if path is None:
        return None
    return output_file(path, option, formats=plot_formats(), force=force, inputs=inputs)


def output_dir(path: Path, option: str, *, create: bool = True) -> Path:
    """An output folder: created if missing, but only inside an existing directory.

    ``create=False`` only checks (before a computation: a failed or interrupted run then
    leaves no empty folder); call it again with ``create=True`` when writing.
    """
    if path.exists() and not path.is_dir():
        raise fail(f"{option} {str(path)!r} is a file, not a folder")
    if not path.exists():
        if not path.parent.is_dir():
            raise fail(f"{option} {str(path)!r}: the directory {str(path.parent)!r} does not "
                       "exist; create it first (only the last folder is created)")
        if not create:
            return path
        try:
            path.mkdir()
        except OSError as exc:
            raise fail(f"{option} {str(path)!r}: cannot create the folder: "
                       f"{exc.strerror or exc}") from None
    return path


@contextmanager
def writing(path: Path, what: str = "") -> Iterator[None]:
    """Turn an OS error while writing ``path`` into the CLI's one-line error."""
    try:
        yield
    except OSError as exc:
        raise fail(f"cannot write {what + ' ' if what else ''}{str(path)!r}: "
                   f"{exc.strerror or exc}") from None


# ---------------------------------------------------------------------------- results
def _plain(value: Any) -> Any:
    """A JSON-safe value (numpy scalars to Python, non-finite floats to None)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and callable(value.item):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def print_records(records: Sequence[Mapping[str, Any]], fmt: OutputFormat,
                  table: Table | None = None, meta: Mapping[str, Any] | None = None) -> None:
    """Print a result on stdout: the rich ``table``, CSV of ``records`` or JSON.

    CSV: one header line with the record keys, one line per record (floats with 10
    significant digits).  JSON: ``{**meta, "rows": records}`` (``records`` alone
    without ``meta``).
    """
    if fmt == OutputFormat.table:
        if table is not None:
            console.print(table)
        return
    if fmt == OutputFormat.csv:
        buf = io.StringIO()
        keys = list(records[0]) if records else []
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(keys)
        for r in records:
            w.writerow([f"{float(v) + 0.0:.10g}" if isinstance(v, float) else v
                        for v in (r[k] for k in keys)])
        sys.stdout.write(buf.getvalue())
    else:
        payload: Any = _plain(list(records)) if meta is None else \
            {**_plain(dict(meta)), "rows": _plain(list(records))}
        sys.stdout.write(json.dumps(payload, indent=2) + "\n")
    sys.stdout.flush()


def new_table(title: str | None = None, caption: str | None = None) -> Table:
    """A table whose cells fold instead of being cut when the console is narrow."""
    return Table(title=title, caption=caption)


def add_columns(table: Table, names: Sequence[str], left: Sequence[str] = ()) -> None:
    for name in names:
        table.add_column(name, justify="left" if name in left else "right", overflow="fold")


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, file: Any = None, line: str | None = None) -> None:
    """Warnings on the CLI: one ``warning: ...`` line on stderr (no file/line/source)."""
    sys.stderr.write(f"warning: {message}\n")


def _usage_error(exc: Exception) -> int:
    """Print a usage error as the one-line ``error: ...`` of the commands; the exit code.

    Plain ``maglevkit`` (or a group without its command) prints the help on stdout, rc 0.
    """
    ctx = getattr(exc, "ctx", None)
    if type(exc).__name__ == "NoArgsIsHelpError" and ctx is not None:
        sys.stdout.write(ctx.get_help() + "\n")
        return 0
    text = exc.format_message() if hasattr(exc, "format_message") else str(exc)
    where = f" (see {ctx.command_path} --help)" if ctx is not None else ""
    fail(f"{text}{where}")
    return int(getattr(exc, "exit_code", 2))


def main() -> None:  # pragma: no cover - console entry point
    import warnings

    warnings.showwarning = _one_line_warning
    try:
        # not standalone: a Ctrl-C outside the commands' own handling (while starting,
        # importing, loading) ends with rc 130 and the "interrupted" line too, not silently
        with recorded_sigint():
            rc = app(prog_name="maglevkit", standalone_mode=False)
    except MaglevkitError as exc:   # a safety net: the commands catch their own errors
        raise SystemExit(fail(exc).exit_code) from None
    except KeyboardInterrupt:
        rc = INTERRUPTED_EXIT_CODE
    except typer.Abort:             # end of input at a prompt
        sys.stderr.write("Aborted!\n")
        raise SystemExit(1) from None
    except TyperException as exc:   # usage errors: one line, as every other error
        raise SystemExit(_usage_error(exc)) from None
    except Exception:
        # a Ctrl-C inside CasADi can surface as a SystemError ("returned a result with an
        # exception set") or a RuntimeError: the interruption, not a traceback
        if not sigint_received():
            raise
        rc = INTERRUPTED_EXIT_CODE
    if rc == INTERRUPTED_EXIT_CODE and not _INTERRUPT_REPORTED:
        interrupted()
    raise SystemExit(rc if isinstance(rc, int) else 0)
