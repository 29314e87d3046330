"""Storage and identity, beneath everything that keeps or names what it made.

* :mod:`~harness.store.files` -- files written atomically, only ever over a regular file; why
  an output path cannot be written, said before any work;
* :mod:`~harness.store.identity` -- canonical JSON of what a result depends on, and the
  version of the code that computed it;
* :mod:`~harness.store.cache` -- the content-addressed result cache;
* :mod:`~harness.store.packs` -- the cache's packs (many records in one file) and their index;
* :mod:`~harness.store.cache_directory` -- the cache's directory: its home, its marker, its
  upkeep;
* :mod:`~harness.store.passed_checks` -- the scenario texts that passed their checks;
* :mod:`~harness.store.cli` -- ``impact-harness cache info|prune|clear``.

Imports nothing of the harness but the shared tools (``harness.collector``) and
``planar_impact`` (whose source the code version hashes).
"""
