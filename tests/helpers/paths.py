"""Where the project and the shared data sets are, independent of the test file's depth."""

from __future__ import annotations

from pathlib import Path

# tests/helpers/paths.py -> parents: [0] tests/helpers, [1] tests, [2] the project.
PROJECT_ROOT = Path(__file__).resolve().parents[2]
SHARED_DATA = PROJECT_ROOT.parent / "shared" / "data"
