"""mkdocs hook: the pictures the documentation shows, drawn when the site is built from a
bundled sample log by the tool itself, so that no picture shows a report the tool no longer
writes. The paper's experiment (flow sensor covered at 115 s) is diagnosed with its ground
truth, and two pages of its PDF report are drawn as images: the sensors against the model,
and the residual index g against its threshold with the binary vector b."""

from io import BytesIO
from pathlib import Path

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

SAMPLE = Path("sample_logs") / "paper-flow-sensor-covered"
DPI = 90


def on_files(files: Files, config: MkDocsConfig) -> Files:
    import matplotlib

    matplotlib.use("Agg")
    from auvdiag_cli import api
    from auvdiag_cli.reports.pdf.plots import residual_page, sensors_page
    from auvdiag_cli.reports.series import series_from_diagnosis

    root = Path(config.config_file_path).parent
    log = root / SAMPLE
    profile = api.load_profile()
    diagnosis = api.diagnose(log, profile, api.load_model(profile=profile),
                             truth=log.with_name(f"{log.name}.truth.csv"))
    report, series = api.build_report(diagnosis), series_from_diagnosis(diagnosis)
    for name, draw in (("img/sample-sensors.png", sensors_page),
                       ("img/sample-residual.png", residual_page)):
        figure = draw(report, series)
        if figure is None:      # the sample's replay judges its signals: never here
            raise RuntimeError(f"{SAMPLE}: no page to draw {name} from")
        buffer = BytesIO()
        figure.savefig(buffer, format="png", dpi=DPI)
        files.append(File.generated(config, name, content=buffer.getvalue()))
    return files
