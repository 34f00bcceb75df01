"""The diagnosis report: verdict, ranking, where the gap lies, figures."""
from dataclasses import asdict

import numpy as np

from .verdict.decision import percent
from .settings import SETTINGS

__all__ = ["GapReport"]


def _plain(x):
    """JSON-ready copy: arrays to lists, numpy scalars to floats."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items() if k != "samples"}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, (np.integer, np.bool_)):
        return x.item()
    return x


def _number(x, digits=2, width=0):
    """``x`` to ``digits`` decimals without a minus sign on a zero
    (``-0.00``), ``diverged`` for the infinite error of a simulation that
    diverged."""
    if not np.isfinite(x):
        text = "diverged"
    else:
        text = f"{x:.{digits}f}"
        if float(text) == 0:
            text = text.lstrip("-")
    return f"{text:>{width}}"


def _percent(fraction, width=0):
    """A closure in whole percent, ``-0`` shown as ``0``; ``-`` when it
    diverged."""
    text = "-" if not np.isfinite(fraction) else f"{round(100 * fraction):d}%"
    return f"{text:>{width}}"


class GapReport:
    """What :meth:`GapDiagnosis.report` finds on validation signals.

    Attributes
    ----------
    best_effect : str or None
        The effect that explains the gap; ``"recalibration"`` when refitting
        the nominal parameters suffices, ``None`` when there is no
        significant gap, ``"unexplained"`` when no candidate explains it.
    significant : bool
        Whether the nominal simulator's gap exceeds the noise floor.
    ranking : list of RankedEffect
        Every candidate, best closure first: name, fitted parameters,
        validation gap before and after (dB), shrink (dB), closure ratio.
    gap_db, noise_floor_db : float
        Validation gap of the nominal simulator and the noise floor, dB.
    noise_source : str or None
        Which estimate set the noise floor (``"periods"``,
        ``"repeated_inputs"``, ``"non_excited_lines"``,
        ``"black_box_residual"``; None: no floor), see
        :mod:`sklearn_pnlss.gap.verdict.noise_floor`.
    noise_detail : str
        What that estimate was read from, in a sentence.
    black_box : dict or None
        The decoupled PNLSS yardstick: its validation gap and closure, and
        the reading of each branch (``branches``).
    where : GapLocation or None
        Frequency, amplitude, state-plane and time analyses (see
        :func:`sklearn_pnlss.gap.where.locate_gap` and
        :mod:`sklearn_pnlss.gap.results`).
    main_effect : str or None
        The best candidate (or the one preferred within the noise), named
        also when it leaves part of the gap unexplained.
    added_effects : list of str
        Effects added to the main one by forward selection, each because
        it closes more of the gap on validation (see
        :func:`sklearn_pnlss.gap.stages.added_effects`).
    reason : str
        One sentence behind the verdict.
    unsettled_signals : list of int
        Training signals left out because they never settled (their
        periods differ far more than the others'), see
        :func:`~sklearn_pnlss.gap.verdict.noise_floor.unsettled_signals`.
    """

    def __init__(self, *, decision, where, scales, noise, black_box, fits, opinions=None, unsettled=()):
        self.decision = decision
        self.where = where
        self.scales = scales
        self.noise = noise
        self.fits = fits
        self.best_effect = decision.best_effect
        self.significant = decision.significant
        self.explained = decision.explained
        self.p_value = decision.p_value
        self.ranking = decision.ranking
        self.gap_db = decision.gap_before_db
        self.noise_floor_db = decision.noise_floor_db
        self.noise_source = decision.noise_source
        self.noise_detail = decision.noise_detail
        self.reason = decision.reason
        self.main_effect = decision.main_effect
        self.added_effects = list(decision.added_names)
        self.unsettled_signals = list(unsettled)
        self.black_box = None
        if black_box is not None:
            self.black_box = dict(gap_after_db=decision.black_box_gap_db,
                                  closure=decision.black_box_closure,
                                  n_params=int(black_box.n_params_), branches=opinions or [])

    # ------------------------------------------------------------------
    def to_dict(self):
        """Everything in the report as plain JSON-ready types."""
        return _plain(dict(
            best_effect=self.best_effect, main_effect=self.main_effect, added_effects=self.added_effects,
            significant=self.significant, explained=self.explained,
            p_value=self.p_value, reason=self.reason, gap_db=self.gap_db,
            per_signal_gap_db=self.decision.per_signal_before_db, noise_floor_db=self.noise_floor_db,
            noise_source=self.noise_source, noise_detail=self.noise_detail,
            sensitive_signals=self.decision.sensitive_signals, unsettled_signals=self.unsettled_signals,
            recalibrated=self.decision.recalibrated,
            ranking=[r.to_dict() for r in self.ranking], black_box=self.black_box,
            where=None if self.where is None else asdict(self.where),
        ))

    def __str__(self):
        lines = ["Sim-to-real gap diagnosis", "=" * 25]
        verdict = {None: "no significant gap", "unexplained": "gap not explained by any candidate"}
        added = f", with {', '.join(self.added_effects)} added" if self.added_effects and self.explained else ""
        lines.append(f"verdict: {verdict.get(self.best_effect, self.best_effect)}{added}{self.recalibration_text()}")
        lines.append(f"  {self.reason}")
        if np.isfinite(self.noise_floor_db):
            lines.append(f"nominal gap {self.gap_db:.2f} dB, noise floor {self.noise_floor_db:.2f} dB"
                         + (f", p = {self.p_value:.2g}" if np.isfinite(self.p_value) else ""))
        else:
            lines.append(f"nominal gap {self.gap_db:.2f} dB, no noise floor")
        # Which estimate set the floor, hence the verdict.
        lines.append(f"  noise: {self.noise_detail}")
        if self.decision.sensitive_signals:
            which = ", ".join(str(i) for i in self.decision.sensitive_signals)
            lines.append(f"  validation signal {which} left out: the best candidate's parameters, moved within "
                         f"what the training data determine (their standard errors), move its simulation "
                         f"above the noise (a chaotic response or a jump); no simulator can follow it sample "
                         f"by sample")
        if self.unsettled_signals:
            which = ", ".join(str(i) for i in self.unsettled_signals)
            lines.append(f"  training signal {which} left out: periods that differ far more than the quietest "
                         f"signal's (never settled: a chaotic response, or a record started too early)")
        if self.black_box is not None:
            head = f"black box (decoupled PNLSS, {self.black_box['n_params']} parameters): "
            if np.isfinite(self.black_box["gap_after_db"]):
                lines.append(head + f"{_number(self.black_box['gap_after_db'])} dB, closure "
                             f"{percent(self.black_box['closure'])}")
            else:  # its simulation of a validation signal ran away
                lines.append(head + "diverged on a validation signal (no yardstick)")
            for i, b in enumerate(self.black_box["branches"]):
                lines.append(f"  branch {i + 1}: {b['reading']}")
        lines.append("")
        rows = self.ranking + self.decision.added_effects
        width = max([22] + [len(r.name) + 2 for r in rows])
        lines.append(f"{'candidate':<{width}}{'params':>7}{'after dB':>10}{'shrink dB':>11}{'closure':>9}")
        for r in rows:
            shrink = _number(r.shrink_db, width=11) if np.isfinite(r.gap_after_db) else f"{'-':>11}"
            lines.append(f"{r.name:<{width}}{r.n_params:>7}{_number(r.gap_after_db, width=10)}{shrink}"
                         f"{_percent(r.closure, width=9)}")
        best = next((r for r in self.ranking if r.name == self.best_effect), None)
        if best is not None and self.decision.added_effects and self.explained:
            best = self.decision.added_effects[-1]
        if best is not None:
            params = ", ".join(f"{k} = {v:.4g}" for k, v in best.params.items())
            lines.append(f"\n{best.name}: {params}")
        freq = None if self.where is None else self.where.frequency
        if freq is not None:
            lines.append("\nwhere in frequency (validation, periodic signals):")
            # The band figures are sums over their lines, not per line: a
            # band's gap and noise compare with each other, not with the
            # nominal gap above (a mean square per sample).
            lines.append("  dB of the power summed over each band's lines (|X_k|^2 / N per line, one period)")
            lines.append(f"  {'band Hz':<16}{'gap dB':>9}{'noise dB':>10}{'significant lines':>19}")
            for b in freq.bands:
                lines.append(f"  {b.f_lo:6.1f}-{b.f_hi:<8.1f}{_number(b.gap_db, 1, 9)}"
                             f"{_number(b.noise_db, 1, 10)}"
                             f"{b.n_significant:>10d} / {b.n_lines}")
            if freq.detection_lines:
                for k, v in freq.line_kinds.items():
                    lines.append(f"  {k}: {v.n_significant} of {v.n_lines} lines significant")
        drift = None if self.where is None else self.where.time.drift
        if drift is not None:
            lines.append(f"\nperiod-to-period change of the training response: "
                         f"{_number(drift.change_vs_noise_db[-1], 1)} dB over noise"
                         + (" (drifting)" if drift.drifting else ""))
        return "\n".join(lines)

    def recalibration_text(self):
        """How far the chosen effect's fit moved the freed nominal
        parameters, e.g. ``", with stiffness recalibrated by -8 %"``
        (changes under half a percent are not named)."""
        moved = {k: v for k, v in self.decision.recalibrated.items()
                 if k != "delay_s" and abs(v) >= SETTINGS.recalibration_shown}
        parts = [f"{name} by {100 * v:+.0f} %" if abs(v) >= 0.01 else f"{name} by {100 * v:+.1f} %"
                 for name, v in moved.items()]
        if parts:
            parts[0] = parts[0].replace(" by", " recalibrated by")
        if "delay_s" in self.decision.recalibrated:  # the measurement chain's, fitted with the effect
            parts.append(f"a channel delay of {1e3 * self.decision.recalibrated['delay_s']:.3g} ms")
        return ", with " + ", ".join(parts) if parts else ""

    def __repr__(self):
        return f"GapReport(best_effect={self.best_effect!r}, gap_db={self.gap_db:.2f})"

    # ------------------------------------------------------------------
    def plot(self, fig=None):
        """Figures of the report: ranking, gap spectrum, amplitude, missing
        force map, gap over time, black-box branches.

        Returns
        -------
        fig : matplotlib Figure
        """
        import matplotlib.pyplot as plt

        if fig is None:
            fig = plt.figure(figsize=(15, 9))
        axes = fig.subplots(2, 3).ravel()
        self._plot_ranking(axes[0])
        self._plot_frequency(axes[1])
        self._plot_amplitude(axes[2])
        self._plot_force_map(fig, axes[3])
        self._plot_time(axes[4])
        self._plot_branches(axes[5])
        fig.suptitle(f"Gap diagnosis: {self.best_effect}")
        fig.tight_layout()
        return fig

    def _plot_ranking(self, ax):
        names = [r.name for r in self.ranking]
        after = [r.gap_after_db for r in self.ranking]
        ax.barh(names, after, color=["C2" if n == self.best_effect else "C0" for n in names])
        ax.axvline(self.gap_db, color="C3", label="nominal")
        if np.isfinite(self.noise_floor_db):
            ax.axvline(self.noise_floor_db, color="k", ls="--", label="noise floor")
        if self.black_box is not None and np.isfinite(self.black_box["gap_after_db"]):
            ax.axvline(self.black_box["gap_after_db"], color="C1", ls=":", label="black box")
        finite = [a for a in after if np.isfinite(a)] + [self.gap_db]
        ax.set_xlim(min(finite + [self.noise_floor_db if np.isfinite(self.noise_floor_db) else self.gap_db]) - 3,
                    self.gap_db + 3)
        ax.invert_yaxis()
        ax.set_xlabel("validation gap (dB)")
        ax.legend(fontsize="small")
        ax.set_title("candidates")

    def _plot_frequency(self, ax):
        freq = self.where.frequency
        ax.set_title("gap spectrum")
        if freq is None:
            ax.text(0.5, 0.5, "no periodic validation signal", ha="center", transform=ax.transAxes)
            return
        f = freq.frequency
        ax.plot(f, 10 * np.log10(np.maximum(freq.gap_power, 1e-300)), ".", ms=2, label="gap")
        sig = freq.significant
        ax.plot(f[sig], 10 * np.log10(freq.gap_power[sig]), "o", mfc="none", ms=3, label="significant")
        ax.plot(f, 10 * np.log10(np.maximum(freq.noise_power, 1e-300)), "k", lw=0.8, label="noise")
        if freq.distortion_power is not None:
            d = freq.distortion_power
            m = d > 0
            ax.plot(f[m], 10 * np.log10(d[m]), ".", ms=2, color="C3", label="NL distortion")
        ax.set_xlim(0, freq.bands[-1].f_hi)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("dB")
        ax.legend(fontsize="small")

    def _plot_amplitude(self, ax):
        amp = self.where.amplitude
        for name, level in (("displacement", amp.displacement), ("velocity", amp.velocity)):
            x = np.arange(len(level.bins)) + 0.5
            ax.plot(x, [r.gap_db for r in level.bins], "o-", label=name)
        if amp.displacement.noise_db is not None:
            ax.axhline(amp.displacement.noise_db, color="k", ls="--", label="noise")
        ax.set_xlabel("level bin (quantiles of |.|)")
        ax.set_ylabel("gap (dB)")
        ax.set_title("gap against amplitude")
        ax.legend(fontsize="small")

    def _plot_force_map(self, fig, ax):
        m = self.where.state_plane
        mesh = ax.pcolormesh(m.displacement_edges, m.velocity_edges, m.force.T, cmap="RdBu_r",
                             shading="flat")
        fig.colorbar(mesh, ax=ax, label="missing force (N)")
        ax.set_xlabel("displacement (m)")
        ax.set_ylabel("velocity (m/s)")
        ax.set_title("missing force map")

    def _plot_time(self, ax):
        t = self.where.time
        if t.sweeps:
            w = t.sweeps[0].windows
            ax.plot([r.frequency for r in w], [r.gap_db for r in w], "o-", label="gap")
            ax.plot([r.frequency for r in w], [r.output_db for r in w], "-", color="0.6", label="output")
            ax.set_xlabel("instantaneous frequency of the sweep (Hz)")
            ax.set_title("gap along the sweep")
        elif t.drift is not None:
            ch = t.drift.change_vs_noise_db
            ax.plot(np.arange(1, len(ch) + 1), ch, "o-")
            ax.set_xlabel("period")
            ax.set_title("change from the first period over noise")
        else:
            ax.text(0.5, 0.5, "no sweep or multi-period signal", ha="center", transform=ax.transAxes)
        ax.set_ylabel("dB")
        if t.sweeps:
            ax.legend(fontsize="small")

    def _plot_branches(self, ax):
        ax.set_title("black-box branches")
        if self.black_box is None or not self.black_box["branches"]:
            ax.text(0.5, 0.5, "no black box", ha="center", transform=ax.transAxes)
            return
        for i, b in enumerate(self.black_box["branches"]):
            ax.plot(b["z"], b["g"], label=f"{i + 1}: {b['label']}")
        ax.set_xlabel("branch input z")
        ax.set_ylabel("g(z)")
        ax.legend(fontsize="x-small")
