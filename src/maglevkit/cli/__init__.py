"""Command-line interface ``maglevkit`` (typer).

Sub-commands live in sibling modules and register themselves on :data:`app`.
"""

from __future__ import annotations

from . import compare as _compare  # noqa: F401,E402  (registers commands)
from . import demo as _demo  # noqa: F401,E402
from . import design as _design  # noqa: F401,E402
from . import discover as _discover  # noqa: F401,E402
from . import export as _export  # noqa: F401,E402
from . import figures as _figures  # noqa: F401,E402
from . import maps as _maps  # noqa: F401,E402
from . import simulate as _simulate  # noqa: F401,E402
from . import statics as _statics  # noqa: F401,E402
from . import sweep as _sweep  # noqa: F401,E402
from . import tables as _tables  # noqa: F401,E402
from . import vehicle as _vehicle  # noqa: F401,E402
from ._app import app, console, err_console, main

__all__ = ["app", "console", "err_console", "main"]
