"""Issue 10, documents and figures: the package's own sources page, the comparison figure's
gap panel and circuit styles, legends clear of the data, non-colliding current marks, and
the AC error of a signal that does not move."""

from __future__ import annotations

import math
import re
import sys
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.colors import to_rgba

import maglevkit as mk
import maglevkit.plotting as plotting
from maglevkit import figures
from maglevkit.compare import (
    AC_MIN_RELATIVE_VARIATION,
    ComparisonScenario,
    _nrms,
    compare_models,
    format_ac_error,
    standard_scenarios,
)
from maglevkit.materials import material_names

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BUNDLED = ("tr09-standard", "tr09-bow", "tr-guidance", "u-magnet")
TITLE = ("Modeling of the Transrapid's Electromagnets and the Application to Large "
         "Mechatronic Vehicle Models")


# ------------------------------------------------------------------------------ helpers
def _capture(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """Make ``maglevkit.plotting.save`` keep the figures instead of writing them."""
    figs: list[Any] = []

    def keep(fig: Any, path: Any) -> Path:
        fig.canvas.draw()
        figs.append(fig)
        return Path(path)

    monkeypatch.setattr(plotting, "save", keep)
    return figs


def _data_points_display(ax: Any, per_segment: int = 20) -> np.ndarray:
    """Display coordinates of every line of ``ax``, densified between samples (so that a
    segment crossing a box is seen even if no sample lies in it)."""
    pts = []
    for line in ax.lines:
        xy = np.asarray(line.get_xydata(), dtype=float)
        if xy.shape[0] == 0:
            continue
        disp = line.get_transform().transform(xy)
        if disp.shape[0] > 1:
            f = np.linspace(0.0, 1.0, per_segment, endpoint=False)
            seg = disp[:-1, None, :] + f[None, :, None] * (disp[1:] - disp[:-1])[:, None, :]
            disp = np.concatenate([seg.reshape(-1, 2), disp[-1:]])
        pts.append(disp)
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def _inside(points: np.ndarray, bbox: Any) -> int:
    return int(np.sum((points[:, 0] > bbox.x0) & (points[:, 0] < bbox.x1)
                      & (points[:, 1] > bbox.y0) & (points[:, 1] < bbox.y1)))


def _legends(fig: Any) -> list[tuple[Any, Any]]:
    return [(ax, ax.get_legend()) for ax in fig.axes if ax.get_legend() is not None]


def _assert_legends_clear(fig: Any) -> None:
    """No legend box contains a point of any line of any axes of the figure."""
    renderer = fig.canvas.get_renderer()
    legends = _legends(fig)
    assert legends, "the figure has no legend"
    for _, leg in legends:
        box = leg.get_window_extent(renderer)
        for ax in fig.axes:
            assert _inside(_data_points_display(ax), box) == 0, (leg.get_texts()[0].get_text(),
                                                                 ax.get_title())


# ------------------------------------------------------------------ comparison results
@pytest.fixture(scope="module")
def guidance_results() -> dict[str, Any]:
    """tr-guidance (two circuits, symmetric) on a short closed loop and the coupling step.

    Coarse maps: the figures, not the model errors, are tested here (~8 s in all).
    """
    mag = mk.load_magnet("tr-guidance", eddy_model="lumped")
    s0, i0 = mag.nominal_gap, mag.nominal_current
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.006, 0.016, 6), currents_A=np.linspace(0, 80, 17))
    coupling = [c for c in standard_scenarios(mag, gap_m=s0, current_A=i0) if c.coupling]
    closed = ComparisonScenario(
        "closed loop", "+1 mm reference step at 0.02 s", 0.25, 1e-3,
        gap_reference_m=lambda t: s0 + (1e-3 if t >= 0.02 else 0.0), kind="closed")
    res = compare_models(mag, mk.CurrentModel(maps), [closed, *coupling], gap_m=s0,
                         current_A=i0, repeat=0)
    return {r.scenario.name: r for r in res}


def test_closed_loop_figure_has_a_gap_panel_with_both_models_and_the_reference(
        guidance_results: dict[str, Any], monkeypatch: pytest.MonkeyPatch,
        tmp_path: Path) -> None:
    r = guidance_results["closed loop"]
    assert r.detailed_gap_m.shape == r.time_s.shape == r.reduced_gap_m.shape
    # the controller moved the gap by about the 1 mm reference step
    assert 0.5e-3 < float(np.ptp(r.detailed_gap_m)) < 2e-3
    figs = _capture(monkeypatch)
    plotting.plot_comparison(r, tmp_path / "c.png")
    fig = figs[0]
    gap_axes = [ax for ax in fig.axes if ax.get_ylabel() == "gap [mm]"]
    assert len(gap_axes) == 1
    drawn = [np.asarray(ln.get_ydata(), dtype=float) for ln in gap_axes[0].lines]
    for expected in (r.detailed_gap_m, r.reduced_gap_m, r.reference_gap_m):
        assert any(np.allclose(y, expected * 1e3) for y in drawn)
    assert {ax.get_ylabel() for ax in fig.axes} >= {"coil current [A]", "circuit force [kN]"}
    _assert_legends_clear(fig)


def test_coinciding_circuits_are_drawn_once_and_named_together(
        guidance_results: dict[str, Any], monkeypatch: pytest.MonkeyPatch,
        tmp_path: Path) -> None:
    r = guidance_results["closed loop"]
    # symmetric magnet and inputs: the circuits agree far below a pixel
    diff = np.max(np.abs(r.detailed_currents_A[:, 1] - r.detailed_currents_A[:, 0]))
    assert diff < plotting.COINCIDE_FRACTION * np.ptp(r.detailed_currents_A)
    figs = _capture(monkeypatch)
    plotting.plot_comparison(r, tmp_path / "c.png")
    cur = next(ax for ax in figs[0].axes if ax.get_ylabel() == "coil current [A]")
    labels = [ln.get_label() for ln in cur.lines]
    assert labels == ["front = rear: detailed", "front = rear: reduced"]


def test_different_circuits_get_different_colours_markers_and_styles(
        guidance_results: dict[str, Any], monkeypatch: pytest.MonkeyPatch,
        tmp_path: Path) -> None:
    r = guidance_results["coupling"]
    figs = _capture(monkeypatch)
    plotting.plot_comparison(r, tmp_path / "c.png")
    fig = figs[0]
    # constant gap: no gap panel in an open-loop run whose gap does not move
    assert all(ax.get_ylabel() != "gap [mm]" for ax in fig.axes)
    cur = next(ax for ax in fig.axes if ax.get_ylabel() == "coil current [A]")
    lines = {ln.get_label(): ln for ln in cur.lines}
    assert set(lines) == {"front: detailed", "front: reduced", "rear: detailed", "rear: reduced"}
    styles = {(to_rgba(ln.get_color()), ln.get_linestyle(), ln.get_marker())
              for ln in lines.values()}
    assert len(styles) == 4                       # four distinguishable traces
    assert to_rgba(lines["front: reduced"].get_color()) != to_rgba(lines["rear: reduced"].get_color())
    assert lines["front: reduced"].get_marker() != lines["rear: reduced"].get_marker()
    assert lines["front: detailed"].get_linestyle() != lines["front: reduced"].get_linestyle()
    _assert_legends_clear(fig)


# ------------------------------------------------------------------------ AC errors
def test_ac_error_of_a_signal_without_variation_is_not_a_number() -> None:
    t = np.linspace(0.0, 1.0, 201)[:, None]
    level = 30.0
    const = np.full_like(t, level)
    tiny = level * (1.0 + 1e-4 * np.sin(2 * np.pi * 3 * t))        # 1e-4 << threshold
    moving = level * (1.0 + 0.05 * np.sin(2 * np.pi * 3 * t))      # 5e-2 >> threshold
    offset = 1e-3 * level
    for ref in (const, tiny):
        _, _, ac = _nrms(ref, ref + offset)
        assert np.isnan(ac[0])
        assert format_ac_error(ac[0]) == "n/a (no variation)"
    # a moving signal: RMS error over the RMS of its AC part, by hand
    _, _, ac = _nrms(moving, moving + offset)
    ac_rms = math.sqrt(float(np.mean((moving - moving.mean()) ** 2)))
    assert ac[0] == pytest.approx(offset / ac_rms, rel=1e-12)
    assert format_ac_error(ac[0]) == f"{100 * offset / ac_rms:.2f} %"
    assert format_ac_error(ac[0], suffix="") == f"{100 * offset / ac_rms:.2f}"
    # the threshold lies between the two
    assert 1e-4 < AC_MIN_RELATIVE_VARIATION < 0.05 / math.sqrt(2)


def test_coupling_row_reports_n_a_for_the_untouched_circuit(
        guidance_results: dict[str, Any]) -> None:
    from rich.console import Console

    from maglevkit.cli.compare import comparison_table, plot_title

    r = guidance_results["coupling"]
    # the stepped circuit moves (finite AC error), the other one hardly (measured 3.6e-4
    # and 1.4e-3 of its level for current and force, below the 5e-3 threshold)
    assert np.isfinite(r.current_error_ac[0]) and np.isfinite(r.force_error_ac[0])
    assert np.isnan(r.current_error_ac[1]) and np.isnan(r.force_error_ac[1])
    assert np.isfinite(r.max_error_ac)
    console = Console(record=True, width=250)
    console.print(comparison_table([r], "t"))
    text = console.export_text()
    row = next(line for line in text.splitlines() if "rear" in line)
    assert row.count("n/a") == 2
    assert "n/a: no variation" in " ".join(text.split())     # the caption explains it
    assert "n/a (no variation)" in plot_title("m", r)
    assert "n/a (no variation)" in r.error_summary()


# ------------------------------------------------------------------- Figs. 6 and 7
def _fig6(nominal_rel: float) -> figures.Fig6Data:
    """Synthetic Fig. 6 data (layout only): F ~ (I/s)^2 saturating, 4 gaps."""
    cur = np.linspace(0.0, 2.2, 89)
    gaps = np.array([0.8, 1.0, 1.2, 1.5]) * 0.01
    lin = (cur[None, :] / (gaps[:, None] / 0.01)) ** 2
    full = lin / np.sqrt(1.0 + (lin / 2.0) ** 2) * math.sqrt(1.25)
    return figures.Fig6Data(gaps, cur, full, lin, 40.0, 60e3, 0.01, nominal_rel * 40.0)


@pytest.mark.parametrize("nominal_rel", [0.75, 0.98, 1.02, 1.1, 1.6, 0.05])
def test_nominal_and_knee_labels_do_not_collide(nominal_rel: float) -> None:
    fig = figures._draw_force_current("m", _fig6(nominal_rel))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    texts = {t.get_text().strip(): t.get_window_extent(renderer) for t in ax.texts}
    assert set(texts) == {"nominal", "knee I0"}
    a, b = texts.values()
    assert not a.overlaps(b), (nominal_rel, a, b)
    # and both stay inside the axes
    box = ax.get_window_extent(renderer)
    for bb in (a, b):
        assert box.x0 <= bb.x0 and bb.x1 <= box.x1, (nominal_rel, bb, box)
    plotting.plt.close(fig)


def test_equal_nominal_and_knee_get_one_label() -> None:
    fig = figures._draw_force_current("m", _fig6(1.0))
    assert [t.get_text().strip() for t in fig.axes[0].texts] == ["nominal = knee I0"]
    plotting.plt.close(fig)


@pytest.mark.parametrize("nominal_rel", [0.75, 1.1])
def test_fig6_legend_covers_no_curve_and_no_label(nominal_rel: float) -> None:
    fig = figures._draw_force_current("m", _fig6(nominal_rel))
    fig.canvas.draw()
    _assert_legends_clear(fig)
    renderer = fig.canvas.get_renderer()
    leg = fig.axes[0].get_legend().get_window_extent(renderer)
    for t in fig.axes[0].texts:
        assert not leg.overlaps(t.get_window_extent(renderer))
    plotting.plt.close(fig)


def test_fig7_legend_covers_no_curve() -> None:
    cur = np.linspace(0.0, 2.2, 89)
    full = 1.0 / (1.0 + np.maximum(cur - 0.8, 0.0) ** 2 * 3)
    steps = np.linspace(0.1, 2.2, 12)
    d = figures.Fig7Data(0.0095, cur, full, np.ones_like(cur), 40.0, 0.5, 30.0, steps,
                         1.33 / (1.0 + np.maximum(steps - 0.8, 0.0) ** 2 * 3),
                         np.full_like(steps, 0.99))
    fig = figures._draw_inductance("m", d)
    fig.canvas.draw()
    _assert_legends_clear(fig)
    plotting.plt.close(fig)


def test_legend_placement_detects_a_crossing_segment() -> None:
    """The overlap test of :func:`place_legend` sees a line that crosses the box between
    two samples (no sample inside), so it cannot report a covered curve as free."""
    fig, ax = plotting.plt.subplots()
    ax.plot([0.0, 1.0], [0.0, 1.0])        # two samples only, the diagonal
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    leg = ax.legend(["diagonal"], loc="center")
    fig.canvas.draw()
    assert plotting.covers_data(leg, ax)
    leg.remove()
    free = plotting.place_legend(ax, fontsize=8)
    fig.canvas.draw()
    assert not plotting.covers_data(free, ax)
    plotting.plt.close(fig)


# ----------------------------------------------------------------------- simulate plot
def test_simulate_figure_distinguishes_every_eddy_trace_and_keeps_legends_outside(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    mag = mk.load_magnet("u-magnet")
    res = mk.simulate(mk.FluxModel(mag), (0.0, 0.02), dt_s=1e-3, gaps_m=0.010,
                      voltages_V=lambda t: 40.0 if t < 0.005 else 60.0, initial_currents_A=20.0)
    assert len(res.eddy_branch_names) == 14      # the 14 traces
    figs = _capture(monkeypatch)
    plotting.plot_simulation(res, tmp_path / "s.png")
    fig = figs[0]
    eddy = next(ax for ax in fig.axes if ax.get_ylabel() == "eddy-current MMF [A]")
    styles = [(to_rgba(ln.get_color()), ln.get_linestyle()) for ln in eddy.lines]
    assert len(styles) == 14 and len(set(styles)) == 14
    # every legend lies outside every axes' plotting area
    renderer = fig.canvas.get_renderer()
    for _, leg in _legends(fig):
        box = leg.get_window_extent(renderer)
        for ax in fig.axes:
            assert not box.overlaps(ax.get_window_extent(renderer))
    _assert_legends_clear(fig)


def test_statics_plot_legend_covers_no_curve(monkeypatch: pytest.MonkeyPatch,
                                             tmp_path: Path) -> None:
    sol = mk.solve_statics(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.004, 0.02, 5),
                           currents_A=np.linspace(0, 60, 7), grid=True)
    figs = _capture(monkeypatch)
    plotting.plot_force_current(sol, tmp_path / "f.png")
    _assert_legends_clear(figs[0])


# ---------------------------------------------------------------------------- documents
def test_no_document_or_package_file_points_to_the_projects_private_reference() -> None:
    files = [*DOCS, *(ROOT / "src" / "maglevkit").rglob("*.py"),
             *(ROOT / "src" / "maglevkit" / "data").rglob("*.toml")]
    assert len(files) > 20
    for f in files:
        text = f.read_text()
        for bad in ("shared/reference", "facts.md", "paper.md"):
            assert bad not in text, f"{f.relative_to(ROOT)} mentions {bad}"


def test_readme_and_equations_cite_the_paper_by_title() -> None:
    for name in ("README.md", "docs/equations.md", "docs/sources.md"):
        assert TITLE in " ".join((ROOT / name).read_text().split()), name


def test_paths_named_in_the_documents_exist() -> None:
    """Every backticked repository path (``src/...``, ``docs/...``, ``tests/...``) exists (and a
    ``file::test`` named the test);
    globs and placeholders (``NAME``) need at least one match."""
    seen = 0
    for f in DOCS:
        for path in re.findall(r"`((?:src|docs|tests)/[^`\s]+)`", f.read_text()):
            seen += 1
            path, _, test = path.partition("::")   # tests/test_x.py::test_y: the test too
            pattern = re.sub(r"\b[A-Z]{3,}\b", "*", path.rstrip("/"))   # NAME.toml: a glob
            found = list(ROOT.glob(pattern))
            assert found, f"{f.name}: {path} does not exist"
            if test:
                name = test.split("[")[0]
                assert any(re.search(rf"^\s*def {re.escape(name)}\(", p.read_text(), re.M)
                           for p in found), f"{f.name}: {path} has no test {name}"
    assert seen >= 5


def _sources_rows(name: str) -> dict[str, tuple[str, str]]:
    """``key -> (value, tag)`` of the table of bundled file ``name`` in docs/sources.md."""
    text = (ROOT / "docs" / "sources.md").read_text()
    m = re.search(rf"^### `{re.escape(name)}`\n(.*?)(?=^#|\Z)", text, flags=re.S | re.M)
    assert m, f"docs/sources.md has no section for {name}"
    rows = {}
    for line in m.group(1).splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and cells[0].startswith("`"):
            rows[cells[0].strip("`")] = (cells[1], cells[2])
    return rows


def _value_text(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, list):
        return "[" + ", ".join(_value_text(v) for v in value) + "]"
    return repr(value)


@pytest.mark.parametrize("name", BUNDLED)
def test_sources_page_lists_every_provenance_entry_with_its_tag_and_value(name: str) -> None:
    data = tomllib.loads((resources.files("maglevkit") / "data" / f"{name}.toml").read_text())
    rows = _sources_rows(name)
    prov = data["provenance"]
    assert set(rows) == set(prov), set(rows) ^ set(prov)
    for key, note in prov.items():
        table, k = key.split(".")
        value, tag = rows[key]
        assert tag == note[:3], (name, key, tag, note)
        # the value, followed by its unit from the file's comment ("0.258 m", "190")
        shown = value if value.startswith(("[", '"')) else value.split(" ")[0]
        assert shown == _value_text(data[table][k]), (name, key, value)


def test_sources_page_material_table_matches_the_built_in_records() -> None:
    text = (ROOT / "docs" / "sources.md").read_text()
    for name in material_names():
        mat = mk.get_material(name)
        row = next(line for line in text.splitlines()
                   if line.startswith(f"| {name} ") or line.startswith(f"| {name} ("))
        cells = [c.strip() for c in row.strip("|").split("|")]
        mu_i, b_max, c_a, c_b, n = (float(c) for c in cells[1:6])
        assert (mu_i, b_max, c_a, c_b, n) == pytest.approx(
            (mat.mu_i, mat.B_mymax, mat.c_a, mat.c_b, mat.n), rel=1e-12), name
        rho = cells[6].split(" ")[0]
        assert (rho == "-") == (mat.resistivity_ohm_m is None), name
        if mat.resistivity_ohm_m is not None:
            assert float(rho) == pytest.approx(mat.resistivity_ohm_m, rel=1e-12), name


def test_figure_copies_shown_by_the_readme_exist() -> None:
    readme = (ROOT / "README.md").read_text()
    shown = re.findall(r"\]\((docs/figures/[^)]+\.png)\)", readme)
    assert len(shown) >= 4
    for p in shown:
        assert (ROOT / p).stat().st_size > 10_000, p

