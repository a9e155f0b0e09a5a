"""FMI 2.0 Co-Simulation FMU of the reduced current-based magnet model (eq. 8).

:func:`export_fmu` writes a self-contained ``.fmu`` (a zip archive) of the reduced model
of every circuit of a magnet (or of a :class:`~maglevkit.reduced.bank.MagnetBank` of
reduced magnets)::

    modelDescription.xml            variables, units, ModelStructure
    binaries/linux64/<id>.so        compiled by the system C compiler (``cc``)
    sources/fmi2_cs.c               the FMI 2.0 interface (maglevkit, MIT)
    sources/model.c, model.h        CasADi-generated: RK4 step of eq. 8 and outputs, with
                                    the maps as per-cell polynomial tables (C arrays)
    sources/config.h                sizes, map ranges, default values, circuit names
    sources/fmi2*.h                 the FMI 2.0.1 headers (Modelica Association, BSD-2-Clause)

The model code is generated from the bank's own CasADi expressions
(:meth:`MagnetBank.circuit_step_function`, :attr:`MagnetBank.circuit_output_function`),
so the FMU computes what :meth:`MagnetBank.step` computes: same RK4 sub-steps of at
most ``max_substep`` (default 1 ms), same linear gap path over a step, same tables.
The FMU runs without Python, CasADi or maglevkit.  Variables and conventions:
``docs/fmu.md``.

Members with the shielded-gap ladder (``CurrentModel(maps, motion_eddy=True)`` or
``MagnetBank(..., motion_eddy=True)``) are exported with their second state per circuit,
the shielding eddy current ``I_e``, inside the FMU (the same kernel as the bank's; the
parameter ``R_ec`` of a ladder circuit is its shunt ``R_a``, and ``max_substep`` starts at
most at the ladder's stable RK4 step, as the bank limits it).  Three-state ladder members
(``CurrentModel(maps, motion_eddy=True, eddy_branches=2)``, ``export_fmu(...,
eddy_branches=2)``) carry their two eddy states ``I_e1``, ``I_e2`` per circuit the same way,
eddy-network members (``CurrentModel(maps, eddy_modes=m)``, ``export_fmu(...,
eddy_modes=m)``) their ``m`` branch currents ``I_k`` (the parameter ``R_ec`` is then the
network's ``R_0``, inf where the network has no current jump).
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..errors import InputError, SolverError
from ..models.compiled import cache_directory, find_compiler, run_compiler
from ..reduced.bank import KERNEL_PARAMETERS, MagnetBank
from ..reduced.core import STEP_FLAG_MESSAGES, StepFlag, circuit_label, substep_rule_c
from ..reduced.current import CurrentModel
from ..reduction.maps import default_eddy_modes
from ..validation import flag

if TYPE_CHECKING:
    from ..reduction.maps import CharacteristicMaps

#: What :func:`export_fmu` takes: maps, a current model, a bank or a mapping of the first two.
ReducedSource = Union["CharacteristicMaps", CurrentModel, MagnetBank,
                      Mapping[str, Union["CharacteristicMaps", CurrentModel]]]

__all__ = ["FMI_HEADERS", "ExportedFmu", "export_fmu", "fmu_platform"]

FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
"""The FMI 2.0.1 C headers shipped in ``sources/`` (2-Clause BSD, Modelica Association)."""

# -O1: a third of -O3's compile time on the generated model (3.6 vs 7.0 s on the loaded
# test machine); the same IEEE arithmetic (no -ffast-math), and the FMU's run time is the
# caller's per-step overhead, not the model (docs/decisions.md, "FMU export")
_CFLAGS = ("-O1", "-shared", "-fPIC", "-std=c99", "-fvisibility=hidden",
           "-DCASADI_SYMBOL_EXPORT=")
_BLOCKS = ("U", "s", "sdot", "I", "F", "I_L", "R_el", "R_ec", "I0")
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_MODEL_ID = re.compile(r"[A-Za-z][A-Za-z0-9]*(_[A-Za-z0-9]+)*\Z")   # also a CasADi name
_UNITS = {   # name -> SI base-unit exponents (FMI 2.0 BaseUnit)
    "V": {"kg": 1, "m": 2, "s": -3, "A": -1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "A": {"A": 1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "Ohm": {"kg": 1, "m": 2, "s": -3, "A": -2},
    "s": {"s": 1},
}


@dataclass(frozen=True)
class ExportedFmu:
    """What :func:`export_fmu` wrote.

    Attributes
    ----------
    path : Path
        The ``.fmu`` file.
    model_identifier : str
        FMI model identifier (C identifier, the binary's name).
    guid : str
        The FMU's GUID (derived from its content: the same model gives the same GUID).
    circuit_names : tuple of str
        Circuits in variable order (prefix of the variable names).
    input_names, output_names, parameter_names : tuple of str
        FMU variable names of each causality.
    platform : str
        FMI platform folder of the binary (``linux64`` or ``darwin64``).
    size_bytes : int
        Size of the ``.fmu`` file [bytes].
    """

    path: Path
    model_identifier: str
    guid: str
    circuit_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    parameter_names: tuple[str, ...]
    platform: str
    size_bytes: int


def fmu_platform() -> tuple[str, str]:
    """FMI 2.0 platform folder and shared-library suffix of this machine.

    Raises
    ------
    InputError
        On platforms other than 64-bit Linux and macOS (Windows is not supported).
    """
    if sys.maxsize <= 2**32:
        raise InputError("FMU export needs a 64-bit Python and C compiler")
    if sys.platform.startswith("linux"):
        return "linux64", ".so"
    if sys.platform == "darwin":
        return "darwin64", ".dylib"
    raise InputError(f"FMU export builds binaries for Linux and macOS only, not {sys.platform!r}")


def export_fmu(magnet_or_maps: ReducedSource, path: str | os.PathLike[str], *,
               model_identifier: str | None = None, description: str | None = None,
               eddy_resistance: str = "fit", interpolation: str = "bicubic",
               max_substep_s: float = 1e-3, start_gaps_m: Any = None,
               initial_currents_A: Any = None, stop_time_s: float = 1.0,
               step_size_s: float = 1e-3, motion_eddy: bool = False,
               eddy_branches: int = 1, eddy_modes: int | None = None) -> ExportedFmu:
    """Write an FMI 2.0 Co-Simulation FMU of the reduced model of every circuit (eq. 8).

    Parameters
    ----------
    magnet_or_maps : CharacteristicMaps, CurrentModel, MagnetBank or mapping
        The magnet's reduced model: its maps (``R_el`` and ``R_ec`` from the maps, see
        ``eddy_resistance``), a :class:`~maglevkit.reduced.current.CurrentModel` (its
        resistances), a bank of reduced members with one gap input per circuit, or a
        mapping name -> maps/CurrentModel (a bank of several magnets).
    path : path
        The ``.fmu`` file to write (its folder must exist; an existing file is replaced).
    model_identifier : str, optional
        FMI model identifier (a C identifier); default from the magnet's name.
    description : str, optional
        The FMU's description.
    eddy_resistance : {"fit", "jump"}
        Which ``R_ec`` of the maps becomes the parameters' start value (as
        :class:`~maglevkit.reduced.current.CurrentModel`).
    interpolation : {"bicubic", "monotone", "bilinear"}
        The maps' per-cell polynomials (:mod:`maglevkit.reduced.tables`); ``"bicubic"``
        equals ``CurrentModel``'s B-spline.
    max_substep_s : float
        Start value of the parameter ``max_substep`` [s]: the longest RK4 sub-step
        (``ceil(h / max_substep)`` sub-steps per communication step ``h``); with
        shielded-gap ladder members at most the bank's ``max_step_s`` (the ladder's
        stable step).
    start_gaps_m, initial_currents_A : float or array (n_circuits,), optional
        Start values of the gap inputs [m] and of the initial currents ``I0`` [A]
        (default: the middle of each circuit's map range; the voltage inputs start at
        the steady-state ``R_el I0``).
    stop_time_s, step_size_s : float
        The DefaultExperiment [s].
    motion_eddy : bool
        ``True``: members given as maps carry the shielded-gap ladder
        (``MagnetBank(..., motion_eddy=True)``: a second state per circuit inside the FMU);
        a ``CurrentModel`` member keeps its own choice, a bank its own (then leave this
        ``False``).
    eddy_branches : {1, 2}
        With ``motion_eddy=True``: the ladder of members given as maps has one shielded
        section (1, default: state ``I_e``) or two (2, the three-state ladder:
        ``I_e1``, ``I_e2`` per circuit inside the FMU; ``MagnetBank(...,
        eddy_branches=2)``).  A ``CurrentModel`` member or a bank keeps its own.
    eddy_modes : {None, 0, 1, 2, 3}
        ``m > 0``: members given as maps carry the maps' eddy network with ``m`` RL
        branches (``MagnetBank(..., eddy_modes=m)``: ``m`` branch currents per circuit
        inside the FMU; not with ``motion_eddy``); 0: eq. 8.  None (default): the maps'
        own default (:attr:`~maglevkit.reduction.maps.CharacteristicMaps.default_eddy_modes`,
        the magnet file's ``[reduced] eddy_modes``; 2 for the bundled TR09 magnets, 0
        for maps without it), or 0 with ``motion_eddy=True``; members given as maps with
        different defaults need it given.  A ``CurrentModel`` member or a bank keeps
        its own.

    Returns
    -------
    ExportedFmu

    Raises
    ------
    InputError
        A model that is not a reduced magnet, a detailed member, pole gap inputs, a bad
        path (not ``.fmu``, missing folder), bad options or start values outside the maps.
    SolverError
        No C compiler (``$CC``, ``cc``, ``gcc``) or the compilation failed.
    """
    target = _target_path(path)
    platform, suffix = fmu_platform()
    for name, value in (("max_substep_s", max_substep_s), ("stop_time_s", stop_time_s),
                        ("step_size_s", step_size_s)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                not (math.isfinite(value) and value > 0):
            raise InputError(f"{name} = {value!r} must be a finite number of seconds > 0")
    if description is not None and not isinstance(description, str):
        raise InputError(f"description = {description!r} must be a string")
    flag(motion_eddy, "motion_eddy")
    if eddy_modes is None:
        eddy_modes = 0 if motion_eddy else _maps_default_eddy_modes(magnet_or_maps)
    bank, default_name = _as_bank(magnet_or_maps, eddy_resistance, interpolation,
                                  bool(motion_eddy), eddy_branches, eddy_modes)
    if bank.n_eddy_states:
        # the ladder's stable RK4 step (MotionEddyLadder.max_step_s) or the eddy
        # network's (eddy_network_parameters), as the bank limits it
        max_substep_s = min(float(max_substep_s), bank.max_step_s)
    ident = _model_identifier(model_identifier, default_name)
    cc = find_compiler()
    if cc is None:
        raise SolverError("FMU export needs a C compiler to build the FMU's binary: none found "
                          "($CC, cc, gcc); install gcc or clang, or set CC",
                          reason="searched $CC, cc and gcc on the PATH")
    circuits = _circuit_labels(bank)
    nc = len(circuits)
    ranges = bank.map_ranges                      # (4, nc): s_min, s_max, I_min, I_max
    s_start = _start_values(start_gaps_m, 0.5 * (ranges[0] + ranges[1]), ranges[0], ranges[1],
                            "start_gaps_m", "m", circuits)
    i_start = _start_values(initial_currents_A, 0.5 * (ranges[2] + ranges[3]), ranges[2],
                            ranges[3], "initial_currents_A", "A", circuits)
    par = bank.circuit_parameters
    r_el = bank.resistance_ohm.copy()
    r_ec = bank.eddy_resistance_ohm.copy()
    names = _variable_names(circuits)

    with tempfile.TemporaryDirectory(prefix="maglevkit-fmu-") as tmp:
        root = Path(tmp)
        src = root / "sources"
        src.mkdir()
        _generate_model_code(bank, ident, src)
        xml_body = _model_description(
            ident, names, circuits, ranges, s_start, i_start, r_el, r_ec, float(max_substep_s),
            description or _default_description(bank, circuits), float(stop_time_s),
            float(step_size_s))
        guid = _guid(xml_body, (src / "model.c").read_bytes(), s_start, i_start, r_el, r_ec,
                     float(max_substep_s))
        (root / "modelDescription.xml").write_text(xml_body.replace("@GUID@", guid),
                                                   encoding="utf-8")
        (src / "config.h").write_text(_config_header(
            ident, guid, circuits, par, ranges, s_start, i_start, r_el, r_ec,
            float(max_substep_s), bank.n_eddy_states) + _messages_header(bank),
            encoding="utf-8")
        pkg = resources.files("maglevkit.export")
        (src / "fmi2_cs.c").write_bytes((pkg / "fmi2_cs.c").read_bytes())
        for h in FMI_HEADERS:
            (src / h).write_bytes((pkg / "fmi2" / h).read_bytes())
        binary = root / "binaries" / platform / f"{ident}{suffix}"
        binary.parent.mkdir(parents=True)
        _compile(cc, src, binary)
        part = target.with_name(f".{target.name}.{os.getpid()}.part")
        try:
            with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as zf:
                for f in sorted(p for p in root.rglob("*") if p.is_file()):
                    zf.write(f, f.relative_to(root).as_posix())
            os.replace(part, target)
        except OSError as exc:
            part.unlink(missing_ok=True)
            raise InputError(f"cannot write the FMU {str(target)!r}: "
                             f"{exc.strerror or exc}") from None
    return ExportedFmu(
        path=target, model_identifier=ident, guid=guid, circuit_names=circuits,
        input_names=tuple(names[b][j] for b in ("U", "s", "sdot") for j in range(nc)),
        output_names=tuple(names[b][j] for b in ("I", "F") for j in range(nc)) + ("F_total",),
        parameter_names=tuple(names[b][j] for b in ("R_el", "R_ec", "I0") for j in range(nc))
        + ("max_substep",),
        platform=platform, size_bytes=target.stat().st_size)


# ---------------------------------------------------------------------------- arguments
def _target_path(path: Any) -> Path:
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)) or not str(path):
        raise InputError(f"path = {path!r}: give the .fmu file to write (str or Path)")
    p = Path(path)
    if p.suffix.lower() != ".fmu":
        raise InputError(f"path {str(p)!r}: an FMU file must end in .fmu")
    if p.is_dir():
        raise InputError(f"path {str(p)!r} is a directory; give a file name ending in .fmu")
    if not p.parent.is_dir():
        raise InputError(f"path {str(p)!r}: the directory {str(p.parent)!r} does not exist "
                         "(nothing is created outside an existing directory)")
    return p


def _as_bank(model: ReducedSource, eddy_resistance: str, interpolation: str,
             motion_eddy: bool = False, eddy_branches: int = 1,
             eddy_modes: int = 0) -> tuple[MagnetBank, str]:
    """The bank to export and a default model name."""
    if isinstance(model, MagnetBank):
        if motion_eddy:
            raise InputError("motion_eddy=True applies to members given as maps; a bank has "
                             "chosen already (build it with MagnetBank(..., motion_eddy=True))")
        if eddy_branches != 1:
            raise InputError(f"eddy_branches = {eddy_branches!r} applies to members given as "
                             "maps; a bank has chosen already (build it with MagnetBank(..., "
                             "motion_eddy=True, eddy_branches=2))")
        if eddy_modes != 0:
            raise InputError(f"eddy_modes = {eddy_modes!r} applies to members given as maps; "
                             "a bank has chosen already (build it with MagnetBank(..., "
                             "eddy_modes=m))")
        kinds = {name: kind for name, kind, _ in model.members}
        detailed = [n for n, k in kinds.items() if k != "reduced"]
        if detailed:
            raise InputError(f"the bank's members {detailed} are detailed (FluxModel); an FMU "
                             "holds reduced magnets only: give their maps instead")
        if model.gap_inputs != "circuit":
            raise InputError("export a bank with gap_inputs='circuit' (one substitute gap per "
                             "circuit is the reduced model's input)")
        if model.interpolation != interpolation and interpolation != "bicubic":
            raise InputError(f"interpolation = {interpolation!r} differs from the bank's "
                             f"{model.interpolation!r}; build the bank with it instead")
        if model.freewheel:
            raise InputError("export a bank with freewheel=False: the FMU takes the voltages "
                             "as given (eq. 8)")
        name = model.member_names[0] if len(model.member_names) == 1 else "magnet_bank"
        return model, name
    if isinstance(model, Mapping):
        members = dict(model)
        for k, v in members.items():
            if not _is_reduced(v):
                raise InputError(f"member {k!r}: a {type(v).__name__}; give CharacteristicMaps or "
                                 "a CurrentModel")
        name = "magnet_bank"
    elif _is_reduced(model):
        maps = model.maps if isinstance(model, CurrentModel) else model
        name = str(maps.dataset.attrs.get("magnet_name") or "magnet")
        members = {_member_name(name): model}
    else:
        hint = (" (build its maps first: maglevkit.build_maps(magnet, gaps_m=..., currents_A=...))"
                if hasattr(model, "network") else "")
        raise InputError("export_fmu needs the reduced model: CharacteristicMaps, a "
                         f"CurrentModel, a MagnetBank or a mapping of them, got "
                         f"{type(model).__name__}{hint}")
    bank = MagnetBank(members, interpolation=interpolation, eddy_resistance=eddy_resistance,
                      compiled="never", motion_eddy=motion_eddy, eddy_branches=eddy_branches,
                      eddy_modes=eddy_modes)
    return bank, name


def _maps_default_eddy_modes(model: ReducedSource) -> int:
    """``export_fmu(eddy_modes=None)``: the default of the members given as maps (0 when
    there are none: a bank or ``CurrentModel`` members keep their own).

    Raises
    ------
    InputError
        Members given as maps whose defaults differ (the bank takes one ``eddy_modes``
        for all of them).
    """
    if isinstance(model, MagnetBank):
        return 0
    members = dict(model) if isinstance(model, Mapping) else {"": model}
    found = {k: default_eddy_modes(v) for k, v in members.items()
             if _is_reduced(v) and not isinstance(v, CurrentModel)}
    values = sorted(set(found.values()))
    if len(values) > 1:
        raise InputError(f"eddy_modes = None: the members given as maps default to different "
                         f"eddy_modes ({found}); give eddy_modes (0, 1, 2 or 3) or members "
                         "CurrentModel(maps, eddy_modes=m)")
    return values[0] if values else 0


def _is_reduced(model: Any) -> bool:
    return isinstance(model, CurrentModel) or (hasattr(model, "dataset")
                                               and hasattr(model, "variable"))


def _member_name(name: str) -> str:
    clean = name.replace("/", "_").strip() or "magnet"
    return clean


def _model_identifier(given: str | None, default: str) -> str:
    if given is not None:
        if not isinstance(given, str) or not _MODEL_ID.match(given) or len(given) > 64:
            raise InputError(f"model_identifier = {given!r} must be a C identifier of letters, "
                             "digits and single '_' between them, starting with a letter, at "
                             "most 64 characters (e.g. 'tr09_standard')")
        return given
    ident = "_".join(re.findall(r"[A-Za-z0-9]+", default))[:64].strip("_")
    if not ident or not ident[0].isalpha():
        ident = "magnet_" + ident if ident else "magnet"
    return ident


def _circuit_labels(bank: MagnetBank) -> tuple[str, ...]:
    """Circuit names for the FMU: without the member prefix when there is one member."""
    names = bank.circuit_names
    if len(bank.member_names) == 1:
        return tuple(n.split("/", 1)[1] for n in names)
    return names


def _name_part(part: str) -> str:
    if _IDENT.match(part):
        return part
    # a q-name of the structured naming convention
    return "'" + part.replace("\\", "\\\\").replace("'", "\\'") + "'"


def _variable_names(circuits: tuple[str, ...]) -> dict[str, list[str]]:
    prefix = [".".join(_name_part(p) for p in c.split("/")) for c in circuits]
    return {b: [f"{p}.{b}" for p in prefix] for b in _BLOCKS}


def _start_values(value: Any, default: np.ndarray, lo: np.ndarray, hi: np.ndarray, what: str,
                  unit: str, circuits: tuple[str, ...]) -> np.ndarray:
    from ..validation import real_array

    if value is None:
        return default.astype(float)
    arr = real_array(value, what, unit)
    if arr.ndim == 0:
        arr = np.full(len(circuits), float(arr))
    if arr.shape != (len(circuits),):
        raise InputError(f"{what}: expected one value per circuit {list(circuits)} [{unit}], got "
                         f"shape {arr.shape}")
    bad = (arr < lo) | (arr > hi)
    if bad.any():
        j = int(np.argmax(bad))
        raise InputError(f"{what}: circuit {circuits[j]!r} = {float(arr[j]):g} {unit} is outside its "
                         f"map range {lo[j]:g}..{hi[j]:g} {unit}")
    return arr


def _default_description(bank: MagnetBank, circuits: tuple[str, ...]) -> str:
    return (f"maglevkit reduced current-based magnet model (paper eq. 8) of {len(circuits)} "
            f"circuit(s) {', '.join(circuits)}: inputs voltages, gaps, gap rates; outputs coil "
            "currents and forces; RK4 with sub-steps of at most max_substep")


# ---------------------------------------------------------------------------- generation
def _generate_model_code(bank: MagnetBank, ident: str, src: Path) -> None:
    """CasADi C of the bank's RK4 step and outputs, mapped over the circuits, parameters
    as an input (``R_el``, ``a`` tunable); the tables are constant C arrays."""
    import casadi as ca

    npar, n = bank.circuit_parameters.shape
    one = bank.circuit_step_function(1)
    vi, vs, vu, vsd = (ca.MX.sym(nm, n) for nm in ("I_L", "s", "U", "sdot"))
    vh = ca.MX.sym("h")
    vp = ca.MX.sym("p", npar, n)
    # shielded-gap ladder members: one more input and output, I_e (MagnetBank), (n, n_e)
    # column-major with n_e eddy states per circuit (I_e1 of every circuit, then I_e2)
    ne = bank.n_eddy_states
    ve = [ca.MX.sym("I_e", n, ne)] if ne else []
    res = one.map(n, "serial")(vi.T, vs.T, vu.T, vsd.T, vh, vp, *(v.T for v in ve))
    outs = [r.T for r in res[:6]] + ([ca.horzcat(*(r.T for r in res[6:]))] if ve else [])
    step = ca.Function(f"{ident}_step", [vi, vs, vu, vsd, vh, vp, *ve], outs,
                       ["I_L", "s", "U", "sdot", "h", "p"] + ["I_e"] * len(ve),
                       ["I_L_next", "I", "F", "I_L_min", "I_L_max", "bad"]
                       + ["I_e_next"] * len(ve))
    out_res = bank.circuit_output_function.map(n, "serial")(vi.T, vs.T, vu.T, vp,
                                                            *(v.T for v in ve))
    out = ca.Function(f"{ident}_out", [vi, vs, vu, vp, *ve], [r.T for r in out_res],
                      ["I_L", "s", "U", "p"] + ["I_e"] * len(ve), ["I", "F", "Ltilde"])
    cg = ca.CodeGenerator("model.c", {"with_header": True})
    cg.add(step)
    cg.add(out)
    cg.generate(str(src) + os.sep)


def _c_array(name: str, values: np.ndarray) -> str:
    vals = ", ".join(_c_double(float(v)) for v in np.ravel(values))
    return f"static const double {name}[] = {{{vals}}};\n"


def _c_double(v: float) -> str:
    if math.isinf(v):
        return "HUGE_VAL" if v > 0 else "-HUGE_VAL"
    return repr(v)


def _c_string(text: str) -> str:
    safe = "".join(ch if (ch.isascii() and ch.isprintable() and ch not in '"\\%#') else "_"
                   for ch in text)
    return f'"{safe}"'


def _config_header(ident: str, guid: str, circuits: tuple[str, ...], par: np.ndarray,
                   ranges: np.ndarray, s_start: np.ndarray, i_start: np.ndarray,
                   r_el: np.ndarray, r_ec: np.ndarray, max_substep: float,
                   n_eddy: int = 0) -> str:
    nc = len(circuits)
    rows = {k: i for i, k in enumerate(KERNEL_PARAMETERS)}
    lines = [
        "/* Generated by maglevkit.export.export_fmu: sizes, ranges and start values. */",
        "#ifndef MAGLEVKIT_FMU_CONFIG_H", "#define MAGLEVKIT_FMU_CONFIG_H", "#include <math.h>",
        f'#define MODEL_IDENTIFIER "{ident}"', f'#define MODEL_GUID "{guid}"',
        f"#define NC {nc}", f"#define N_PAR {par.shape[0]}",
        "/* 1: circuits with eddy states (shielded-gap ladder, eddy network), I_e too */",
        f"#define MOTION_EDDY {1 if par.shape[0] > len(KERNEL_PARAMETERS) else 0}",
        "/* eddy states per circuit (MagnetBank.n_eddy_states: 1 I_e, 2 I_e1 and I_e2, or the",
        "   eddy network's branch currents I_k) */",
        f"#define N_EDDY {max(n_eddy, 1)}",
        f"#define PAR_R_EL {rows['resistance_ohm']}", f"#define PAR_A {rows['a']}",
        f"#define MK_STEP {ident}_step", f"#define MK_STEP_WORK {ident}_step_work",
        f"#define MK_OUT {ident}_out", f"#define MK_OUT_WORK {ident}_out_work",
        f"#define START_MAX_SUBSTEP {_c_double(max_substep)}",
        "/* the kernel's reason codes (maglevkit.reduced.core.StepFlag) */",
        *(f"#define STEP_FLAG_{flag.name} {int(flag)}" for flag in StepFlag),
        "/* kernel parameters, one column of N_PAR per circuit (MagnetBank.circuit_parameters) */",
    ]
    text = "\n".join(lines) + "\n"
    text += _c_array("PAR0", par.ravel(order="F"))
    text += "/* map ranges [m], [A] (messages) and the checked bounds with rounding allowances */\n"
    text += _c_array("GAP_MIN", ranges[0]) + _c_array("GAP_MAX", ranges[1])
    text += _c_array("CUR_MIN", ranges[2]) + _c_array("CUR_MAX", ranges[3])
    text += _c_array("GAP_LO", par[rows["gap_lower_m"]]) + _c_array("GAP_HI", par[rows["gap_upper_m"]])
    text += _c_array("CUR_LO", par[rows["current_lower_A"]])
    text += _c_array("CUR_HI", par[rows["current_upper_A"]])
    text += _c_array("START_S", s_start) + _c_array("START_I0", i_start)
    text += _c_array("START_U", r_el * i_start)
    text += _c_array("START_R_EL", r_el) + _c_array("START_R_EC", r_ec)
    text += ("static const char *const CIRCUIT_NAMES[] = {"
             + ", ".join(_c_string(c) for c in circuits) + "};\n")
    return text + "#endif\n"


def _c_literal(text: str) -> str:
    """``text`` as a C string literal (printable ASCII kept, ``%`` too: a format)."""
    safe = "".join(ch if (ch.isascii() and ch.isprintable()) else "_" for ch in text)
    return '"' + safe.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _messages_header(bank: MagnetBank) -> str:
    """The sub-step rule and the reason codes' messages for the C wrapper, from their one
    source (:func:`~maglevkit.reduced.core.substep_rule_c`,
    :data:`~maglevkit.reduced.core.STEP_FLAG_MESSAGES`), and the bank's circuit names and
    labels that the messages name."""
    lines = ["#ifndef MAGLEVKIT_FMU_MESSAGES_H", "#define MAGLEVKIT_FMU_MESSAGES_H",
             "/* the sub-step rule of maglevkit.reduced.core.substep_counts */",
             "#define SUBSTEP_COUNT(h, max_step) " + substep_rule_c("(h)", "(max_step)"),
             "/* the order in which reasons are reported (StepFlag.by_priority) */",
             "#define STEP_FLAG_PRIORITY {" + ", ".join(str(int(f)) for f in
                                                        StepFlag.by_priority()) + "}",
             "/* the reason codes' messages (maglevkit.reduced.core.STEP_FLAG_MESSAGES) */"]
    lines += [f"#define MSG_{key.upper()} {_c_literal(text)}"
              for key, text in STEP_FLAG_MESSAGES.items()]
    names = bank.circuit_names
    text = "\n".join(lines) + "\n"
    text += ("static const char *const BANK_CIRCUITS[] = {"
             + ", ".join(_c_literal(c) for c in names) + "};\n")
    text += ("static const char *const CIRCUIT_LABELS[] = {"
             + ", ".join(_c_literal(circuit_label(c)) for c in names) + "};\n")
    return text + "#endif\n"


def _xml_double(v: float) -> str:
    if math.isinf(v):
        return "INF" if v > 0 else "-INF"
    return repr(float(v))


def _model_description(ident: str, names: dict[str, list[str]], circuits: tuple[str, ...],
                       ranges: np.ndarray, s_start: np.ndarray, i_start: np.ndarray,
                       r_el: np.ndarray, r_ec: np.ndarray, max_substep: float,
                       description: str, stop_time: float, step_size: float) -> str:
    from .._version import __version__

    nc = len(circuits)
    vars_: list[str] = []

    def var(name: str, causality: str, variability: str, initial: str | None, unit: str,
            desc: str, start: float | None = None, lo: float | None = None,
            hi: float | None = None) -> None:
        vr = len(vars_)
        attrs = f'name={quoteattr(name)} valueReference="{vr}" description={quoteattr(desc)} ' \
                f'causality="{causality}" variability="{variability}"'
        if initial is not None:
            attrs += f' initial="{initial}"'
        real = f'unit="{escape(unit)}"'
        if lo is not None:
            real += f' min="{_xml_double(lo)}"'
        if hi is not None:
            real += f' max="{_xml_double(hi)}"'
        if start is not None:
            real += f' start="{_xml_double(start)}"'
        vars_.append(f"    <ScalarVariable {attrs}>\n      <Real {real}/>\n    </ScalarVariable>")

    for j, c in enumerate(circuits):
        var(names["U"][j], "input", "continuous", None, "V",
            f"circuit {c}: coil voltage U, held over each communication step",
            float(r_el[j] * i_start[j]))
    for j, c in enumerate(circuits):
        var(names["s"][j], "input", "continuous", None, "m",
            f"circuit {c}: substitute air gap s at the communication point (map range "
            f"{ranges[0, j]:g}..{ranges[1, j]:g} m)", float(s_start[j]), ranges[0, j],
            ranges[1, j])
    for j, c in enumerate(circuits):
        var(names["sdot"][j], "input", "continuous", None, "m/s",
            f"circuit {c}: gap rate ds/dt; the gap moves linearly with it over each step", 0.0)
    for j, c in enumerate(circuits):
        var(names["I"][j], "output", "continuous", "calculated", "A",
            f"circuit {c}: coil current I = (U - U_L)/R_el (Fig. 8)")
    for j, c in enumerate(circuits):
        var(names["F"][j], "output", "continuous", "calculated", "N",
            f"circuit {c}: attraction force F(s, I_L) from the force map")
    for j, c in enumerate(circuits):
        var(names["I_L"][j], "local", "continuous", "calculated", "A",
            f"circuit {c}: inductor current I_L, the state of eq. 8")
    for j, c in enumerate(circuits):
        var(names["R_el"][j], "parameter", "tunable", "exact", "Ohm",
            f"circuit {c}: ohmic coil resistance R_el", float(r_el[j]))
    for j, c in enumerate(circuits):
        var(names["R_ec"][j], "parameter", "tunable", "exact", "Ohm",
            f"circuit {c}: equivalent eddy-current resistance R_ec (INF: none; the shunt R_a "
            "of a shielded-gap ladder circuit)", float(r_ec[j]))
    for j, c in enumerate(circuits):
        var(names["I0"][j], "parameter", "fixed", "exact", "A",
            f"circuit {c}: initial inductor current I_L(t0) (the coil current in steady state)",
            float(i_start[j]), ranges[2, j], ranges[3, j])
    var("F_total", "output", "continuous", "calculated", "N", "sum of the circuit forces")
    var("max_substep", "parameter", "fixed", "exact", "s",
        "longest RK4 sub-step: ceil(h / max_substep) sub-steps per communication step h",
        max_substep)

    def index(block: str, j: int) -> int:       # 1-based ScalarVariable index
        return _BLOCKS.index(block) * nc + j + 1

    f_total = 9 * nc + 1
    outputs = [f'      <Unknown index="{index("I", j)}" dependencies="{index("U", j)}" '
               'dependenciesKind="dependent"/>' for j in range(nc)]
    outputs += [f'      <Unknown index="{index("F", j)}" dependencies="{index("s", j)}" '
                'dependenciesKind="dependent"/>' for j in range(nc)]
    outputs.append(f'      <Unknown index="{f_total}" dependencies="'
                   + " ".join(str(index("s", j)) for j in range(nc)) + '" dependenciesKind="'
                   + " ".join(["dependent"] * nc) + '"/>')
    initial = [f'      <Unknown index="{index(b, j)}"/>' for b in ("I", "F") for j in range(nc)]
    initial.append(f'      <Unknown index="{f_total}"/>')
    units = []
    for u, exps in _UNITS.items():
        base = " ".join(f'{k}="{v}"' for k, v in exps.items())
        units.append(f'    <Unit name="{escape(u)}">\n      <BaseUnit {base}/>\n    </Unit>')
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(ident)} guid="@GUID@"
  description={quoteattr(description)}
  generationTool={quoteattr("maglevkit " + __version__)}
  variableNamingConvention="structured" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{ident}" needsExecutionTool="false"
    canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false"
    maxOutputDerivativeOrder="0" canRunAsynchronuously="false"
    canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="false"
    canGetAndSetFMUstate="false" canSerializeFMUstate="false"
    providesDirectionalDerivative="false">
    <SourceFiles>
      <File name="fmi2_cs.c"/>
      <File name="model.c"/>
    </SourceFiles>
  </CoSimulation>
  <UnitDefinitions>
{chr(10).join(units)}
  </UnitDefinitions>
  <LogCategories>
    <Category name="logStatusError"
      description="errors: inputs outside the maps, non-finite values, bad calls"/>
    <Category name="logAll" description="all messages"/>
  </LogCategories>
  <DefaultExperiment startTime="0.0" stopTime="{_xml_double(stop_time)}" stepSize="{_xml_double(step_size)}"/>
  <ModelVariables>
{chr(10).join(vars_)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{chr(10).join(outputs)}
    </Outputs>
    <InitialUnknowns>
{chr(10).join(initial)}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def _guid(xml: str, code: bytes, *arrays: Any) -> str:
    h = hashlib.sha256(xml.encode() + code)
    for a in arrays:
        h.update(np.asarray(a, dtype=float).tobytes())
    return "{" + str(uuid.UUID(hex=h.hexdigest()[:32])) + "}"


def _compile(cc: str, src: Path, binary: Path) -> None:
    """Compile the sources into ``binary``; cached on disk under the SHA-256 of the
    sources, compiler and flags (:func:`maglevkit.models.compiled.cache_directory`), so
    exporting the same model again only copies the library."""
    h = hashlib.sha256(" ".join([cc, *_CFLAGS]).encode())
    for f in sorted(src.iterdir()):
        h.update(f.name.encode() + b"\0" + f.read_bytes())
    cache = cache_directory() / "fmu"
    cached = cache / f"{binary.stem}_{h.hexdigest()[:24]}{binary.suffix}"
    if cached.is_file():
        shutil.copyfile(cached, binary)
        return
    cmd = [cc, *_CFLAGS, "-I", str(src), str(src / "fmi2_cs.c"), str(src / "model.c"),
           "-o", str(binary), "-lm"]
    try:
        proc = run_compiler(cmd)
    except (OSError, subprocess.SubprocessError) as exc:
        raise SolverError(f"compiling the FMU's binary with {cc} failed",
                          reason=str(exc)) from None
    if proc.returncode != 0:
        lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
        raise SolverError(f"compiling the FMU's binary with {Path(cc).name} failed",
                          reason=lines[-1] if lines else f"exit code {proc.returncode}")
    try:
        cache.mkdir(parents=True, exist_ok=True)
        part = cache / f".{cached.name}.{os.getpid()}.tmp"
        shutil.copyfile(binary, part)
        os.replace(part, cached)          # atomic: a concurrent export never sees half a file
    except OSError:
        pass                              # no cache: the next export compiles again
