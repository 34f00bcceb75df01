"""The command line ``python -m sklearn_pnlss``: the Bouc-Wen study
(:func:`~sklearn_pnlss.app.study.run_study`) or, with ``--gap-demo``, the
diagnosis demo (:func:`~sklearn_pnlss.app.gap_demo.run_gap_demo`); ``--help``
lists the options."""
import argparse
import math
from pathlib import Path

from .study import MODELS, format_grid, format_table, run_study

__all__ = ["main"]


def main(argv=None):
    """Command-line entry point (``python -m sklearn_pnlss``)."""
    parser = argparse.ArgumentParser(
        prog="python -m sklearn_pnlss",
        description=(
            "Bouc-Wen hysteresis benchmark, end to end: simulate training data "
            "with the library's simulator, fit the models (BLA, full PNLSS, "
            "decoupled PNLSS selected over a grid of branches and degrees), "
            "score them on the test multisine and swept sine, and write figures, "
            "results.json and results.csv (and grid.csv, the saved models) to "
            "the output folder."
        ),
        epilog="Example: python -m sklearn_pnlss --models bla decoupled --branches 2 3 --degrees 6 10 --n-jobs 2",
    )
    data = parser.add_argument_group("data")
    data.add_argument("--data-dir", help="folder with the official benchmark .mat files; test on them instead of "
                      "simulated test data (training data are always simulated)")
    data.add_argument("--n-realizations", type=int, default=2, help="training multisine realisations (default: %(default)s)")
    data.add_argument("--n-periods", type=int, default=2, help="steady-state periods per realisation (default: %(default)s)")
    data.add_argument("--rms", type=float, default=55.0, help="training input rms in N (default: %(default)s, the seed paper's)")
    data.add_argument("--noise-rms", type=float, default=8e-6, help="output noise rms in m (default: %(default)s)")
    data.add_argument("--random-state", type=int, default=0, help="seed of the training data (default: %(default)s)")
    fit = parser.add_argument_group("models")
    fit.add_argument("--models", nargs="+", choices=MODELS, default=list(MODELS),
                     help="models to fit: bla, pnlss (states only), pnlss_si (states and input), decoupled "
                     "(default: all)")
    fit.add_argument("--branches", type=int, nargs="+", default=[3], metavar="R",
                     help="decoupled model: numbers of branches to try (default: %(default)s)")
    fit.add_argument("--degrees", type=int, nargs="+", default=[10], metavar="D",
                     help="decoupled model: branch degrees to try; the grid is every (R, D) pair, the one "
                     "best on the validation realisation is kept (default: %(default)s)")
    fit.add_argument("--branch-basis", choices=["powers", "signed_powers"], default="powers",
                     help="decoupled model: branch terms, z**k or the odd signed powers z|z|**(k-1) "
                     "(default: %(default)s)")
    fit.add_argument("--n-init", type=int, default=5, help="starts of each decoupled model (default: %(default)s)")
    fit.add_argument("--max-iter", type=int, default=None,
                     help="Levenberg-Marquardt iterations of every nonlinear model (default: 40 pnlss, "
                     "200 pnlss_si, 100 decoupled)")
    fit.add_argument("--n-jobs", type=int, default=-1,
                     help="threads for the simulation and the decoupled starts; -1: all cores (default: %(default)s)")
    output = parser.add_argument_group("output")
    output.add_argument("--output-dir", default="bouc_wen_results",
                        help="where figures and results.json/csv go (default: %(default)s)")
    output.add_argument("--save-models", action="store_true",
                        help="also write each fitted model to <model>.joblib (load with sklearn_pnlss.persistence.load)")
    output.add_argument("--no-plots", action="store_true", help="skip the figures")
    output.add_argument("--no-progress", action="store_true", help="no progress bar")
    gap = parser.add_argument_group("sim-to-real gap diagnosis")
    gap.add_argument("--gap-demo", action="store_true",
                     help="run the diagnosis demo instead of the study: a mass-spring-damper simulator "
                          "against Bouc-Wen data (it finds the missing hysteresis); writes gap_report.json, "
                          ".txt and .png to the output folder")
    args = parser.parse_args(argv)
    if args.gap_demo:
        from .gap_demo import run_gap_demo

        report, seconds = run_gap_demo(args.output_dir, n_jobs=2 if args.n_jobs in (-1, None) else args.n_jobs,
                                       random_state=args.random_state, plot=not args.no_plots,
                                       progress=not args.no_progress)
        print(report)
        # run_gap_demo writes the figure only with plot=True.
        files = ["gap_report.json", "gap_report.txt"] + ([] if args.no_plots else ["gap_report.png"])
        print(f"\ndiagnosis in {seconds:.1f} s; {_wrote(files, args.output_dir)}")
        return 0
    summary = run_study(
        data_dir=args.data_dir, output_dir=args.output_dir, models=args.models,
        n_realizations=args.n_realizations, n_periods=args.n_periods, rms=args.rms,
        noise_rms=args.noise_rms, random_state=args.random_state,
        branches=args.branches, degrees=args.degrees, branch_basis=args.branch_basis, n_init=args.n_init,
        max_iter=args.max_iter,
        n_jobs=args.n_jobs, save_models=args.save_models,
        plots=not args.no_plots, progress=not args.no_progress,
    )
    print(format_table(summary))
    grid = format_grid(summary)
    if grid:
        print("\nDecoupled model selection (validation realisation):")
        print(grid)
    if "bla" in summary:
        print(_bla_poles(summary["bla"]["natural_frequencies_hz"], summary["bla"]["damping_ratios"]))
    print(_wrote(summary["files"], args.output_dir))
    return 0


def _bla_poles(frequencies, damping):
    """The BLA's poles in words: its modes (complex pairs) by frequency
    and damping, its real poles by time constant, which a damping of 100 %
    would pass off as a mode."""
    modes = [f"{f:.2f} Hz ({100 * z:.2f} % damping)" for f, z in zip(frequencies, damping) if z < 1 - 1e-9]
    real = [f"time constant {1e3 / (2 * math.pi * f):.1f} ms" if f > 0 else "an integrator"
            for f, z in zip(frequencies, damping) if z >= 1 - 1e-9]
    line = "BLA modes: " + (", ".join(modes) or "none")
    return line + (f"; real poles: {', '.join(real)}" if real else "")


def _wrote(files, folder):
    """The closing line: the files actually written, and where."""
    return f"wrote {', '.join(files)} in {Path(folder).resolve()}"
