"scripts/partnet.py foliage end to end, tiny: weights, card and record; bad flags stop it before any work."
import json, subprocess, sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "partnet.py"


def run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), "foliage", *args], capture_output=True, text=True, cwd=ROOT)


def test_tiny_run(tmp_path):
    r = run("--per-species", "1", "--test-per-species", "1", "--skeleton-trees", "0", "--steps", "3", "--width", "8",
            "--work", str(tmp_path / "work"), "--out", str(tmp_path / "foliage.pt"), "--results", str(tmp_path / "foliage.json"))
    assert r.returncode == 0, r.stderr[-2000:]
    rec = json.loads((tmp_path / "foliage.json").read_text())
    assert rec["steps"] == 3 and rec["train_scans"] == 6 and rec["test_scans"] == 6
    assert 0 <= rec["held_out"]["accuracy"] <= 1
    assert "FoliageNet" in (tmp_path / "foliage.md").read_text()
    from treebook.foliage import load_foliage
    assert load_foliage(tmp_path / "foliage.pt").cfg["width"] == 8
    # run again: the pools are read from --work, the finished checkpoint is not trained further
    r = run("--per-species", "1", "--test-per-species", "1", "--skeleton-trees", "0", "--steps", "3", "--width", "8",
            "--work", str(tmp_path / "work"), "--out", str(tmp_path / "foliage.pt"), "--results", str(tmp_path / "foliage.json"))
    assert r.returncode == 0 and "training scans" not in r.stderr
    assert json.loads((tmp_path / "foliage.json").read_text())["steps"] == 3


@pytest.mark.parametrize("args", [["--steps", "0"], ["--skeleton-trees", "9"], ["--per-species", "-1"]])
def test_bad_flags(args, tmp_path):
    r = run(*args, "--work", str(tmp_path / "w"))
    assert r.returncode != 0 and "must be" in r.stderr
    assert not (tmp_path / "w").exists()
