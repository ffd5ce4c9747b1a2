"""`python -m tidem` runs the command-line interface."""

from tidem.cli.commands import main

main()
