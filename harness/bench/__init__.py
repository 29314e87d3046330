"""``impact-harness bench``: solver throughput (:mod:`~harness.bench.solver`), engine overhead
against bare stepping (:mod:`~harness.bench.engines`) and run time against error
(:mod:`~harness.bench.accuracy`). The command line lives in :mod:`harness.bench.solver`."""
