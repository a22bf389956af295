"""The documentation: a README a newcomer reads to the end, and a site that builds with
`mkdocs build --strict` (a broken link, a missing page or a stale API reference fails)."""

import html
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _build(project: Path, site: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                           "-f", str(project / "mkdocs.yml"), "-d", str(site)],
                          cwd=project, capture_output=True, text=True,
                          env={"NO_MKDOCS_2_WARNING": "1", "PATH": "/usr/bin:/bin"})


def test_the_site_builds_strictly_and_renders_the_library_reference(tmp_path):
    result = _build(ROOT, tmp_path / "site")
    assert result.returncode == 0, result.stdout + result.stderr
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    assert "load_model" in api and "diagnose" in api     # mkdocstrings read the docstrings
    # a console block's copy button copies the commands, not the prompts or the output
    home = (tmp_path / "site" / "index.html").read_text()
    copied = html.unescape(re.findall(r'data-copy="([^"]*)"', home)[0])
    assert copied.splitlines()[1].startswith("auvdiag diagnose sample_logs/paper-flow")
    assert "$ " not in copied and "verdict" not in copied


def test_a_console_block_copies_its_commands_whole():
    from scripts.docs_console_copy import commands, with_copy_text

    block = "$ auvdiag train a.csv \\\n    --output m   # exit 1\nmodel written\n$ ls\nm\n"
    assert commands(block) == "auvdiag train a.csv \\\n    --output m   # exit 1\nls"
    page = ('<pre><code><span class="gp">$ </span>echo<span class="w"> </span>&quot;a&quot;'
            "\na\n</code></pre><pre><code>plain</code></pre>")
    assert with_copy_text(page) == ('<pre><code data-copy="echo &quot;a&quot;">'
                                    + page.removeprefix("<pre><code>"))


def test_a_broken_link_fails_the_build(tmp_path):
    copy = tmp_path / "project"
    shutil.copytree(ROOT / "docs", copy / "docs")
    for name in ("mkdocs.yml", "auvdiag_cli", "auvdiag_errors", "adapters", "models",
                 "scripts", "sample_logs"):
        source = ROOT / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, copy / name)
    page = copy / "docs" / "limits.md"
    page.write_text(page.read_text() + "\nSee [the page that is not](no-such-page.md).\n")
    result = _build(copy, tmp_path / "site")
    assert result.returncode != 0 and "no-such-page.md" in result.stdout + result.stderr


def test_the_readme_is_short_and_lists_every_page():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    pages = sorted(p.name for p in (ROOT / "docs").glob("*.md") if p.name != "index.md")
    assert all(f"docs/{name}" in readme for name in pages), pages


def test_the_json_table_names_every_key_of_a_report():
    """The documented keys are a report's keys: a new key without its row (or
    a row for a key gone) fails."""
    import json
    import re

    page = (ROOT / "docs" / "reports.md").read_text()
    table = page[page.index("| key | what it holds |"):page.index("## Reports and fleet audits")]
    documented = [key for row in table.splitlines()[2:] if row.startswith("| `")
                  for key in re.findall(r"`(\w+)`", row.split("|")[1])]
    report = json.loads((ROOT / "sample_logs" / "mission-thruster-1-dead.expected.json")
                        .read_text())
    assert sorted(documented) == sorted(report)


def test_the_sample_logs_table_in_the_docs_is_what_their_reports_say():
    """The figures the method page quotes for the sample logs are generated from their
    expected reports (which other tests hold to what the tool writes): regenerate them with
    `make bench-samples` when a report changes."""
    for page, name, option, row in [
            ("method.md", "sample_facts", [], "| mission-thruster-0-dead | thruster_0 |"),
            ("simulator.md", "sample_logs", ["--catalogue"], "| `paper-normal` | ros2-mcap |")]:
        generated = subprocess.run(
            [sys.executable, str(ROOT / "benchmarks" / "sample_facts.py"), *option],
            capture_output=True, text=True, check=True).stdout.strip()
        text = (ROOT / "docs" / page).read_text()
        block = text.split(f"<!-- bench:{name} -->\n")[1].split(f"<!-- /bench:{name}")[0]
        assert block.strip() == generated and row in block
