"""`python -m tidem` runs the command-line interface."""

from tidem.cli import app

app(prog_name="tidem")
