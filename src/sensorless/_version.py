"""The library version, in one place (imported by files that record it)."""

__version__ = "0.1.0"
