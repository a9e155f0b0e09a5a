"""``python -m maglevkit``: the command-line interface (the same as ``maglevkit``)."""

from __future__ import annotations

from .cli import main

if __name__ == "__main__":  # pragma: no cover - exercised by a subprocess test
    main()
