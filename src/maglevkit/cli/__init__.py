"""Command-line interface ``maglevkit`` (typer).

Sub-commands live in sibling modules and register themselves on :data:`app`.
"""

from __future__ import annotations

from . import simulate as _simulate  # noqa: F401  (registers commands)
from . import statics as _statics  # noqa: F401  (registers commands)
from ._app import app, console, main

__all__ = ["app", "console", "main"]
