"""``maglevkit figures``: the paper's Figs. 6-7 analogs and the circuit coupling of a magnet."""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Annotated

import typer

from ..errors import MaglevkitError
from ._app import app, fail, info, load_magnet_or_exit, output_dir, writing


@app.command(short_help="The paper's Fig. 6/7 analogs and the circuit coupling (PNG).")
def figures(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET", help="Magnet TOML file or bundled name "
                                               "(e.g. tr09-standard).")],
    out: Annotated[Path, typer.Option(help="Output folder for the PNG files (created inside "
                                           "an existing directory).")] = Path("figures"),
) -> None:
    """Fig. 6 analog (F/F0 over I/I0), Fig. 7 analog (static L~ and step-response tau R_el
    over I/I0 at 9.5 mm) and, for several circuits, their coupling time response, as PNG.

    Needs the magnet file's [operating] table (nominal gap and current).

    \b
    Example:
      maglevkit figures tr09-standard --out figures
    """
    from ..figures import write_figures

    mag = load_magnet_or_exit(magnet)
    created = not out.exists()
    output_dir(out, "--out")
    try:
        with writing(out, "figures in"):
            paths = write_figures(mag, out)
    except BaseException as exc:
        # a failed (or interrupted) run leaves no empty folder behind
        if created:
            with contextlib.suppress(OSError):
                out.rmdir()     # only if empty: figures written before stay
        if isinstance(exc, MaglevkitError):
            raise fail(exc) from None
        raise
    for p in paths:
        info(f"wrote {p}")
