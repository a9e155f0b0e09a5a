"""Shared fixtures: the U-magnet and variants of it, hand-built linear networks with closed forms."""

from __future__ import annotations

import copy
import importlib.util
import os
import sys
from importlib import resources
from typing import Any

import pytest

import maglevkit as mk
from maglevkit.materials import MU0, ConstantPermeability

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


HAVE_SKFEM = importlib.util.find_spec("skfem") is not None
SKIP_FEM_VAR = "MAGLEVKIT_SKIP_FEM"


def pytest_report_header(config: pytest.Config) -> str:
    """State in the log whether the FEM validation (tests/test_fem_validation.py) runs."""
    if HAVE_SKFEM:
        return "maglevkit: scikit-fem found, the FEM validation runs"
    if os.environ.get(SKIP_FEM_VAR) == "1":
        return (f"maglevkit: scikit-fem NOT installed, FEM validation SKIPPED on request "
                f"({SKIP_FEM_VAR}=1)")
    return ("maglevkit: scikit-fem NOT installed: the FEM validation FAILS "
            f"(install the 'validation' extra, or set {SKIP_FEM_VAR}=1 to skip it)")


def u_params() -> dict[str, Any]:
    """A fresh copy of the bundled U-magnet parameter dictionary."""
    text = (resources.files("maglevkit") / "data" / "u-magnet.toml").read_text()
    return copy.deepcopy(tomllib.loads(text))


def build_u(*, material: str | None = None, magnet: dict | None = None, rail: dict | None = None,
            **options: bool) -> mk.Magnet:
    """The U-magnet with changed parameters and physics switches (eddy currents off by default)."""
    p = u_params()
    if material is not None:
        p["magnet"]["material"] = material
        p["rail"]["material"] = material
    p["magnet"].update(magnet or {})
    p["rail"].update(rail or {})
    opts = {"eddy_currents": False, **options}
    return mk.build_magnet(p, options=mk.ModelOptions(**opts))


#: The former lumped TR09 network and its nominal current (the bundled files' values before
#: issue 26's switch to ``flux_paths = "split"``, docs/decisions.md, tr09switch).
PAPER_NOMINAL_CURRENT_A = 33.5


def load_script(path: Any) -> Any:
    """A script of this repository (``benchmarks/``, ``tools/``) loaded as a module by its path.

    Its folder goes on ``sys.path`` (the scripts import their siblings, e.g. ``fem_common``)
    and the module is registered under its file name in ``sys.modules`` (dataclasses and
    pickling look it up there; a name registered already keeps its module).
    """
    from pathlib import Path

    p = Path(path)
    if str(p.parent) not in sys.path:
        sys.path.insert(0, str(p.parent))
    spec = importlib.util.spec_from_file_location(p.stem, p)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(p.stem, mod)
    spec.loader.exec_module(mod)
    return mod


def tr09_params(name: str = "tr09-standard", *, flux_paths: str | None = None) -> dict[str, Any]:
    """A fresh copy of a bundled TR09 parameter dictionary, optionally with another ``flux_paths``.

    ``flux_paths="paper"`` gives the former lumped network with its nominal current (33.5 A):
    the tests of that network's laws load it explicitly since the bundled files are split.
    """
    text = (resources.files("maglevkit") / "data" / f"{name}.toml").read_text()
    p = copy.deepcopy(tomllib.loads(text))
    if flux_paths is not None:
        p["magnet"]["flux_paths"] = flux_paths
        p["provenance"]["magnet.flux_paths"] = f"[E] modelling choice: {flux_paths!r} network"
    if flux_paths == "paper":   # the former network: lumped eddy elements, eq. 8 (switch26m)
        p["operating"]["nominal_current"] = PAPER_NOMINAL_CURRENT_A
        for key in ("eddy_model", "eddy_layers"):
            p["magnet"].pop(key, None)
            p["provenance"].pop(f"magnet.{key}", None)
        p.pop("reduced", None)
        p["provenance"].pop("reduced.eddy_modes", None)
    return p


def paper_tr09(name: str = "tr09-standard", **options: Any) -> mk.Magnet:
    """The TR09 magnet ``name`` on the former lumped ``"paper"`` network (options: ModelOptions)."""
    opts = mk.ModelOptions(**options) if options else None
    return mk.build_magnet(tr09_params(name, flux_paths="paper"), options=opts)


def without_eddy_lines(text: str) -> str:
    """A bundled magnet file's text without its eddy-model lines (``eddy_model``,
    ``eddy_layers``, the ``[reduced]`` table and their provenance): the former network with
    the lumped eddy elements and eq. 8 as its reduced model (the TR09 files' lines since
    switch26m, the guidance file's since guideswitch)."""
    return "\n".join(line for line in text.split("\n") if not line.startswith(
        ("eddy_model = ", "eddy_layers = ", "[reduced]", "eddy_modes = ", '"magnet.eddy_model"',
         '"magnet.eddy_layers"', '"reduced.eddy_modes"')))


def paper_tr09_file(directory: Any, name: str = "tr09-standard") -> str:
    """Write the ``"paper"`` variant of a bundled TR09 file into ``directory``; its path."""
    text = (resources.files("maglevkit") / "data" / f"{name}.toml").read_text()
    # the value lines (line starts: the header comments name them too)
    assert '\nflux_paths = "split"' in text and "\nnominal_current = 31.7" in text
    text = text.replace('\nflux_paths = "split"', '\nflux_paths = "paper"', 1)
    text = text.replace("\nnominal_current = 31.7", f"\nnominal_current = {PAPER_NOMINAL_CURRENT_A}", 1)
    # the former network's lumped eddy elements and eq. 8 (the file's lines since switch26m)
    text = without_eddy_lines(text)
    out = os.path.join(str(directory), f"{name}-paper.toml")
    with open(out, "w") as fh:
        fh.write(text)
    return out


def paper_tr09_vehicle(directory: Any) -> str:
    """The bundled ``tr09`` vehicle file with its magnets on the ``"paper"`` network; its path
    (for runs recorded before issue 26's switch of the TR09 files to ``"split"``)."""
    text = (resources.files("maglevkit") / "data" / "vehicle" / "tr09.toml").read_text()
    for name, key in (("tr09-standard", "standard_magnet"), ("tr09-bow", "bow_magnet")):
        old = f'{key} = "{name}"'
        assert old in text
        text = text.replace(old, f'{key} = "{paper_tr09_file(directory, name)}"', 1)
    out = os.path.join(str(directory), "tr09-paper.toml")
    with open(out, "w") as fh:
        fh.write(text)
    return out


# A single flux loop: iron core (length L_FE, area AREA, mu_r) with an n-turn coil,
# closed by one air gap.  Reluctance Rm = L_FE/(mu0 mu_r A) + s/(mu0 A), L = n^2/Rm.
AREA = 4e-4       # m^2
L_FE = 0.2        # m
MU_R = 1000.0
TURNS = 200.0
R_EL = 1.5        # ohm
G_EC = 50.0       # S, eddy conductance of the core (R_ec = n^2/G = 800 ohm)


def loop_network(*, eddy: bool, g_ec: float = G_EC) -> mk.Network:
    els: list = [mk.IronPath("core_iron", L_FE, AREA, ConstantPermeability(MU_R))]
    if eddy:
        els.append(mk.EddyCurrent("core_eddy", g_ec))
    return mk.Network(
        (mk.Branch("core", "A", "B", tuple(els)),
         mk.Branch("gap", "B", "A", (mk.AirGap("airgap", gap_input="s", pole_area_m2=AREA),))),
        (mk.Circuit("coil", R_EL, (mk.Coil("core", TURNS),)),),
        name="single loop",
    )


def loop_inductance(gap: float) -> float:
    rm = L_FE / (MU0 * MU_R * AREA) + gap / (MU0 * AREA)
    return TURNS**2 / rm


@pytest.fixture(scope="session")
def u_magnet() -> mk.Magnet:
    """The bundled U-magnet with eddy-current elements (statics ignore them)."""
    return mk.load_magnet("u-magnet")


def interrupt_after_steps(monkeypatch: pytest.MonkeyPatch, steps: int) -> None:
    """Press Ctrl-C in a vehicle run once ``steps`` steps are done: ``ProgressReporter.advance``
    (where both vehicles' time loops check for an interrupt) raises KeyboardInterrupt from
    then on."""
    from maglevkit._progress import ProgressReporter

    original = ProgressReporter.advance

    def advance(rep: ProgressReporter, n: int = 1) -> None:
        original(rep, n)
        if rep.done >= steps:
            raise KeyboardInterrupt

    monkeypatch.setattr(ProgressReporter, "advance", advance)


def open_fmu(exported: Any, directory: Any) -> tuple[Any, dict[str, int], dict[str, Any]]:
    """An exported FMU (``export_fmu``'s result) unzipped into ``directory``, instantiated
    with FMPy and left in initialisation mode at time 0 (the caller sets its start inputs
    and calls ``exitInitializationMode``).  Returns the FMU, the value reference and the
    start value of each variable by name."""
    from fmpy import extract, read_model_description
    from fmpy.simulation import instantiate_fmu

    md = read_model_description(str(exported.path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    start = {v.name: v.start for v in md.modelVariables}
    fmu = instantiate_fmu(extract(str(exported.path), str(directory)), md)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    return fmu, vr, start


# ---------------------------------------------------------------- suite timing (CPU time)
#: The 30 test files that take longest, most CPU first (the test process's and its
#: compilers'; measured with ``MAGLEVKIT_TEST_CPU_LOG`` on a cold cache, docs/decisions.md
#: "suite10").  ``make test`` hands whole files to its two workers (``--dist loadfile
#: --no-loadscope-reorder``) in collection order; collecting these first is longest-first
#: scheduling, so that the workers finish together instead of one running a heavy file
#: alone at the end.  A file not listed keeps its place after them; a stale entry only
#: costs balance, never a test.
HEAVY_FILES = (
    "test_vehicle_motion_eddy.py", "test_vehicle_controllers.py", "test_first_hour.py",
    "test_compare.py", "test_vehicle_ladder3.py", "test_design_split.py", "test_docs.py",
    "test_current_tables.py", "test_magnets_characteristics.py", "test_reduction_transient.py",
    "test_reduction.py", "test_bank.py", "test_plausible_files.py", "test_vehicle_compiled.py",
    "test_design_tr09.py", "test_figures_docs.py", "test_current_tables_network.py",
    "test_sweep.py", "test_statics_csv_multi.py", "test_bank_eddy_modes.py", "test_lanes.py",
    "test_vehicle_default_eddy.py", "test_mpc_realtime.py", "test_vehicle_eddy_modes.py",
    "test_realism.py", "test_mpc.py", "test_fmu.py", "test_calibration.py", "test_cli.py",
    "test_network_freewheel.py",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Collect the :data:`HEAVY_FILES` first, in their order (the rest keeps its order)."""
    rank = {name: k for k, name in enumerate(HEAVY_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))   # stable: files stay whole


#: Set to a file path to append each test's CPU time there, one line per test phase:
#: ``nodeid<TAB>phase<TAB>cpu_s<TAB>children_cpu_s`` (this process's CPU time, and that of
#: its finished subprocesses: compilers, CLI runs, process pools).  CPU time, not wall time:
#: the suite's machine is shared, and wall times there move with the load (docs/testing.md).
CPU_LOG_VAR = "MAGLEVKIT_TEST_CPU_LOG"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Any:
    """Log the CPU time of each test's set-up, call and teardown (``CPU_LOG_VAR``)."""
    path = os.environ.get(CPU_LOG_VAR)
    if not path:
        yield
        return
    import resource
    import time

    def children() -> float:
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    t0, c0 = time.process_time(), children()
    yield
    with open(path, "a") as fh:
        fh.write(f"{item.nodeid}\tall\t{time.process_time() - t0:.3f}\t{children() - c0:.3f}\n")
