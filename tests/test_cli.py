"""The `treebook` command end to end, in subprocesses, and the wheel on its own."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from treebook.tree import Tree, example_tree

ROOT = Path(__file__).resolve().parent.parent


def run(cmd, *args, cwd=None):
    return subprocess.run([cmd, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.fixture
def tree_file(tmp_path):
    return example_tree(levels=4, seed=5).save(tmp_path / "x.npz")


@pytest.mark.parametrize("ext", ["glb", "obj", "ply"])
def test_export_loads_back_with_the_trees_bounds(treebook_cmd, tree_file, tmp_path, ext):
    r = run(treebook_cmd, "export", tree_file, "--out", tmp_path / f"x.{ext}")
    assert r.returncode == 0, r.stderr
    mesh = trimesh.load(tmp_path / f"x.{ext}", force="mesh")
    tree = Tree.load(tree_file)
    # the mesh is the tree's skeleton thickened by its radii: same box, padded by at most the largest radius
    rmax = max(tree.start[:, 3].max(), tree.end[:, 3].max())
    assert np.allclose(mesh.bounds, tree.bounds(with_radius=True), atol=rmax)
    assert np.all(mesh.bounds[0] <= tree.bounds()[0] + 1e-6) and np.all(mesh.bounds[1] >= tree.bounds()[1] - 1e-6)


def test_export_skeleton_and_render(treebook_cmd, tree_file, tmp_path):
    r = run(treebook_cmd, "export", tree_file, "--out", tmp_path / "s.ply", "--skeleton")
    assert r.returncode == 0, r.stderr
    from treebook.mesh import read_skeleton
    assert read_skeleton(tmp_path / "s.ply").parent.tolist() == Tree.load(tree_file).parent.tolist()
    r = run(treebook_cmd, "render", tree_file, "--out", tmp_path / "x.png", "--size", "200")
    assert r.returncode == 0, r.stderr
    from PIL import Image
    img = np.asarray(Image.open(tmp_path / "x.png").convert("RGB"))
    assert img.shape == (200, 200, 3)
    assert img.std() > 5 and (img.min(-1) < 200).mean() > 0.01  # not blank: some dark (bark) pixels


def test_info(treebook_cmd, tree_file):
    r = run(treebook_cmd, "info", tree_file, "--json")
    assert r.returncode == 0, r.stderr
    import json
    assert json.loads(r.stdout)["branches"] == Tree.load(tree_file).n


def _bad_files(d: Path):
    t = example_tree(levels=2)
    np.savez(d / "noparent.npz", start=t.start, end=t.end)
    s = t.start.copy(); s[1, 0] = np.nan
    np.savez(d / "nan.npz", start=s, end=t.end, parent=t.parent)
    e = t.end.copy(); e[0, 3] = -1
    np.savez(d / "negative.npz", start=t.start, end=e, parent=t.parent)
    p = t.parent.copy(); p[2] = 4  # branch 4 is on another limb: forward, but no cycle
    np.savez(d / "forward.npz", start=t.start, end=t.end, parent=p)
    p = t.parent.copy(); p[1] = 7 * t.n
    np.savez(d / "range.npz", start=t.start, end=t.end, parent=p)
    p = t.parent.copy(); p[1], p[2] = 2, 1
    np.savez(d / "cycle.npz", start=t.start, end=t.end, parent=p)
    np.savez(d / "empty.npz", start=np.zeros((0, 4)), end=np.zeros((0, 4)), parent=np.zeros(0, int))
    (d / "tree.txt").write_text("not a tree")
    return {"missing.npz": "no such file", "tree.txt": "expected a .npz or .json", "noparent.npz": "missing the array(s) parent",
            "nan.npz": "not a finite number", "negative.npz": "negative radius", "forward.npz": "comes after it",
            "range.npz": "out of range", "cycle.npz": "form a cycle", "empty.npz": "the tree is empty"}


@pytest.mark.parametrize("cmd", ["info", "export", "render"])
def test_bad_input_is_one_line_and_exit_2(treebook_cmd, tmp_path, cmd):
    for name, msg in _bad_files(tmp_path).items():
        extra = {"info": [], "export": ["--out", tmp_path / "o.obj"], "render": ["--out", tmp_path / "o.png"]}[cmd]
        r = run(treebook_cmd, cmd, tmp_path / name, *extra)
        assert r.returncode == 2, (name, r.returncode, r.stderr)
        assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1 and msg in r.stderr, (name, r.stderr)
        assert "Traceback" not in r.stderr
        assert not (tmp_path / "o.obj").exists() and not (tmp_path / "o.png").exists()


def test_wrong_flags_are_one_line_and_exit_2(treebook_cmd, tree_file, tmp_path):
    for args in (["export", tree_file], ["export", tree_file, "--out", tmp_path / "x.stl"], ["frobnicate"],
                 ["render", tree_file, "--out", tmp_path / "x.png", "--size", "ten"], []):
        r = run(treebook_cmd, *args)
        assert r.returncode == 2 and r.stderr.startswith("error: ") and r.stderr.count("\n") == 1, (args, r.stderr)


def test_help_of_every_subcommand(treebook_cmd):
    for sub in ([], *([c] for c in ("demo", "info", "export", "render", "generate", "grammar", "enhance", "propagate", "reconstruct",
                                      "train", "sample", "grow", "complete", "sketch2tree", "points2tree", "image2tree"))):
        r = run(treebook_cmd, *sub, "--help")
        assert r.returncode == 0 and "usage: treebook" in r.stdout, (sub, r.stderr)


def test_wheel_runs_the_demo_on_its_own(tmp_path):
    "Build the wheel, install it alone into a folder away from the source tree, and run the whole demo from it: an OBJ and a picture of the tree, and every step's files."
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-w", tmp_path / "dist", ROOT],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    wheel = next((tmp_path / "dist").glob("treebook-*.whl"))
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--target", target, wheel], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    work = tmp_path / "elsewhere"; work.mkdir()
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import treebook, treebook.cli; "
            "assert treebook.__file__.startswith(sys.argv[1]), treebook.__file__; "
            "sys.exit(treebook.cli.main(['demo', '--out', 'out']))")
    r = subprocess.run([sys.executable, "-I", "-c", code, str(target)], capture_output=True, text=True, cwd=work, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    obj = trimesh.load(work / "out" / "tree.obj", force="mesh")
    assert len(obj.faces) > 100
    from PIL import Image
    assert np.asarray(Image.open(work / "out" / "tree.png")).std() > 5
    for name in ("species_gallery.png", "grammar/grammar.json", "reconstruct/reconstructed_tree13.obj",
                 "measure/measured_cylinders.csv"):
        assert (work / "out" / name).exists(), name
    assert any((work / "out" / "growth").rglob("growth_filmstrip.png"))


def test_generate_every_species_from_the_command_line(treebook_cmd, tmp_path):
    "`treebook generate` makes 100 elms and 20 trees of each other species: valid Trees within their caps."
    from treebook.botany import SPECIES
    from treebook.datasets import load_trees
    for name, spec in SPECIES.items():
        n = 100 if name == "elm" else 20
        r = run(treebook_cmd, "generate", "--species", name, "--n", n, "--stages", 10, "--trees", "--out", tmp_path / name)
        assert r.returncode == 0, r.stderr
        trees = load_trees(tmp_path / name)
        assert len(trees) == n and all(2 <= t.n <= spec.max_branches for t in trees)
        files = sorted((tmp_path / name / "trees").glob("tree_*.npz"))
        assert len(files) == n and Tree.load(files[0]).n == trees[0].n


def test_image2tree_fits_the_silhouette_by_default(treebook_cmd, tmp_path):
    "The shipped elm-image model from a PNG: fitted and best of 2 by default flags, and the network's own tree with --no-fit."
    from PIL import Image
    from treebook.botany import grow
    from treebook.scan import silhouette
    from treebook.condition import silhouette_scores
    im = silhouette(grow("elm", seed=123456, max_branches=120)[-1])
    Image.fromarray(255 - im).save(tmp_path / "sil.png")          # dark tree on white, as a user would draw it
    iou = {}
    for tag, flags in (("fit", ["--candidates", "2"]), ("raw", ["--no-fit", "--candidates", "1"])):
        r = run(treebook_cmd, "image2tree", tmp_path / "sil.png", "--seed", "1", "--out", tmp_path / tag, *flags)
        assert r.returncode == 0, r.stderr
        files = sorted((tmp_path / tag).glob("*.npz"))
        assert len(files) == 1, r.stdout
        iou[tag] = silhouette_scores(silhouette(Tree.load(files[0])), im)["iou"]
    assert iou["fit"] > iou["raw"], iou
    r = run(treebook_cmd, "image2tree", tmp_path / "sil.png", "--candidates", "0", "--out", tmp_path / "x")
    assert r.returncode == 2 and "argument --candidates: must be a whole number in 1..64" in r.stderr
