"""The application's error tree. Only the CLI prints these and turns them into exit codes."""

from adapters.errors import LogError


class AuvdiagError(Exception):
    """Base of the errors a user can act on; the message is one line."""


class ProfileError(AuvdiagError):
    """A vehicle profile does not validate; the message names the key."""


class ModelError(AuvdiagError):
    """A model directory is missing, unreadable, or does not fit the log."""


class UsageError(AuvdiagError):
    """The options given do not make sense together."""


# Errors that mean "this input cannot be analysed" (exit status 2), not a bug.
INPUT_ERRORS: tuple[type[Exception], ...] = (AuvdiagError, LogError)
