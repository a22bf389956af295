"""The application's errors: the one tree every layer shares. Only the CLI prints these
and turns them into exit codes; audit workers record them as the log's error."""

from auvdiag_errors import AuvdiagError, LogError, ModelError, ProfileError, UsageError

__all__ = ["AuvdiagError", "LogError", "ModelError", "ProfileError", "UsageError"]
