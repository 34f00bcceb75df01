"""The deep LRU network of LRUAboveBandRegressor: exact gradients, exact
periodic steady state, stable recursions, and a map that explains the
response above the band of a knocking system on a record it never saw."""
import copy

import numpy as np
import pytest
from scipy.signal import lfilter
from sklearn.base import clone

from sklearn_pnlss import AveragedRegressor, BLAEstimator, DecoupledPNLSSRegressor, LRUAboveBandRegressor
from sklearn_pnlss.estimators._lru import LRUNetwork, Workspace, batch_loss, one_cycle
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
    """Trained on two records, the network takes most of the error above
    the band off a third record (the linear model's NRMSE there 0.0121,
    with the network 0.0043; 0.0078 without the gate, which the force's
    content above the band then reaches when the output does not rattle);
    the recursions stay stable; the band is left to the linear model (but
    for the edges of a record from rest, where the network's output, kept
    above the cutoff over the record padded with zeros, leaks a little into
    it)."""
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
    assert after < 0.45 * before
    ungated = clone(model).set_params(gate=False).fit([u1, u2], [y1, y2])
    assert after < 0.7 * nrmse_by_band(y_new, ungated.predict(u_new), fs=1.0, edges=above)[0, 0]
    in_band = (0.0, 0.1)
    np.testing.assert_allclose(nrmse_by_band(y_new, model.predict(u_new), fs=1.0, edges=in_band),
                               nrmse_by_band(y_new, alone.predict(u_new), fs=1.0, edges=in_band), rtol=2e-3)
    for k in range(model.n_layers):
        assert np.abs(model.networks_[0].eigenvalues(k)).max() < 1.0
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


@pytest.mark.parametrize("single", [False, True])
def test_a_workspace_changes_no_bit(single):
    """Forward and backward through a workspace kept over iterations and
    batches of two shapes give the same outputs and gradients, bit for
    bit, as through new arrays (a fit's losses are reproducible whatever
    the workspace held before)."""
    rng = np.random.default_rng(6)
    net = LRUNetwork(3, 2, width=4, n_layers=2, n_modes=5, rng=rng, single=single)
    work = Workspace()
    for periodic, x in [(True, rng.standard_normal((2, 30, 3))), (False, rng.standard_normal((3, 50, 3)))] * 2:
        kept = net.forward(x, periodic, keep=True, work=work)
        grads = net.backward(kept, work)
        new = net.forward(x, periodic, keep=True)
        assert np.array_equal(kept, new)
        for name, g in net.backward(new).items():
            assert np.array_equal(grads[name], g), name


@pytest.mark.parametrize("with_floor", [False, True])
def test_the_loss_gradient_matches_finite_differences(with_floor):
    rng = np.random.default_rng(5)
    error, weights = rng.standard_normal((2, 30, 3)), rng.uniform(0.1, 1.0, (2, 30, 3)) / 30
    floor = rng.uniform(0.01, 0.1, (2, 3)) if with_floor else None
    _, grad = batch_loss(error, weights, floor)
    step = np.zeros_like(error)
    for index in [(0, 0, 0), (1, 7, 2), (0, 29, 1)]:
        step[index] = 1e-6
        numeric = (batch_loss(error + step, weights, floor)[0] - batch_loss(error - step, weights, floor)[0]) / 2e-6
        step[index] = 0.0
        assert numeric == pytest.approx(grad[index], rel=1e-5, abs=1e-9)


def test_the_nrmse_loss_is_the_mean_nrmse_of_the_simulation():
    """With loss="nrmse" the training loss is what the field scores: the
    mean over the training signals of the NRMSE of the whole simulation
    (the linear model's error in the band, the network's above it), here
    at the last iteration, whose step is too small to change it."""
    rng = np.random.default_rng(6)
    (u1, y1), (u2, y2) = knocking_record(rng, 4096, 1024), knocking_record(rng, 4096, 1024)
    model = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0, period=1024), cutoff=0.1, width=8, n_layers=1,
                                  n_modes=8, max_iter=30, random_state=0).fit([u1, u2], [y1, y2])

    def nrmse(u, y):  # of the periods' mean, as the fit takes a periodic signal
        y_mean = y.reshape(4, 1024).mean(axis=0)
        return np.sqrt(np.mean((model.predict(u)[:1024, 0] - y_mean) ** 2) / np.mean(y_mean**2))

    scored = np.mean([nrmse(u1, y1), nrmse(u2, y2)])
    assert model.loss_curve_[-1] == pytest.approx(scored, rel=1e-3)
    squared = model.set_params(loss="squared").fit([u1, u2], [y1, y2])
    assert squared.loss_curve_[-1] < 0.05 * scored  # the NRMSE squared above the band only


def test_the_gate_shuts_the_force_above_the_band_at_small_motion():
    """The force's content above the band reaches the network through the
    gate: on a record too small to rattle, a sliver of what a record of
    the training amplitude passes."""
    rng = np.random.default_rng(7)
    u, y = knocking_record(rng)
    model = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, width=4, n_layers=1, n_modes=4, max_iter=2,
                                  random_state=0).fit(u, y)
    u_new, _ = knocking_record(rng)

    def passed(u):  # the gated force's rms over the force's rms above the band
        view = model._view(u)[0]
        return np.sqrt(np.mean(view[:, 1] ** 2) / np.mean(fast(u[:, 0], 0.1) ** 2))

    assert passed(0.3 * u_new) < 0.1 * passed(u_new)
    assert model.n_map_params_ == model.networks_[0].n_params + model.gate_coef_.size == model.networks_[0].n_params + 4
    ungated = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, width=4, n_layers=1, n_modes=4, max_iter=2,
                                    gate=False, random_state=0).fit(u, y)
    assert not hasattr(ungated, "gate_coef_") and ungated.n_map_params_ == ungated.networks_[0].n_params


def test_an_averaged_model_gates_with_its_members_states_side_by_side():
    rng = np.random.default_rng(8)
    (u1, y1), (u2, y2) = knocking_record(rng), knocking_record(rng)
    members = DecoupledPNLSSRegressor(2, n_branches=1, degree=3, init="random", n_init=1, max_iter=3)
    averaged = AveragedRegressor(members, n_estimators=2, random_state=0)
    model = LRUAboveBandRegressor(averaged, cutoff=0.1, width=4, n_layers=1, n_modes=4, max_iter=2,
                                  random_state=0).fit([u1, u2], [y1, y2])
    assert model.state_scale_.shape == (4,) and model.gate_coef_.shape == (1 + 4 * 5 // 2,)
    assert model.n_params_ == sum(m.n_params_ for m in model.regressor_.estimators_) + model.n_map_params_
    _, prediction, _ = model._view(u1)
    np.testing.assert_allclose(prediction, model.regressor_.predict(u1))


def test_several_networks_are_averaged_and_reproducible_whatever_n_jobs():
    """``n_networks`` networks: the first is the one network's of the same
    ``random_state``, the prediction their mean, and fitting two in worker
    processes gives the same networks as fitting them here."""
    rng = np.random.default_rng(9)
    (u1, y1), (u2, y2), (u_new, _) = (knocking_record(rng) for _ in range(3))
    settings = dict(cutoff=0.1, width=4, n_layers=1, n_modes=4, max_iter=20, segment_length=2048, burn_in=128,
                    random_state=0)
    one = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), **settings).fit([u1, u2], [y1, y2])
    here = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), n_networks=2, **settings).fit([u1, u2], [y1, y2])
    workers = clone(here).set_params(n_jobs=2).fit([u1, u2], [y1, y2])
    for name, value in one.networks_[0].params.items():
        np.testing.assert_array_equal(here.networks_[0].params[name], value)
        assert not np.allclose(here.networks_[1].params[name], value) or name.startswith("ln_")
        for k in range(2):
            np.testing.assert_array_equal(workers.networks_[k].params[name], here.networks_[k].params[name])
    assert here.n_map_params_ == 2 * one.networks_[0].n_params + one.gate_coef_.size
    second = copy.copy(one)  # the first fit with the second network alone
    second.networks_ = here.networks_[1:]
    alone = one.regressor_.predict(u_new)
    np.testing.assert_allclose(here.predict(u_new) - alone,
                               0.5 * (one.predict(u_new) - alone + second.predict(u_new) - alone), atol=1e-9)  # float32
