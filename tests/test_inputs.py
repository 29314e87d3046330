"""Bad input is exit 2 with one line, never exit 3 or a hang (issue 23 item 7): each of the
issue's reproducers, through ``impact-harness``'s ``main`` in this process, and the reader
of :mod:`harness.inputs` itself."""

from __future__ import annotations

import json
import os
import threading

import pytest

from harness import cli, inputs
from harness.scenarios import SCENARIO_DIR

DISK = SCENARIO_DIR / "disk-direct.toml"
POPULATION = SCENARIO_DIR.parent / "populations" / "disk-disk.toml"


def one_line_exit_2(status, capsys, *words) -> str:
    said = capsys.readouterr()
    text = said.out + said.err
    assert status == 2, text
    assert "internal error" not in text and "Traceback" not in text
    lines = [line for line in said.err.splitlines() if line.strip()]
    assert len(lines) == 1 or said.err == "", said.err  # validate says it on stdout
    for word in words:
        assert word in text, text
    return text


def deep_scenario(tmp_path, depth=1200):
    path = tmp_path / "deep.toml"
    path.write_text(DISK.read_text(encoding="utf-8") + "\n[engine_settings]\nx = "
                    + "[" * depth + "]" * depth + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("command", ["validate", "run", "survey"])
def test_nesting_1200_deep_is_one_line_exit_2(tmp_path, capsys, command):
    path = deep_scenario(tmp_path)
    argv = {"validate": ["validate", str(path)],
            "run": ["run", str(path), "--no-cache", "--json", str(tmp_path / "r.json")],
            "survey": ["survey", str(path), "--out", str(tmp_path / "s")]}[command]
    one_line_exit_2(cli.main(argv), capsys, "deep.toml", "nested too deep")


def test_nesting_deep_in_a_results_file_is_one_line_exit_2(tmp_path, capsys):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 5000 + "]" * 5000, encoding="utf-8")
    one_line_exit_2(cli.main(["compare", str(deep), str(deep)]), capsys, "deep.json")


def test_a_non_utf8_population_file_is_one_line_exit_2(tmp_path, capsys):
    path = tmp_path / "latin1.toml"
    path.write_bytes(POPULATION.read_text(encoding="utf-8").replace(
        "description", "# caf\xe9\ndescription").encode("latin-1"))
    one_line_exit_2(cli.main(["survey", str(path), "--out", str(tmp_path / "s")]), capsys,
                    "latin1.toml", "not UTF-8")


@pytest.mark.parametrize("command", ["validate", "compare"])
def test_dev_zero_and_a_fifo_are_refused_not_read(tmp_path, capsys, command):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for endless in ("/dev/zero", str(fifo)):
        argv = ["validate", endless] if command == "validate" else ["compare", endless, endless]
        finished = []
        worker = threading.Thread(target=lambda done=finished, line=argv: done.append(
            cli.main(line)), daemon=True)
        worker.start()
        worker.join(timeout=20)
        if worker.is_alive():  # unblock the reader, or the test process hangs at exit
            with open(fifo, "wb"):
                pass
            pytest.fail(f"impact-harness {' '.join(argv)} never finished")
        one_line_exit_2(finished[0], capsys, "not a regular file")


def test_a_file_over_the_size_cap_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("IMPACT_HARNESS_MAX_INPUT_BYTES", "100")
    one_line_exit_2(cli.main(["validate", str(DISK)]), capsys, "larger than the 100 bytes",
                    "IMPACT_HARNESS_MAX_INPUT_BYTES")


@pytest.mark.parametrize("out", ["a-file", "/dev/null"])
def test_survey_out_at_a_file_or_device_is_one_line_exit_2(tmp_path, capsys, out):
    (tmp_path / "a-file").write_text("x")
    out = out if out.startswith("/") else str(tmp_path / out)
    one_line_exit_2(cli.main(["survey", "disk-disk", "--samples", "2", "--out", out]), capsys,
                    "--out", "not a directory")
    assert (tmp_path / "a-file").read_text() == "x"


def test_a_too_long_json_path_is_one_line_exit_2(tmp_path, capsys):
    one_line_exit_2(cli.main(["run", str(DISK), "--json", str(tmp_path / ("a" * 300))]),
                    capsys, "--json", "File name too long")


@pytest.fixture(scope="module")
def results_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("results") / "r.json"
    assert cli.main(["run", str(DISK), "--engines", "pymunk", "--preset", "defaults",
                     "--no-cache", "--json", str(path)]) == 0
    return path


def test_compare_csv_at_a_directory_is_one_line_exit_2(tmp_path, capsys, results_file):
    one_line_exit_2(cli.main(["compare", str(results_file), str(results_file), "--csv",
                              str(tmp_path)]), capsys, "--csv", "not a regular file")


@pytest.mark.parametrize("damage", ["not a dict", "missing fields", "speeds not numbers",
                                    "records not a list"])
def test_compare_on_malformed_records_is_one_line_exit_2(tmp_path, capsys, results_file,
                                                         damage):
    document = json.loads(results_file.read_text(encoding="utf-8"))
    if damage == "not a dict":
        document["records"][0] = "x"
    elif damage == "missing fields":
        document["records"][0] = {"scenario": 5}
    elif damage == "speeds not numbers":
        for record in document["records"]:
            record["u_after"] = ["a", "b", "c"]
    else:
        document["records"] = {"a": 1}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    one_line_exit_2(cli.main(["compare", str(results_file), str(bad)]), capsys)


def test_the_reader_refuses_directories_and_reads_regular_files(tmp_path):
    with pytest.raises(inputs.InputError, match="is a directory"):
        inputs.read_bytes(tmp_path)
    (tmp_path / "f").write_bytes(b"abc")
    assert inputs.read_bytes(tmp_path / "f") == b"abc"
    with pytest.raises(inputs.InputError, match="byte 0xff at offset 1"):
        inputs.decode(b"a\xff")


def test_depth_is_counted_without_recursion():
    inputs.check_depth({"a": [[1]]}, most=3)
    with pytest.raises(inputs.InputError, match="at most 3 deep"):
        inputs.check_depth({"a": [[[1]]]}, most=3)
    deep: list = []
    for _ in range(100_000):  # far past the recursion limit
        deep = [deep]
    with pytest.raises(inputs.InputError):
        inputs.check_depth(deep)


@pytest.mark.parametrize("command", [["report"], ["paper"], ["stress", "--quick"],
                                     ["bench", "--quick"], ["suite"], ["survey"],
                                     ["new", "draft"]])
@pytest.mark.parametrize("out", ["a-file", "/dev/null", "n" * 300])
def test_every_commands_out_at_a_file_a_device_or_a_bad_name_is_one_line_exit_2(
        tmp_path, capsys, command, out):
    (tmp_path / "a-file").write_text("x")
    out = out if out.startswith("/") else str(tmp_path / out)
    one_line_exit_2(cli.main([*command, "--out", out]), capsys, "--out")
    assert (tmp_path / "a-file").read_text() == "x"
