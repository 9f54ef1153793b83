"""Per-point labels back to the user's tools (chapter 08b): `write_points` in every format, `read_fields` reading them.

Round trips keep coordinates to the scale's precision and fields exactly; a LAS written `like` a scan keeps that scan's
header; every bad input is one `TreebookError` line, and a failed write leaves no file and no temporary file.
"""
from pathlib import Path

import laspy
import numpy as np
import pytest

from treebook.pointio import FIELD_FORMATS, read_fields, read_points, write_points
from treebook.tree import TreebookError

SCAN = "pytlidar_tree_1.las"


@pytest.fixture(scope="module")
def cloud():
    "Points in UTM metres (x around 4.5e5, y around 5.4e6) on a 0.1 mm grid, and the four labels the CLI writes."
    rng = np.random.default_rng(7)
    n = 500
    p = np.round(rng.random((n, 3)) * [20, 20, 25] * 1e4) / 1e4 + [452103.0, 5401207.0, 312.0]
    labels = {"tree": np.repeat([3, 4], n // 2), "branch": rng.integers(-1, 80, n),
              "cylinder": rng.integers(-1, 900, n), "wood": rng.random(n) < 0.4}
    return p, labels


def listing(folder: Path) -> list:
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("ext", FIELD_FORMATS)
def test_round_trip(ext, cloud, tmp_path):
    p, labels = cloud
    fields = {**labels, "radius": np.linspace(0.001, 0.5, len(p)), "none": np.full(len(p), np.nan)}
    out = write_points(tmp_path / f"tree{ext}", p, fields)
    assert out == tmp_path / f"tree{ext}" and listing(tmp_path) == [out.name]
    back = read_points(out)
    if ext == ".ply": np.testing.assert_array_equal(back, p)
    else: np.testing.assert_allclose(back, p, rtol=0, atol=0.0005 + 1e-9)   # millimetres (scale 0.001)
    got = read_fields(out)
    assert list(got) == list(fields)
    for k in labels:
        assert got[k].dtype == np.int32
        np.testing.assert_array_equal(got[k], labels[k].astype(np.int32))
    np.testing.assert_array_equal(got["radius"].astype(np.float32), fields["radius"].astype(np.float32))
    assert np.isnan(got["none"]).all()


def test_las_header_and_laz(cloud, tmp_path):
    p, labels = cloud
    las = laspy.read(write_points(tmp_path / "tree.laz", p, labels))
    with laspy.open(tmp_path / "tree.laz") as f: assert f.header.are_points_compressed
    assert list(las.point_format.extra_dimension_names) == list(labels)
    assert las["tree"].dtype == np.int32
    np.testing.assert_array_equal(las.header.scales, [0.001] * 3)
    np.testing.assert_array_equal(las.header.offsets, np.floor(p.min(0)))   # offset = floor of the minimum
    np.testing.assert_array_equal(las.header.mins, np.round(p.min(0), 3))
    assert (las.header.version, las.header.point_format.id) == ("1.4", 6)


def test_map_coordinates_keep_millimetres(tmp_path):
    "Coordinates on a millimetre grid at map scale come back exactly (to float error) from LAS, LAZ and text."
    mm = np.array([[451234567, 5412345001, 301250], [451236000, 5412347999, 310500], [451235123, 5412346456, 305789]])
    p = mm / 1000
    for ext in (".las", ".laz", ".xyz", ".csv"):
        np.testing.assert_allclose(_points(write_points(tmp_path / f"m{ext}", p)), p, rtol=0, atol=1e-7)


def _points(path: Path) -> np.ndarray:
    "x, y, z of a written file without `read_points`' checks for a tree (three points are not one)."
    if path.suffix in (".las", ".laz"):
        las = laspy.read(path)
        return np.column_stack([las.x, las.y, las.z])
    return np.loadtxt(path, delimiter="," if path.suffix == ".csv" else None, comments="//", ndmin=2)[:, :3]


def test_scale_keyword(cloud, tmp_path):
    p, labels = cloud
    las = laspy.read(write_points(tmp_path / "cm.las", p, labels, scale=0.01))
    np.testing.assert_array_equal(las.header.scales, [0.01] * 3)
    np.testing.assert_allclose(np.column_stack([las.x, las.y, las.z]), p, rtol=0, atol=0.005 + 1e-9)
    row = (write_points(tmp_path / "cm.txt", p, labels, scale=0.01)).read_text().splitlines()[1].split()
    assert [len(v.split(".")[1]) for v in row[:3]] == [2, 2, 2]


def test_like_real_scan(shared_scans, tmp_path):
    "Written like the scan it came from, a LAS keeps that scan's header and the very integers of its points."
    scan = shared_scans / SCAN
    if not scan.exists(): pytest.skip(f"{scan} is missing")
    src = laspy.read(scan)
    p = read_points(scan)
    tree = np.arange(len(p)) % 7
    for ext in (".las", ".laz"):
        out = laspy.read(write_points(tmp_path / f"labelled{ext}", p, {"tree": tree}, like=scan))
        np.testing.assert_array_equal(out.header.scales, src.header.scales)
        np.testing.assert_array_equal(out.header.offsets, src.header.offsets)
        assert (out.header.version, out.header.point_format.id) == (src.header.version, src.header.point_format.id)
        for d in "XYZ": np.testing.assert_array_equal(out[d], src[d])
        np.testing.assert_array_equal(out["tree"], tree)


def test_like_copies_crs_and_ignores_other_formats(cloud, tmp_path):
    from laspy.vlrs.known import WktCoordinateSystemVlr
    p, labels = cloud
    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales, h.offsets = [0.0005, 0.0005, 0.0001], [452000.0, 5401000.0, 300.0]
    h.vlrs.append(WktCoordinateSystemVlr('PROJCS["ETRS89 / UTM zone 32N"]'))
    scan = laspy.LasData(h)
    scan.x, scan.y, scan.z = p.T
    scan.write(tmp_path / "scan.laz")
    out = laspy.read(write_points(tmp_path / "out.las", p, labels, like=tmp_path / "scan.laz"))
    assert out.header.point_format.id == 3 and str(out.header.version) == "1.2"
    np.testing.assert_array_equal(out.header.scales, h.scales)
    np.testing.assert_array_equal(out.header.offsets, h.offsets)
    wkt = [v for v in out.header.vlrs if isinstance(v, WktCoordinateSystemVlr)]
    assert len(wkt) == 1 and "UTM zone 32N" in wkt[0].string
    np.testing.assert_array_equal(out.X, scan.X)
    # LAS 1.4 may keep its WKT in an extended record, flagged in the global encoding
    from laspy.vlrs.vlrlist import VLRList
    h14 = laspy.LasHeader(point_format=6, version="1.4")
    h14.offsets, h14.scales, h14.global_encoding.wkt = [452000.0, 5401000.0, 300.0], [0.001] * 3, True
    h14.evlrs = VLRList([WktCoordinateSystemVlr('PROJCS["ETRS89 / UTM zone 33N"]')])
    scan14 = laspy.LasData(h14)
    scan14.x, scan14.y, scan14.z = p.T
    scan14.write(tmp_path / "scan14.las")
    with laspy.open(write_points(tmp_path / "out14.laz", p, labels, like=tmp_path / "scan14.las")) as f:
        assert f.header.global_encoding.wkt and "zone 33N" in f.header.evlrs[0].string
    # a text scan has no header to lend: the choice falls back to floor(min) and millimetres
    np.savetxt(tmp_path / "scan.xyz", p)
    out = laspy.read(write_points(tmp_path / "out2.las", p, labels, like=tmp_path / "scan.xyz"))
    np.testing.assert_array_equal(out.header.offsets, np.floor(p.min(0)))


def bad_cases(tmp_path, p):
    n = len(p)
    ok = {"tree": np.zeros(n, int)}
    return [
        (dict(path=tmp_path / "out.e57"), "give a name that ends in one of .las .laz .ply .xyz .txt .csv"),
        (dict(path=tmp_path / "out"), "give a name that ends in one of"),
        (dict(points=p[:, :2]), "must have shape (n, 3) for x, y, z; got (500, 2)"),
        (dict(points=np.c_[p, p[:, :1]]), "must have shape (n, 3)"),
        (dict(points=np.zeros((0, 3))), "is empty"),
        (dict(points=np.where(np.arange(n)[:, None] == 9, np.nan, p)), "1 point(s) with NaN or infinity (first: point"),
        (dict(points=p + 1j), "complex numbers"),
        (dict(fields={"tree": np.zeros(n - 1)}), f"field 'tree' has {n - 1} values for {n} points"),
        (dict(fields={"tree": np.zeros((n, 2))}), f"field 'tree' has shape ({n}, 2) for {n} points"),
        (dict(fields={"tree id": np.zeros(n)}), "field name 'tree id' must be a plain name"),
        (dict(fields={"": np.zeros(n)}), "must be a plain name"),
        (dict(fields={"x": np.zeros(n)}), "field name 'x' is taken by the coordinates or a standard point attribute"),
        (dict(fields={"Classification": np.zeros(n)}), "'Classification' is taken"),
        (dict(fields={"intensity": np.zeros(n)}), "'intensity' is taken"),
        (dict(fields={"red": np.zeros(n)}), "'red' is taken"),
        (dict(fields={**ok, "TREE": np.zeros(n)}), "differ only in letter case"),
        (dict(fields={"tree": np.array(["a"] * n)}), "must hold numbers"),
        (dict(fields={"tree": np.full(n, 2**33)}), "beyond"),
        (dict(fields=[1, 2, 3]), "`fields` must be a dict"),
        (dict(like=tmp_path / "gone.las"), "no such file"),
        (dict(scale=-0.001), "`scale` must be a positive number"),
        (dict(scale=1e-9), "more than 32-bit coordinates hold at scale"),
        (dict(path=tmp_path / "no" / "out.las"), "does not exist"),
        (dict(path=tmp_path), "give a name that ends in one of"),
    ]


@pytest.mark.parametrize("i", range(24))
def test_bad_inputs(i, cloud, tmp_path):
    "Each bad input: one TreebookError line that says what was wrong, and nothing left in the folder."
    p, labels = cloud
    cases = bad_cases(tmp_path, p)
    assert len(cases) == 24
    change, says = cases[i]
    args = {"path": tmp_path / "out.las", "points": p, "fields": labels, **change}
    before = listing(tmp_path)
    with pytest.raises(TreebookError) as e: write_points(**args)
    assert says in str(e.value) and "\n" not in str(e.value)
    assert listing(tmp_path) == before


@pytest.mark.parametrize("ext", FIELD_FORMATS)
def test_failed_write_leaves_old_file(ext, cloud, tmp_path):
    "A write that fails leaves the file that was there untouched, and no temporary file beside it."
    p, labels = cloud
    out = write_points(tmp_path / f"tree{ext}", p, labels)
    old = out.read_bytes()
    with pytest.raises(TreebookError): write_points(out, p, {**labels, "cylinder": np.zeros(3)})
    assert out.read_bytes() == old and listing(tmp_path) == [out.name]


def test_write_that_breaks_midway_leaves_nothing(cloud, tmp_path, monkeypatch):
    "An error while the bytes go out (a full disk) removes the temporary file."
    import treebook.pointio as pio
    p, labels = cloud
    def broken(*a, **k): raise OSError(28, "No space left on device")
    monkeypatch.setattr(pio.np, "savetxt", broken)
    with pytest.raises(TreebookError, match="cannot write"): write_points(tmp_path / "t.xyz", p, labels)
    assert listing(tmp_path) == []


def test_read_fields_bad_inputs(cloud, tmp_path):
    p, labels = cloud
    (tmp_path / "a.npy").write_bytes(b"x")
    (tmp_path / "plain.xyz").write_text("".join(f"{a} {b} {c} 1\n" for a, b, c in p[:20]))
    ply = write_points(tmp_path / "t.ply", p, labels)
    (tmp_path / "cut.ply").write_bytes(ply.read_bytes()[:-7])
    (tmp_path / "faces.ply").write_text("ply\nformat ascii 1.0\nelement face 1\n"
                                        "property list uchar int vertex_indices\nelement vertex 3\nproperty float x\n"
                                        "property float y\nproperty float z\n"
                                        "end_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n")
    (tmp_path / "junk.las").write_bytes(b"junk" * 100)
    (tmp_path / "short.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\nproperty int tree\nend_header\n0 0 0 1\n1 0 0 2\n")
    for path, says in ((tmp_path / "gone.las", "no such file"), (tmp_path / "a.npy", "expected one of .las .laz .ply"),
                       (tmp_path / "plain.xyz", "no line above its points naming them"),
                       (tmp_path / "cut.ply", "its data ends early"), (tmp_path / "faces.ply", "the vertex element"),
                       (tmp_path / "short.ply", "its data ends early"), (tmp_path / "junk.las", "cannot read")):
        with pytest.raises(TreebookError) as e: read_fields(path)
        assert says in str(e.value) and "\n" not in str(e.value), (path.name, str(e.value))


def test_read_fields_of_other_writers(tmp_path):
    "Big-endian PLY, a CSV whose names are a plain first line, a LAS without extra dimensions."
    a = np.zeros(3, [("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("label", ">u2"), ("conf", ">f8")])
    a["x"], a["label"], a["conf"] = [1, 2, 3], [7, 8, 9], [0.5, 0.25, 1.0]
    head = ("ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty ushort label\nproperty double conf\nend_header\n")
    (tmp_path / "be.ply").write_bytes(head.encode() + a.tobytes())
    got = read_fields(tmp_path / "be.ply")
    assert list(got) == ["label", "conf"] and got["label"].tolist() == [7, 8, 9]
    assert got["label"].dtype == np.uint16 and got["conf"].tolist() == [0.5, 0.25, 1]
    (tmp_path / "cc.csv").write_text("X,Y,Z,Scalar field,Classes\n1.5,2,3,0.25,1\n2.5,3,4,0.5,2\n")
    got = read_fields(tmp_path / "cc.csv")
    assert got["Scalar field"].tolist() == [0.25, 0.5] and got["Classes"].dtype == np.int32
    las = laspy.LasData(laspy.LasHeader(point_format=6, version="1.4"))
    las.x, las.y, las.z = np.eye(3)
    las.write(tmp_path / "plain.las")
    assert read_fields(tmp_path / "plain.las") == {}
