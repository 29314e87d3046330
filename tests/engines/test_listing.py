"""``impact-harness engines`` (issue 39, item 9): every engine of the registry, whether it is
installed here and why not, its presets and its settings with units, values and bounds; an
engine added to the registry is listed with no change to the command."""

from __future__ import annotations

import pytest

from harness import bounds, cli
from harness import engines as registry
from harness.engines import EngineNotInstalled, listing
from tests.engines.toy_engine import ToyEngine


def test_every_registered_engine_is_listed_with_its_settings_and_bounds(capsys):
    assert cli.main(["engines"]) == 0
    out = capsys.readouterr().out
    for name in registry.engine_names():
        assert f"\n{name}: " in f"\n{out}"
        try:
            adapter = registry.engine_class(name)
        except EngineNotInstalled:
            continue
        block = out[out.index(f"{name}: "):]
        for key in adapter.setting_docs:
            assert f"    {key}" in block, (name, key)
            if key in bounds.BOUNDS:
                assert bounds.BOUNDS[key].allowed() in block, (name, key)
    assert "margin [m]: defaults 0, matched-bounce 0; allowed: a number, 0 <= value <= 100 m" \
        in out


def test_an_engine_registered_later_appears_without_a_change_here(capsys):
    registry.register_engine("toy", ToyEngine)
    try:
        text = listing.engines_text()
    finally:
        registry.unregister_engine("toy")
    assert "\ntoy: installed" in text
    for key in ToyEngine.setting_docs:
        assert f"    {key}" in text


def test_an_engine_not_installed_says_why(monkeypatch):
    real = registry.engine_class

    def missing_box2d(name):
        if name == "box2d":
            raise EngineNotInstalled("box2d", "cannot import Box2D")
        return real(name)

    monkeypatch.setattr(listing, "engine_class", missing_box2d)
    text = listing.engines_text()
    assert "box2d: NOT INSTALLED (engine 'box2d' is not installed (cannot import Box2D); " \
           "install it with `pip install" in text


def test_the_docs_table_of_bounds_is_the_one_the_code_holds():
    """docs/bounds.md is `impact-harness engines --bounds`: regenerate it after a change."""
    from pathlib import Path

    docs = Path(__file__).resolve().parents[2] / "docs" / "bounds.md"
    assert docs.read_text(encoding="utf-8") == listing.bounds_markdown(), (
        "docs/bounds.md is stale: `impact-harness engines --bounds > docs/bounds.md`")


@pytest.mark.parametrize("knob", sorted(bounds.BOUNDS))
def test_every_knob_is_a_row_of_the_docs_table(knob):
    assert f"| `{knob}` | {bounds.BOUNDS[knob].allowed()} |" in listing.bounds_markdown()
