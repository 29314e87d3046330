"""The report's "Against experiments" section without the Fazeli data (issue 25, item 7)."""

import os

from harness.report import experiments
from harness.report.figures import png_tag


def test_section_without_data_shows_kharaz_and_where_to_get(tmp_path, monkeypatch):
    monkeypatch.delenv("IMPACT_HARNESS_FAZELI_DIR", raising=False)
    html = experiments.experiments_section(tmp_path)
    assert "id='experiments'" in html
    assert "github.com/mcubelab/planar-impact-dataset" in html
    assert "digitised" in html and "write_usr0.f" in html  # the points' source is cited
    figure = tmp_path / "figures" / experiments.KHARAZ_FIGURE
    assert figure.is_file() and figure.with_suffix(".svg").is_file()
    tag = png_tag(figure)
    assert tag
    before = os.stat(figure).st_mtime_ns
    experiments.experiments_section(tmp_path)  # same inputs: not redrawn
    assert os.stat(figure).st_mtime_ns == before and png_tag(figure) == tag


def test_section_with_a_directory_names_it(tmp_path, monkeypatch):
    data = tmp_path / "data"
    data.mkdir()
    monkeypatch.setenv("IMPACT_HARNESS_FAZELI_DIR", str(data))
    html = experiments.experiments_section(tmp_path / "out")
    assert str(data) in html and "mcubelab" not in html
