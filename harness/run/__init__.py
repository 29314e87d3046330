"""Running scenarios: from a scenario to records, one way.

* :mod:`~harness.run.command` -- ``impact-harness run``: options checked, scenarios read, the
  results file written, the exit status;
* :mod:`~harness.run.runner` -- :func:`~harness.run.runner.run`, in named steps: every point
  through every law and engine, gates checked;
* :mod:`~harness.run.plan` -- engines and presets asked for, the engine runs and references
  to compute (the cache's misses);
* :mod:`~harness.run.tasks` -- what a worker computes: engine runs, chunks, references;
* :mod:`~harness.run.executor` -- the local process pool or a Dask cluster;
* :mod:`~harness.run.point_records` -- one sweep point's records (departures, verdicts);
* :mod:`~harness.run.scenario_records` -- a scenario's records built, kept whole, read back;
* :mod:`~harness.run.gates` -- ``[expect.gate]`` against the records;
* :mod:`~harness.run.metrics` -- departures of an engine from a law;
* :mod:`~harness.run.records` -- the records and the versioned results file;
* :mod:`~harness.run.provenance` -- versions, commit and machine, for every output file;
"""
