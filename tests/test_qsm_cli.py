"""`treebook qsm`: a folder of scans measured in this process, in worker processes and on a dask cluster alike; bad
files on one line; labels back on the points; a second run skipping what is done."""
import subprocess

import laspy
import numpy as np
import pytest

from treebook.pointio import read_fields
from treebook.qsm import CYLINDER_COLUMNS, example_in_metres, read_cylinders
from treebook.scan import scan


def run(cmd, *args):
    return subprocess.run([cmd, *map(str, args)], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def plot(tmp_path_factory):
    "Two scans of trees in metres (one as LAS in map coordinates), a broken file and a note."
    d = tmp_path_factory.mktemp("plot")
    for i in range(2):
        p = scan(example_in_metres(seed=i), n_points=15000, views=3, noise=0.0003, outliers=0.0, sides=24,
                 seed=i).points.astype(float)
        if i == 0: np.savetxt(d / "t0.xyz", p, fmt="%.4f")
        else:
            h = laspy.LasHeader(point_format=3, version="1.2"); h.offsets = [512000.0, 5400000.0, 200.0]
            h.scales = [0.001] * 3
            las = laspy.LasData(h); las.x, las.y, las.z = (p + h.offsets).T; las.write(d / "t1.las")
    (d / "broken.xyz").write_text("1 2 3\n")
    (d / "notes.md").write_text("not a scan")
    return d


def tables(out):
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.suffix in (".csv", ".json")}


@pytest.fixture(scope="module")
def one_by_one(plot, treebook_cmd, tmp_path_factory):
    out = tmp_path_factory.mktemp("q1")
    r = run(treebook_cmd, "qsm", plot, "--out", out, "--workers", 1, "--labels", "las")
    return out, r


def test_folder_with_a_bad_file(one_by_one, plot, treebook_cmd):
    out, r = one_by_one
    assert r.returncode == 2
    errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
    assert len(errors) == 1 and "broken.xyz" in errors[0]
    assert "2 measured, 0 already there, 1 failed, of 3 scans" in r.stdout
    for s in ("t0", "t1"):
        cyl = read_cylinders(out / f"{s}_cylinders.csv")
        assert list(cyl) == list(CYLINDER_COLUMNS) and len(cyl["radius"]) > 20
    rows = (out / "summary.csv").read_text().splitlines()
    assert rows[0].startswith("scan,tree,name,") and len(rows) == 3
    again = run(treebook_cmd, "qsm", plot, "--out", out, "--workers", 1)
    assert "0 measured, 2 already there, 1 failed" in again.stdout


def test_map_coordinates_and_labels(one_by_one, plot):
    out, _ = one_by_one
    cyl = read_cylinders(out / "t1_cylinders.csv")
    assert 511990 < cyl["start_x"][0] < 512010 and 5399990 < cyl["start_y"][0] < 5400010   # the scan's own frame
    lab, scan_ = laspy.read(out / "t1_labels.las"), laspy.read(plot / "t1.las")
    assert np.allclose(lab.header.offsets, scan_.header.offsets) and np.allclose(lab.header.scales, scan_.header.scales)
    f = read_fields(out / "t1_labels.las")
    assert f["cylinder"].max() == len(cyl["radius"]) and (f["tree"] == (f["cylinder"] > 0)).all()
    assert (f["cylinder"] > 0).mean() > 0.8


def test_workers_and_dask_measure_the_same(one_by_one, plot, treebook_cmd, tmp_path):
    out, _ = one_by_one
    two = tmp_path / "q2"
    run(treebook_cmd, "qsm", plot, "--out", two, "--workers", 2)
    assert tables(two) == tables(out)
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        r = run(treebook_cmd, "qsm", plot, "--out", tmp_path / "qd", "--scheduler", c.scheduler_address)
    assert r.returncode == 2 and tables(tmp_path / "qd") == tables(out)


def test_short_tree_and_empty_folder(treebook_cmd, tmp_path):
    p = scan(example_in_metres(height=1.0, base=0.02), n_points=5000, noise=0.0003, outliers=0.0, seed=0).points
    np.savetxt(tmp_path / "sapling.xyz", p, fmt="%.5f")
    r = run(treebook_cmd, "qsm", tmp_path / "sapling.xyz", "--out", tmp_path / "o")
    assert r.returncode == 2 and "needs a taller tree" in r.stderr and "Traceback" not in r.stderr
    (tmp_path / "none").mkdir()
    r = run(treebook_cmd, "qsm", tmp_path / "none", "--out", tmp_path / "o2")
    assert r.returncode == 2 and r.stderr.startswith("error: no scans in folder")
