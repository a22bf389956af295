"""What the tool finds on each faulty sample log, read from the sample logs' expected reports
(`sample_logs/NAME.expected.json`, which the tests keep equal to what `auvdiag diagnose`
writes): the hypotheses' peak g against the threshold for every actuator failing outright,
the commands' shares of the departure, and the Substituting Control figures.

With --catalogue, the list of the sample logs instead: each log's format, what happens in
it (from NAME.truth.json) and the diagnosis.

Usage: python benchmarks/sample_facts.py [--catalogue]
"""

import argparse
import json
from pathlib import Path
from typing import Any

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.0f} %"


def _dead_actuators(hypotheses: dict[str, Any], actuators: list[str]) -> str:
    """Peak g / threshold with each actuator assumed dead: how far each explains the log."""
    dead = {h["component"]: h["peak_g_over_threshold"] for h in hypotheses.get("ranked", [])
            if h["kind"] == "dead" and h["component"] in actuators}
    return ", ".join(f"{name} {_percent(dead.get(name))}" for name in actuators) or "-"


def _shares(check: dict[str, Any] | None) -> str:
    explained = (check or {}).get("explained") or {}
    return ", ".join(f"{name} {share:.3g}" for name, share in explained.items()) or "-"


def _substitution(report: dict[str, Any]) -> str:
    sub = report.get("substitution")
    if not sub:
        return "-"
    unit = sub["unit"]
    parts = [f"substitute {sub['truth_error_rms']:.2g} {unit} rms, failed sensor "
             f"{sub['failed_sensor_error_rms']:.2g} {unit} (model expected "
             f"{sub['expected_error_rms']:.2g})"]
    track = sub.get("track_end_error_m")
    if track:
        parts.append(f"track ends {track['substituted']:.2f} m off (failed sensor: "
                     f"{track['failed']:.1f} m)")
    closed = sub.get("closed_loop")
    if closed and closed.get("reached_last_waypoint"):
        parts.append(f"closed loop reaches the last waypoint at {closed['finished_s']:g} s, "
                     f"{closed['miss_m']:.2f} m from it")
    return "; ".join(parts)


def _reports() -> list[tuple[str, dict[str, Any]]]:
    return [(path.name.removesuffix(".expected.json"), json.loads(path.read_text("utf-8")))
            for path in sorted(SAMPLES.glob("*.expected.json"))]


def catalogue() -> list[str]:
    lines = ["| log | format | what happens | diagnosis (onset → detection) |",
             "|---|---|---|---|"]
    for name, report in _reports():
        truth = json.loads((SAMPLES / f"{name}.truth.json").read_text("utf-8"))
        found = ("normal" if report["verdict"] == "normal" else
                 f"{report['component'] or ' or '.join(report['candidates'])}, case "
                 f"{report['case']} ({report['onset_s']:.1f} → {report['detected_at_s']:.1f} s)")
        lines.append(f"| `{truth['log']}` | {truth['format']} | {truth['description']} | "
                     f"{found} |")
    return lines


def findings() -> list[str]:
    lines = ["| sample log | verdict | onset / detected | peak g / threshold with each "
             "thruster dead | commands: share of the departure | Substituting Control "
             "against the truth |", "|---|---|---|---|---|---|"]
    for name, report in _reports():
        if report["verdict"] != "fault":
            continue
        actuators = list((report.get("commands_check") or {}).get("extra_effort_allowed") or {})
        lines.append(
            f"| {name} | {report['component']} | "
            f"{report['onset_s']:g} s / {report['detected_at_s']:g} s | "
            f"{_dead_actuators(report.get('hypotheses') or {}, actuators)} | "
            f"{_shares(report.get('commands_check'))} | {_substitution(report)} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--catalogue", action="store_true")
    args = parser.parse_args()
    if args.catalogue:
        print("\n".join(["Read from `sample_logs/NAME.truth.json` and `NAME.expected.json`.",
                         "", *catalogue()]))
    else:
        print("\n".join(["Read from `sample_logs/*.expected.json` (the faulty ones).", "",
                         *findings()]))


if __name__ == "__main__":
    main()
