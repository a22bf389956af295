"""The errors a user can act on, for every layer: the log readers (`adapters`), the model
store (`models`) and the application (`auvdiag_cli`) all raise these, so one ``except
AuvdiagError`` separates "this input cannot be used" (exit status 2, one line) from a bug.

Each message is one line that names the file (or option) and the problem. Third-party
exceptions are wrapped at the boundary where they arise, ``from None``."""

from pathlib import Path


class AuvdiagError(Exception):
    """Root of every error caused by the input: a log, a profile, a model, an option."""


class LogError(AuvdiagError):
    """A log could not be read, or lacks what the profile needs."""

    def __init__(self, path: Path | str, problem: str) -> None:
        super().__init__(f"{path}: {problem}")
        self.path = Path(path)
        self.problem = problem


class ProfileError(AuvdiagError):
    """A vehicle profile does not validate; the message names the key."""


class ModelError(AuvdiagError):
    """A model directory is missing, unreadable, or does not fit the log."""


class UsageError(AuvdiagError):
    """The options given do not make sense together, or a file given is not what the
    command expects (e.g. a JSON that is not an auvdiag report)."""


__all__ = ["AuvdiagError", "LogError", "ModelError", "ProfileError", "UsageError"]
