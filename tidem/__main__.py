"""`python -m tidem` runs the command-line interface."""

from tidem.cli import main

main()
