"""The command line, `tidem ...` (Typer): the commands (commands), what they share (common), the
study commands (studies) and the last line of defence that turns an unexpected exception into one
line (crash). Layer 8, beside tidem.api: may import every layer below."""

from tidem.cli.commands import app, main

__all__ = ["app", "main"]
