"""A command logged more slowly than the model steps (QGroundControl's 2 Hz
SERVO_OUTPUT_RAW) is said, with what it costs, by `inspect` and `diagnose`."""


import numpy as np
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()


def _thin_commands(source, target, keep_every=5):
    """The tlog with only every fifth SERVO_OUTPUT_RAW frame: 2 Hz instead of 10 Hz."""
    from adapters.mavlink import _message_names
    from adapters.mavlink_scan import index_file

    index = index_file(source, "tlog", _message_names())
    servo = next(i for i, name in _message_names().items() if name == "SERVO_OUTPUT_RAW")
    ends = np.append(index.offsets[1:], index.data.size)
    data, seen, parts = bytes(index.data), 0, []
    for start, end, kind in zip(index.offsets.tolist(), ends.tolist(),
                                index.type_ids.tolist(), strict=True):
        if kind == servo:
            seen += 1
            if seen % keep_every:
                continue
        parts.append(data[start:end])
    target.write_bytes(b"".join(parts))
    return target


def test_slow_commands_are_reported_by_inspect_and_diagnose(make_log, tmp_path):
    log = _thin_commands(make_log("paper-normal", 11, "tlog"), tmp_path / "slow.tlog")
    shown = runner.invoke(app, ["inspect", str(log), "--profile", "twin_burger"])
    assert shown.exit_code == 0
    warnings = [line for line in shown.stdout.splitlines() if "warning:" in line]
    assert len(warnings) == 1 and "thruster_0, thruster_1 are logged at 2.0 Hz" in warnings[0]
    assert "below the model's 10 Hz step" in warnings[0]
    notes = diagnose_json(log)[1]["notes"]
    assert sum("are logged at 2.0 Hz" in note for note in notes) == 1


def test_commands_at_the_model_rate_raise_no_warning(make_log):
    shown = runner.invoke(app, ["inspect", str(make_log("paper-normal", 11, "tlog")),
                                "--profile", "twin_burger"])
    assert shown.exit_code == 0 and "warning:" not in shown.stdout
