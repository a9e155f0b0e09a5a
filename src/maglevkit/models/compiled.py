"""Compile CasADi functions to machine code through the system C compiler, cached on disk.

``compile_function(f)`` generates C for ``f`` (CasADi code generation), compiles it with
``cc -O3 -shared -fPIC`` into a shared library named after the SHA-256 of the source,
compiler and flags, and loads it with ``casadi.external``.  A second call with the same
function finds the library in the cache and only loads it (milliseconds instead of the
compile time).  Without a working C compiler it warns once
(:class:`~maglevkit.errors.CompilationWarning`) and returns ``f`` itself, evaluated by
CasADi's virtual machine.

Cache directory: ``$MAGLEVKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/maglevkit``, else
``~/.cache/maglevkit``.  The compiler: ``$CC``, else ``cc``, else ``gcc``.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import casadi as ca

from ..errors import CompilationWarning, SolverError

__all__ = ["COMPILE_MODES", "cache_directory", "compile_function", "find_compiler"]

COMPILE_MODES = ("auto", "always", "never")
_FLAGS = ("-O3", "-shared", "-fPIC")


def cache_directory() -> Path:
    """The on-disk cache of compiled libraries (created on first use)."""
    env = os.environ.get("MAGLEVKIT_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "maglevkit"


def find_compiler() -> str | None:
    """Path of the C compiler to use, or None."""
    for name in (os.environ.get("CC"), "cc", "gcc"):
        if name:
            path = shutil.which(name)
            if path:
                return path
    return None


def compile_function(f: ca.Function, *, mode: str = "auto",
                     cache_dir: str | Path | None = None) -> tuple[ca.Function, bool]:
    """``f`` as compiled machine code (cached), or ``f`` itself where that is impossible.

    Parameters
    ----------
    f : casadi.Function
        Any CasADi function that supports code generation.
    mode : {"auto", "always", "never"}
        ``"auto"``: compile, fall back to ``f`` with a :class:`CompilationWarning` if no
        compiler works; ``"always"``: raise :class:`SolverError` instead of falling back;
        ``"never"``: return ``f`` (CasADi's virtual machine).
    cache_dir : path, optional
        Overrides :func:`cache_directory`.

    Returns
    -------
    (casadi.Function, bool)
        The function to call and whether it is compiled.
    """
    if mode not in COMPILE_MODES:
        from ..errors import InputError

        raise InputError(f"compiled = {mode!r}; use one of {list(COMPILE_MODES)}")
    if mode == "never":
        return f, False
    try:
        return _compile(f, Path(cache_dir) if cache_dir is not None else cache_directory()), True
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        reason = _last_line(str(exc))
        if mode == "always":
            raise SolverError(f"compiling {f.name()!r} to machine code failed (needs a C "
                              "compiler such as gcc; compiled='auto' falls back to the "
                              "interpreter)", reason=reason) from None
        warnings.warn(f"could not compile {f.name()!r} ({reason}); using CasADi's virtual "
                      "machine, which is much slower", CompilationWarning, stacklevel=3)
        return f, False


def _compile(f: ca.Function, cache: Path) -> ca.Function:
    cc = find_compiler()
    if cc is None:
        raise OSError("no C compiler found ($CC, cc, gcc)")
    name = f.name()
    with tempfile.TemporaryDirectory(prefix="maglevkit-cg-") as tmp:
        src = Path(tmp) / f"{name}.c"
        cg = ca.CodeGenerator(src.name, {"with_header": False})
        cg.add(f)
        cg.generate(tmp + os.sep)
        code = src.read_bytes()
        key = hashlib.sha256(code + cc.encode() + " ".join(_FLAGS).encode()
                             + str(getattr(ca, "__version__", "")).encode()).hexdigest()[:24]
        lib = cache / f"{name}_{key}.so"
        if not lib.exists():
            cache.mkdir(parents=True, exist_ok=True)
            part = cache / f".{lib.name}.{os.getpid()}.tmp"
            proc = subprocess.run([cc, *_FLAGS, str(src), "-o", str(part), "-lm"],
                                  capture_output=True, text=True, timeout=600)
            if proc.returncode != 0:
                part.unlink(missing_ok=True)
                raise RuntimeError(f"{Path(cc).name} failed: {_last_line(proc.stderr)}")
            os.replace(part, lib)        # atomic: concurrent builders never see half a file
    return ca.external(name, str(lib))


def _last_line(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else text
