"""`subvec batch`: every image done, failures listed without stopping the others, outputs
independent of --jobs, resumable, atomic, the CSV summary, the progress bar on a terminal only."""

import csv
import os
import pty
import select
import subprocess

import numpy as np
import pytest

import subvec
from conftest import disk_image


def read_summary(out_dir):
    with open(out_dir / "summary.csv", newline="") as f:
        return {row["image"]: row for row in csv.DictReader(f)}


@pytest.fixture
def folder(tmp_path):
    """Three small photographs, a broken PNG and a file that is not an image."""
    d = tmp_path / "in"
    d.mkdir()
    for k, (w, h) in enumerate([(96, 72), (80, 64), (64, 80)]):
        subvec.write_png(d / f"img{k}.png", disk_image(w, h, cx=w / 2 - 3, cy=h / 2 + 2,
                                                       r=min(w, h) / 3.5, hue=30 * k))
    (d / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n not really")
    (d / "notes.txt").write_text("not an image")
    return d


def test_batch_does_every_image_and_lists_failures(cli, folder, tmp_path):
    out = tmp_path / "out"
    r = cli("batch", folder, "-o", out, "--jobs", "2", "--ratio", "0.03", "--render-png",
            check=False)
    assert r.returncode == 1
    lines = r.stderr.strip().splitlines()
    assert lines[-1] == "subvec: 1 of 4 images failed (listed above; the others are done)"
    assert lines[0].startswith(f"subvec: {folder / 'broken.png'}: ")
    assert "\r" not in r.stderr  # no progress bar when stderr is not a terminal
    assert "4 images: 3 vectorized, 0 skipped (already done), 1 failed" in r.stdout

    rows = read_summary(out)
    assert sorted(rows) == ["broken.png", "img0.png", "img1.png", "img2.png"]
    assert rows["broken.png"]["status"] == "failed" and rows["broken.png"]["error"]
    assert rows["broken.png"]["output"] == "" and rows["broken.png"]["mae"] == ""
    for k, (w, h) in enumerate([(96, 72), (80, 64), (64, 80)]):
        row = rows[f"img{k}.png"]
        assert row["status"] == "ok" and row["error"] == ""
        assert (int(row["width"]), int(row["height"])) == (w, h)
        image = subvec.load(out / f"img{k}.svec")
        assert (image.width, image.height) == (w, h)
        assert int(row["vertices"]) == image.info()["levels"][0]["vertices"]
        assert int(row["triangles"]) == image.info()["levels"][0]["triangles"]
        # MAE of the saved file at 1x against the input, as the summary says.
        photo = subvec.read_image(folder / f"img{k}.png")
        assert float(row["mae"]) == pytest.approx(
            subvec.compare(photo, image.render())["mae_mean"], abs=1e-4)
        assert 0 < float(row["mae"]) < 8
        assert float(row["seconds"]) > 0
        # --render-png writes what `subvec render` draws from the saved file.
        cli("render", out / f"img{k}.svec", "-o", tmp_path / "r.png")
        assert (out / f"img{k}.png").read_bytes() == (tmp_path / "r.png").read_bytes()
    assert not (out / "notes.svec").exists() and not (out / "broken.svec").exists()
    assert not [n for n in os.listdir(out) if ".tmp-" in n]


def test_outputs_do_not_depend_on_jobs(cli, folder, tmp_path):
    results = {}
    for jobs in ("1", "3"):
        out = tmp_path / f"out{jobs}"
        cli("batch", folder, "-o", out, "--jobs", jobs, "--ratio", "0.03", check=False)
        results[jobs] = {n: (out / n).read_bytes() for n in sorted(os.listdir(out))
                         if n.endswith(".svec")}
    assert sorted(results["1"]) == ["img0.svec", "img1.svec", "img2.svec"]
    assert results["1"] == results["3"]
    # --threads (per image) does not change them either.
    out = tmp_path / "threads"
    cli("batch", folder, "-o", out, "--jobs", "1", "--threads", "2", "--ratio", "0.03",
        check=False)
    assert (out / "img1.svec").read_bytes() == results["1"]["img1.svec"]
    # And they are what `subvec vectorize` writes with the same options.
    cli("vectorize", folder / "img2.png", "-o", tmp_path / "single.svec", "--ratio", "0.03")
    assert (tmp_path / "single.svec").read_bytes() == results["1"]["img2.svec"]


def test_batch_resumes_and_redoes_damaged_outputs(cli, folder, tmp_path):
    out = tmp_path / "out"
    (folder / "broken.png").unlink()
    cli("batch", folder, "-o", out, "--ratio", "0.03")
    first = read_summary(out)
    kept = {n: (out / n).stat().st_mtime_ns for n in ("img0.svec", "img1.svec", "img2.svec")}
    original = (out / "img1.svec").read_bytes()
    (out / "img1.svec").write_bytes(original[: len(original) // 2])  # an interrupted writer
    r = cli("batch", folder, "-o", out, "--ratio", "0.03")
    assert "3 images: 1 vectorized, 2 skipped" in r.stdout
    rows = read_summary(out)
    assert [rows[n]["status"] for n in ("img0.png", "img1.png", "img2.png")] == \
        ["skipped", "ok", "skipped"]
    assert (out / "img1.svec").read_bytes() == original
    assert (out / "img0.svec").stat().st_mtime_ns == kept["img0.svec"]
    for name in rows:  # a skipped image reports what a fresh run reported
        for key in ("width", "height", "vertices", "triangles", "mae"):
            assert rows[name][key] == first[name][key]


def test_same_stem_fails_the_second_image(cli, folder, tmp_path):
    subvec.write_png(folder / "img0.bmp.png", disk_image(40, 30))  # stem img0.bmp: no clash
    (folder / "img0.jpg").write_bytes((folder / "img0.png").read_bytes())  # PNG bytes, .jpg name
    r = cli("batch", folder, "-o", tmp_path / "out", "--ratio", "0.03", check=False)
    assert r.returncode == 1
    rows = read_summary(tmp_path / "out")
    # By name, img0.jpg comes first and owns img0.svec; img0.png fails, the others are done.
    assert rows["img0.png"]["status"] == "failed"
    assert rows["img0.png"]["error"] == "its output img0.svec would be the output of img0.jpg"
    assert rows["img0.jpg"]["status"] == "ok" and rows["img0.bmp.png"]["status"] == "ok"
    assert (tmp_path / "out" / "img0.bmp.svec").exists()


def test_bad_arguments(cli, tmp_path):
    r = cli("batch", tmp_path / "nope", "-o", tmp_path / "out", check=False)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "nope: no such directory" in r.stderr
    (tmp_path / "empty").mkdir()
    r = cli("batch", tmp_path / "empty", "-o", tmp_path / "out", check=False)
    assert r.returncode == 1 and "no images" in r.stderr
    assert not (tmp_path / "out" / "summary.csv").exists()
    r = cli("batch", tmp_path / "empty", "-o", tmp_path / "out", "--ratio", "2", check=False)
    assert r.returncode == 105 and "--ratio" in r.stderr
    r = cli("batch", tmp_path / "empty", "-o", tmp_path / "out", "--jobs", "-1", check=False)
    assert r.returncode == 105


def test_progress_bar_with_eta_on_a_terminal(cli, tmp_path):
    d = tmp_path / "in"
    d.mkdir()
    for k in range(6):
        subvec.write_png(d / f"p{k}.png", disk_image(200, 150, cx=90 + k, hue=10 * k))
    master, slave = pty.openpty()
    proc = subprocess.Popen([cli.path, "batch", d, "-o", tmp_path / "out", "--jobs", "1",
                             "--ratio", "0.02"], stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    seen = b""
    while True:
        ready, _, _ = select.select([master], [], [], 60)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the other end closed
            break
        if not chunk:
            break
        seen += chunk
    proc.wait(timeout=120)
    os.close(master)
    assert proc.returncode == 0
    text = seen.decode()
    assert "subvec: batch [" in text and "/6 images" in text
    assert "ETA" in text
    assert text.endswith("\r")  # the bar is erased at the end: the terminal keeps the summary


def test_help_lists_batch_and_its_options(cli):
    assert "batch" in cli("--help").stdout
    text = cli("batch", "--help").stdout
    for word in ("--jobs", "--threads", "--ratio", "--vertices", "--render-png", "--max-pixels",
                 "resumes"):
        assert word in text, word
