"""The small data the gap-diagnosis tests share: a structure driven by two
multisine realisations for training and, for validation, a third
realisation's period and a sweep from rest (1024-sample periods at 750 Hz,
integrated at ten times the rate)."""
import numpy as np

from sklearn_pnlss.gap.fitting.simulate import SignalSet, simulate_signals
from sklearn_pnlss.signals import linear_chirp, multisine

FS, N = 750.0, 1024


def gap_data(real, seed=0, n_periods=2, noise=2e-6, transform=None):
    """``(u_train, y_train, u_val, y_val)`` of ``real`` (an Oscillator),
    with band-limited output noise of rms ``noise`` and an optional input
    transform (a delay, a saturation) applied at the integration rate."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=n_periods, n_realizations=3,
                     random_state=seed)
    sweep = linear_chirp(np.arange(3000) / FS, f_start=15.0, rate=8.0, amplitude=10.0)
    train = SignalSet.from_signals([x[:, 0] for x in X[:2]], N, FS, 10)
    val = SignalSet.from_signals([X[2, :N, 0], sweep], N, FS, 10)
    rng = np.random.RandomState(seed)
    y_train = simulate_signals(real, train, transform, noise_rms=noise, random_state=rng)
    y_val = simulate_signals(real, val, transform, noise_rms=noise, random_state=rng)
    return train.u, y_train, val.u, y_val


def stub_effect(name, n_params=1, recalibration=False):
    """An effect as the verdict sees it (its name and parameter count;
    nothing to build), for tests of the decision and the report."""
    from sklearn_pnlss.gap import Effect
    attributes = dict(name=name, param_names=tuple(f"p{i}" for i in range(n_params)),
                      limits=((-1.0, 1.0),) * n_params, listed_starts=((0.0,) * n_params,),
                      is_recalibration=recalibration)
    return type("Stub", (Effect,), attributes)()
