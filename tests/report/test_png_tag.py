"""``figure_cache.png_tag`` reads the digest from the PNG's text chunk, as Pillow does."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness import plotting
from harness.report import figure_cache


def test_png_tag_reads_the_saved_digest_like_pillow(tmp_path):
    image = pytest.importorskip("PIL.Image")
    figure = plotting.new_figure(2, 2)
    figure.add_subplot().plot([0, 1], [1, 0])
    path = plotting.save_png(figure, tmp_path / "f.png", tag="d" * 64)
    assert figure_cache.png_tag(path) == "d" * 64
    with image.open(path) as opened:
        assert opened.text[plotting.TAG_KEY] == figure_cache.png_tag(path)
    untagged = plotting.save_png(figure, tmp_path / "g.png")
    assert figure_cache.png_tag(untagged) is None


def test_png_tag_of_missing_truncated_and_foreign_files_is_none(tmp_path):
    assert figure_cache.png_tag(tmp_path / "none.png") is None
    (tmp_path / "short.png").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00")
    assert figure_cache.png_tag(tmp_path / "short.png") is None
    (tmp_path / "text.png").write_text("not a png")
    assert figure_cache.png_tag(tmp_path / "text.png") is None


def test_figure_digests_cover_every_module_of_the_report_package():
    # a figure reads views (departure grids, labels) and history as well as figures.py: an
    # edit to views.py once left a stale heat map (its digest covered figures.py only)
    from harness.report import figure_cache, figures, history, views

    code = figure_cache.code_digest()
    for module in (figures, figure_cache, views, history):
        assert Path(module.__file__).read_bytes() in code


def test_figure_digests_cover_the_preset_names_users_see(monkeypatch):
    # titles and legends show preset_label's names (harness/engines/preset_names): a rename
    # redraws
    from harness.engines import preset_names
    from harness.report import figure_cache

    figure_cache.code_digest.cache_clear()  # computed once per process
    before = figure_cache.code_digest()
    monkeypatch.setitem(preset_names._PRESET_NAMES, "pymunk", {"accurate": "renamed"})
    figure_cache.code_digest.cache_clear()
    try:
        assert figure_cache.code_digest() != before
    finally:
        monkeypatch.undo()
        figure_cache.code_digest.cache_clear()
