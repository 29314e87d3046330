"""Shared test configuration.

Hypothesis runs derandomized (the same examples on every run, here and in CI), so a
property test fails or passes for a reason in the code, never by the draw of a seed; set
``HYPOTHESIS_PROFILE=explore`` to search with fresh random examples.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, deadline=None)
settings.register_profile("explore", deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))
