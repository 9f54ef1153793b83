"""Which commit a script's results come from, for the records in results/ and the model cards."""
import os, subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUTPUTS = ("results", "treebook/data/weights")   # what the scripts themselves write: changes there do not make a run's code differ


def _git(*args) -> str:
    try: return subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT).stdout.strip()
    except OSError: return ""


def commit(short: bool = False) -> str:
    """$TREEBOOK_COMMIT where it is set (a copy of the tree on another machine, whose git history may be stale, as on the
    lent GPU machines), else the checkout's HEAD, with "+modified" when tracked files other than the outputs (results/,
    the shipped weights) differ from it: the run's code was not exactly that commit. "unknown" without either."""
    c = os.environ.get("TREEBOOK_COMMIT", "")
    if c: return c[:7] if short else c
    c = _git("rev-parse", "HEAD")
    if not c: return "unknown"
    c = c[:7] if short else c
    if _git("status", "--porcelain", "--untracked-files=no", "--", ".", *(f":!{p}" for p in OUTPUTS)): c += "+modified"
    return c


def record(script: str, res: dict, out, **machine) -> dict:
    """`res` after the run's command (`script` and this process's arguments), commit, time and machine (`machine`
    adds to it), written as JSON to `out` (relative to the repository) by way of a temporary name; returns it."""
    import platform
    head = stamp(script) | {"machine": {"platform": platform.platform(), "cpus": os.cpu_count(), **machine}}
    return _write(head | res, out)


def _write(res: dict, out) -> dict:
    "`res` as JSON at `out` (relative to the repository), by way of a temporary name: a stopped call leaves the old."
    import json
    out = ROOT / out
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.part")
    tmp.write_text(json.dumps(res, indent=1)); tmp.replace(out)
    return res


def stamp(script: str) -> dict:
    "The command (`script` and this process's arguments), commit and time: a record's head, or a row's."
    import sys, time
    return {"command": " ".join(["python", script, *sys.argv[1:]]), "commit": commit(),
            "time": time.strftime("%Y-%m-%d %H:%M:%S")}


def kept_rows(out, **same) -> dict:
    """The rows (its "species") of the record at `out` (relative to the repository) if it was made with the settings
    `same`, so that a call which runs some rows keeps the others; else none."""
    import json
    out = ROOT / out
    old = json.loads(out.read_text()) if out.is_file() else {}
    return dict(old.get("species", {})) if all(old.get(k) == v for k, v in same.items()) else {}


def write_rows(out, rows: dict, **settings) -> dict:
    """The record `settings` with `rows` as its "species", written to `out` as `record` writes; returns it."""
    return _write(settings | {"species": rows}, out)
