"benchmarks/reach.py --drop removes rows of results/reach.json and runs nothing; an unknown row is refused."
import json, subprocess, sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "reach.py"


def _run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True)


def test_drop(tmp_path):
    out = tmp_path / "reach.json"
    rows = {"elm": {"window": 0}, "elm-4000": {"window": 128}, "tulip": {"window": 0}}
    out.write_text(json.dumps({"far": 16, "seed": 0, "species": rows}))
    r = _run("--drop", "elm-4000", "--out", str(out))
    assert r.returncode == 0, r.stderr
    got = json.loads(out.read_text())
    assert list(got["species"]) == ["elm", "tulip"] and got["far"] == 16


def test_drop_unknown_row_changes_nothing(tmp_path):
    out = tmp_path / "reach.json"
    out.write_text(json.dumps({"far": 16, "seed": 0, "species": {"elm": {}}}))
    before = out.read_text()
    r = _run("--drop", "elm", "nothere", "--out", str(out))
    assert r.returncode != 0 and "no row nothere" in r.stderr
    assert out.read_text() == before
