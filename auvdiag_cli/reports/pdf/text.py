"""Text pages: lines laid out top-down with measured heights, wrapped to the page width, and
continued on a new page instead of overlapping or running off the bottom."""

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from auvdiag_cli.reports.pdf.style import COLOURS, PAGE_INCHES, new_page

if TYPE_CHECKING:
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

LEFT, RIGHT, TOP, BOTTOM = 0.05, 0.95, 0.93, 0.05
LINE_SPACING = 1.35
# Average advance of a character in em; wrapping with these never reaches the margin.
CHAR_WIDTH_EM = {"sans-serif": 0.58, "monospace": 0.61}
BOLD_WIDTH = 1.1          # bold sans-serif letters are this much wider


@dataclass(frozen=True)
class Line:
    text: str
    size: float = 9.5
    bold: bool = False
    colour: str = COLOURS["text"]
    family: str = "sans-serif"
    indent: float = 0.0               # fraction of the page width
    banner: str | None = None         # background colour: a verdict banner


def heading(text: str) -> list[Line]:
    return [Line(""), Line(text, size=12, bold=True)]


def columns(size: float, family: str = "sans-serif", indent: float = 0.0,
            bold: bool = False) -> int:
    """How many characters of this size fit across the text width."""
    width_pt = (RIGHT - LEFT - indent) * PAGE_INCHES[0] * 72
    em = CHAR_WIDTH_EM[family] * (BOLD_WIDTH if bold and family == "sans-serif" else 1.0)
    return max(20, int(width_pt / (size * em)))


def paragraph(text: str, size: float = 9.5, indent: float = 0.0, colour: str = COLOURS["text"],
              family: str = "sans-serif", bold: bool = False) -> list[Line]:
    """One logical line, wrapped to the text width (continuation lines indented a little)."""
    wrapped = textwrap.wrap(text, columns(size, family, indent, bold), subsequent_indent="   ",
                            break_on_hyphens=False,
                            replace_whitespace=family != "monospace",
                            drop_whitespace=family != "monospace") or [""]
    return [Line(part, size, bold, colour, family, indent) for part in wrapped]


def _height(line: Line) -> float:
    """Figure fraction the line occupies."""
    extra = 0.6 if line.banner else 0.0
    return line.size * (LINE_SPACING + extra) / 72 / PAGE_INCHES[1]


def _start_page(title: str, page_title: str) -> "Figure":
    figure = new_page()
    figure.text(LEFT, 0.965, page_title, fontsize=14, weight="bold", color=COLOURS["text"],
                va="top")
    if title:       # "": the page title says it already
        figure.text(RIGHT, 0.965, title, fontsize=8, color=COLOURS["muted"], va="top",
                    ha="right")
    return figure


def text_height(lines: Sequence[Line]) -> float:
    """Figure fraction the lines occupy on one page."""
    return sum(_height(line) for line in lines)


def _draw(figure: "Figure", line: Line, y: float) -> None:
    box = (None if line.banner is None else
           {"facecolor": line.banner, "edgecolor": "none", "pad": 6.0})
    figure.text(LEFT + line.indent, y, line.text, fontsize=line.size,
                weight="bold" if line.bold else "normal",
                color="white" if line.banner else line.colour, family=line.family,
                va="bottom", bbox=box)


def text_page(lines: Sequence[Line], title: str, page_title: str) -> tuple["Figure", float]:
    """A page headed ``page_title`` with ``lines`` (which must fit: `text_height`) at its
    top, and the figure fraction below them left free for charts."""
    figure, y = _start_page(title, page_title), TOP
    for line in lines:
        y -= _height(line)
        _draw(figure, line, y)
    return figure, y


def write_text_pages(pdf: "PdfPages", lines: Sequence[Line], title: str,
                     page_title: str) -> int:
    """Lay ``lines`` out on as many pages as they need; returns the number of pages."""
    figure, y, pages = _start_page(title, page_title), TOP, 1
    for line in lines:
        height = _height(line)
        if y - height < BOTTOM:
            pdf.savefig(figure)
            figure, y, pages = _start_page(title, f"{page_title} (continued)"), TOP, pages + 1
        y -= height
        _draw(figure, line, y)
    pdf.savefig(figure)
    return pages
