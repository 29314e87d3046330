"""The cache's seal (issue 37, item 4): a header or body edited after it was written, even
with its SHA-256 recomputed, is a miss and is computed again; a key file that cannot be
believed makes the whole cache a miss and is never written through."""

from __future__ import annotations

import hashlib
import json
import os
import re

import pytest

from harness import cli
from harness.scenarios import SCENARIO_DIR
from harness.store.cache import ResultCache
from harness.store.packs import PACK_DIRECTORY
from harness.store.passed_checks import PassedChecks
from harness.store.sealing import KEY_FILE, KeyProblem, Seal


def _forge_single(path) -> None:
    """Replace an entry's record, its SHA-256 recomputed, its seal kept: what a forger
    without the key can do."""
    head, _, _ = path.read_bytes().partition(b"\n")
    header = json.loads(head)
    body = json.dumps({"status": "ok", "forged": True}).encode()
    header["sha256"] = hashlib.sha256(body).hexdigest()
    path.write_bytes(json.dumps(header).encode() + b"\n" + body)


def test_a_key_is_made_once_with_mode_0600_and_kept(tmp_path):
    cache = ResultCache(tmp_path / "c", version="v")
    cache.put(cache.key({"n": 1}), {"status": "ok"})
    key_file = tmp_path / "c" / KEY_FILE
    assert (os.stat(key_file).st_mode & 0o777) == 0o600
    assert re.fullmatch(rb"[0-9a-f]{64}", key_file.read_bytes())
    first = key_file.read_bytes()
    other = ResultCache(tmp_path / "c", version="v")
    other.put(other.key({"n": 2}), {"status": "ok"})
    assert key_file.read_bytes() == first  # a second writer uses it, never replaces it
    assert not [name for name in os.listdir(tmp_path / "c") if name.endswith(".tmp")]


def test_a_forged_body_with_its_checksum_recomputed_is_a_miss(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    key = cache.key({"n": 1})
    cache.put(key, {"status": "ok", "forged": False})
    _forge_single(cache.path(key))
    again = ResultCache(tmp_path, version="v")
    assert again.get(key) is None
    assert len(again.rejected) == 1 and "seal does not verify" in again.rejected[0]


def test_a_forged_pack_is_a_miss_for_every_record(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    items = [(cache.key({"n": n}), {"status": "ok", "n": n}) for n in range(3)]
    cache.put_many(items)
    (pack,) = (tmp_path / PACK_DIRECTORY).glob("*.pack")
    head, _, rest = pack.read_bytes().partition(b"\n")
    header = json.loads(head)
    body = json.dumps({"status": "ok", "n": 99}).encode()
    bodies = [body, rest[header["sizes"][0]:]]
    header["sizes"] = [len(body), *header["sizes"][1:]]
    header["sha256"][0] = hashlib.sha256(body).hexdigest()
    pack.write_bytes(json.dumps(header).encode() + b"\n" + b"".join(bodies))
    again = ResultCache(tmp_path, version="v")
    assert all(again.get(key) is None for key, _ in items)
    assert any("seal does not verify" in line for line in again.rejected)


def test_an_entry_sealed_by_another_cache_is_not_believed(tmp_path):
    mine, theirs = ResultCache(tmp_path / "mine", version="v"), ResultCache(tmp_path / "t",
                                                                            version="v")
    key = mine.key({"n": 1})
    mine.put(key, {"status": "ok"})
    theirs.put(key, {"status": "ok", "theirs": True})
    mine.path(key).write_bytes(theirs.path(key).read_bytes())  # a whole entry copied over
    again = ResultCache(tmp_path / "mine", version="v")
    assert again.get(key) is None and "seal does not verify" in again.rejected[0]


@pytest.mark.parametrize("damage", ["mode-0644", "link", "not-hex", "missing"])
def test_a_key_that_cannot_be_believed_makes_every_entry_a_miss(tmp_path, damage):
    cache = ResultCache(tmp_path / "c", version="v")
    key = cache.key({"n": 1})
    cache.put(key, {"status": "ok"})
    key_file = tmp_path / "c" / KEY_FILE
    if damage == "mode-0644":
        key_file.chmod(0o644)
    elif damage == "link":
        (tmp_path / "elsewhere").write_bytes(key_file.read_bytes())
        key_file.unlink()
        key_file.symlink_to(tmp_path / "elsewhere")
    elif damage == "not-hex":
        key_file.write_bytes(b"z" * 64)
    else:
        key_file.unlink()
    before = sorted(os.listdir(tmp_path / "c" / key[:2]))
    again = ResultCache(tmp_path / "c", version="v")
    assert again.get(key) is None
    if damage == "missing":  # no key: nothing believed, and the next write makes a new one
        again.put(again.key({"n": 2}), {"status": "ok"})
        assert (os.stat(key_file).st_mode & 0o777) == 0o600
        return
    assert len(again.rejected) == 1 and "nothing in the cache is believed" in again.rejected[0]
    again.put(again.key({"n": 2}), {"status": "ok"})  # never written with an untrusted key
    assert sorted(os.listdir(tmp_path / "c" / key[:2])) == before
    with pytest.raises(KeyProblem):
        Seal(tmp_path / "c").key(create=True)


def test_a_key_planted_in_the_checks_store_skips_nothing(tmp_path):
    store = PassedChecks(tmp_path / "c")
    store.add(store.key("good text"))
    store.save()
    stored = json.loads(store.path.read_text())
    stored["passed"].append(hashlib.sha256(b"\0bad text").hexdigest())  # the planted key
    store.path.write_text(json.dumps(stored))
    again = PassedChecks(tmp_path / "c")
    assert not again.passed(again.key("good text")) and not again.passed(again.key("bad text"))
    assert again.problems and "seal does not verify" in again.problems[0]


def test_a_gate_flipped_to_pass_in_a_cached_header_still_fails_the_run(tmp_path, capsys):
    strict = tmp_path / "strict.toml"
    strict.write_text((SCENARIO_DIR / "rod-45-slip-reversal.toml").read_text().replace(
        'name = "rod-45-slip-reversal"', 'name = "strict-rod"')
        + '"pymunk.defaults" = { law = "poisson", max_departure = 1e-12 }\n')
    argv = ["run", str(strict), "--engines", "pymunk", "--preset", "defaults", "--workers", "1",
            "--cache-dir", str(tmp_path / "c"), "--json", str(tmp_path / "r.json")]
    assert cli.main(argv) == 1
    (entry,) = (tmp_path / "c").glob("??/*.jsonl")
    head, _, rest = entry.read_bytes().partition(b"\n")
    header = json.loads(head)
    assert "FAIL" in [gate["status"] for gate in header["summary"]["gates"]]
    for gate in header["summary"]["gates"]:
        gate["status"] = "pass"
    entry.write_bytes(json.dumps(header).encode() + b"\n" + rest)
    capsys.readouterr()
    assert cli.main(argv) == 1  # the forged summary is a miss: the records are built again
    assert "seal does not verify" in capsys.readouterr().err
