"""The typer application and shared CLI helpers."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

from ..errors import MaglevkitError

app = typer.Typer(
    name="maglevkit",
    help="Electromagnet models of EMS maglev vehicles: statics, dynamics, reduced models.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)
console = Console(stderr=True, soft_wrap=True)


@app.callback()
def _root() -> None:
    """Electromagnet models of EMS maglev vehicles: statics, dynamics, reduced models."""


def fail(exc: Exception) -> typer.Exit:
    """Print a maglevkit error without a traceback and return an exit (code 2)."""
    console.print(f"[bold red]error:[/] {escape(str(exc))}")
    return typer.Exit(code=2)


def parse_values(text: str, what: str, unit: str) -> np.ndarray:
    """Parse ``start:stop:count`` or a comma list into a float array."""
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


def load_magnet_or_exit(source: str | Path, **options: Any) -> Any:
    from ..magnets import load_magnet

    try:
        return load_magnet(source, **options)
    except MaglevkitError as exc:
        raise fail(exc) from None


def main() -> None:  # pragma: no cover - console entry point
    app()
