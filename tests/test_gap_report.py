"""The printed gap report (sklearn_pnlss.gap.report): what an engineer
reads once must say what it means.  Built on decisions of chosen numbers."""
from types import SimpleNamespace

import numpy as np

from sklearn_pnlss.gap.fitting.calibrate import EffectFit
from sklearn_pnlss.gap.verdict.decision import decide, percent
from gap_signals import stub_effect
from sklearn_pnlss.gap.verdict.noise_floor import NoiseFloor
from sklearn_pnlss.gap.report import GapReport
from sklearn_pnlss.gap.results import Band

S2 = 1e-12
SIZE = 10_000
NOISE = NoiseFloor(S2, np.full(513, S2), 1.0, source="periods",
                   detail="spread over the periods of 2 training signals (4 periods)")


def _fit(name):
    effect = stub_effect(name)
    return EffectFit(effect, np.zeros(1), {"p": 1.5}, train_mse=S2, n_evaluations=1, converged=True, message="")


def _report(candidates, black_box=None, noise=NOISE, where=None):
    """A report of one signal with a nominal gap of -80 dB, 40 dB above the floor;
    ``candidates``: name -> mean square (None: diverged); ``black_box``:
    its mean square (None: diverged), or no black box when absent."""
    def sim(mse):
        return None if mse is None else [np.full(SIZE, np.sqrt(mse))]

    fits = [_fit(n) for n in candidates]
    y_bb = None if black_box is False else [None if black_box is None else np.full(SIZE, np.sqrt(black_box))]
    d = decide(fits, [np.zeros(SIZE)], [np.full(SIZE, 1e-4)], [sim(m) for m in candidates.values()], y_bb,
               noise, 1e-3)
    bb = None if black_box is False else SimpleNamespace(n_params_=58)
    return GapReport(decision=d, where=where, scales=None, noise=noise, black_box=bb, fits=fits)


def test_a_diverged_black_box_says_diverged():
    text = str(_report({"c": 10 * S2}, black_box=None))
    assert "black box (decoupled PNLSS, 58 parameters): diverged on a validation signal (no yardstick)" in text
    assert "inf" not in text
    text = str(_report({"c": 10**2 * S2}, black_box=None))  # leaves 20 of the 40 dB
    assert "closes only 50 % of the gap; the black box diverged" in text


def test_a_diverged_candidate_says_diverged_in_the_ranking():
    lines = str(_report({"ok": S2, "runaway": None}, black_box=False)).splitlines()
    row = next(line for line in lines if line.startswith("runaway"))
    assert row.split() == ["runaway", "1", "diverged", "-", "-"]
    assert "inf" not in "\n".join(lines)


def test_no_minus_zero():
    """A candidate that makes the gap 0.004 dB worse closes -0.01 %:
    printed 0 % and a shrink of 0.00 dB, not -0 % and -0.00."""
    worse = 1e-8 * 10 ** (0.004 / 10)
    text = str(_report({"ok": S2, "nothing": worse}, black_box=1e-8 * 10 ** (-0.001 / 10)))
    row = next(line for line in text.splitlines() if line.startswith("nothing"))
    assert row.split()[-2:] == ["0.00", "0%"], row
    assert "-0 %" not in text and "-0%" not in text and "-0.00" not in text
    assert "closure 0 %" in text  # the black box line
    assert percent(-0.004) == "0 %" and percent(-np.inf) == "diverged"


def test_the_noise_estimate_is_named():
    text = str(_report({"c": S2}, black_box=False))
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("nominal gap"))
    assert lines[i] == "nominal gap -80.00 dB, noise floor -120.00 dB, p = 0"
    assert lines[i + 1] == "  noise: spread over the periods of 2 training signals (4 periods)"
    estimated = NoiseFloor(S2, np.full(513, S2), 1.0, source="non_excited_lines", upper_bound=True,
                           detail="residual of the c model at the 616 DFT lines the input does not excite")
    report = _report({"c": S2}, black_box=False, noise=estimated)
    assert "  noise: residual of the c model at the 616 DFT lines" in str(report)
    assert report.to_dict()["noise_source"] == "non_excited_lines"
    text = str(_report({"c": S2}, black_box=False, noise=None))
    assert "nominal gap -80.00 dB, no noise floor" in text and "nan" not in text


def test_the_band_table_says_its_figures_are_sums():
    band = Band(f_lo=0.0, f_hi=37.5, gap_db=-20.6, noise_db=-82.3, distortion_db=None, n_lines=102, n_significant=102)
    where = SimpleNamespace(frequency=SimpleNamespace(bands=[band], detection_lines=False, line_kinds={}),
                            time=SimpleNamespace(drift=None))
    lines = str(_report({"c": S2}, black_box=False, where=where)).splitlines()
    i = lines.index("where in frequency (validation, periodic signals):")
    assert lines[i + 1] == "  dB of the power summed over each band's lines (|X_k|^2 / N per line, one period)"
    assert lines[i + 2].split() == ["band", "Hz", "gap", "dB", "noise", "dB", "significant", "lines"]
    assert lines[i + 3].split() == ["0.0-37.5", "-20.6", "-82.3", "102", "/", "102"]
