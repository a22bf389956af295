"""Put a benchmark's Markdown output into README.md, between the markers
<!-- bench:NAME --> and <!-- /bench:NAME -->, so `make bench` keeps the figures current.

Usage: python benchmarks/readme.py NAME OUTPUT.md [--readme README.md]
"""

import argparse
import re
from pathlib import Path


def splice(readme: str, name: str, block: str) -> str:
    pattern = re.compile(rf"(<!-- bench:{re.escape(name)} -->\n).*?(<!-- /bench:"
                         rf"{re.escape(name)} -->)", re.DOTALL)
    if not pattern.search(readme):
        raise SystemExit(f"README has no <!-- bench:{name} --> ... <!-- /bench:{name} --> block")
    return pattern.sub(lambda m: m.group(1) + block.strip() + "\n" + m.group(2), readme)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name")
    parser.add_argument("output", type=Path)
    parser.add_argument("--readme", type=Path, default=Path(__file__).parents[1] / "README.md")
    args = parser.parse_args()
    args.readme.write_text(splice(args.readme.read_text(), args.name,
                                  args.output.read_text()))


if __name__ == "__main__":
    main()
