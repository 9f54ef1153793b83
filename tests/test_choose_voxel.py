"benchmarks/choose_voxel.py refuses bad flags before any work."
import subprocess, sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "choose_voxel.py"


@pytest.mark.parametrize("args, says", [(["--fractions", "a,b"], "numbers"), (["--fractions", "0.2"], "[0, 0.05)"),
                                        (["--trees-per-species", "0"], ">= 1")])
def test_bad_flags(args, says, tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(tmp_path / "v.json")], capture_output=True, text=True)
    assert r.returncode != 0 and says in r.stderr
    assert not (tmp_path / "v.json").exists()
