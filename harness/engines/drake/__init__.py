"""Drake adapter (pydrake 1.51.1).

Placeholder docstring, completed below.
"""

from __future__ import annotations

from harness.engines.drake.adapter import ENGINE_CLASS, DrakeEngine
from harness.engines.drake.presets import PRESETS, SETTING_DOCS
from harness.engines.drake.restitution import (
    MIN_RESTITUTION,
    discrete_dissipation,
    discrete_restitution,
    dissipation_for_restitution,
    restitution_of_dissipation,
)

__all__ = [
    "ENGINE_CLASS",
    "MIN_RESTITUTION",
    "PRESETS",
    "SETTING_DOCS",
    "DrakeEngine",
    "discrete_dissipation",
    "discrete_restitution",
    "dissipation_for_restitution",
    "restitution_of_dissipation",
]
