"""Compile CasADi functions to machine code through the system C compiler, cached on disk.

``compile_function(f)`` generates C for ``f`` (CasADi code generation), compiles it with
``cc -O3 -shared -fPIC`` into a shared library named after the SHA-256 of the source,
compiler and flags, and loads it with ``casadi.external``.  A second call with the same
function finds the library in the cache and only loads it (milliseconds instead of the
compile time).  Without a working C compiler it warns once
(:class:`~maglevkit.errors.CompilationWarning`) and returns ``f`` itself, evaluated by
CasADi's virtual machine.  ``compile_library(name, functions)`` does the same for several
functions in one C file (one compiler run), e.g. a DAE and the residual, Jacobian and
quadrature functions an integrator looks up in the DAE's library.

``BoundCall(f)`` is the one place that binds a CasADi function's input and output
buffers to NumPy arrays (``Function.buffer``, ``set_arg``/``set_res`` by pointer) so
that it is called in place with no per-call conversion: the hot loops of the reduced
models, the bank, its stepper and the controllers call ``bound.eval()``.

Cache directory: ``$MAGLEVKIT_CACHE_DIR``, else ``$XDG_CACHE_HOME/maglevkit``, else
``~/.cache/maglevkit``.  The compiler: ``$CC``, else ``cc``, else ``gcc``.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from ..errors import CompilationWarning, SolverError

__all__ = ["COMPILE_MODES", "DEFAULT_FLAGS", "BoundCall", "build_source", "cache_directory",
           "compile_function",
           "compile_library", "compile_linked", "find_compiler", "run_compiler"]

COMPILE_MODES = ("auto", "always", "never")
#: Default C compiler flags of the compiled kernels (optimised, position-independent shared
#: library); callers add linker options to these.
DEFAULT_FLAGS = ("-O3", "-shared", "-fPIC")


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


def _check_mode(mode: str) -> None:
    if mode not in COMPILE_MODES:
        from ..errors import InputError

        raise InputError(f"compiled = {mode!r}; use one of {list(COMPILE_MODES)}")


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
    funcs, ok = compile_library(f.name(), [f], mode=mode, cache_dir=cache_dir, stacklevel=4)
    return (funcs[0] if ok else f), ok


def compile_library(name: str, functions: Sequence[ca.Function], *, mode: str = "auto",
                    cache_dir: str | Path | None = None, flags: Sequence[str] = DEFAULT_FLAGS,
                    stacklevel: int = 3) -> tuple[list[ca.Function], bool]:
    """Several CasADi functions generated as ONE C file, compiled into one cached library.

    Functions of the library may find each other by name: an integrator whose DAE is
    the loaded ``functions[0]`` takes ``daeF``/``jacF``/``quadF`` from the same library
    if they are in it (``casadi.external`` looks factory functions up by name).

    Parameters
    ----------
    name : str
        Stem of the C file and the library (a C identifier).
    functions : sequence of casadi.Function
        The functions (distinct names; each supports code generation).
    mode, cache_dir
        As in :func:`compile_function`.
    flags : sequence of str
        Compiler flags (part of the cache key).
    stacklevel : int, default 3
        ``stacklevel`` of the :class:`CompilationWarning` issued when ``mode="auto"``
        falls back to the interpreter (so that it points at the caller's caller).

    Returns
    -------
    (list of casadi.Function, bool)
        The loaded functions in the order given and True, or ``functions`` unchanged and
        False (``mode="never"``, or ``"auto"`` without a working compiler).
    """
    _check_mode(mode)
    funcs = list(functions)
    if mode == "never":
        return funcs, False
    try:
        cache = Path(cache_dir) if cache_dir is not None else cache_directory()
        lib = _build(name, funcs, cache, tuple(flags))
        return [ca.external(f.name(), str(lib)) for f in funcs], True
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        reason = _last_line(str(exc))
        if mode == "always":
            raise SolverError(f"compiling {name!r} to machine code failed (needs a C "
                              "compiler such as gcc; compiled='auto' falls back to the "
                              "interpreter)", reason=reason) from None
        warnings.warn(f"could not compile {name!r} ({reason}); using CasADi's virtual "
                      "machine, which is much slower", CompilationWarning, stacklevel=stacklevel)
        return funcs, False


def library_path(name: str, functions: Sequence[ca.Function], *,
                 cache_dir: str | Path | None = None,
                 flags: Sequence[str] = DEFAULT_FLAGS) -> Path:
    """Where :func:`compile_library` caches this library (it need not exist)."""
    cc = find_compiler() or ""
    with tempfile.TemporaryDirectory(prefix="maglevkit-cg-") as tmp:
        code = _generate(name, list(functions), tmp)
    cache = Path(cache_dir) if cache_dir is not None else cache_directory()
    return cache / f"{name}_{_key(code, cc, tuple(flags))}.so"


def _generate(name: str, funcs: list[ca.Function], tmp: str) -> bytes:
    src = Path(tmp) / f"{name}.c"
    cg = ca.CodeGenerator(src.name, {"with_header": False})
    for f in funcs:
        cg.add(f)
    cg.generate(tmp + os.sep)
    return src.read_bytes()


def _key(code: bytes, cc: str, flags: tuple[str, ...]) -> str:
    # the platform too: machines sharing a cache directory (a network home) may write
    # the same source
    return hashlib.sha256(code + cc.encode() + " ".join(flags).encode()
                          + str(getattr(ca, "__version__", "")).encode()
                          + f"{platform.machine()} {sys.platform}".encode()).hexdigest()[:24]


def _build(name: str, funcs: list[ca.Function], cache: Path, flags: tuple[str, ...]) -> Path:
    with tempfile.TemporaryDirectory(prefix="maglevkit-cg-") as tmp:
        code = _generate(name, funcs, tmp)
    return build_source(name, code, cache=cache, flags=flags)


def compile_linked(f: ca.Function, library: Path, *,
                   flags: Sequence[str] = DEFAULT_FLAGS) -> ca.Function | None:
    """``f`` as generated C linked against the shared ``library`` that defines the external
    functions it calls (e.g. the magnet bank's SIMD-lane step), or None where that fails.

    The library is loaded from where it lies (rpath), so it must stay there; the result is
    kept in the default cache directory like the library itself.

    Parameters
    ----------
    f : casadi.Function
        The function; its name names the compiled library.
    library : Path
        The shared library ``f``'s external calls resolve to.
    flags : sequence of str
        Compiler flags before the linker options (default :data:`DEFAULT_FLAGS`).

    Returns
    -------
    casadi.Function or None
        The compiled function; None when no compiler is found or compiling or linking
        fails (e.g. a linker without ``--no-as-needed``): the caller keeps its own path.
    """
    try:
        funcs, _ = compile_library(f.name(), [f], mode="always", cache_dir=None,
                                   flags=(*flags, "-Wl,--no-as-needed", str(library),
                                          f"-Wl,-rpath,{library.parent}"))
    except SolverError:
        return None
    return funcs[0]


def build_source(name: str, code: bytes, *, cache: Path, flags: Sequence[str] = DEFAULT_FLAGS) -> Path:
    """Compile C source ``code`` into the cached shared library ``<cache>/<name>_<key>.so``
    (key: SHA-256 of source, compiler, flags and CasADi version) unless it is there.

    Parameters
    ----------
    name : str
        Stem of the library's file name.
    code : bytes
        The C source.
    cache : Path
        Cache folder (created if missing; keyword only).
    flags : sequence of str
        Compiler flags (default optimised, position-independent shared library).

    Returns
    -------
    Path
        The shared library (written atomically).

    Raises
    ------
    OSError, RuntimeError, subprocess.SubprocessError
        No compiler, or the compiler failed (its last line of output).
    """
    cc = find_compiler()
    if cc is None:
        raise OSError("no C compiler found ($CC, cc, gcc)")
    flags = tuple(flags)
    lib = cache / f"{name}_{_key(code, cc, flags)}.so"
    if not lib.exists():
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="maglevkit-cc-") as tmp:
            src = Path(tmp) / f"{name}.c"
            src.write_bytes(code)
            # unique per call (threads of one process too): builders never share a part file
            fd, name_part = tempfile.mkstemp(prefix=f".{lib.name}.", suffix=".tmp", dir=cache)
            os.close(fd)
            part = Path(name_part)
            try:
                proc = run_compiler([cc, *flags, str(src), "-o", str(part), "-lm"])
                if proc.returncode != 0:
                    raise RuntimeError(f"{Path(cc).name} failed: {_last_line(proc.stderr)}")
                os.replace(part, lib)    # atomic: concurrent builders never see half a file
            finally:
                part.unlink(missing_ok=True)
    return lib


def run_compiler(cmd: Sequence[str], *, timeout_s: float = 600.0) -> subprocess.CompletedProcess:
    """Run a compiler command; on a time-out or an interrupt end its whole process group.

    ``subprocess.run(..., timeout=)`` ends only the process it started: the compiler
    driver (``cc``), not the compiler proper (``cc1``) the driver runs, which then keeps a
    core busy for minutes as an orphan.  Here the command starts in a session of its own,
    and a time-out, Ctrl-C or any other exception while waiting kills that whole group.

    Parameters
    ----------
    cmd : sequence of str
        The command (compiler first).
    timeout_s : float
        Seconds to wait for it [s].

    Returns
    -------
    subprocess.CompletedProcess
        With ``returncode``, ``stdout`` and ``stderr`` (text).

    Raises
    ------
    subprocess.TimeoutExpired
        The command did not finish within ``timeout_s`` (its process group is killed).
    OSError
        The command could not be started.
    """
    posix = os.name == "posix"
    proc = subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=posix)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except BaseException:
        if posix:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        else:  # pragma: no cover - no process groups
            proc.kill()
        proc.communicate()
        raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _last_line(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else text


class BoundCall:
    """A CasADi function bound once to NumPy arrays by pointer and called in place.

    ``args[i]`` and ``res[i]`` hold the nonzeros of input and output ``i`` (column-major,
    as CasADi stores them); write the inputs into ``args``, call :meth:`eval` (CasADi's
    buffer evaluation: no conversion, no allocation), read ``res``.  Arrays passed in
    ``args``/``res`` are bound as they are (any shape whose C-order flattening is the
    nonzeros, e.g. a ``(steps, n)`` block, or a slice of a larger block); the others are
    new zero arrays of shape ``(nnz,)``.  The object keeps every bound array alive.

    Parameters
    ----------
    f : casadi.Function
        The function to bind (compiled or not).
    args : mapping int -> numpy.ndarray, optional
        Arrays to bind as inputs, by input index (units those of ``f``'s inputs).
    res : mapping int -> numpy.ndarray, optional
        Arrays to bind as outputs, by output index (units those of ``f``'s outputs).
    unbound : sequence of int, optional
        Inputs left unbound here (the caller binds them later with :meth:`bind_arg`,
        e.g. one block of a long input array per call); their ``args`` entry is None.
    unbound_res : sequence of int, optional
        Outputs left unbound here (bound later with :meth:`bind_res`); their ``res``
        entry is None.

    Raises
    ------
    SolverError
        A given array is not C-contiguous float64 with as many elements as the nonzeros of
        its input or output (names the function, the buffer and what it needs).

    Attributes
    ----------
    function : casadi.Function
        ``f``.
    eval : callable
        Evaluate ``f`` in place (no arguments, returns None).
    args, res : list of numpy.ndarray
        The bound input and output arrays.
    buffer : casadi.FunctionBuffer
        CasADi's buffer object (``ret()``, ``stats()`` of the last evaluation).
    """

    __slots__ = ("function", "eval", "args", "res", "buffer")

    def __init__(self, f: ca.Function, *, args: Mapping[int, np.ndarray] | None = None,
                 res: Mapping[int, np.ndarray] | None = None,
                 unbound: Sequence[int] = (), unbound_res: Sequence[int] = ()) -> None:
        buf: Any
        buf, self.eval = f.buffer()
        self.buffer = buf
        self.function = f
        given_a, given_r = dict(args or {}), dict(res or {})
        self.args: list[Any] = []
        for i in range(f.n_in()):
            if i in unbound:
                self.args.append(None)
                continue
            a = given_a.get(i)
            a = np.zeros(f.nnz_in(i)) if a is None else a
            self.bind_arg(i, a)
            self.args.append(a)
        self.res: list[Any] = []
        for i in range(f.n_out()):
            if i in unbound_res:
                self.res.append(None)
                continue
            r = given_r.get(i)
            r = np.zeros(f.nnz_out(i)) if r is None else r
            self.bind_res(i, r)
            self.res.append(r)

    def bind_arg(self, i: int, a: np.ndarray) -> None:
        """Bind input ``i`` to array ``a`` (C-contiguous float64, as many elements as its
        nonzeros; the caller keeps ``a`` alive while it is bound).

        Parameters
        ----------
        i : int
            Input index.
        a : numpy.ndarray
            The array (units those of the input).
        """
        _check_buffer(self.function, f"input {i}", a, self.function.nnz_in(i))
        self.buffer.set_arg(i, memoryview(a.reshape(-1)))  # type: ignore[arg-type]

    def bind_res(self, i: int, r: np.ndarray) -> None:
        """Bind output ``i`` to array ``r`` (as :meth:`bind_arg`).

        Parameters
        ----------
        i : int
            Output index.
        r : numpy.ndarray
            The array (units those of the output).
        """
        _check_buffer(self.function, f"output {i}", r, self.function.nnz_out(i))
        self.buffer.set_res(i, memoryview(r.reshape(-1)))  # type: ignore[arg-type]

    def __call__(self, *args: Any) -> list[np.ndarray]:
        """Copy ``args`` into the bound inputs, evaluate, return copies of the outputs
        (a convenience; hot loops write ``args`` and call :attr:`eval` themselves)."""
        for a, v in zip(self.args, args, strict=True):
            a[:] = v
        self.eval()
        return [r.copy() for r in self.res]


def _check_buffer(f: ca.Function, what: str, a: np.ndarray, n: int) -> None:
    if (not isinstance(a, np.ndarray) or a.size != n or a.dtype != np.float64
            or not a.flags["C_CONTIGUOUS"]):
        raise SolverError(f"{what} of {f.name()!r} must be bound to {n} contiguous float64 "
                          f"values, not {getattr(a, 'shape', type(a).__name__)} "
                          f"{getattr(a, 'dtype', '')}".rstrip())
