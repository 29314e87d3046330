"""Storage and identity, beneath everything that keeps or names what it made.

* :mod:`~harness.store.files` -- files written atomically, only ever over a regular file; why
  an output path cannot be written, said before any work.

Imports nothing of the harness but the shared tools (``harness.collector``).
"""
