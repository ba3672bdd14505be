"""Bundled example scenes (package data, read with importlib.resources)."""
