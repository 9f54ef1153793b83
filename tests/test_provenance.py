"The commit that scripts/provenance.py writes into results/ and model cards."
import json, sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance


def fake_git(head: str, status: str):
    return lambda *args: head if args[0] == "rev-parse" else status


def test_environment_wins(monkeypatch):
    monkeypatch.setenv("TREEBOOK_COMMIT", "0123456789abcdef")
    monkeypatch.setattr(provenance, "_git", fake_git("ffffffffffff", " M nbs/00_tree.ipynb"))
    assert provenance.commit() == "0123456789abcdef" and provenance.commit(short=True) == "0123456"


@pytest.mark.parametrize("status, suffix", [("", ""), (" M nbs/09a_partnet.ipynb", "+modified")])
def test_head_and_modified(monkeypatch, status, suffix):
    monkeypatch.delenv("TREEBOOK_COMMIT", raising=False)
    monkeypatch.setattr(provenance, "_git", fake_git("abcdef0123456789", status))
    assert provenance.commit(short=True) == "abcdef0" + suffix
    assert provenance.commit() == "abcdef0123456789" + suffix


def test_no_git(monkeypatch):
    monkeypatch.delenv("TREEBOOK_COMMIT", raising=False)
    monkeypatch.setattr(provenance, "_git", lambda *args: "")
    assert provenance.commit() == "unknown"


def test_outputs_do_not_count(monkeypatch):
    "The status query leaves out results/ and the shipped weights, which the scripts write themselves."
    monkeypatch.delenv("TREEBOOK_COMMIT", raising=False)
    seen = []
    monkeypatch.setattr(provenance, "_git", lambda *args: seen.append(args) or ("abc1234" if args[0] == "rev-parse" else ""))
    provenance.commit()
    status = [a for a in seen if a[0] == "status"][0]
    assert ":!results" in status and ":!treebook/data/weights" in status


def test_record(monkeypatch, tmp_path):
    "A script's record: command, commit, time and machine first, then its numbers; written whole."
    monkeypatch.setenv("TREEBOOK_COMMIT", "0123456789abcdef")
    monkeypatch.setattr(sys, "argv", ["x.py", "--n", "3"])
    res = provenance.record("scripts/x.py", {"score": 0.5, "command": "kept"}, tmp_path / "r" / "x.json", threads=2)
    back = json.loads((tmp_path / "r" / "x.json").read_text())
    assert back == res and list(back)[:4] == ["command", "commit", "time", "machine"]
    assert back["command"] == "kept" and back["commit"] == "0123456789abcdef" and back["score"] == 0.5
    assert back["machine"]["threads"] == 2 and not list((tmp_path / "r").glob(".*.part"))
    res = provenance.record("scripts/x.py", {"score": 1}, tmp_path / "y.json")
    assert res["command"] == "python scripts/x.py --n 3"


def test_rows_kept_only_with_the_same_settings(monkeypatch, tmp_path):
    "A benchmark that writes row by row keeps the rows of an earlier call made with the same settings, and no others."
    monkeypatch.setenv("TREEBOOK_COMMIT", "0123456789abcdef")
    monkeypatch.setattr(sys, "argv", ["b.py", "--species", "elm"])
    out = tmp_path / "b.json"
    assert provenance.kept_rows(out, n=2) == {}   # no record yet
    row = {"x": 1} | provenance.stamp("benchmarks/b.py")
    assert row["command"] == "python benchmarks/b.py --species elm" and row["commit"] == "0123456789abcdef"
    res = provenance.write_rows(out, {"elm": row}, n=2, seed=0)
    assert json.loads(out.read_text()) == res == {"n": 2, "seed": 0, "species": {"elm": row}}
    assert not list(tmp_path.glob(".*.part"))
    assert provenance.kept_rows(out, n=2, seed=0) == {"elm": row} == provenance.kept_rows(out, n=2)
    assert provenance.kept_rows(out, n=3, seed=0) == {}   # other settings: the rows are not comparable
    kept = provenance.kept_rows(out, n=2); kept["tulip"] = {}
    assert "tulip" not in provenance.kept_rows(out, n=2)   # a copy: adding rows writes nothing until write_rows
