"""Measured impacts as a source beside the laws: datasets (``registry``), the measured-impact
record (``records``), loaders (``fazeli``, ``kharaz``), the paper's error metric (``metric``),
the laws' predictions (``predict``), fitting (``fitting``), the comparison (``analysis``) and
``impact-harness experiments`` (``cli``)."""
