"""The Python module against the library and the CLI: NumPy round trips, render() equal to
`subvec render` byte for byte, info, edits equal to `subvec edit`, stencils, exception classes,
the GIL released during long calls."""

import json
import pickle
import threading
import time

import numpy as np
import pytest

import subvec
from conftest import ROOT, disk_image

EXAMPLES = ROOT / "examples"
BUTTERFLY = ROOT / "docs" / "figures" / "butterfly.svec"
BUTTERFLY_OPS = ROOT / "docs" / "figures" / "butterfly-ops.json"


@pytest.fixture(scope="module")
def disk():
    photo = disk_image()
    return photo, subvec.vectorize(photo, ratio=0.05, levels=1)


# ---- NumPy round trips ---------------------------------------------------------------------


def test_vectorize_then_render_reproduces_the_photo(disk):
    photo, image = disk
    assert (image.width, image.height) == (96, 72)
    assert image.num_levels == 1
    pixels = image.render()
    assert pixels.shape == (72, 96, 3) and pixels.dtype == np.uint8
    mae = np.abs(pixels.astype(int) - photo.astype(int)).mean()
    assert mae < 4.0, mae
    # The module's compare() is the library's metric: the same MAE.
    assert subvec.compare(photo, pixels)["mae_mean"] == pytest.approx(mae, abs=1e-9)
    # A flat gray image reproduces much worse than the disk does: the assertion above can fail.
    assert np.abs(pixels.astype(int) - 128).mean() > 20


def test_vectorize_refuses_an_image_over_max_memory(disk):
    photo, _ = disk
    # The library's estimate against the keyword, before any work: its error class and words.
    with pytest.raises(subvec.LimitError, match=r"^max_memory is 10 MB, and vectorizing this 96x72 "
                       r"image needs an estimated \d+ MB$"):
        subvec.vectorize(photo, max_memory=10_000_000)
    with pytest.raises(subvec.InvalidArgumentError, match="max_memory must be 0"):
        subvec.vectorize(photo, max_memory=-1)
    assert subvec.vectorize(photo, levels=1, max_memory=1 << 40).width == 96


def test_float_input_in_0_1_equals_uint8_input(disk):
    photo, image = disk
    as_float = subvec.vectorize(photo.astype(np.float32) / 255, ratio=0.05, levels=1)
    assert as_float.to_bytes(lossless=True) == image.to_bytes(lossless=True)
    # Non-contiguous views are read correctly too.
    wide = np.zeros((72, 96 * 2, 3), np.uint8)
    wide[:, ::2] = photo
    assert subvec.vectorize(wide[:, ::2], ratio=0.05, levels=1).to_bytes() == image.to_bytes()


def test_read_image_and_write_png_round_trip(tmp_path, disk):
    photo, _ = disk
    subvec.write_png(tmp_path / "photo.png", photo)
    back = subvec.read_image(tmp_path / "photo.png")
    assert back.dtype == np.uint8 and np.array_equal(back, photo)


def test_mesh_arrays_and_set_positions_round_trip(disk):
    _, image = disk
    image = image.copy()
    mesh = image.mesh()
    v = len(mesh["positions"])
    assert mesh["positions"].shape == (v, 2) and mesh["positions"].dtype == np.float64
    assert mesh["triangles"].shape[1] == 3 and mesh["triangles"].max() < v
    assert mesh["triangle_colors"].max() < len(mesh["colors"])
    assert image.info()["levels"][0]["vertices"] == v
    assert any(f["closed"] for f in mesh["features"])  # the disk's outline
    # Move one interior vertex a little: the render changes, and the change reads back.
    interior = np.flatnonzero((mesh["positions"][:, 0] > 5) & (mesh["positions"][:, 0] < 90) &
                              (mesh["positions"][:, 1] > 5) & (mesh["positions"][:, 1] < 66))
    before = image.render()
    moved = mesh["positions"].copy()
    moved[interior[0]] += (0.3, -0.2)
    image.set_positions(moved)
    assert np.array_equal(image.mesh()["positions"], moved)
    colors = mesh["colors"].copy()
    colors[:] = (10, 200, 30)
    image.set_colors(colors)
    after = image.render()
    assert not np.array_equal(before, after)
    assert np.abs(after.astype(int) - (10, 200, 30)).max() <= 1  # one flat color everywhere


@pytest.mark.parametrize("name", ["x.svec", "x.svec.json"])
def test_save_load_round_trip(tmp_path, disk, name):
    _, image = disk
    image.save(tmp_path / name, lossless=True)
    loaded = subvec.load(str(tmp_path / name))
    for key in ("positions", "colors", "triangles", "triangle_colors"):
        assert np.array_equal(loaded.mesh()[key], image.mesh()[key]), key
    assert np.array_equal(loaded.render(), image.render())


def test_pickle_and_bytes_round_trip(disk):
    _, image = disk
    again = pickle.loads(pickle.dumps(image))
    assert again.to_bytes(lossless=True) == image.to_bytes(lossless=True)
    assert subvec.from_bytes(image.to_bytes(format="json")).to_bytes(lossless=True) == \
        image.to_bytes(lossless=True)


def test_compact_version_2_on_request(tmp_path, disk):
    # compact_version=2 writes the older payload (the header's version field), holding the same
    # mesh and picture as version 3 (which alone rounds saliencies to float32, docs/format.md);
    # other versions raise the library's message and write nothing.
    _, image = disk
    v2, v3 = image.to_bytes(compact_version=2), image.to_bytes()
    assert v2[8] == 2 and v3[8] == 3
    a, b = subvec.from_bytes(v2), subvec.from_bytes(v3)
    for key in ("positions", "colors", "triangles", "triangle_colors"):
        assert np.array_equal(a.mesh()[key], b.mesh()[key]), key
    assert np.array_equal(a.render(), b.render())
    image.save(tmp_path / "old.svec", compact_version=2)
    assert (tmp_path / "old.svec").read_bytes() == v2
    with pytest.raises(subvec.InvalidArgumentError, match=r"compact \.svec version 4 is not one this build writes \(2 or 3\)"):
        image.save(tmp_path / "bad.svec", compact_version=4)
    assert not (tmp_path / "bad.svec").exists()


# ---- render() against the CLI ----------------------------------------------------------------

RENDER_CASES = [
    ({}, []),
    ({"width": 150}, ["--width", "150"]),
    ({"scale": 2.5}, ["--scale", "2.5"]),
    ({"window": (10, 5, 40, 30), "scale": 4}, ["--window", "10,5,40,30", "--scale", "4"]),
    ({"window": (-8, -4, 30, 20), "width": 77}, ["--window", "-8,-4,30,20", "--width", "77"]),
    ({"overlay": "mesh", "scale": 2}, ["--overlay", "mesh", "--scale", "2"]),
    ({"antialias": False, "depth": 2}, ["--no-aa", "--depth", "2"]),
]


@pytest.mark.parametrize("source", ["01-disk.svec.json", "03-junction.svec.json", "vectorized"])
@pytest.mark.parametrize("kwargs,args", RENDER_CASES)
def test_render_equals_the_cli_png_byte_for_byte(tmp_path, cli, disk, source, kwargs, args):
    if source == "vectorized":
        path = tmp_path / "v.svec"
        disk[1].save(path)
    else:
        path = EXAMPLES / source
    image = subvec.load(path)
    pixels = image.render(**kwargs)
    cli("render", path, "-o", tmp_path / "cli.png", *args)
    subvec.write_png(tmp_path / "py.png", pixels)
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    if pixels.shape[2] == 3:  # the reader composites alpha: compare decoded pixels for RGB only
        assert np.array_equal(subvec.read_image(tmp_path / "cli.png"), pixels)


def test_info_matches_the_cli(cli):
    path = EXAMPLES / "03-junction.svec.json"
    expected = json.loads(cli("info", path, "--json").stdout)
    info = subvec.load(path).info()
    for key in ("width", "height", "strokes", "metadata"):
        assert info[key] == expected[key], key
    assert len(info["levels"]) == len(expected["levels"])
    for mine, cli_level in zip(info["levels"], expected["levels"]):
        assert mine == {k: cli_level[k] for k in mine}


# ---- edits -----------------------------------------------------------------------------------


def test_edit_ops_equal_subvec_edit(tmp_path, cli):
    image = subvec.load(BUTTERFLY)
    log = image.edit(json.loads(BUTTERFLY_OPS.read_text()))
    assert len(log) == 6
    image.save(tmp_path / "py.svec")
    cli("edit", BUTTERFLY, "-o", tmp_path / "cli.svec", "--ops", BUTTERFLY_OPS)
    assert (tmp_path / "py.svec").read_bytes() == (tmp_path / "cli.svec").read_bytes()


def test_mouse_edits_change_what_they_should():
    image = subvec.load(BUTTERFLY)
    before = image.render()
    # A blend toward blue around a point: pixels there get bluer, far ones stay.
    image.recolor((223, 262), (30, 80, 220), radius=14, amount=0.8)
    after = image.render()
    assert after[262, 223, 2] > before[262, 223, 2] + 20
    assert np.array_equal(after[:40, :40], before[:40, :40])
    # A feature drag moves positions; a drag of a corner toward the inside is clamped there.
    positions = image.mesh()["positions"]
    line = image.drag((111, 126), (104, 104), select="feature", sigma=45)
    assert "drag feature" in line
    assert not np.array_equal(image.mesh()["positions"], positions)
    # Stylize adds strokes, deterministically.
    copy = image.copy()
    report = image.stylize(seed=3)
    assert report["strokes"] > 0 and image.num_strokes == report["strokes"]
    copy.stylize(seed=3)
    assert copy.to_bytes(lossless=True) == image.to_bytes(lossless=True)


def test_region_selection_is_a_fill_that_the_tolerance_bounds():
    image = subvec.load(BUTTERFLY)
    # No cap by default; a wider tolerance fills at least as much; the radius caps it.
    tight = image.select_colors((223, 262), select="region", tolerance=10)["colors"]
    wide = image.select_colors((223, 262), select="region", tolerance=40)["colors"]
    capped = image.select_colors((223, 262), select="region", tolerance=40, radius=5)["colors"]
    assert 0 < tight.size <= wide.size and set(tight) <= set(wide)
    assert set(capped) <= set(wide) and capped.size < wide.size
    with pytest.raises(subvec.InvalidArgumentError, match="tolerance applies to select='region'"):
        image.select_colors((223, 262), select="vertex", tolerance=10)
    with pytest.raises(subvec.InvalidArgumentError, match="'vertex', 'feature', 'region', 'vertices' or 'all'"):
        image.select_colors((223, 262), select="blob")
    with pytest.raises(subvec.InvalidArgumentError, match='grabs a "vertex" or a "feature"'):
        image.drag((111, 126), (104, 104), select="region")
    before = image.mesh()["colors"]
    image.recolor((223, 262), (255, 0, 0), select="region", tolerance=40, amount=1)
    after = image.mesh()["colors"]
    changed = np.flatnonzero(np.any(after != before, axis=1))
    assert set(changed) <= set(wide) and changed.size > 0


def test_direct_handles_move_and_recolor_control_points():
    image = subvec.load(BUTTERFLY)
    positions = image.mesh()["positions"]
    inner = np.flatnonzero((positions[:, 0] > 100) & (positions[:, 0] < 300) &
                           (positions[:, 1] > 100) & (positions[:, 1] < 250))[:4]
    line = image.move_vertices(inner, (2, -1), region=60)
    assert "4 control points moved by [2, -1]" in line
    assert np.allclose(image.mesh()["positions"][inner], positions[inner] + (2, -1))
    before = image.mesh()["colors"]
    image.recolor(None, (0, 255, 0), select="vertices", vertices=inner, amount=1)  # no click point
    changed = np.flatnonzero(np.any(image.mesh()["colors"] != before, axis=1))
    assert changed.size >= 4 and np.allclose(image.mesh()["colors"][changed], (0, 255, 0))
    with pytest.raises(subvec.InvalidArgumentError, match="vertices go with select='vertices'"):
        image.recolor((5, 5), (0, 0, 0), select="vertices")
    with pytest.raises(subvec.InvalidArgumentError, match="at is needed unless select='vertices'"):
        image.recolor(None, (0, 0, 0), select="region")
    with pytest.raises(subvec.InvalidArgumentError, match="out of range"):
        image.move_vertices([10**6], (1, 1))


def _smallest_area(image):
    mesh = image.mesh()
    p = mesh["positions"][mesh["triangles"]]
    return ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) -
            (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])).min()


def test_deform_never_folds_and_says_how_far_it_went():
    image = subvec.load(BUTTERFLY)
    positions = image.mesh()["positions"]
    v = int(np.argmin(np.hypot(positions[:, 0] - 200, positions[:, 1] - 180)))
    assert image.deform([v], [positions[v] + (3, 2)], region=60) == 1.0
    assert np.array_equal(image.mesh()["positions"][v], positions[v] + (3, 2))
    # Far past the right border: the frame stops it, a margin inside, and nothing folds.
    reached = image.deform([v], [positions[v] + (5000, 0)])
    assert 0 < reached < 1
    assert image.mesh()["positions"][v][0] <= image.width - 0.25
    assert _smallest_area(image) > 0
    # A feature drag the plain ARAP solve would flip: it goes all the way now, or stops and says so.
    line = image.drag((200, 180), (230, 150), select="feature", sigma=25, region=75)
    assert "dragged by" in line and _smallest_area(image) > 0


def test_add_and_delete_features():
    image = subvec.load(BUTTERFLY)
    before = image.render()
    count = len(image.mesh()["features"])
    # A closed tear in the blurred green top-left corner: the picture barely changes.
    t = np.linspace(0, 2 * np.pi, 60)
    line = image.add_feature(np.stack([40 + 12 * np.cos(t), 60 + 12 * np.sin(t)], axis=1).tolist())
    assert "closed tear feature" in line
    features = image.mesh()["features"]
    assert len(features) == count + 1 and features[-1]["closed"]
    assert np.abs(image.render().astype(int) - before.astype(int)).mean() < 0.5
    # Deleted again: the feature is gone.
    assert "deleted" in image.delete_feature((52, 60))
    assert len(image.mesh()["features"]) == count
    with pytest.raises(ValueError, match="kind must be"):
        image.add_feature([[10, 10], [20, 20]], kind="fold")
    with pytest.raises(ValueError, match=r"\[x, y\] pairs"):
        image.add_feature([[10, 10], "x"])


def test_objects():
    image = subvec.load(EXAMPLES / "01-disk.svec.json")
    before = image.render()
    line = image.make_object((48, 48), name="disk")
    assert 'object 0 ("disk") made of the region inside feature 0' in line
    assert image.objects == [{"level": 0, "name": "disk", "visible": True,
                              "vertices": image.object_mesh(0)["positions"].shape[0],
                              "triangles": image.object_mesh(0)["triangles"].shape[0], "features": 0,
                              "strokes": 0}]
    assert image.info()["objects"] == image.objects
    # In place, the picture is the same but along the object's anti-aliased rim.
    assert np.abs(image.render().astype(int) - before.astype(int)).mean() < 0.5
    start = image.object_mesh(0)["positions"]
    assert "moved by [10, 0]" in image.move_object(0, translate=(10, 0))
    assert np.allclose(image.object_mesh(0)["positions"], start + (10, 0))
    image.move_object(0, rotate=90, pivot=(48, 48))
    image.set_object_visible(0, False)
    assert not image.objects[0]["visible"]
    # Hidden, the completed background shows: smooth where the disk was.
    hidden = image.render().astype(float)
    assert np.abs(np.diff(hidden[36:60, 36:60], axis=1)).max() < 12
    assert image.order_object(0, 0).endswith("(0 is the bottom)")
    # Saved and read back, in both forms.
    for form in ("svec", "json"):
        back = subvec.from_bytes(image.to_bytes(format=form, lossless=True))
        assert back.objects == image.objects
        assert np.array_equal(back.render(), image.render())
    # Edits inside the object reach its own mesh, not the level's.
    level_colors = image.mesh()["colors"].copy()
    centre = image.object_mesh(0)["positions"].mean(axis=0)
    assert "object 0: " in image.recolor(tuple(centre), (0, 0, 255), amount=1.0, radius=6, object=0)
    assert np.array_equal(image.mesh()["colors"], level_colors)
    assert np.abs(image.object_mesh(0)["colors"] - (0, 0, 255)).min() < 1e-3
    moved = image.object_mesh(0)["positions"].copy()
    image.move_vertices([0], (2, 1), object=0)
    assert np.allclose(image.object_mesh(0)["positions"][0], moved[0] + (2, 1))
    with pytest.raises(IndexError, match="object 3 is out of range"):
        image.move_object(3, translate=(1, 1))
    with pytest.raises(IndexError, match="object 3 is out of range"):
        image.drag((40, 40), (42, 42), object=3)
    with pytest.raises(ValueError, match="scale must be a positive number"):
        image.move_object(0, scale=0)
    with pytest.raises(ValueError, match="no closed feature of level 0 encloses"):
        image.make_object((3, 3))
    with pytest.raises(ValueError, match="give at or rect"):
        image.make_object()
    # A rectangle framing the disk makes the same object as a click inside it.
    framed = subvec.load(EXAMPLES / "01-disk.svec.json")
    assert "frames" in framed.make_object(rect=(14, 14, 68, 68))
    clicked = subvec.load(EXAMPLES / "01-disk.svec.json")
    clicked.make_object((48, 48))
    assert framed.objects == clicked.objects


def test_object_stylize_and_filter():
    image = subvec.load(EXAMPLES / "01-disk.svec.json")
    image.make_object((48, 48))
    # The object's outline (and features) stroked into its own strokes, which move with it.
    report = image.stylize(object=0, threshold=0)
    assert report["strokes"] >= 1 and image.objects[0]["strokes"] == report["strokes"]
    assert image.info()["strokes"] == 0
    image.move_object(0, translate=(6, 0))
    back = subvec.from_bytes(image.to_bytes(format="svec", lossless=True))
    assert back.objects == image.objects and np.array_equal(back.render(), image.render())
    # Filtered alone through its own pyramid: colors only leave the positions as they were.
    before = image.object_mesh(0)["positions"]
    soft = image.filter(color_eta=[0.2], object=0)
    assert np.array_equal(soft.object_mesh(0)["positions"], before)
    assert np.array_equal(soft.mesh()["colors"], image.mesh()["colors"])
    with pytest.raises(IndexError, match="object 2 is out of range"):
        image.filter(color_eta=[0.5], object=2)
    with pytest.raises(IndexError, match="object 2 is out of range"):
        image.stylize(object=2)


def test_color_selection_blend_and_transform():
    image = subvec.load(BUTTERFLY)
    sel = image.select_colors((160, 175), radius=40)
    assert sel["colors"].size > 1 and sel["seed_color"] in sel["colors"]
    colors = image.mesh()["colors"]
    factors = image.transform_colors(sel["colors"], colors[sel["seed_color"]], (255, 190, 20))
    after = image.mesh()["colors"]
    assert np.allclose(after[sel["seed_color"]], (255, 190, 20), atol=1e-3)
    assert np.allclose(after[sel["colors"]], colors[sel["colors"]] * np.array(factors), atol=1e-2)
    untouched = np.setdiff1d(np.arange(len(colors)), sel["colors"])
    assert np.array_equal(after[untouched], colors[untouched])
    image.blend_colors(sel["colors"], (0, 0, 0), amount=1.0)
    assert np.abs(image.mesh()["colors"][sel["colors"]]).max() < 1e-6


# ---- stencils --------------------------------------------------------------------------------


@pytest.mark.parametrize("limit", [True, False])
def test_stencils_map_control_values_to_the_refined_mesh(disk, limit):
    import scipy.sparse

    _, image = disk
    mesh = image.mesh()
    refined = image.subdivide(depth=2, limit=limit)
    s_pos, s_col = refined["position_stencils"], refined["color_stencils"]
    assert isinstance(s_pos, scipy.sparse.csr_matrix)
    assert s_pos.shape == (len(refined["positions"]), len(mesh["positions"]))
    assert s_col.shape == (len(refined["colors"]), len(mesh["colors"]))
    assert np.allclose(s_pos @ mesh["positions"], refined["positions"], atol=2e-3)
    assert np.allclose(s_col @ mesh["colors"], refined["colors"], atol=2e-2)
    assert np.allclose(np.asarray(s_pos.sum(axis=1)).ravel(), 1, atol=1e-6)
    assert refined["triangles"].max() < len(refined["positions"])
    assert len(refined["triangle_parent"]) == len(refined["triangles"])
    # Depth 2 has 16 children per control triangle.
    assert len(refined["triangles"]) == 16 * len(mesh["triangles"])
    # The plain CSR arrays, without SciPy.
    data, indices, indptr, shape = image.subdivide(depth=2, limit=limit,
                                                   sparse="arrays")["position_stencils"]
    assert shape == s_pos.shape and np.array_equal(indptr, s_pos.indptr)
    assert np.array_equal(indices, s_pos.indices) and np.array_equal(data, s_pos.data)


# ---- errors ----------------------------------------------------------------------------------


def test_exception_hierarchy():
    for cls in (subvec.InvalidArgumentError, subvec.InvalidMeshError, subvec.BadFileError,
                subvec.LimitError):
        assert issubclass(cls, subvec.Error) and issubclass(cls, ValueError)
    assert issubclass(subvec.FileError, subvec.Error) and issubclass(subvec.FileError, OSError)
    assert issubclass(subvec.CancelledError, subvec.Error)
    assert subvec.InvalidArgumentError.__module__ == "subvec"


def test_bad_arrays_raise_invalid_argument():
    with pytest.raises(subvec.InvalidArgumentError, match=r"H x W x 3.*\(10, 10\)"):
        subvec.vectorize(np.zeros((10, 10), np.uint8))
    with pytest.raises(subvec.InvalidArgumentError, match="dtype int16"):
        subvec.vectorize(np.zeros((10, 10, 3), np.int16))
    with pytest.raises(subvec.InvalidArgumentError, match=r"\[0, 1\]"):
        subvec.vectorize(np.full((10, 10, 3), 2.0, np.float32))
    with pytest.raises(subvec.InvalidArgumentError, match=r"\[0, 1\]"):
        subvec.vectorize(np.full((10, 10, 3), np.nan, np.float32))
    with pytest.raises(subvec.InvalidArgumentError, match="ratio"):
        subvec.vectorize(disk_image(), ratio=0)
    with pytest.raises(subvec.InvalidArgumentError, match="levels"):
        subvec.vectorize(disk_image(), levels=0)
    with pytest.raises(subvec.InvalidArgumentError, match="refine"):
        subvec.vectorize(disk_image(), refine=-1)
    with pytest.raises(subvec.InvalidArgumentError, match="relocate"):
        subvec.vectorize(disk_image(), relocate=51)
    with pytest.raises(ValueError):  # the built-in base class works for callers that know no subvec
        subvec.vectorize(np.zeros((0, 4, 3), np.uint8))


def test_bad_files_raise_file_and_bad_file_errors(tmp_path):
    with pytest.raises(subvec.FileError) as e:
        subvec.load(tmp_path / "missing.svec")
    assert str(e.value) == f"{tmp_path / 'missing.svec'}: no such file" and isinstance(e.value, OSError)
    # A photograph where a vector image belongs: the library's reader names it, as the CLI does.
    photo = EXAMPLES / "04-rocket.png"
    with pytest.raises(subvec.BadFileError, match=r"04-rocket\.png: a PNG image, not a \.svec or "
                       r"\.svec\.json file; vectorize it first: subvec vectorize .* -o 04-rocket\.svec"):
        subvec.load(photo)
    (tmp_path / "junk.svec").write_bytes(b"SUBVEC\x00\x1a truncated")
    with pytest.raises(subvec.BadFileError, match="junk.svec"):
        subvec.load(tmp_path / "junk.svec")
    with pytest.raises(subvec.BadFileError):
        subvec.from_bytes(b"not a vector image")
    (tmp_path / "junk.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    with pytest.raises(subvec.Error, match="junk.png"):
        subvec.read_image(tmp_path / "junk.png")
    with pytest.raises(subvec.InvalidArgumentError, match="extension"):
        subvec.load(EXAMPLES / "01-disk.svec.json").save(tmp_path / "x.txt")
    with pytest.raises(subvec.BadFileError, match="missing key"):
        subvec.load(BUTTERFLY).edit([{"op": "drag", "select": "vertex", "from": [1, 1]}])


def test_bad_render_and_edit_arguments(disk):
    _, image = disk
    image = image.copy()
    with pytest.raises(subvec.InvalidArgumentError, match="level 2 is out of range"):
        image.render(level=2)
    with pytest.raises(subvec.InvalidArgumentError, match="width or scale"):
        image.render(width=10, scale=2)
    with pytest.raises(subvec.InvalidArgumentError, match="window"):
        image.render(window=(10, 10, 5, 20))
    with pytest.raises(subvec.InvalidArgumentError, match="overlay"):
        image.render(overlay="grid")
    with pytest.raises(subvec.LimitError):
        image.render(scale=1e4)
    with pytest.raises(subvec.InvalidArgumentError, match="shape"):
        image.set_positions(np.zeros((3, 2)))
    # A position that flips a triangle: refused, and the image keeps its old positions.
    positions = image.mesh()["positions"]
    flipped = positions.copy()
    flipped[:, 0] = image.width - flipped[:, 0]
    with pytest.raises(subvec.InvalidMeshError):
        image.set_positions(flipped)
    assert np.array_equal(image.mesh()["positions"], positions)
    with pytest.raises(subvec.InvalidArgumentError, match="outside|inside"):
        image.recolor((500, 500), (1, 2, 3))
    with pytest.raises(subvec.InvalidArgumentError, match="out of range"):
        image.blend_colors([10**6], (0, 0, 0))


# ---- the GIL ---------------------------------------------------------------------------------


def test_long_calls_release_the_gil():
    photo = disk_image(320, 240)
    stamps = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            stamps.append(time.monotonic())
            time.sleep(0.001)

    thread = threading.Thread(target=tick)
    thread.start()
    try:
        start = time.monotonic()
        subvec.vectorize(photo, ratio=0.02, levels=1)
        end = time.monotonic()
    finally:
        stop.set()
        thread.join()
    # With the GIL held for the whole call the other thread could not run inside it (beyond one
    # switch interval, 5 ms, at either end).
    inside = [t for t in stamps if start + 0.03 < t < end - 0.03]
    assert end - start > 0.1
    assert len(inside) >= 5, (end - start, len(inside))


# ---- docs/python.md --------------------------------------------------------------------------


def test_the_tour_in_docs_runs(tmp_path, monkeypatch):
    text = (ROOT / "docs" / "python.md").read_text()
    start = text.index("```python\nimport numpy as np\nimport subvec")
    code = text[start + len("```python\n"):text.index("```\n", start + 10)]
    code = code.replace('"examples/04-rocket.png"', repr(str(EXAMPLES / "04-rocket.png")))
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(compile(code, "docs/python.md", "exec"), scope)
    assert scope["image"].info()["levels"][0]["vertices"] == 983
    assert scope["before"].shape == (432, 260, 3)
    assert not np.array_equal(scope["before"], scope["after"])
    assert scope["styled"].num_strokes > 0
    assert (tmp_path / "rocket-edited.png").exists() and (tmp_path / "rocket-edited.svec").exists()


def test_the_stub_declares_the_whole_api():
    import ast

    tree = ast.parse((ROOT / "python" / "subvec" / "__init__.pyi").read_text())
    top = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    assert set(subvec.__all__) <= top
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "VectorImage")
    methods = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    assert methods == {n for n in dir(subvec.VectorImage) if not n.startswith("_")}


# ---- levels of abstraction -----------------------------------------------------------------


def test_levels_and_filter_equal_the_cli(tmp_path, cli, disk):
    photo, _ = disk
    image = subvec.vectorize(photo, ratio=0.05, levels=3)
    assert image.num_levels == 3 and image.has_pyramid
    counts = [lv["vertices"] for lv in image.info()["levels"]]
    assert counts[0] > counts[1] > counts[2]
    subvec.write_png(tmp_path / "photo.png", photo)
    cli("vectorize", tmp_path / "photo.png", "-o", tmp_path / "cli.svec", "--ratio", "0.05",
        "--levels", "3")
    image.save(tmp_path / "py.svec")
    assert (tmp_path / "py.svec").read_bytes() == (tmp_path / "cli.svec").read_bytes()
    # The quality options reach the library as the command's do.
    cli("vectorize", tmp_path / "photo.png", "-o", tmp_path / "cli2.svec", "--ratio", "0.05",
        "--levels", "1", "--refine", "2", "--l1-iterations", "1")
    assert subvec.vectorize(photo, ratio=0.05, levels=1, refine=2, l1_iterations=1).to_bytes() == \
        (tmp_path / "cli2.svec").read_bytes()
    assert np.array_equal(subvec.load(tmp_path / "py.svec").render(level=2),
                          subvec.load(tmp_path / "cli.svec").render(level=2))
    flat = image.filter(geometry_eta=[1], color_eta=[0])
    assert flat.num_levels == 3
    assert not np.array_equal(flat.render(), image.render())
    with pytest.raises(subvec.InvalidArgumentError):
        subvec.vectorize(photo, ratio=0.05, levels=1).filter(color_eta=[0])
