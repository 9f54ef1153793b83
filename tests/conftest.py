import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent


@pytest.fixture(scope="session")
def treebook_cmd():
    "The installed `treebook` console script of this environment."
    exe = BIN / "treebook"
    if not exe.exists(): pytest.fail(f"{exe} is missing: install the package first (make install)")
    return str(exe)


@pytest.fixture(scope="session")
def shared_scans():
    return ROOT.parent / "shared" / "data" / "scans"
