"""Files written so that a reader never sees half of one."""

import json
from pathlib import Path
from typing import Any


def write_json(document: dict[str, Any], target: Path) -> None:
    """Write atomically: a reader never sees half a report."""
    text = json.dumps(document, indent=2) + "\n"
    temporary = target.with_name(f".{target.name}.tmp")
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(target)
