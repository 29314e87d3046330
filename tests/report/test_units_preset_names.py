"""Users see an engine's own name for a preset role (harness/engines/preset_names.py):
MuJoCo's ``accurate`` role is ``matched-bounce`` in every table of a generated report and
survey summary, never the role's name."""

from __future__ import annotations

import re

import pytest

from harness.cli import main
from harness.engines import preset_label
from harness.report.contacts import contacts_section
from harness.report.summary import write_summary
from harness.run import runner
from harness.run.records import Results
from harness.scenarios import load_scenario

pytest.importorskip("mujoco")

# "mujoco.accurate", "| mujoco | accurate |", "engine mujoco accurate": the role where the
# engine's name for it belongs
ROLE_AS_NAME = re.compile(r"mujoco\W{1,5}accurate\b")


def test_the_renamed_role_is_what_this_test_looks_for():
    assert preset_label("mujoco", "accurate") != "accurate"


def test_report_summary_and_contacts_tables_use_the_engines_preset_name(tmp_path):
    scenarios = [load_scenario("scenarios/flat-box.toml"),
                 load_scenario("scenarios/box-corner.toml")]
    outcome = runner.run(scenarios, engines=("mujoco",), presets=("defaults", "accurate"),
                         cache=None, workers=1, log=None)
    results = Results(records=outcome.records, provenance=outcome.provenance,
                      scenarios=outcome.scenarios)
    summary = write_summary(results, tmp_path).read_text(encoding="utf-8")
    html, _ = contacts_section(results)
    assert "mujoco.matched-bounce" in summary and "mujoco.matched-bounce" in html
    assert ROLE_AS_NAME.findall(summary) == [] and ROLE_AS_NAME.findall(html) == []


def test_survey_summary_uses_the_engines_preset_name_in_every_table(tmp_path):
    assert main(["survey", "spinning-disk", "--samples", "1", "--engines", "mujoco",
                 "--preset", "accurate", "--out", str(tmp_path), "--no-figures"]) == 0
    summary = (tmp_path / "summary.md").read_text(encoding="utf-8")
    assert "| mujoco | matched-bounce |" in summary
    assert ROLE_AS_NAME.findall(summary) == []
