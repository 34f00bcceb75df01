"""The main job: the Bouc-Wen study end to end.

Simulates training data with the library's own benchmark simulator, fits the
models, scores them on the test multisine (steady state) and the swept sine
(from rest), and writes figures plus a JSON and CSV summary to an output
folder; :func:`format_table` and :func:`format_grid` give the text the
command line (:mod:`sklearn_pnlss.app.cli`, ``python -m sklearn_pnlss``)
prints.
"""
import csv
import itertools
import json
import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from .. import DivergenceError
from ..metrics import rms_error
from ..statespace.fitting import iteration_listener

__all__ = ["MODELS", "format_grid", "format_table", "run_study"]

#: The models the study can fit, in the order they are fitted.
MODELS = ("bla", "pnlss", "pnlss_si", "decoupled")


class _Steps:
    """Progress over the study's stages (tqdm when available), with the
    Levenberg-Marquardt iterations of the fit under way: the bar moves
    inside long fits too, and stays on screen at the end."""

    def __init__(self, total, enabled):
        self._bar = None
        self._listening = ExitStack()
        self._drawn = 0.0
        if enabled:
            try:
                from tqdm.auto import tqdm

                self._bar = tqdm(total=total, unit="step")
            except ImportError:  # pragma: no cover - tqdm is optional
                self._bar = None
        if self._bar is not None:
            self._listening.enter_context(iteration_listener(self._iteration))

    def _iteration(self, iteration, cost_db):
        # Called from the fitting threads (parallel starts interleave);
        # redrawn at most twice a second, so that a log file does not fill
        # with one line per iteration.
        now = time.monotonic()
        if now - self._drawn >= 0.5:
            self._drawn = now
            self._bar.set_postfix_str(f"LM iteration {iteration}, cost {cost_db:.1f} dB", refresh=True)

    def counted(self, scorer, total, what):
        """``scorer`` that, each time it has scored one of ``total``
        candidates, says so on the bar (``what 3/8 done, -91.2 dB``): the
        progress of a grid search whose candidates take minutes each."""
        scored = itertools.count(1)

        def score(estimator, X, y):
            value = scorer(estimator, X, y)
            k = next(scored)
            if self._bar is not None:
                self._bar.set_description(f"{what} {k}/{total} done, {-value:.1f} dB")
            else:
                print(f"... {what} {k}/{total} done, {-value:.1f} dB", flush=True)
            return value

        return score

    def start(self, text):
        if self._bar is not None:
            self._bar.set_description(text)
            self._bar.set_postfix_str("")
        else:
            print(f"... {text}", flush=True)

    def done(self):
        if self._bar is not None:
            self._bar.update(1)

    def close(self):
        self._listening.close()
        if self._bar is not None:
            self._bar.set_description("done")
            self._bar.set_postfix_str("")
            self._bar.close()


TEST_SIGNALS = ("multisine", "sweep")


def _score_row(name, model, fit_time, data):
    """The results row of one model and its predictions of the test signals.
    A model that diverges on a test signal gets a row that says where, not a
    traceback: the table, the files and the other models' figures still come."""
    row = {"model": name, "n_params": int(model.n_params_), "fit_time_s": round(fit_time, 3)}
    preds, failures = {}, []
    for key in TEST_SIGNALS:
        X, y = data[f"X_test_{key}"], data[f"y_test_{key}"]
        try:
            preds[key] = model.predict(X)
        except DivergenceError as exc:
            row[f"{key}_rms_m"], row[f"{key}_db"] = None, None
            failures.append(f"{key} diverged at sample {exc.sample}")
            continue
        rms = rms_error(y, preds[key])
        row[f"{key}_rms_m"], row[f"{key}_db"] = rms, round(20 * np.log10(rms), 2)
    row["status"] = "; ".join(failures) or "ok"
    return row, preds


def _fit_models(names, data, *, grid, branch_basis, n_init, n_jobs, max_iter, steps):
    """Fit the requested models; the decoupled model starts from the
    states-and-input PNLSS (fitted here if not requested on its own), keeps
    the start best on the validation realisation, and, when ``grid`` holds
    several (branches, degree) candidates, is the candidate best on it.

    Returns ``{name: (model, fit_time)}`` and the grid rows (empty without a
    decoupled model)."""
    from .. import BLAEstimator, PNLSSRegressor

    P = data.period

    def iterations(default):
        return default if max_iter is None else max_iter

    make = {
        "bla": lambda: BLAEstimator(n_states=3, period=P, fs=data.fs),
        # Noel et al. 2017: states only, degrees 2-3, 64 parameters.
        "pnlss": lambda: PNLSSRegressor(3, degrees=(2, 3), variables="states", period=P, max_iter=iterations(40),
                                        linear_model=BLAEstimator(3, period=P, fs=data.fs)),
        # The seed paper's start: states and input, degrees 2-3, 90 nonlinear parameters.
        "pnlss_si": lambda: PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=P,
                                           max_iter=iterations(200), linear_model=BLAEstimator(3, period=P, fs=data.fs)),
    }
    fitted, grid_rows = {}, []
    for name in [n for n in MODELS if n in names or (n == "pnlss_si" and "decoupled" in names)]:
        if name == "decoupled":
            continue
        steps.start(f"fitting {name}")
        model, t0 = make[name](), time.perf_counter()
        model.fit(data.X_train, data.y_train)
        fitted[name] = (model, time.perf_counter() - t0)
        steps.done()
    if "decoupled" in names:
        start, start_time = fitted["pnlss_si"]
        model, fit_time, grid_rows = _select_decoupled(start, data, grid, branch_basis=branch_basis,
                                                       n_init=n_init, n_jobs=n_jobs,
                                                       max_iter=iterations(100), steps=steps)
        fitted["decoupled"] = (model, fit_time + start_time)
    return {name: fitted[name] for name in names}, grid_rows


def _select_decoupled(start, data, grid, *, branch_basis, n_init, n_jobs, max_iter, steps):
    """The decoupled model over the (branches, degree) grid, each candidate
    started from the fitted ``start`` and scored on the validation
    realisation: with several candidates, the library's own selection
    (``GridSearchCV`` on :func:`held_out_signals`), then the best refitted on
    the training signals; with one, that one.

    Returns the model, its fit time and one row per candidate."""
    from sklearn.base import clone
    from sklearn.frozen import FrozenEstimator
    from sklearn.model_selection import GridSearchCV
    from sklearn.pipeline import Pipeline

    from .. import DecoupledPNLSSRegressor
    from ..model_selection import held_out_signals, mean_rms_db_scorer, n_nonlinear_params_scorer

    # The fitted start is frozen: every candidate starts from it, none refits it.
    pipe = Pipeline([
        ("start", FrozenEstimator(start)),
        # The seed paper's pick is 3 branches of degree 10 (51 nonlinear parameters).
        ("decoupled", DecoupledPNLSSRegressor(3, period=data.period, branch_basis=branch_basis, n_init=n_init,
                                              n_jobs=n_jobs, max_iter=max_iter, random_state=0)),
    ])
    validation = {"decoupled__X_val": data.X_val, "decoupled__y_val": data.y_val}

    def refit(r, d):
        model = clone(pipe).set_params(decoupled__n_branches=r, decoupled__degree=d)
        t0 = time.perf_counter()
        try:
            model.fit(data.X_train, data.y_train, **validation)
        except ValueError:
            return None, time.perf_counter() - t0  # every start diverged
        return model[-1], time.perf_counter() - t0

    rows = []
    if len(grid) == 1:
        steps.start(f"fitting decoupled r={grid[0][0]} d={grid[0][1]}")
        model, fit_time = refit(*grid[0])
        rows.append(_grid_row(*grid[0], model, -np.min(model.init_scores_) if model is not None else np.nan,
                              fit_time))
        steps.done()
    else:
        steps.start(f"selecting the decoupled model over {len(grid)} candidates")
        X, y, cv = held_out_signals(data.X_train, data.y_train, data.X_val, data.y_val)
        param_grid = {"decoupled__n_branches": sorted({r for r, _ in grid}),
                      "decoupled__degree": sorted({d for _, d in grid})}
        n_candidates = len(param_grid["decoupled__n_branches"]) * len(param_grid["decoupled__degree"])
        search = GridSearchCV(
            pipe, param_grid,
            scoring={"db": steps.counted(mean_rms_db_scorer, n_candidates, "decoupled candidate"),
                     "n_nonlinear_params": n_nonlinear_params_scorer},
            cv=cv, refit=False, error_score=np.nan,
        ).fit(X, y, **validation)
        res = search.cv_results_
        for params, score, n_par, seconds in zip(res["params"], res["mean_test_db"],
                                                 res["mean_test_n_nonlinear_params"], res["mean_fit_time"]):
            rows.append(_grid_row(params["decoupled__n_branches"], params["decoupled__degree"],
                                  None if np.isnan(n_par) else int(n_par), score, seconds))
        steps.done()
        ok = [row for row in rows if row["validation_db"] is not None]
        if not ok:
            raise RuntimeError("Every decoupled candidate diverged; try more iterations or other branches/degrees.")
        best = min(ok, key=lambda row: row["validation_db"])
        steps.start(f"refitting decoupled r={best['n_branches']} d={best['degree']}")
        model, fit_time = refit(best["n_branches"], best["degree"])
        steps.done()
    if model is None:
        raise RuntimeError("Every start of the decoupled model diverged; try more iterations.")
    return model, fit_time, rows


def _grid_row(r, d, model_or_count, score, fit_time):
    """One candidate of the decoupled grid: its size, validation error in dB
    (None when it failed) and fit time."""
    count = getattr(model_or_count, "n_nonlinear_params_", model_or_count)
    failed = not np.isfinite(score)
    return {
        "n_branches": int(r), "degree": int(d),
        "n_nonlinear_params": None if failed or count is None else int(count),
        "validation_db": None if failed else round(-float(score), 2),
        "fit_time_s": round(float(fit_time), 3),
    }


def run_study(
    *,
    data_dir=None,
    output_dir="bouc_wen_results",
    models=MODELS,
    n_realizations=2,
    n_periods=2,
    rms=55.0,
    noise_rms=8e-6,
    random_state=0,
    branches=(3,),
    degrees=(10,),
    branch_basis="powers",
    n_init=5,
    max_iter=None,
    n_jobs=-1,
    save_models=False,
    plots=True,
    progress=True,
):
    """Run the Bouc-Wen study; return its summary and write it to
    ``output_dir`` as ``results.json`` and ``results.csv``, beside the
    figures.

    Parameters
    ----------
    data_dir : path or None, default=None
        Folder with the official benchmark files; when given, the models are
        scored on the official test multisine and sweep (training data are
        always simulated: the benchmark forbids training on test data).
    output_dir : path, default="bouc_wen_results"
        Where figures, ``results.json`` / ``results.csv`` (and the grid's
        ``grid.csv``, the saved models) are written.
    models : sequence of str, default=MODELS
        Models to fit, among ``MODELS``: ``"bla"``, ``"pnlss"`` (states only),
        ``"pnlss_si"`` (states and input), ``"decoupled"``.
    n_realizations, n_periods, rms, noise_rms, random_state
        Training data of :func:`sklearn_pnlss.datasets.make_bouc_wen`; one
        more realisation is simulated for validation (best iterate and start
        of the decoupled model, and its selection). The default 55 N rms is
        the seed paper's: a little above the 50 N of the official test
        multisine, so that the test's peaks stay inside the range the
        polynomials were fitted on. Without ``data_dir`` the simulated
        test multisine is drawn at ``rms`` too (the sweep is the
        benchmark's).
    branches, degrees : sequence of int, default=(3,) and (10,)
        The decoupled model's selection grid: every (branches, degree) pair
        is fitted and the one with the lowest validation error is kept. The
        default is the seed paper's pick alone.
    branch_basis : {"powers", "signed_powers"}, default="powers"
        The decoupled model's branch terms (see
        :class:`~sklearn_pnlss.DecoupledPNLSSRegressor`): the seed paper's
        powers, or the odd signed powers, which fit Bouc-Wen's hysteresis
        closer.
    n_init : int, default=5
        Starts of each decoupled model.
    max_iter : int or None, default=None
        Levenberg-Marquardt iterations of every nonlinear model; None: 40
        (``pnlss``), 200 (``pnlss_si``), 100 (``decoupled``).
    n_jobs : int or None, default=-1
        Threads for the simulation of the training data and the decoupled
        starts (-1: all cores; None: one). Results do not depend on it.
    save_models : bool, default=False
        Write every fitted model to ``<name>.joblib`` in ``output_dir``
        (:func:`sklearn_pnlss.persistence.save`).
    plots : bool, default=True
        Write figures (needs matplotlib).
    progress : bool, default=True
        Show a progress bar over the stages.

    Returns
    -------
    summary : dict
        ``training`` (the data settings), ``results`` (one row per model:
        parameters, fit time, rms error in m and dB on each test signal),
        ``models`` (each model's :meth:`summary`), ``grid`` (the decoupled
        candidates), with the BLA its modes and distortion levels, and
        ``files``: the names of the files written to ``output_dir``.
    """
    from ..datasets import load_bouc_wen_official, make_bouc_wen

    unknown = sorted(set(models) - set(MODELS))
    if unknown:
        raise ValueError(f"Unknown model(s) {unknown}; choose among {list(MODELS)}.")
    grid = [(int(r), int(d)) for r in branches for d in degrees]
    if "decoupled" in models and not grid:
        raise ValueError("The decoupled model needs at least one value in branches and in degrees.")
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    n_fits = len([m for m in models if m != "decoupled"]) + ("decoupled" in models) * (
        (1 if len(grid) == 1 else 2) + ("pnlss_si" not in models))
    steps = _Steps(2 + n_fits + bool(data_dir) + bool(plots) + bool(save_models), progress)
    t0 = time.perf_counter()
    steps.start("simulating Bouc-Wen training data")
    data = make_bouc_wen(
        n_realizations=n_realizations + 1, n_periods=n_periods, rms=rms,
        noise_rms=noise_rms, random_state=random_state, n_jobs=n_jobs,
    )
    # The last realisation is for validation only (its last period: steady state).
    data["X_val"], data["y_val"] = data.X_train[-1:, -data.period :], data.y_train[-1:, -data.period :]
    data["X_train"], data["y_train"] = data.X_train[:-1], data.y_train[:-1]
    t_sim = time.perf_counter() - t0
    steps.done()
    test_source = "simulated"
    if data_dir:
        steps.start("loading official test data")
        official = load_bouc_wen_official(data_dir)
        for key in ("X_test_multisine", "y_test_multisine", "X_test_sweep", "y_test_sweep"):
            data[key] = official[key]
        test_source = "official"
        steps.done()
    fitted, grid_rows = _fit_models(models, data, grid=grid, branch_basis=branch_basis, n_init=n_init,
                                    n_jobs=n_jobs, max_iter=max_iter, steps=steps)
    steps.start("scoring on the test multisine and sweep")
    rows, preds = [], {}
    for name, (model, fit_time) in fitted.items():
        row, preds[name] = _score_row(name, model, fit_time, data)
        row["test_data"] = test_source
        rows.append(row)
    steps.done()
    # The names of the files written, in order: the command line reports
    # these, not a fixed list (no figures with plots=False, no grid.csv
    # without a decoupled model, ...).
    written = []
    if plots:
        steps.start("drawing figures")
        written += _figures(out, data, fitted, preds, grid_rows)
        steps.done()
    if save_models:
        from ..persistence import save

        steps.start("saving the models")
        for name, (model, _) in fitted.items():
            save(model, out / f"{name}.joblib")
            written.append(f"{name}.joblib")
        steps.done()
    steps.close()
    summary = {
        "training": {
            "n_realizations": n_realizations, "n_periods": n_periods, "rms_N": rms,
            "noise_rms_m": noise_rms, "random_state": random_state,
            "simulation_time_s": round(t_sim, 2),
        },
        "results": rows,
        "models": {name: model.summary().to_dict() for name, (model, _) in fitted.items()},
    }
    if grid_rows:
        summary["grid"] = grid_rows
        with open(out / "grid.csv", "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(grid_rows[0]))
            writer.writeheader()
            writer.writerows(grid_rows)
        written.append("grid.csv")
    if "bla" in fitted:
        bla = fitted["bla"][0]
        summary["bla"] = {
            "natural_frequencies_hz": bla.natural_frequencies_.tolist(),
            "damping_ratios": bla.damping_ratios_.tolist(),
            "distortion_levels_db": bla.distortion_levels_,
        }
    summary["files"] = ["results.json", "results.csv", *written]
    (out / "results.json").write_text(json.dumps(summary, indent=2, default=_json_default))
    with open(out / "results.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return summary


def _json_default(value):
    """NaN-free JSON for numpy scalars (``json`` does not know them)."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _figures(out, data, fitted, preds, grid_rows):
    """Draw the figures into ``out``; return the names of the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import plot_bla, plot_branches, plot_error_spectra, plot_grid_search, plot_time_errors

    written = []
    if "bla" in fitted:
        ax = plot_bla(fitted["bla"][0])
        ax.figure.savefig(out / "bla_frf.png", dpi=120, bbox_inches="tight")
        written.append("bla_frf.png")
        plt.close(ax.figure)
    ax = plot_error_spectra(
        data.y_test_multisine[0, :, 0], {k: v["multisine"][0, :, 0] for k, v in preds.items() if "multisine" in v},
        data.fs,
    )
    ax.set_title("Test multisine: output and simulation-error spectra")
    ax.figure.savefig(out / "error_spectra_multisine.png", dpi=120, bbox_inches="tight")
    written.append("error_spectra_multisine.png")
    plt.close(ax.figure)
    ax = plot_time_errors(
        data.y_test_sweep[0, :, 0], {k: v["sweep"][0, :, 0] for k, v in preds.items() if "sweep" in v}, data.fs
    )
    ax.set_title("Swept sine: simulation error over time")
    ax.figure.savefig(out / "error_time_sweep.png", dpi=120, bbox_inches="tight")
    written.append("error_time_sweep.png")
    plt.close(ax.figure)
    if "decoupled" in fitted:
        axes = plot_branches(fitted["decoupled"][0], data.X_test_multisine)
        axes[0].figure.suptitle("Decoupled model: branches, and their values on the test multisine")
        axes[0].figure.savefig(out / "decoupled_branches.png", dpi=120, bbox_inches="tight")
        written.append("decoupled_branches.png")
        plt.close(axes[0].figure)
    if len(grid_rows) > 1:
        ok = [row for row in grid_rows if row["validation_db"] is not None]
        results = {
            "param_n_branches": np.array([row["n_branches"] for row in ok], dtype=object),
            "param_degree": np.array([row["degree"] for row in ok], dtype=object),
            "mean_test_score": np.array([-row["validation_db"] for row in ok]),
            "mean_test_n_nonlinear_params": np.array([row["n_nonlinear_params"] for row in ok]),
        }
        fig, (ax_d, ax_n) = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
        plot_grid_search(results, "degree", group="n_branches", ax=ax_d)
        plot_grid_search(results, "n_nonlinear_params", group="n_branches", ax=ax_n)
        ax_d.set_ylabel("validation rms error (dB)")
        ax_n.set_ylabel("")
        fig.suptitle("Decoupled model selection")
        fig.savefig(out / "decoupled_grid.png", dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append("decoupled_grid.png")
    return written


def format_table(summary):
    """The results table as text; a model that diverged on a test signal
    says where instead of its error."""
    head = f"{'model':<11}{'params':>8}{'fit (s)':>10}{'multisine rms (m)':>20}{'dB':>9}{'sweep rms (m)':>16}{'dB':>9}"
    lines = [head, "-" * len(head)]
    for r in summary["results"]:
        cells = []
        for key, width in (("multisine", 20), ("sweep", 16)):
            if r[f"{key}_rms_m"] is None:
                cells.append(f"{'diverged':>{width}}{'-':>9}")
            else:
                cells.append(f"{r[f'{key}_rms_m']:>{width}.3e}{r[f'{key}_db']:>9.2f}")
        line = f"{r['model']:<11}{r['n_params']:>8}{r['fit_time_s']:>10.2f}" + "".join(cells)
        lines.append(line + (f"  ({r['status']})" if r.get("status", "ok") != "ok" else ""))
    return "\n".join(lines)


def format_grid(summary):
    """The decoupled candidates as text, the selected one marked."""
    rows = summary.get("grid", [])
    if len(rows) < 2:
        return ""
    best = min((r for r in rows if r["validation_db"] is not None), key=lambda r: r["validation_db"])
    lines = [f"{'branches':>9}{'degree':>8}{'nonlinear params':>18}{'validation dB':>15}", "-" * 50]
    for r in rows:
        val = f"{r['validation_db']:.2f}" if r["validation_db"] is not None else "diverged"
        n_par = r["n_nonlinear_params"] if r["n_nonlinear_params"] is not None else "-"
        mark = "  <- selected" if r is best else ""
        lines.append(f"{r['n_branches']:>9}{r['degree']:>8}{n_par:>18}{val:>15}{mark}")
    return "\n".join(lines)

