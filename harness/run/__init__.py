"""Running scenarios: from a scenario to records, one way.

* :mod:`~harness.run.runner` -- ``impact-harness run``: every point through every law and
  engine, gates checked;
* :mod:`~harness.run.executor` -- the local process pool or a Dask cluster;
* :mod:`~harness.run.metrics` -- departures of an engine from a law;
* :mod:`~harness.run.records` -- the records and the versioned results file;
* :mod:`~harness.run.provenance` -- versions, commit and machine, for every output file;
"""
