"""Helpers the test files share (the fixtures are in conftest)."""

import json
from pathlib import Path
from typing import Any

from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.results import Observations
from models.card import ModelIdentity


def diagnose_outcome(log: Path, *options: str) -> tuple[int, dict[str, Any] | str]:
    """`auvdiag diagnose LOG --json - --quiet OPTIONS`, as a user runs it: the exit status
    and the JSON report, or for a log it cannot analyse (exit status 2) the one line that
    names the log and the problem. Never a traceback or an unexpected error."""
    result = CliRunner().invoke(app, ["diagnose", str(log), "--json", "-", "--quiet",
                                      *options])
    assert "Traceback" not in result.output and "unexpected" not in result.output, (
        result.output)
    if result.exit_code == 2:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and str(log) in lines[0], result.stderr
        return 2, lines[0]
    assert result.exit_code in (0, 1), result.output
    return result.exit_code, json.loads(result.stdout)


LIBRARY_OPTIONS = {"--model", "--profile", "--mission", "--truth", "--with"}


def diagnose_json(log: Path, *options: str) -> tuple[int, dict[str, Any]]:
    """The diagnosis of ``log`` through the library, as `auvdiag diagnose LOG OPTIONS`
    would give it: the exit status it would have (1 for a fault, else 0) and the JSON
    report as written and read back. A verdict must come out; the command line's own
    behaviour (exit status 2, one-line errors) is `diagnose_outcome`'s."""
    from auvdiag_cli import api

    pairs = list(zip(options[::2], options[1::2], strict=True))
    assert {o for o, _ in pairs} <= LIBRARY_OPTIONS, f"not a library option: {pairs}"
    given = dict(pairs)
    profile = api.load_profile(given.get("--profile"))
    model = api.load_model(Path(given["--model"]) if "--model" in given else None, profile)
    diagnosis = api.diagnose(Path(log), profile, model,
                             companions=[Path(v) for o, v in pairs if o == "--with"],
                             mission=Path(given["--mission"]) if "--mission" in given else None,
                             truth=Path(given["--truth"]) if "--truth" in given else None)
    code = 1 if diagnosis.verdict == api.Verdict.FAULT else 0
    return code, json.loads(json.dumps(api.to_json(diagnosis)))


def assert_same_signals(read: Any, reference: Any) -> None:
    """Two reads of one log: the same messages, the same samples at the same times."""
    import numpy as np

    assert read.messages_read == reference.messages_read > 0
    assert read.series.keys() == reference.series.keys()
    for name, series in read.series.items():
        assert np.array_equal(series.times_ns, reference.series[name].times_ns), name
        assert np.array_equal(series.values, reference.series[name].values), name
    assert len(read.markers) == len(reference.markers)


def zeroed_column(log: Path, column_name: str, out: Path) -> Path:
    """A copy of the CSV ``log`` with one column's cells all 0 (a channel written but never
    fed)."""
    lines = log.read_text().splitlines()
    column = lines[0].split(",").index(column_name)
    out.write_text("\n".join([lines[0]] + [",".join(
        "0.0" if i == column and cell else cell for i, cell in enumerate(line.split(",")))
        for line in lines[1:]]) + "\n")
    return out


FMT_TYPE = 128


def rewrite_dataflash(source: Path, target: Path, change: Any) -> Path:
    """The DataFlash log with each record (header included) replaced by
    ``change(record, type_id, formats)``: bytes, empty to drop it, or several records."""
    import numpy as np

    from adapters.mavlink_scan import index_file

    index = index_file(source, "bin")
    data, ends = bytes(index.data), np.append(index.offsets[1:], index.data.size)
    target.write_bytes(b"".join(
        change(data[start:end], kind, index.formats) for start, end, kind in zip(
            index.offsets.tolist(), ends.tolist(), index.type_ids.tolist(), strict=True)))
    return target


def refit_format(record: bytes, old: tuple[bytes, bytes], new: tuple[bytes, bytes],
                 shrink: int) -> bytes:
    """An FMT record whose format characters and columns begin ``new`` instead of ``old``
    (each a (format, columns) prefix pair), its record length ``shrink`` bytes less."""
    fmt, columns = record[9:25].rstrip(b"\0"), record[25:89].rstrip(b"\0")
    assert fmt.startswith(old[0]) and columns.startswith(old[1]), (fmt, columns)
    fmt, columns = new[0] + fmt[len(old[0]):], new[1] + columns[len(old[1]):]
    return (record[:4] + bytes([record[4] - shrink]) + record[5:9] + fmt.ljust(16, b"\0")
            + columns.ljust(64, b"\0"))


def observed(effort: EffortCheck | None, not_judged: dict[str, str],
             vehicle: str = "arducopter_quad") -> Observations:
    """What a diagnosis of a log of ``vehicle`` saw, where only the effort check and the
    signals the replay does not judge matter."""
    identity = ModelIdentity(None, vehicle, "m", None, None, None, None, None, {}, (), True,
                             None)
    return Observations(log=Path("flight.bin"), format="dataflash", vehicle=vehicle,
                        segments=(), segment_source="commands", model=identity,
                        window_samples=10, decision_window_s=1.0, sensor_units={},
                        not_judged=not_judged, effort_check=effort)
