"""The README's commands run as written: every shell line of it names a Makefile target or
parses as the command line it is, and all but the suite's (``make``, ``run --tags``) are
run, in order, in a scratch copy of the repository's scenarios, with ``/tmp/`` read as a
scratch directory (its ``survey --quick`` once exited 2 there, refusing to replace the
suite's survey)."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from harness import cli

ROOT = Path(__file__).resolve().parents[1]
#: Commands run here (a scenario or two, the quick survey); ``run --tags`` (the suite's
#: scenarios, a report of them) is parsed only.
RUN = ("new", "validate", "run", "compare", "report", "survey")
#: The exit statuses a run of each may end with as the README shows it (``compare``: 1 when
#: a record moved by more than ``--fail-above``, as its example's do).
STATUSES = {"compare": (0, 1)}


def readme_commands() -> list[list[str]]:
    """Each command of the README's ``sh`` blocks as words: comments dropped, lines joined
    at a trailing backslash."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, re.M | re.S):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(words)
    return commands


def test_the_readme_has_the_two_commands_and_the_three_jobs():
    commands = [" ".join(words) for words in readme_commands()]
    assert commands[:2] == ["make validate", "make test"]
    named = {words[1] for words in readme_commands() if words[0].endswith("impact-harness")}
    assert {"run", "report", "compare", "new", "validate"} <= named


def test_every_readme_command_parses():
    targets = set(re.findall(r"^([a-z]+):", (ROOT / "Makefile").read_text(), re.M))
    for words in readme_commands():
        if words[0] == "make":
            assert set(words[1:]) <= targets, words
            continue
        assert words[0] == ".venv/bin/impact-harness", words  # the path make venv gives
        command, arguments = words[1], words[2:]
        assert command in cli.COMMANDS, words
        try:
            cli.build_parser(command).parse_args([command, *arguments])
        except SystemExit as error:  # argparse's way of refusing
            raise AssertionError(f"README: {' '.join(words)} does not parse") from error


def test_the_cheap_readme_commands_run_as_written(tmp_path):
    work = tmp_path / "work"
    shutil.copytree(ROOT / "scenarios", work / "scenarios")
    if (ROOT / "reports" / "survey").is_dir():  # as make validate leaves it
        shutil.copytree(ROOT / "reports" / "survey", work / "reports" / "survey")
    scratch = tmp_path / "tmp"
    program = Path(sys.executable).with_name("impact-harness")
    environment = {"IMPACT_HARNESS_CACHE_DIR": str(tmp_path / "cache"), "PATH": "/usr/bin:/bin"}
    ran = []
    for words in readme_commands():
        if words[0] == "make" or words[1] not in RUN or "--tags" in words or (
                words[1] == "report" and "/tmp/quick" in " ".join(words)):
            continue
        arguments = [word.replace("/tmp/", f"{scratch}/") for word in words[2:]]
        for word in arguments:  # a file it writes lands in a directory that exists
            if word.startswith(str(scratch)):
                Path(word).parent.mkdir(parents=True, exist_ok=True)
        done = subprocess.run([str(program), words[1], *arguments], cwd=work,
                              capture_output=True, text=True, env=environment, timeout=600)
        assert done.returncode in STATUSES.get(words[1], (0,)), (words, done.stderr[-2000:])
        ran.append(words[1])
    assert ran.count("run") >= 3 and set(RUN) <= set(ran)


if __name__ == "__main__":  # the commands the README shows, one a line
    for words in readme_commands():
        print(" ".join(words))
    pytest.main([__file__])
