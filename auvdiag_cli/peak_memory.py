"""This process's own peak resident memory, as an audit records it for every log."""

import resource
import sys
from pathlib import Path

_STATUS = Path("/proc/self/status")


def peak_rss_mb() -> float:
    """The high-water resident memory of this process image, in MB. On Linux it is VmHWM,
    which starts afresh at exec: ``ru_maxrss`` keeps the peak of the process that started
    this one (spawning shares its memory until the exec), so a worker started by a large
    program looked as large as that program."""
    if _STATUS.is_file():
        for line in _STATUS.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1 << 20) if sys.platform == "darwin" else peak / 1024
