"""Errors raised while reading a log. Messages name the file and the problem."""

from pathlib import Path


class LogError(Exception):
    """A log could not be read, or lacks what the profile needs."""

    def __init__(self, path: Path | str, problem: str) -> None:
        super().__init__(f"{path}: {problem}")
        self.path = Path(path)
        self.problem = problem
