"""Measured impacts as a source beside the laws: datasets (``registry``), the measured-impact
record (``records``), loaders (``fazeli``, ``kharaz``), the paper's error metric (``metric``),
the laws' predictions (``predict``), fitting (``fitting``), the comparison (``analysis``),
the engines on the drops and the Kharaz disk (``drops_engines``, ``engine_curves``),
calibration (``calibrate``), the report's aggregates (``aggregates``) and
``impact-harness experiments`` (``cli``)."""
