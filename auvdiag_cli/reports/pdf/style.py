"""One look for every report page: page size, fonts, and a colour per role."""

from collections.abc import Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from auvdiag_cli import __version__

if TYPE_CHECKING:
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

PAGE_INCHES = (11.69, 8.27)          # A4 landscape
COLOURS = {
    "measured": "#1f4e79",           # SS: the sensor
    "modelled": "#e07b00",           # SM: the model
    "truth": "#2e7d32",
    "threshold": "#c62828",
    "alarm": "#c62828",              # b = 1, detection
    "onset": "#6a1b9a",
    "autopilot": "#37474f",          # a text of trouble the vehicle's own software wrote
    "dms": "#9e9e9e",                # DMS segments
    "closed_loop": "#00838f",
    "healthy": "#2e7d32",            # the model of the healthy vehicle from the onset
    "normal": "#2e7d32",
    "fault": "#c62828",
    "undetermined": "#ef6c00",
    "partial": "#827717",            # NORMAL over part of the signals and actuators
    "error": "#616161",
    "text": "#212121",
    "muted": "#616161",
}
COMMAND_CYCLE = ["#1f4e79", "#e07b00", "#2e7d32", "#6a1b9a", "#00838f", "#8d6e63"]
RC: dict[str, Any] = {
    "pdf.fonttype": 42,              # embedded TrueType: the text stays searchable
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
}


def new_page() -> "Figure":
    from matplotlib.figure import Figure

    return Figure(figsize=PAGE_INCHES, layout="constrained")


@contextmanager
def pdf_document(target: Path, title: str, subject: str) -> Iterator["PdfPages"]:
    """A PDF written to a temporary name and moved into place when complete, so a reader
    never sees half a report."""
    import matplotlib
    from matplotlib.backends.backend_pdf import PdfPages

    temporary = target.with_name(f".{target.name}.tmp")
    metadata: dict[str, Any] = {"Title": title, "Subject": subject,
                                "Creator": f"auvdiag {__version__}",
                                "CreationDate": datetime.now(UTC)}
    try:
        with matplotlib.rc_context(RC), PdfPages(  # type: ignore[arg-type]
                temporary, metadata=metadata) as pdf:
            yield pdf
        temporary.replace(target)
    finally:
        temporary.unlink(missing_ok=True)


def seconds_label() -> str:
    return "time since the log's first message [s]"
