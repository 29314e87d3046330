"""The validation harness: engines, scenarios, runner, metrics, reports and the CLI.

The theory lives in :mod:`planar_impact` (numpy only); everything here depends on it, never
the reverse. Engines and matplotlib are imported only by the commands that need them.
"""

__version__ = "0.1.0"
