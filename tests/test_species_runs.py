"""A model per species (chapter 05a): the GPU script on the CPU (DEVICE=cpu, two species, tiny settings), its tars
unpacked and shipped by scripts/ship_elm.py; a dataset that needs no trimesh; `make species`' commands."""
import json, os, subprocess, sys
from pathlib import Path
import pytest
from treebook.species_runs import run_status, unpack_run

ROOT = Path(__file__).resolve().parent.parent
TINY = ["--trees", "60", "--max-branches", "30", "--dim", "16", "--depth", "5", "--heads", "2", "--batch-size", "4",
        "--val-trees", "4", "--warmup", "20", "--probe", "20"]


def test_gpu_script_on_the_cpu_then_ship(tmp_path):
    path = f"{Path(sys.executable).parent}:{os.environ['PATH']}"          # python3: this environment's
    env = dict(os.environ, DEVICE="cpu", TREEBOOK_COMMIT="0123abc", PATH=path)
    r = subprocess.run(["bash", "scripts/gpu.sh", "species", "70", str(tmp_path / "out"), "elm", "shadbush", *TINY,
                        "--root", str(tmp_path / "runs"), "--data-root", str(tmp_path / "data")],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == ["elm.tar", "log.txt", "shadbush.tar"]
    assert all((out / f"{n}.tar").stat().st_size < 16 * 2**20 for n in ("elm", "shadbush"))   # a lent machine's limit
    log = (out / "log.txt").read_text()
    assert "probe: 20 steps" in log and "exit 0" in log, log
    run = unpack_run(out / "shadbush.tar", tmp_path / "back")
    st = run_status(run)
    assert st["done"] and not st["weights"] and st["step"] > 20 and "2 runs side by side" in st["device"]
    e = subprocess.run([sys.executable, "scripts/ship_elm.py", "--species", "shadbush", "--run", str(run), "--data",
                        str(tmp_path / "data" / "shadbush"), "--n-samples", "4", "--n-connect", "2", "--batch", "2",
                        "--workers", "1", "--threads", "1", "--no-ship", "--out-json", str(tmp_path / "eval.json")],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert e.returncode == 0, e.stderr[-2000:]
    res = json.loads((tmp_path / "eval.json").read_text())
    assert res["species"] == "shadbush" and res["data"]["max_branches"] == 30 and res["run"]["last_step"] == st["step"]
    assert res["run"]["trained_by"].startswith("scripts/gpu.sh species 70 ") and res["run"]["commit"] == "0123abc"
    assert "runs side by side" in res["run"]["device"] and res["recipe"] == "make species SPECIES=shadbush"


def test_ship_refuses_another_species_data(tmp_path):
    from treebook.species_runs import species_data
    d = species_data("elm", tmp_path / "elm", n=4, workers=1, max_branches=8, progress=False)
    e = subprocess.run([sys.executable, "scripts/ship_elm.py", "--species", "spruce", "--run", str(tmp_path / "run"),
                        "--data", str(d), "--no-ship"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert e.returncode == 2 and e.stderr.strip().endswith("holds no spruce dataset"), e.stderr


def test_dataset_needs_no_trimesh(tmp_path):
    "The GPU machine has numpy, scipy and torch but not trimesh: a dataset without scans or images must not need it."
    code = ("import sys; sys.modules['trimesh'] = sys.modules['rtree'] = None\n"
            "from treebook.species_runs import species_data\n"
            f"species_data('spruce', {str(tmp_path / 's')!r}, n=3, workers=1, max_branches=20, progress=False)\n"
            "assert 'treebook.scan' not in sys.modules")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]


def test_make_species_commands():
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}   # under make test too
    r = subprocess.run(["make", "-n", "--no-print-directory", "species", "SPECIES=hickory"], cwd=ROOT,
                       capture_output=True, text=True, env=env)
    lines = [l for l in r.stdout.replace("\\\n", "").splitlines() if not l.startswith("make")]
    assert "-m treebook.species_runs data hickory --trees 10000 --workers 2" in lines[0]
    assert "-m treebook.species_runs train hickory --run runs/hickory --threads 2 --time-limit 6000" in lines[1]
    assert "scripts/ship_elm.py --species hickory --run runs/hickory" in lines[2] and \
        '--recipe "make species SPECIES=hickory"' in lines[2]


def test_recipe_flags_round_trip(tmp_path):
    "The command `gpu_runs` writes for a run parses back to the same recipe, switches (--ends) included."
    from treebook.species_runs import RECIPE, _train_cmd, parser
    for recipe in ({"window": 128, "ends": True, "steps": 50}, {"window": 64}, {"ends": False, "lr": 1e-3},
                   {"order": "bfs", "arch": "hg2r"}, {"order": "hilbert", "steps": 20}):
        argv = _train_cmd("spruce", tmp_path / "r", tmp_path / "d", "cpu", 1, recipe)[3:]
        a = parser().parse_args(argv)
        got = {k: getattr(a, k) for k in RECIPE if getattr(a, k, None) is not None}
        assert got == {k: v for k, v in recipe.items() if v is not False}, (argv, got)
    assert parser().parse_args(["train", "elm"]).ends is None                    # unset: the recipe's False
    assert parser().parse_args(["train", "elm"]).order is None                   # unset: the recipe's dfs
    with pytest.raises(SystemExit): parser().parse_args(["train", "elm", "--order", "random"])   # not an order
