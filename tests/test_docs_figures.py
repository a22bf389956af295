"""A figure on a page is either generated (inside a <!-- bench:NAME --> block a benchmark
writes) or backed by one: a hand-typed share, "N of M" or "N/M" outside the blocks must be a
figure some block says, or a constant listed here with why it is one. So a result typed by
hand and left behind when the benchmark's figures move fails here. The changelog is history
and keeps the figures of its day."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"<!-- bench:([\w-]+) -->\n(.*?)<!-- /bench:\1 -->", re.DOTALL)
CODE = re.compile(r"```.*?```", re.DOTALL)
FIGURE = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?\s?%|\d+ of \d+|\d+/\d+(?![\w/]))")

# Figures that are not results: the paper's constants, the method's own settings, and
# examples of what the tool prints.
CONSTANTS = {
    "README.md": {"1 of 4"},                                 # a verdict's wording
    "glossary.md": {"2 of 2"},                               # a verdict's wording
    "reports.md": {"0/1", "1 of 6", "0 of 4", "1/6",         # JSON keys' example values
                   "96 %", "64 %"},                          # the trend example's thrust
    "limits.md": {"1/3",                                     # the skill threshold
                  "5.4 %"},                  # the extra command that makes up 10 % thrust
    "method.md": {"10 %", "7 %", "75 %", "1/3", "1/1",       # the paper's thresholds,
                  "95 %", "5.4 %"},
    # the hypotheses' thrust levels, the skill threshold and its derivation, the confidence
    # of the spread that alike logs are judged against, the commands' relation's floor
    "results.md": {"1/25",                                   # ZA's command, of full thrust
                   "10 %",                                   # the paper's yaw threshold
                   "97.96 %"},                               # a published classifier
    "robustness.md": {"4/8"},                                # 2/4/8-byte fields
}


def _pages() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _plain(figure: str) -> str:
    return re.sub(r"\s", "", figure)


def unbacked_figures(pages: dict[str, str]) -> list[str]:
    """'page: figure' for each figure outside the generated blocks that no block says and
    that is not a listed constant."""
    generated = " ".join(m.group(2) for text in pages.values() for m in BLOCK.finditer(text))
    backed = {_plain(f) for f in FIGURE.findall(generated)}
    found = []
    for name, text in pages.items():
        if name == "changelog.md":
            continue
        prose = CODE.sub("", BLOCK.sub("", text))
        allowed = {_plain(f) for f in CONSTANTS.get(name, set())}
        found += [f"{name}: {figure}" for figure in FIGURE.findall(prose)
                  if _plain(figure) not in backed | allowed]
    return found


def test_every_figure_outside_a_generated_block_is_backed_by_one():
    assert unbacked_figures({p.name: p.read_text() for p in _pages()}) == []


def test_a_hand_typed_result_that_no_block_says_is_caught():
    pages = {p.name: p.read_text() for p in _pages()}
    results = pages["results.md"]
    block = BLOCK.search(results)
    assert block is not None
    said = FIGURE.findall(block.group(2))
    assert said, "the results page's first block says no figure"
    # the same figure typed outside the block is backed; one no block says is not
    pages["results.md"] = results + f"\nOn this data it finds {said[0]}.\n"
    assert unbacked_figures(pages) == []
    pages["results.md"] = results + "\nOn this data it finds 99 of 101 failures.\n"
    assert unbacked_figures(pages) == ["results.md: 99 of 101"]
