"""Put a benchmark's Markdown output into the documentation page that holds the markers
<!-- bench:NAME --> and <!-- /bench:NAME --> (README.md or docs/*.md), so `make bench` keeps
the figures current.

Usage: python benchmarks/readme.py NAME OUTPUT.md [--page PAGE.md]
"""

import argparse
import re
from pathlib import Path

ROOT = Path(__file__).parents[1]


def _pattern(name: str) -> re.Pattern[str]:
    return re.compile(rf"(<!-- bench:{re.escape(name)} -->\n).*?(<!-- /bench:"
                      rf"{re.escape(name)} -->)", re.DOTALL)


def splice(page: str, name: str, block: str) -> str:
    pattern = _pattern(name)
    if not pattern.search(page):
        raise SystemExit(f"no <!-- bench:{name} --> ... <!-- /bench:{name} --> block")
    return pattern.sub(lambda m: m.group(1) + block.strip() + "\n" + m.group(2), page)


def page_of(name: str) -> Path:
    """The README or documentation page that holds the block."""
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        if _pattern(name).search(page.read_text()):
            return page
    raise SystemExit(f"no page holds a <!-- bench:{name} --> block")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name")
    parser.add_argument("output", type=Path)
    parser.add_argument("--page", type=Path, default=None)
    args = parser.parse_args()
    page = args.page or page_of(args.name)
    page.write_text(splice(page.read_text(), args.name, args.output.read_text()))


if __name__ == "__main__":
    main()
