"""The package version (stored in every store and recording)."""

__version__ = "0.11.0"
