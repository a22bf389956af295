"""`python -m auvdiag_cli` runs the command line."""

from auvdiag_cli.cli import main

main()
