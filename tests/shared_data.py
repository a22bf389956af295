"""Where the real logs lie beside the checkout (../shared/data). A test that reads them is
marked `@pytest.mark.shared_data("haizhe/train")`: where that folder is absent (a fresh
clone has none) it is skipped with the reason, and the summary says how many such tests
ran (conftest)."""

from pathlib import Path

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
