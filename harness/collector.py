"""Pausing Python's cyclic garbage collector around work that makes many containers.

Shared by the engines (:meth:`harness.engines.contract.Engine.run_many`), the run side
(:mod:`harness.run.records`, :mod:`harness.run.scenario_records`) and the store
(:mod:`harness.store.cache`), which must not depend on each other for it.
"""

from __future__ import annotations

import contextlib
import gc
from collections.abc import Iterator


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """The cyclic garbage collector off inside the block, as it was before after it.

    For work that builds many small containers none of which can be garbage yet (reading a
    results file; a batch of engine runs): each allocation threshold crossed would set the
    collector off to walk every container made so far, though it can free none of them.
    Reference counting still frees what is dropped; a cycle made inside is collected at the
    next collection after the block.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
