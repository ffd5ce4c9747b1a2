"""tidem's version, in a module of its own so that modules can read it without importing the
package's public API (`tidem/__init__.py` imports `tidem.api`)."""

__version__ = "0.1.0"
