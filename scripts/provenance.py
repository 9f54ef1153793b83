"""Which commit a script's results come from, for the records in results/ and the model cards."""
import os, subprocess
from pathlib import Path

def commit(short: bool = False) -> str:
    """$TREEBOOK_COMMIT where it is set (a copy of the tree on another machine, whose git history may be stale, as on the
    lent GPU machines), else the checkout's HEAD; "unknown" without either."""
    c = os.environ.get("TREEBOOK_COMMIT", "")
    if not c:
        try: c = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=Path(__file__).resolve().parent).stdout.strip()
        except OSError: c = ""
    return (c[:7] if short else c) or "unknown"
