"""Peak memory of PNLSS and decoupled fits on a large training set.

10 realisations x 10 periods x 8192 samples of the Bouc-Wen benchmark
(819 200 samples). The Levenberg-Marquardt normal equations are accumulated
segment by segment, so only one segment's Jacobian is ever held; with the
periods averaged (the default) a segment is one period. Each fit runs in a
fresh interpreter and reports its peak resident memory (``ru_maxrss``).

    python benchmarks/bench_memory.py [--iterations 5] [--output FILE]

Results go to ``benchmarks/results/memory.json``.
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "memory.json"

_RUN = """
import json, resource, sys, time
import numpy as np
from sklearn_pnlss import DecoupledPNLSSRegressor, PNLSSRegressor
from sklearn_pnlss.datasets import make_bouc_wen
case, iterations = sys.argv[1], int(sys.argv[2])
data = make_bouc_wen(n_realizations=10, n_periods=10, random_state=0, n_jobs=2)
after_data = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
P = data.period
if case == "pnlss_averaged":
    est = PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", period=P, max_iter=iterations)
elif case == "pnlss_all_periods":
    est = PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", period=P, max_iter=iterations, average_periods=False)
else:
    est = DecoupledPNLSSRegressor(3, n_branches=3, degree=10, period=P, n_init=2, n_jobs=2, max_iter=iterations,
                                  start_model=PNLSSRegressor(3, variables="states_inputs", period=P, max_iter=iterations))
t0 = time.perf_counter()
est.fit(data.X_train, data.y_train)
print(json.dumps({"case": case, "n_samples": int(data.X_train.size), "n_params": int(est.n_params_),
                  "fit_s": time.perf_counter() - t0, "peak_rss_after_data_mb": after_data,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--iterations", type=int, default=5)
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)
    results = header()
    results["cases"] = []
    for case in ("pnlss_averaged", "pnlss_all_periods", "decoupled"):
        out = subprocess.run([sys.executable, "-c", _RUN, case, str(args.iterations)], check=True,
                             capture_output=True, text=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        results["cases"].append(row)
        print(f"  {row['case']:18s} {row['n_samples']} samples, {row['n_params']} parameters: peak {row['peak_rss_mb']:.0f} MB "
              f"(data alone {row['peak_rss_after_data_mb']:.0f} MB), fit {row['fit_s']:.1f} s", flush=True)
    write_results(results, args.output)


if __name__ == "__main__":
    main()
