"""The main job writes its table, summary files and figures."""
import json
import re
from pathlib import Path

import pytest

from sklearn_pnlss.app.cli import main
from sklearn_pnlss.app.study import format_table, run_study


def test_study_writes_results_and_figures(tmp_path):
    summary = run_study(output_dir=tmp_path, models=("bla", "pnlss"), progress=False)
    row, pnlss = summary["results"]
    assert row["model"] == "bla" and row["n_params"] == 16
    # Trained at 55 N (the seed paper's level), tested at 50 N: the BLA,
    # an amplitude-dependent linearisation, is about 1 dB off its 50 N level.
    assert row["multisine_db"] < -74 and row["sweep_db"] < -74
    # Measured -88.3 / -97.2 dB on the simulated test multisine and the sweep.
    assert pnlss["n_params"] == 64 and pnlss["multisine_db"] < -87.5 and pnlss["sweep_db"] < -96.5
    saved = json.loads((tmp_path / "results.json").read_text())
    assert saved["results"][0]["multisine_db"] == row["multisine_db"]
    assert (tmp_path / "results.csv").read_text().startswith("model,")
    for name in ("bla_frf.png", "error_spectra_multisine.png", "error_time_sweep.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    assert "bla" in format_table(summary)


def test_help_documents_the_options(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    for option in ("--data-dir", "--output-dir", "--models", "--n-realizations", "--branches", "--degrees",
                   "--n-init", "--max-iter", "--n-jobs", "--save-models", "--no-progress", "--gap-demo"):
        assert option in text


def test_decoupled_grid_selects_on_validation_and_saves_models(tmp_path, capsys):
    """A tiny grid: every candidate is reported, the one with the lowest
    validation error is kept, and the saved models load back."""
    from sklearn_pnlss.persistence import load

    code = main([
        "--models", "decoupled", "--branches", "1", "2", "--degrees", "3", "--n-init", "1",
        "--max-iter", "3", "--n-realizations", "1", "--n-jobs", "2", "--save-models",
        "--no-progress", "--output-dir", str(tmp_path),
    ])
    assert code == 0
    printed = capsys.readouterr().out
    assert "<- selected" in printed and "decoupled" in printed
    assert "... decoupled candidate 2/2 done, " in printed  # the grid's progress
    summary = json.loads((tmp_path / "results.json").read_text())
    grid = summary["grid"]
    assert [(row["n_branches"], row["degree"]) for row in grid] == [(1, 3), (2, 3)]
    assert [row["n_nonlinear_params"] for row in grid] == [(2 * 3 + 1 + 3) * r for r in (1, 2)]
    best = min(grid, key=lambda row: row["validation_db"])
    (row,) = summary["results"]
    assert row["model"] == "decoupled" and row["n_params"] == 16 + best["n_nonlinear_params"]
    model = summary["models"]["decoupled"]
    assert model["n_nonlinear_params"] == best["n_nonlinear_params"] and model["fs"] == 750.0
    assert (tmp_path / "grid.csv").read_text().splitlines()[0].startswith("n_branches,degree")
    for name in ("decoupled_grid.png", "decoupled_branches.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    decoupled = load(tmp_path / "decoupled.joblib")
    assert decoupled.n_params_ == row["n_params"]
    assert (decoupled.n_branches, decoupled.degree) == (best["n_branches"], best["degree"])


def test_closing_line_names_the_files_written(tmp_path, capsys):
    """With --no-plots the job writes no figure, and its last line says so
    (it used to announce "figures and results.json/results.csv" whatever it
    wrote)."""
    assert main(["--models", "bla", "--no-plots", "--no-progress", "--output-dir", str(tmp_path)]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == f"wrote results.json, results.csv in {tmp_path.resolve()}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv", "results.json"]
    assert json.loads((tmp_path / "results.json").read_text())["files"] == ["results.json", "results.csv"]


def test_unknown_model_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="Unknown model"):
        run_study(output_dir=tmp_path, models=("bla", "arx"), progress=False, plots=False)


def test_gap_demo_finds_the_missing_hysteresis(tmp_path, capsys):
    assert main(["--gap-demo", "--output-dir", str(tmp_path), "--no-plots"]) == 0
    out = capsys.readouterr().out
    assert "verdict: hysteresis" in out
    saved = json.loads((tmp_path / "gap_report.json").read_text())
    assert saved["best_effect"] == "hysteresis"
    # the Bouc-Wen benchmark's alpha, recovered
    assert saved["ranking"][0]["params"]["alpha"] == pytest.approx(5e4, rel=0.01)
    assert (tmp_path / "gap_report.txt").exists()
    assert out.rstrip().endswith(f"wrote gap_report.json, gap_report.txt in {tmp_path.resolve()}")
    _gap_guide_shows_this_report(out, saved)


_GAP_GUIDE = Path(__file__).resolve().parents[1] / "docs" / "user_guide" / "gap.rst"
_NUMBER = re.compile(r"(?:(?<![\w)\]])[-−])?(?<![\w.])\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def _same_to_printed_precision(want, got):
    """The same text, and numbers equal to the precision ``want`` prints
    them at, within one unit of its last digit."""
    if _NUMBER.split(want) != _NUMBER.split(got):
        return False
    for a, b in zip(_NUMBER.findall(want), _NUMBER.findall(got)):
        digits = len(a.split("e")[0].split(".")[1]) if "." in a.split("e")[0] else 0
        if abs(float(a.replace("−", "-")) - float(b)) > 10.0 ** -digits + 1e-12:
            return False
    return True


def _gap_guide_shows_this_report(printed, saved):
    """docs/user_guide/gap.rst, "Reading a report", shows the demo's report
    and reads figures from it: they are the ones this run prints."""
    guide = _GAP_GUIDE.read_text()
    section = guide[guide.index("Reading a report"):guide.index("Accuracy and cost")]
    block = section[section.index("::\n\n") + 3:]
    shown = [line[4:] for line in block.splitlines()[1:]]
    shown = shown[:shown.index("...")]
    lines = printed[printed.index("Sim-to-real gap diagnosis\n"):].splitlines()
    assert len(lines) >= len(shown)
    for want, got in zip(shown, lines):
        assert _same_to_printed_precision(want, got), f"gap.rst shows {want!r}, the demo prints {got!r}"
    # The prose under the report.
    ranking = {row["name"]: row for row in saved["ranking"]}
    p = ranking["hysteresis"]["params"]
    products = {"alpha": p["alpha"], "beta*gamma": p["beta_gamma"], "beta*delta": p["beta_delta"]}
    prose = " ".join(section.split())
    assert f"\\alpha = {products['alpha'] / 1e4:.3f} \\cdot 10^4" in prose
    assert f"\\beta\\gamma = {products['beta*gamma']:.0f}` and :math:`\\beta\\delta = {products['beta*delta']:.0f}`" in prose
    assert f"closes only {100 * ranking['recalibration']['closure']:.0f} % of the gap" in prose
    assert f"and the black box {100 * saved['black_box']['closure']:.0f} %" in prose
    # "the Bouc-Wen parameters of the demo below to within 0.1 %" (How a candidate is fitted)
    truth = {"alpha": 5e4, "beta*gamma": 800.0, "beta*delta": -1100.0}
    assert "the Bouc-Wen parameters of the demo below to within 0.1 %" in " ".join(guide.split())
    assert all(abs(products[k] / truth[k] - 1) < 1e-3 for k in truth), products


def test_the_library_never_imports_the_app():
    """sklearn_pnlss.app is an application of the library: no library module
    imports it, at the top or inside a function (only ``__main__``, the
    ``python -m sklearn_pnlss`` shim, does)."""
    import ast
    from pathlib import Path

    import sklearn_pnlss

    root = Path(sklearn_pnlss.__file__).parent
    offenders = []
    for path in root.rglob("*.py"):
        rel = path.relative_to(root)
        if rel.parts[0] == "app" or rel == Path("__main__.py"):
            continue
        # The module's package, to resolve relative imports.
        package = ["sklearn_pnlss", *rel.parent.parts]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = package[: len(package) - node.level + 1] if node.level else []
                module = ".".join(base + ([node.module] if node.module else []))
                names = [module] + [f"{module}.{alias.name}" for alias in node.names]
            else:
                continue
            if any(name == "sklearn_pnlss.app" or name.startswith("sklearn_pnlss.app.") for name in names):
                offenders.append(f"{rel}:{node.lineno}")
    assert not offenders, offenders


def test_grid_candidates_are_counted_as_they_are_scored(capsys):
    """The main job's grid search says each candidate as it is scored (issue
    18: progress inside long fits, grid candidates included)."""
    from sklearn_pnlss.app.study import _Steps

    steps = _Steps(1, enabled=False)
    score = steps.counted(lambda estimator, X, y: 91.25, 2, "decoupled candidate")
    assert score(None, None, None) == 91.25 and score(None, None, None) == 91.25
    steps.close()
    assert capsys.readouterr().out.splitlines() == ["... decoupled candidate 1/2 done, -91.2 dB",
                                                    "... decoupled candidate 2/2 done, -91.2 dB"]
