"""Errors raised while reading a log (the shared tree lives in `auvdiag_errors`)."""

from auvdiag_errors import LogError

__all__ = ["LogError"]
