"""auvdiag: offline model-based fault diagnosis of autonomous underwater vehicles."""

__version__ = "0.1.0"
