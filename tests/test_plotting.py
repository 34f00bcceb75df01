"""Figures render headless and carry the data they claim to show."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from sklearn_pnlss import BLAEstimator  # noqa: E402
from sklearn_pnlss.plotting import plot_error_spectra, plot_hysteresis, plot_time_errors  # noqa: E402
from sklearn_pnlss.signals import multisine  # noqa: E402


def _fitted():
    X, _ = multisine(256, fs=100.0, f_band=(1, 40), n_periods=2, n_realizations=2, random_state=0)
    y = np.roll(X, 1, axis=1) * 0.5 + 0.01 * X**3
    y = y + 1e-3 * np.random.default_rng(0).standard_normal(y.shape)
    return BLAEstimator(n_states=2, period=256, fs=100.0).fit(X, y), X, y


def test_plot_bla_draws_frf_and_levels():
    model, _, _ = _fitted()
    ax = model.plot()
    labels = [line.get_label() for line in ax.get_lines()]
    assert "BLA (nonparametric)" in labels and "noise std" in labels
    bla = ax.get_lines()[0]
    np.testing.assert_allclose(bla.get_xdata(), model.frequencies_)
    np.testing.assert_allclose(bla.get_ydata(), 20 * np.log10(np.abs(model.frf_[:, 0, 0])))
    plt.close(ax.figure)


def test_error_and_time_plots_contain_the_errors():
    model, X, y = _fitted()
    pred = model.predict(X[0])
    ax = plot_error_spectra(y[0, :256, 0], {"bla": pred[:256, 0]}, fs=100.0)
    assert len(ax.get_lines()) == 2
    plt.close(ax.figure)
    ax = plot_time_errors(y[0, :, 0], {"bla": pred[:, 0]}, fs=100.0)
    np.testing.assert_allclose(ax.get_lines()[1].get_ydata(), y[0, :, 0] - pred[:, 0])
    plt.close(ax.figure)
    ax = plot_hysteresis(X[0], y[0])
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), y[0, :, 0])
    plt.close(ax.figure)


def test_error_spectra_hold_the_spectra_in_db():
    model, X, y = _fitted()
    pred = model.predict(X[0])[:256, 0]
    out = y[0, :256, 0]
    ax = plot_error_spectra(out, {"bla": pred}, fs=100.0)
    output_line, error_line = ax.get_lines()
    np.testing.assert_allclose(output_line.get_xdata(), np.fft.rfftfreq(256, 1 / 100.0))
    expected = 20 * np.log10(np.abs(np.fft.rfft(out - pred)) / np.sqrt(256))
    np.testing.assert_allclose(error_line.get_ydata(), expected, atol=1e-9)
    assert error_line.get_label() == "bla error"
    plt.close(ax.figure)


def test_branches_show_the_curve_and_the_evaluated_points(small_pipeline, small_data):
    from sklearn_pnlss.plotting import plot_branches

    dec = small_pipeline[-1]
    axes = plot_branches(dec, small_data.X_val)
    assert len(axes) == dec.n_branches == 1
    points, curve = axes[0].get_lines()
    z_grid, g_grid = dec.branch_values()
    np.testing.assert_allclose(curve.get_xdata(), z_grid[:, 0])
    np.testing.assert_allclose(curve.get_ydata(), g_grid[:, 0])
    z_eval = dec.branch_inputs(small_data.X_val)[0, :, 0]
    np.testing.assert_allclose(points.get_xdata(), z_eval)
    np.testing.assert_allclose(points.get_ydata(), dec.branch_values(z_eval)[1][:, 0])
    plt.close(axes[0].figure)
    # Without signals: the curves alone, on the caller's axes.
    fig, ax = plt.subplots()
    (drawn,) = plot_branches(dec, axes=[ax])
    assert drawn is ax and len(ax.get_lines()) == 1
    plt.close(fig)


def test_branch_inputs_span_the_training_range(small_pipeline, small_data):
    dec = small_pipeline[-1]
    z = np.concatenate(dec.branch_inputs(small_data.X))
    np.testing.assert_allclose(z.min(axis=0), dec.z_range_[:, 0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(z.max(axis=0), dec.z_range_[:, 1], rtol=1e-9, atol=1e-12)


def test_grid_search_map_draws_one_line_per_group_sorted_by_x():
    from sklearn_pnlss.plotting import plot_grid_search

    # As GridSearchCV lays out cv_results_: degrees varying fastest, one NaN (a failed fit).
    branches = np.ma.masked_array([1, 1, 1, 2, 2, 2], dtype=object)
    degrees = np.ma.masked_array([7, 3, 5, 3, 5, 7], dtype=object)
    scores = np.array([80.0, 82.0, 81.0, 90.0, np.nan, 95.0])
    n_params = np.array([14.0, 10.0, 12.0, 20.0, 24.0, 28.0])
    results = {"param_dec__n_branches": branches, "param_dec__degree": degrees,
               "mean_test_db": scores, "mean_test_n_nonlinear_params": n_params}
    ax = plot_grid_search(results, "dec__degree", group="dec__n_branches", score="db")
    one, two = ax.get_lines()
    np.testing.assert_array_equal(one.get_xdata(), [3, 5, 7])
    np.testing.assert_array_equal(one.get_ydata(), [-82.0, -81.0, -80.0])
    np.testing.assert_array_equal(two.get_ydata(), [-90.0, np.nan, -95.0])
    assert [line.get_label() for line in (one, two)] == ["n_branches = 1", "n_branches = 2"]
    np.testing.assert_array_equal(ax.get_xticks(), [3, 5, 7])
    assert ax.get_xlabel() == "degree" and "dB" in ax.get_ylabel()
    plt.close(ax.figure)
    # Against the parameter count recorded as a second metric.
    ax = plot_grid_search(results, "n_nonlinear_params", group="dec__n_branches", score="db")
    np.testing.assert_array_equal(ax.get_lines()[1].get_xdata(), [20.0, 24.0, 28.0])
    assert ax.get_xlabel() == "number of nonlinear params"
    plt.close(ax.figure)


def test_grid_search_map_names_what_is_missing():
    from sklearn_pnlss.plotting import plot_grid_search

    results = {"param_degree": np.array([3, 5], dtype=object), "mean_test_score": np.array([1.0, 2.0])}
    with pytest.raises(KeyError, match="mean_test_db"):
        plot_grid_search(results, "degree", score="db")
    with pytest.raises(KeyError, match="parameters: \\['degree'\\]"):
        plot_grid_search(results, "branches")


def test_grid_search_map_takes_a_fitted_search(small_data):
    from sklearn.model_selection import GridSearchCV

    from sklearn_pnlss import BLAEstimator
    from sklearn_pnlss.model_selection import held_out_signals, mean_rms_db_scorer
    from sklearn_pnlss.plotting import plot_grid_search

    X, y, cv = held_out_signals(small_data.X, small_data.y, small_data.X_val, small_data.y_val)
    search = GridSearchCV(BLAEstimator(period=small_data.period), {"n_states": [1, 2, 3]}, cv=cv,
                          scoring=mean_rms_db_scorer, refit=False).fit(X, y)
    ax = plot_grid_search(search, "n_states")
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), -search.cv_results_["mean_test_score"])
    plt.close(ax.figure)


def test_hysteresis_loops_overlay_with_labels():
    _, X, y = _fitted()
    ax = plot_hysteresis(X[0], y[0], label="system")
    plot_hysteresis(X[0], 0.9 * y[0], ax=ax, label="model")
    system, model = ax.get_lines()
    np.testing.assert_allclose(system.get_ydata(), X[0, :, 0])
    np.testing.assert_allclose(model.get_xdata(), 0.9 * y[0, :, 0])
    assert (system.get_label(), model.get_label()) == ("system", "model")
    plt.close(ax.figure)


def test_level_modes_show_each_modes_shift_and_damping_against_the_level():
    from sklearn_pnlss.level_modes import LevelModes
    from sklearn_pnlss.plotting import plot_level_modes

    modes = LevelModes(np.array([1.0, 2.0, 3.0]), np.array([[10.0, 20.0], [9.9, 20.0], [9.8, 19.8]]),
                       np.array([[0.01, 0.02], [0.015, 0.02], [0.02, 0.03]]),
                       np.array([[10.0, 20.0], [9.95, 20.1], [9.8, 19.8]]),
                       np.array([[0.01, 0.02], [0.012, 0.02], [0.02, 0.03]]))
    shift, damping = plot_level_modes(modes)
    measured, model = shift.get_lines()[:2]
    np.testing.assert_allclose(measured.get_xdata(), [1.0, 2.0, 3.0])
    np.testing.assert_allclose(measured.get_ydata(), [0.0, -1.0, -2.0])
    np.testing.assert_allclose(model.get_ydata(), [0.0, -0.5, -2.0])
    np.testing.assert_allclose(damping.get_lines()[1].get_ydata(), [1.0, 1.2, 2.0])
    assert len(damping.get_lines()) == 4 and model.get_label() == "10 (model)"
    plt.close(shift.figure)
    # Measured modes only, on the caller's axes.
    fig, axes = plt.subplots(1, 2)
    drawn = plot_level_modes(LevelModes(modes.input_rms, modes.frequencies, modes.damping), axes=axes)
    assert drawn[0] is axes[0] and len(axes[1].get_lines()) == 2
    with pytest.raises(ValueError, match="two Axes"):
        plot_level_modes(modes, axes=axes[:1])
    plt.close(fig)
