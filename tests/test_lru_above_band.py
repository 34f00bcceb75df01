"""The deep LRU network of LRUAboveBandRegressor: exact gradients, exact
periodic steady state, stable recursions, and a map that explains the
response above the band of a knocking system on a record it never saw."""
import numpy as np
import pytest
from scipy.signal import lfilter

from sklearn_pnlss import BLAEstimator, LRUAboveBandRegressor
from sklearn_pnlss.estimators._lru import LRUNetwork, one_cycle
from sklearn_pnlss.metrics import nrmse_by_band


def small_network(seed=0):
    return LRUNetwork(3, 2, width=4, n_layers=2, n_modes=5, rng=np.random.default_rng(seed), r_min=0.5, r_max=0.95,
                      single=False)


@pytest.mark.parametrize("periodic", [False, True])
def test_gradients_match_finite_differences(periodic):
    """Every parameter's gradient (a complex one's real and imaginary
    parts), from rest and in periodic steady state, equals the central
    difference of the loss."""
    rng = np.random.default_rng(1)
    net = small_network()
    x, target = rng.standard_normal((40, 3)), rng.standard_normal((40, 2))

    def loss():
        return 0.5 * np.sum((net.forward(x, periodic) - target) ** 2)

    grads = net.backward(net.forward(x, periodic, keep=True) - target)
    checked = 0
    for name, value in net.params.items():
        flat = value.reshape(-1)
        for i in range(min(flat.size, 4)):
            for part in ([1.0, 1j] if np.iscomplexobj(value) else [1.0]):
                old = flat[i]
                flat[i] = old + 1e-6 * part
                up = loss()
                flat[i] = old - 1e-6 * part
                down = loss()
                flat[i] = old
                numeric = (up - down) / 2e-6
                analytic = grads[name].reshape(-1)[i]
                analytic = analytic.real if part == 1.0 else analytic.imag
                assert abs(numeric - analytic) <= 1e-5 * max(1.0, abs(numeric)), (name, i, part)
                checked += 1
    assert checked > 80


def test_one_period_circular_is_the_periodic_steady_state():
    """The network in steady state over one period equals its response to
    that period repeated from rest, once the transient has died out."""
    rng = np.random.default_rng(2)
    net = small_network()
    period = rng.standard_normal((64, 3))
    circular = net.forward(period, True)
    repeated = np.tile(period, (60, 1))  # radii at most 0.95: 0.95**3000 is nothing
    from_rest = net.forward(repeated, False)
    np.testing.assert_allclose(from_rest[-64:], circular, atol=1e-10)
    assert np.abs(from_rest[:64] - circular).max() > 1e-3  # the start from rest differs


def test_one_cycle_schedule():
    lrs, betas = map(np.array, zip(*one_cycle(100, 1e-2)))
    assert lrs[0] == pytest.approx(1e-2 / 25) and lrs.max() == pytest.approx(1e-2)
    assert np.argmax(lrs) == 10 and lrs[-1] == pytest.approx(1e-2 / 25 / 1e4)
    assert betas[0] == pytest.approx(0.95) and betas[10] == pytest.approx(0.85) and betas[-1] == pytest.approx(0.95)


def fast(u, cutoff):
    U = np.fft.rfft(u)
    U[np.fft.rfftfreq(u.size) <= cutoff] = 0
    return np.fft.irfft(U, u.size)


def knocking_record(rng, n=4096, period=None):
    """A slow force with some fast content; past twice its variance the
    output rattles, the force's fast content ringing a fast mode."""
    u = lfilter([0.1], [1, -0.9], rng.standard_normal(n)) + 0.05 * rng.standard_normal(n)
    if period is not None:
        u = np.tile(u[:period], n // period)
    y = lfilter([0.0, 0.1], [1, -0.9], u)
    knock = np.maximum(y**2 - 2 * np.var(y), 0) * fast(u, 0.1)
    return u[:, None], (y + lfilter([0.0, 1.0], [1, 0.5], knock))[:, None]


def test_explains_the_rattle_on_a_new_record():
    """Trained on two records, the network takes half the power above the
    band off a third record's error (the linear model's NRMSE there 0.0121,
    with the network 0.0083); the recursions stay stable; the band is left
    to the linear model (but for the edges of a record from rest, where the
    network's output, kept above the cutoff over the record padded with
    zeros, leaks a little into it)."""
    rng = np.random.default_rng(0)
    (u1, y1), (u2, y2), (u_new, y_new) = (knocking_record(rng) for _ in range(3))
    model = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, width=8, n_layers=2, n_modes=16,
                                  max_iter=200, segment_length=2048, burn_in=128, random_state=0)
    model.fit([u1, u2], [y1, y2])
    alone = model.regressor_
    above = (0.1, 0.51)
    before = nrmse_by_band(y_new, alone.predict(u_new), fs=1.0, edges=above)[0, 0]
    after = nrmse_by_band(y_new, model.predict(u_new), fs=1.0, edges=above)[0, 0]
    assert before == pytest.approx(0.0121, abs=5e-4)
    assert after < 0.75 * before
    in_band = (0.0, 0.1)
    np.testing.assert_allclose(nrmse_by_band(y_new, model.predict(u_new), fs=1.0, edges=in_band),
                               nrmse_by_band(y_new, alone.predict(u_new), fs=1.0, edges=in_band), rtol=2e-3)
    for k in range(model.n_layers):
        assert np.abs(model.network_.eigenvalues(k)).max() < 1.0
    assert model.loss_curve_.shape == (200,) and model.explained_fraction_[0] > 0.5
    assert model.n_params_ == model.regressor_.n_params_ + model.n_map_params_


def test_periodic_signals_in_steady_state():
    """A signal of whole periods is predicted period by period alike (the
    network's own steady state), one from rest is not."""
    rng = np.random.default_rng(3)
    u, y = knocking_record(rng, n=4096, period=1024)
    model = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0, period=1024), cutoff=0.1, width=4, n_layers=1,
                                  n_modes=4, max_iter=5, random_state=0).fit(u, y)
    pred = model.predict(u).reshape(4, 1024)
    np.testing.assert_allclose(pred[0], pred[3], atol=1e-12)
    from_rest = model.predict(u[:4000])
    assert np.abs(from_rest[:1024, 0] - pred[0]).max() > 1e-6


@pytest.mark.parametrize("cutoff, message", [(None, "cutoff: pass"), (0.5, "Nyquist")])
def test_bad_cutoff(cutoff, message):
    u, y = knocking_record(np.random.default_rng(0), n=512)
    with pytest.raises(ValueError, match=message):
        LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=cutoff, max_iter=1).fit(u, y)


def test_a_batch_is_its_sequences_one_by_one():
    """Sequences stacked go through as each alone would, forward and
    backward (the gradients add up)."""
    rng = np.random.default_rng(4)
    net = small_network()
    x = rng.standard_normal((3, 20, 3))
    for periodic in (False, True):
        batch = net.forward(x, periodic, keep=True)
        together = net.backward(batch)
        alone = [net.forward(s, periodic) for s in x]
        np.testing.assert_allclose(batch, np.stack(alone), atol=1e-12)
        summed = {}
        for s in x:
            g = net.backward(net.forward(s, periodic, keep=True))
            summed = {k: summed.get(k, 0) + v for k, v in g.items()}
        for k in together:
            np.testing.assert_allclose(together[k], summed[k], atol=1e-10)
