"""An audit on a real Dask cluster: `dask scheduler` and two `dask worker` processes on
127.0.0.1, one worker killed (SIGKILL) while the audit runs. The audit still ends with every
log's row, and no result finished before the kill is lost or redone."""

import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app

pytestmark = pytest.mark.slow    # trains models or simulates fleets

distributed = pytest.importorskip("distributed")
DASK = Path(sys.executable).parent / "dask"
LOGS = [("paper-flow-sensor-covered", "bag"), ("paper-normal", "db3"),
        ("mission-thruster-0-dead", "mcap"), ("mission-fast-ccw", "tlog"),
        ("mission-large-cw", "bin"), ("mission-yaw-rate-sensor-dead", "ros2-mcap")]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def cluster(tmp_path):
    if not DASK.exists():
        pytest.skip(f"no dask command beside {sys.executable} (pip install 'auvdiag[dask]')")
    address = f"tcp://127.0.0.1:{_free_port()}"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    output = (tmp_path / "cluster.log").open("w")
    port = address.rsplit(":", 1)[1]
    processes = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port",
                                   port, "--no-dashboard"], stdout=output, stderr=output,
                                  env=env)]
    processes += [subprocess.Popen([str(DASK), "worker", address, "--nthreads", "1",
                                    "--no-nanny", "--no-dashboard", "--death-timeout", "60",
                                    "--name", f"worker-{n}"], stdout=output, stderr=output,
                                   env=env) for n in range(2)]
    try:
        with distributed.Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address, processes[1:]
    finally:
        for process in reversed(processes):
            process.kill()
            process.wait(timeout=30)
        output.close()


def test_audit_survives_a_killed_worker(cluster, make_log, tmp_path):
    address, workers = cluster
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for copy in range(2):
        for scenario, fmt in LOGS:
            source = make_log(scenario, 11, fmt)
            target = fleet / f"{scenario}-{copy}{source.suffix}"
            (shutil.copytree if source.is_dir() else shutil.copy)(source, target)
    results = tmp_path / "out" / "logs"
    before_kill: dict[str, int] = {}

    def kill_after_first_result() -> None:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            done = list(results.glob("*.json")) if results.is_dir() else []
            if done:
                before_kill.update({p.name: p.stat().st_mtime_ns for p in done})
                workers[0].send_signal(signal.SIGKILL)
                return
            time.sleep(0.05)

    killer = threading.Thread(target=kill_after_first_result)
    killer.start()
    result = CliRunner().invoke(app, ["audit", str(fleet), "--output", str(tmp_path / "out"),
                                      "--scheduler", address])
    killer.join()
    assert workers[0].wait(timeout=10) == -signal.SIGKILL
    assert 0 < len(before_kill) < 2 * len(LOGS), "the worker was not killed mid-audit"
    assert result.exit_code == 1, result.output            # faults found, no log lost
    frame = pd.read_csv(tmp_path / "out" / "audit.csv")
    assert len(frame) == 2 * len(LOGS) and frame["error"].isna().all()
    assert sorted(p.name for p in results.glob("*.json")) == sorted(
        frame["result_file"].tolist())
    for name, mtime in before_kill.items():                # finished before: kept as it was
        assert (results / name).stat().st_mtime_ns == mtime
