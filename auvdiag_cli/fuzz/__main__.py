"""``python -m auvdiag_cli.fuzz``: a seeded fuzzing campaign over every log format.

Prints one line per seed log (cases, read, rejected, defects, slowest case, peak memory)
and writes every count and every defect case (seed log, case number, mutations, what
happened) as JSON. A defect is reproduced with ``--seed-log``/``--first-case``/``--cases 1``.
Exit status 0 when no case is a defect, 1 otherwise."""

import argparse
import json
import os
import sys
import time
from pathlib import Path


def _arguments(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m auvdiag_cli.fuzz", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", type=int, default=300, help="cases per seed log")
    parser.add_argument("--first-case", type=int, default=0, help="number of the first case")
    parser.add_argument("--formats", default=None,
                        help="simulated seed logs to write, comma-separated ('' for none; "
                             "default: every format the simulator writes, and each ROS "
                             "format again with its software's words: bag+words, ...)")
    parser.add_argument("--seed-log", type=Path, action="append", default=[],
                        help="a real log to damage as well (repeatable)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--time-limit", type=float, default=20.0, help="seconds per case")
    parser.add_argument("--memory-limit-mb", type=int, default=1024,
                        help="address space a case may add to the fuzzer's")
    parser.add_argument("--json", type=Path, help="write the counts and defects here")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(variable, "1")   # forked children must not share BLAS pools
    import tempfile

    from auvdiag_cli.fuzz.harness import Case, Limits, exercise, run_cases, summarise
    from auvdiag_cli.fuzz.seeds import SEED_FORMATS, real_seed, simulated_seeds
    from auvdiag_cli.vehicle.profile import load_profile
    from auvdiag_errors import AuvdiagError
    from models.store import load_model

    options = _arguments(argv)
    profile = load_profile()
    model = load_model(None, profile.name)
    limits = Limits(options.time_limit, options.memory_limit_mb)
    report: dict[str, object] = {"cases_per_seed": options.cases, "jobs": options.jobs,
                                 "time_limit_s": limits.time_s,
                                 "memory_limit_mb": limits.memory_mb, "seeds": {}}
    with tempfile.TemporaryDirectory(prefix="auvdiag-seeds-") as folder:
        formats = SEED_FORMATS if options.formats is None else tuple(
            f for f in options.formats.split(",") if f)
        try:
            seeds = simulated_seeds(Path(folder), profile, formats)
            seeds += [real_seed(path) for path in options.seed_log]
        except AuvdiagError as error:
            print(f"fuzz: {error}", file=sys.stderr)
            return 2
        for seed in seeds:   # warm up: every import and compilation done before forking
            exercise(seed.path, profile, model)
        started = time.perf_counter()
        for seed in seeds:
            cases = [Case(seed, n) for n in range(options.first_case,
                                                  options.first_case + options.cases)]
            results = list(run_cases(cases, profile, model, limits, options.jobs))
            summary = summarise(results)
            report["seeds"][seed.name] = summary   # type: ignore[index]
            print(f"{seed.name:<24} {summary['cases']:>6} cases  read {summary['read']:>6}  "
                  f"rejected {summary['rejected']:>6}  defects {summary['defects']:>4}  "
                  f"slowest {summary['slowest_s']:.2f} s (case {summary['slowest_case']})  "
                  f"peak {summary['peak_rss_mb']:.0f} MB",
                  flush=True)
        report["seconds"] = round(time.perf_counter() - started, 1)
    if options.json is not None:
        options.json.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    defects = sum(s["defects"] for s in report["seeds"].values())   # type: ignore[attr-defined]
    return 1 if defects else 0


if __name__ == "__main__":
    sys.exit(main())
