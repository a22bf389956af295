"""A mutation fuzzer for the log readers: valid logs of every format, damaged in the ways
field logs are, each run through `inspect`, `init-profile` and `diagnose` in a child process
with limits.

``python -m auvdiag_cli.fuzz --help`` runs it; the test suite runs a short seeded campaign,
``benchmarks/fuzz.py`` a long one."""
