"benchmarks/check_trees.py refuses bad flags before any work."
import json, subprocess, sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "check_trees.py"


@pytest.mark.parametrize("args, says", [(["--trees-per-species", "0"], ">= 1"), (["--first-seed", "7100"], ">= 7300")])
def test_bad_flags(args, says, tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(tmp_path / "t.json")], capture_output=True, text=True)
    assert r.returncode != 0 and says in r.stderr
    assert not (tmp_path / "t.json").exists()
