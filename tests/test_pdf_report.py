"""PDF reports, rendered for real and read back: page count, text, metadata, and pixels."""

from pathlib import Path

import numpy as np
import pypdf
import pypdfium2
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
MEASURED_RGB = (0x1F, 0x4E, 0x79)      # the sensor (and the first command)
MODELLED_RGB = (0xE0, 0x7B, 0x00)      # the model's output, the substituted signal


def page_pixels(pdf: Path, index: int) -> np.ndarray:
    document = pypdfium2.PdfDocument(pdf)
    try:
        return np.asarray(document[index].render(scale=1.0).to_pil().convert("RGB"))
    finally:
        document.close()


def inked_fraction(pixels: np.ndarray) -> float:
    return float((pixels.min(axis=2) < 200).mean())


def has_colour(pixels: np.ndarray, rgb: tuple[int, int, int], tolerance: int = 40) -> bool:
    return bool((np.abs(pixels.astype(int) - rgb).max(axis=2) < tolerance).sum() > 200)


@pytest.fixture(scope="module")
def paper_report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The paper's scenario (flow sensor covered at 115 s), as a user would produce it."""
    folder = tmp_path_factory.mktemp("report")
    log = folder / "paper.bag"
    simulated = runner.invoke(app, ["simulate", "paper-flow-sensor-covered", "--format", "bag",
                                    "--output", str(log), "--seed", "11"])
    assert simulated.exit_code == 0, simulated.output
    json_path, pdf_path = folder / "paper.json", folder / "paper.pdf"
    result = runner.invoke(app, ["diagnose", str(log), "--json", str(json_path),
                                 "--pdf", str(pdf_path), "--quiet"])
    assert result.exit_code == 1, result.output
    return log, json_path, pdf_path


def test_paper_scenario_report_reads_right(paper_report):
    _, _, pdf = paper_report
    reader = pypdf.PdfReader(pdf)
    # summary and segments, sensors, g and b, commands, Substituting Control
    assert len(reader.pages) == 5
    assert reader.metadata.title == "auvdiag report: paper.bag"
    assert reader.metadata.creator.startswith("auvdiag ")
    first = reader.pages[0].extract_text()
    assert "FAULT: flow sensor" in first
    assert "Component:  flow sensor" in first
    assert "onset about 115" in first and "detected at 11" in first
    assert "case 2, b = flow=1 yaw_rate=0" in first
    assert "Hypotheses:  best explained by flow sensor dead (" in first
    assert "the controller reaches the last waypoint" in first
    assert "At most one sensor or actuator is defective at a time." in first
    # The segments follow on the first page: no page of their own, nearly empty.
    assert "Segments and evidence" in first and "MISSION" in first
    assert "Residual index g" in reader.pages[2].extract_text()
    assert "Substituting Control" in reader.pages[4].extract_text()


def test_plot_pages_are_drawn_not_blank(paper_report):
    _, _, pdf = paper_report
    curves = {1: [MEASURED_RGB, MODELLED_RGB], 2: [MEASURED_RGB], 3: [MEASURED_RGB],
              4: [MODELLED_RGB]}
    for page, colours in curves.items():
        pixels = page_pixels(pdf, page)
        assert inked_fraction(pixels) > 0.01, f"page {page + 1} is nearly blank"
        for colour in colours:
            assert has_colour(pixels, colour), f"page {page + 1} lacks the curve in {colour}"


def test_report_command_redraws_the_saved_diagnosis(paper_report, tmp_path):
    _, json_path, pdf = paper_report
    assert (json_path.parent / "paper.series.npz").is_file()
    redrawn = tmp_path / "again.pdf"
    result = runner.invoke(app, ["report", str(json_path), "--output", str(redrawn)])
    assert result.exit_code == 0, result.output
    original, again = pypdf.PdfReader(pdf), pypdf.PdfReader(redrawn)
    assert len(again.pages) == len(original.pages)
    assert again.pages[0].extract_text() == original.pages[0].extract_text()


def test_report_without_time_histories_has_summary_pages_only(paper_report, tmp_path):
    _, json_path, _ = paper_report
    lone = tmp_path / "lone.json"
    lone.write_text(json_path.read_text())          # its series file is not beside it
    result = runner.invoke(app, ["report", str(lone)])
    assert result.exit_code == 0, result.output
    assert "no time histories" in result.output
    reader = pypdf.PdfReader(tmp_path / "lone.pdf")
    assert len(reader.pages) == 1
    assert "not checked (no time histories" in reader.pages[0].extract_text()


def test_normal_dive_report(make_log, tmp_path):
    pdf = tmp_path / "normal.pdf"
    result = runner.invoke(app, ["diagnose", str(make_log("routine-and-mission", 11)),
                                 "--pdf", str(pdf), "--quiet"])
    assert result.exit_code == 0, result.output
    reader = pypdf.PdfReader(pdf)
    assert len(reader.pages) == 4                  # no Substituting Control page
    first = reader.pages[0].extract_text()
    assert "NORMAL: no fault detected" in first
    assert "4 (3 Diagnosis Motion Sequences)" in first
    assert all(name in first for name in ("ZA", "ZB", "ZC", "MISSION"))
    # Its sequences are shaded on the time histories, and their titles say so.
    assert "shaded: Diagnosis Motion Sequences" in reader.pages[1].extract_text()
    assert "Commands, with the Diagnosis Motion Sequences" in reader.pages[3].extract_text()


@pytest.mark.parametrize("content", ["{not json", '{"a": 1}'])
def test_report_refuses_what_is_not_a_report(tmp_path, content):
    path = tmp_path / "bad.json"
    path.write_text(content)
    result = runner.invoke(app, ["report", str(path)])
    assert result.exit_code == 2
    assert str(path) in result.output and len(result.output.strip().splitlines()) == 1


def test_the_segment_table_keeps_its_columns_apart_for_many_signals():
    """Columns as wide as their cells; where the signals no longer fit side by side across
    the page, a row per signal under each segment, never cells run into each other."""
    from types import SimpleNamespace

    from auvdiag_cli.reports.pdf.dive import _segment_table
    from auvdiag_cli.reports.pdf.text import columns

    def report(signals: int) -> SimpleNamespace:
        names = [f"signal_{k}" for k in range(signals)]
        segment = SimpleNamespace(
            name="MISSION", mode="mission", start_s=0.0, end_s=156.6, case=None,
            thresholds={n: 15.0 for n in names}, max_g={n: 1525.5 for n in names},
            b={n: 0 for n in names})
        return SimpleNamespace(b={n: 0 for n in names}, not_judged={}, segments=[segment])

    few = [line.text for line in _segment_table(report(3))]
    assert few[0].startswith("Columns per signal, in the order signal_0, signal_1, signal_2.")
    header, row = few[-2:]
    assert row.split() == ["MISSION", "mission", "0.0-156.6", *["15"] * 3, *["1525.5"] * 3,
                           *["0"] * 3, "-"]
    assert header.index("max g") == row.index("1525.5")       # the columns line up
    many = [line.text for line in _segment_table(report(14))]
    assert max(len(text) for text in many) <= columns(8.5, "monospace")
    assert "MISSION (mission, 0.0-156.6 s, case -)" in many
    assert many[-1].split() == ["signal_13", "15", "1525.5", "0"]
