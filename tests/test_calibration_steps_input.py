"""Voltage steps on the user's path (issue 25 item 2): held-out step labels (commas
included) from the command line and from Python, and bad step files -- a typo'd column, a
label that does not exist, a magnet not at rest before the step, a label reused for
another step, gaps in mm and times in ms -- each a one-line named error (exit code 2, no
traceback) or a warning naming the row; and the step scheme against CasADi's collocation
integrator (the same root, one Newton per step on the DAE's sparse form)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit import calibration
from maglevkit.calibration import StepResponses, VoltageStep, calibrate, read_steps
from maglevkit.cli import app
from maglevkit.errors import DataError, DataWarning, InputError

ROOT = Path(__file__).resolve().parents[1]
FEM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics.csv"
#: labels as a test bed's log names its steps: with commas
STEPS = (("10 mm, 10 -> 20 A", 0.010, 10.0, 40.0), ("6 mm, 20 -> 35 A", 0.006, 20.0, 70.0))
HEADER = ("step", "time_s", "current_A", "gap_m", "initial_current_A", "voltage_V")


@pytest.fixture(scope="module")
def magnet() -> mk.Magnet:
    return mk.load_magnet("u-magnet")          # lumped eddy elements


@pytest.fixture(scope="module")
def records(magnet: mk.Magnet) -> list[tuple[str, float, float, float, np.ndarray, np.ndarray]]:
    """The nominal magnet's steps by IDAS (an independent integrator), 9 samples each."""
    out = []
    for label, gap, i0, u in STEPS:
        r = mk.voltage_step_response(magnet, gap_m=gap, voltage_V=u, initial_current_A=i0,
                                     duration_s=0.2, dt_s=0.001, rtol=1e-10, atol=1e-12)
        t, i = np.asarray(r.time_s), np.asarray(r.currents_A)[:, 0]
        idx = np.unique(np.r_[1:5, np.linspace(8, t.size - 1, 5).astype(int)])
        out.append((label, gap, i0, u, t[idx], i[idx]))
    return out


def _write(path: Path, records: list, *, header: tuple[str, ...] = HEADER,
           time_factor: float = 1.0, gap_factor: float = 1.0,
           before_A: float | None = None) -> Path:
    """A step file: two rows before the step (at rest unless ``before_A``), then the
    samples; ``time_factor``/``gap_factor`` make the unit slips."""
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for label, gap, i0, u, t, i in records:
            g = gap * gap_factor
            w.writerow([label, -0.001 * time_factor, i0 if before_A is None else before_A, g,
                        i0, u])
            w.writerow([label, 0.0, i0, g, i0, u])
            for tk, ik in zip(t, i, strict=True):
                w.writerow([label, repr(float(tk) * time_factor), repr(float(ik)), g, i0, u])
    return path


def _cli(*args: str) -> tuple[int, str]:
    res = CliRunner().invoke(app, ["calibrate", "u-magnet", str(FEM), *args])
    return res.exit_code, res.output


def _one_line_error(code: int, out: str) -> str:
    """The CLI's failure: exit code 2, one ``error:`` line, no traceback."""
    assert code == 2, out
    assert "Traceback" not in out, out
    lines = [ln for ln in out.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, out
    return lines[0]


# ---------------------------------------------------------------------------- labels
def test_cli_holds_out_a_label_with_commas(records: list, tmp_path: Path) -> None:
    """--holdout-step takes one label as it is; the comma form --holdout-steps finds the
    one way to read the same text as labels.  Both hold out the same step."""
    steps = _write(tmp_path / "steps.csv", records)
    outs = []
    for option in ("--holdout-step", "--holdout-steps"):
        code, out = _cli("--steps", str(steps), "--params", "resistance_scale", "-o",
                         str(tmp_path / "c.toml"), "--force", option, "6 mm, 20 -> 35 A",
                         "--format", "json")
        assert code == 0, out
        outs.append(out)
    for out in outs:
        # the held-out step's samples are reported as such, the other step's as fitted
        assert '"set": "holdout step 6 mm, 20 -> 35 A"' in out
        assert '"set": "step 10 mm, 10 -> 20 A"' in out
        assert '"set": "step 6 mm, 20 -> 35 A"' not in out


def test_cli_comma_list_still_splits_labels_without_commas(records: list,
                                                           tmp_path: Path) -> None:
    from maglevkit.cli.tables import _comma_labels

    assert _comma_labels("a, b", ["a", "b", "c"]) == ["a", "b"]
    assert _comma_labels("a,,b,", ["a", "b"]) == ["a", "b"]
    # a label with commas and plain labels: one reading each
    labels = ["6 mm, 20 -> 35 A", "b"]
    assert _comma_labels("6 mm, 20 -> 35 A,b", labels) == ["6 mm, 20 -> 35 A", "b"]


@pytest.mark.parametrize(("args", "needle"), [
    # "a,b" is a label and so are "a" and "b": two readings
    (["--holdout-steps", "a,b"], "is ambiguous: it reads as ['a', 'b'] or as ['a,b']"),
    (["--holdout-steps", "a,x"], "no step with the label(s) ['x']; the steps: ['a', 'b', "
                                 "'a,b']; labels with commas: give each with --holdout-step"),
    (["--holdout-step", "a, b"], "--holdout-step 'a, b': no step with that label; the steps: "
                                 "['a', 'b', 'a,b']"),
])
def test_cli_unknown_and_ambiguous_labels_are_named_errors(
        records: list, tmp_path: Path, args: list[str], needle: str) -> None:
    base = records[0]
    steps = _write(tmp_path / "steps.csv", [(lab, *base[1:]) for lab in ("a", "b", "a,b")])
    line = _one_line_error(*_cli("--steps", str(steps), "-o", str(tmp_path / "c.toml"),
                                 *args))
    assert needle in line, line


def test_api_takes_a_string_as_one_label(magnet: mk.Magnet, records: list) -> None:
    data = StepResponses(tuple(
        VoltageStep(label=lab, time_s=t, current_A=i, gap_m=g, initial_current_A=i0,
                    voltage_V=u, circuit="", rows=np.arange(4, 4 + t.size))
        for lab, g, i0, u, t, i in records))
    # a str is one label, not a comma list nor its characters
    with pytest.raises(InputError, match=r"holdout_steps \['10 mm, 6 mm'\]: no step with "
                                         r"that label; the steps: \['10 mm, 10 -> 20 A'"):
        calibrate(magnet, None, steps=data, holdout_steps="10 mm, 6 mm")
    with pytest.raises(InputError, match="holds out every step and there are no static data"):
        calibrate(magnet, None, steps=data, holdout_steps=[r[0] for r in records])
    with pytest.raises(InputError, match=r"holdout_steps: 2 is not a step label"):
        calibrate(magnet, None, steps=data, holdout_steps=[2])  # type: ignore[list-item]


# ---------------------------------------------------------------------------- bad files
@pytest.mark.parametrize(("kind", "needle"), [
    ("typo", "unknown ['gap_mm'], missing ['gap_m'] (did you mean 'gap_mm' -> 'gap_m'?)"),
    ("mm", "row 2: gap_m = 10 lies outside 0.0001-0.1 m; is the gap in mm?"),
    # 0.2 s written as 200 s: 2933 time constants of 68 ms (L~ / R_el at 10 mm, 10 A)
    ("ms", "step '10 mm, 10 -> 20 A' (last row 12): time_s reaches 200 s, 2933 time "
           "constants"),
])
def test_cli_bad_step_files_are_one_line_errors(records: list, tmp_path: Path, kind: str,
                                                needle: str) -> None:
    path = _write(tmp_path / f"{kind}.csv", records,
                  header=tuple("gap_mm" if h == "gap_m" and kind == "typo" else h
                               for h in HEADER),
                  time_factor=1000.0 if kind == "ms" else 1.0,
                  gap_factor=1000.0 if kind == "mm" else 1.0)
    line = _one_line_error(*_cli("--steps", str(path), "-o", str(tmp_path / "c.toml"),
                                 "--params", "resistance_scale"))
    assert needle in line, line


def test_time_span_check_passes_the_recorded_fem_steps(magnet: mk.Magnet) -> None:
    # the transient FEM's records (2.7-8.2 time constants) are far inside the limit
    import json

    runs = json.loads((ROOT / "benchmarks" / "results" / "fem_transient_cases.json")
                      .read_text())["runs"]
    steps = StepResponses(tuple(
        VoltageStep(label=r["label"], time_s=np.asarray(r["time_s"][1:]),
                    current_A=np.asarray(r["current_A"][1:]), gap_m=r["gap_m"],
                    initial_current_A=r["i0_A"], voltage_V=2.0 * r["i1_A"], circuit="",
                    rows=np.arange(2, 1 + len(r["time_s"]))) for r in runs))
    calibration._check_step_times(steps, magnet.network)
    slow = StepResponses((steps.steps[0],))
    with pytest.raises(DataError, match="is the time in ms"):
        calibration._check_step_times(
            StepResponses((VoltageStep(**{**slow.steps[0].__dict__,
                                          "time_s": 1000.0 * slow.steps[0].time_s}),)),
            magnet.network)


def test_a_magnet_not_at_rest_before_the_step_is_warned_naming_the_row(
        records: list, tmp_path: Path) -> None:
    path = _write(tmp_path / "moving.csv", records[:1], before_A=12.0)
    with pytest.warns(DataWarning, match=r"row 2: step '10 mm, 10 -> 20 A' before the step "
                                         r"\(time_s = -0.001 s\) has current_A = 12 A, not "
                                         r"initial_current_A = 10 A"):
        read_steps(path)
    # at rest (the rows before the step at initial_current_A): no warning
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        read_steps(_write(tmp_path / "rest.csv", records[:1]))


def test_a_label_reused_for_another_step_names_both_rows(records: list,
                                                         tmp_path: Path) -> None:
    # the second step carries the first one's label: holding out or reporting by label
    # would mix them
    path = _write(tmp_path / "dup.csv", [records[0], (records[0][0], *records[1][1:])])
    with pytest.raises(DataError, match=r"row 13: step '10 mm, 10 -> 20 A' again \(its rows "
                                        r"start at row 2\)"):
        read_steps(path)


# ---------------------------------------------------------------------------- the scheme
def test_step_scheme_equals_casadis_collocation_integrator(magnet: mk.Magnet) -> None:
    """The Radau steps on the DAE's sparse form ``K y' = h`` (one Newton rootfinder per
    step) against CasADi's ``collocation`` integrator on its explicit form ``y' = T pinv(K)
    h``, same grid and tolerance: response and exact derivatives (the same root)."""
    ladder = mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=2)
    names = ("eddy_conductance_scale", "resistance_scale", "leakage_factor")
    values = np.array([0.8, 1.02, 0.95])
    times = np.array([2e-4, 1e-3, 4e-3, 0.015, 0.04, 0.08, 0.15])
    out = {}
    for scheme in ("radau", "casadi"):
        step = calibration._ParametricStep(ladder, names, gap_m=0.01, current_A=20.0,
                                           times_s=times, circuit=0, voltage_V=70.0,
                                           scheme=scheme)
        out[scheme] = step.evaluate(values)
    (cur, jac), (cur_c, jac_c) = out["radau"], out["casadi"]
    change = float(np.max(np.abs(cur_c - 20.0)))
    # equivalent equations, each Newton stopped at 1e-10 on its own scaled rows: measured
    # 1.2e-11 of the change and 7e-12 relative in the derivatives (6-layer ladder, six
    # parameters: 1.9e-11 / 4.6e-9, benchmarks/bench_calibration_steps.py)
    assert np.max(np.abs(cur - cur_c)) / change < 1e-10
    assert np.max(np.abs(jac - jac_c)) / np.max(np.abs(jac_c)) < 1e-7


@pytest.mark.parametrize(("text", "needle"), [
    # initial_current_A logged as the measured current: the step falls apart at row 3
    ("time_s,current_A,gap_m,initial_current_A,voltage_V\n0.001,11,0.01,10,40\n"
     "0.002,12,0.01,10.5,40\n0.003,12,0.01,10.5,40\n0.004,12,0.01,10.5,40\n",
     "row 3: initial_current_A 10.0 -> 10.5 after 1 samples at time_s > 0 of the step "
     "starting at row 2"),
    # the hold voltage written on the rows before the step
    ("time_s,current_A,gap_m,initial_current_A,voltage_V\n-0.001,10,0.01,10,20\n"
     "0.001,11,0.01,10,40\n0.002,12,0.01,10,40\n0.003,12,0.01,10,40\n",
     "row 3: voltage_V 20.0 -> 40.0 after 0 samples at time_s > 0 of the step starting at row "
     "2: a step needs at least 3 with the same step, gap_m, initial_current_A, voltage_V and "
     "circuit (a change starts a new step; voltage_V is the voltage after the step, on the "
     "rows before it too)"),
])
def test_a_step_whose_fixed_columns_change_names_the_row_and_column(
        tmp_path: Path, text: str, needle: str) -> None:
    path = tmp_path / "s.csv"
    path.write_text(text)
    with pytest.raises(DataError) as info:
        read_steps(path)
    assert needle in str(info.value), str(info.value)
