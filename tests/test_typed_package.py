"""A user's program type-checks against the installed package: the packages ship
`py.typed`, and the library's values are typed for the user's checker."""

import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = '''\
from pathlib import Path

from auvdiag_cli import api

profile = api.load_profile("bluerov2")
model = api.load_model(profile=profile)
diagnosis = api.diagnose(Path("dive.tlog"), profile, model)
verdict: str = diagnosis.verdict
delay: float | None = diagnosis.detected_at_s
text: str = api.summary_text(diagnosis)
'''


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The package installed (not in development mode) into a bare virtual environment:
    a type checker finds it there only through its `py.typed` markers."""
    home = tmp_path_factory.mktemp("installed")
    venv.create(home / "venv", with_pip=False)
    python = home / "venv" / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], capture_output=True, text=True, check=True)
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                    "--no-build-isolation", "--target", site.stdout.strip(), str(ROOT)],
                   check=True, capture_output=True)
    return home, python


def _mypy(home: Path, python: Path, program: str) -> subprocess.CompletedProcess[str]:
    source = home / "program.py"
    source.write_text(program)
    return subprocess.run([sys.executable, "-m", "mypy", "--python-executable", str(python),
                           "--no-incremental", "--strict", str(source)],
                          capture_output=True, text=True, cwd=home)


def test_a_users_program_type_checks_against_the_installed_package(installed):
    home, python = installed
    result = _mypy(home, python, PROGRAM)
    assert result.returncode == 0, result.stdout


def test_a_users_type_error_is_caught(installed):
    home, python = installed
    result = _mypy(home, python, PROGRAM + "wrong: int = diagnosis.component\n")
    assert result.returncode == 1
    assert 'has type "str | None", variable has type "int"' in result.stdout
