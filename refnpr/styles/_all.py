"""Imports every style module so that each registers itself (used by the registry)."""

from . import smooth, toon  # noqa: F401
