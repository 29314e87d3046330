"""The survey: departure distributions over whole families of impacts.

Data flows through the modules in this order:

* :mod:`~harness.survey.population` -- population files (TOML under ``populations/``,
  format in docs/populations.md) read into frozen dataclasses;
* :mod:`~harness.survey.sampling` -- seeded draws of a population into checked
  :class:`harness.scene.Scene` objects;
* :mod:`~harness.survey.laws` -- every sample through every law in one
  ``planar_impact.solve_batch`` call per law;
* :mod:`~harness.survey.engines` -- every sample through an engine and preset (the one
  function to swap for a bulk path), and the bare-stepping timing;
* :mod:`~harness.survey.statistics` -- departures and their statistics per engine × preset
  × family × Poisson collision type;
* :mod:`~harness.survey.outputs` -- Parquet tables, the Markdown summary and the figures;
* :mod:`~harness.survey.cli` -- ``impact-harness survey``.
"""
