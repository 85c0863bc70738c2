"""Test-wide setup: this folder is on ``sys.path`` (pytest inserts a root conftest's folder),
so tests import the shared helper :mod:`realdata`."""
