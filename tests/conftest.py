"""Test-wide setup: this folder is on ``sys.path`` (pytest inserts a root conftest's folder),
so tests import the shared helper :mod:`realdata`."""

import os

# The first `afmforce analyze` after an install runs its kernels as Python and starts a background
# warmup (afmforce.cli._firstrun): a test run is not a user's first run. Commands the tests start
# compile as before, so no test's stderr depends on which test ran first, and no detached warmup
# outlives the suite; tests/cli/test_coldstart.py removes this to test the first run itself.
os.environ.setdefault("AFMFORCE_FIRST_RUN", "compile")
