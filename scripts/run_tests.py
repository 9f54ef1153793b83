"""Run every notebook (nbdev_test) and tests/ (pytest); end with one line `N passed, N failed`.

Usage: python scripts/run_tests.py [--flags "slow"] [pytest args...]
A notebook counts as one test; each pytest test counts as one.
"""
import argparse, re, subprocess, sys, time
import xml.etree.ElementTree as ET
from pathlib import Path

root = Path(__file__).resolve().parent.parent
bindir = Path(sys.executable).parent


def run_notebooks(flags):
    cmd = [str(bindir / "nbdev_test"), "--do_print", "--timing", "--n_workers", "2"]
    if flags: cmd += ["--flags", flags]
    t0 = time.time()
    proc = subprocess.run(cmd, cwd=root, capture_output=True, text=True)
    sys.stdout.write(proc.stdout)
    sys.stderr.write(proc.stderr)
    started = re.findall(r"Starting (\S+?\.ipynb)", proc.stdout)  # not anchored: two workers can print on one line
    failed = []
    if "Failed On The Following Notebooks" in proc.stderr:
        tail = proc.stderr.split("Failed On The Following Notebooks", 1)[1]
        failed = re.findall(r"^\s+(\S+\.ipynb)\s*$", tail, flags=re.M)
    if proc.returncode and not failed: failed = ["nbdev_test"]  # crashed before reporting
    print(f"notebooks: {len(started) - len(failed)} passed, {len(failed)} failed in {time.time() - t0:.0f}s")
    return len(started) - len(failed), len(failed)


def run_pytest(extra):
    xml = root / ".pytest_cache" / "junit.xml"
    xml.parent.mkdir(exist_ok=True)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", f"--junitxml={xml}", "tests", *extra], cwd=root)
    if not xml.exists(): return 0, 1
    suites = ET.parse(xml).getroot()
    suites = [suites] if suites.tag == "testsuite" else list(suites)
    total = sum(int(s.get("tests", 0)) for s in suites)
    bad = sum(int(s.get("failures", 0)) + int(s.get("errors", 0)) for s in suites)
    skipped = sum(int(s.get("skipped", 0)) for s in suites)
    if proc.returncode not in (0, 1, 5) and bad == 0: bad = 1  # pytest itself broke
    return total - bad - skipped, bad


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--flags", default="", help="nbdev_test flags to run, e.g. 'slow'")
    args, extra = ap.parse_known_args()
    nb_ok, nb_bad = run_notebooks(args.flags)
    py_ok, py_bad = run_pytest(extra)
    print(f"{nb_ok + py_ok} passed, {nb_bad + py_bad} failed")
    sys.exit(1 if nb_bad + py_bad else 0)
