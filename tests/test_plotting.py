"""Figures render headless and carry the data they claim to show."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

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
