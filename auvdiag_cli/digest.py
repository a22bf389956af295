"""Content digests of logs (a file, or every file of a bag directory)."""

import hashlib
from pathlib import Path

CHUNK = 1 << 20


def log_digest(path: Path) -> str:
    """SHA-256 over the log's bytes; for a directory, over its files' names and bytes."""
    digest = hashlib.sha256()
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    for file in files:
        digest.update(file.relative_to(path).as_posix().encode() if path.is_dir() else b"")
        with file.open("rb") as stream:
            while block := stream.read(CHUNK):
                digest.update(block)
    return digest.hexdigest()
