"""The errors a user can act on, for every layer: the log readers (`adapters`), the model
store (`models`) and the application (`auvdiag_cli`) all raise these, so one ``except
AuvdiagError`` separates "this input cannot be used" (exit status 2, one line) from a bug.

Each message is one line that names the file (or option) and the problem. Third-party
exceptions are wrapped at the boundary where they arise, ``from None``."""

from pathlib import Path

MAX_PROBLEM_CHARS = 400


def one_line(text: str, limit: int = MAX_PROBLEM_CHARS) -> str:
    """``text`` on one line (a wrapped library message may span many), cut to ``limit``."""
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[:limit - 1] + "…"


class AuvdiagError(Exception):
    """Root of every error caused by the input: a log, a profile, a model, an option."""


class LogError(AuvdiagError):
    """A log could not be read, or lacks what the profile needs."""

    def __init__(self, path: Path | str, problem: str) -> None:
        self.path = Path(path)
        self.problem = one_line(problem)
        super().__init__(f"{path}: {self.problem}")


class LogNotOperating(LogError):
    """The vehicle never operates in the log (never armed, or idle throughout): there is
    nothing in it to judge or to learn from."""


class ProfileError(AuvdiagError):
    """A vehicle profile does not validate; the message names the key."""


class ModelError(AuvdiagError):
    """A model directory is missing, unreadable, or does not fit the log."""


class CompanionError(AuvdiagError):
    """A file that goes with a log (its mission plan) is missing or unreadable; the message
    names it."""


class DerivationError(AuvdiagError):
    """The pattern table cannot be derived from what was given: no mission to fly the
    faults on, or a log with nothing to replay."""


class UsageError(AuvdiagError):
    """The options given do not make sense together, or a file given is not what the
    command expects (e.g. a JSON that is not an auvdiag report)."""


__all__ = ["AuvdiagError", "CompanionError", "DerivationError", "LogError", "LogNotOperating",
           "ModelError", "ProfileError", "UsageError", "one_line"]
