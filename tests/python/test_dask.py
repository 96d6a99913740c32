"""The Dask example (python/examples/dask_batch.py) on a LocalCluster with 2 workers over the
shared photographs: the same outputs, byte for byte, and the same summary as `subvec batch`, with
a failure reported and every task failing once on purpose to exercise the retry."""

import csv
import os
import subprocess
import sys

import pytest

from conftest import ROOT

pytest.importorskip("distributed")
EXAMPLE = ROOT / "python" / "examples" / "dask_batch.py"


def summary(out_dir):
    with open(out_dir / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        del row["seconds"]  # wall-clock: the one column that differs between runs
    return rows


def test_dask_example_matches_subvec_batch(cli, shared_images, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in sorted(os.listdir(shared_images)):
        if name.endswith(".png"):
            (folder / name).symlink_to(shared_images / name)
    (folder / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")

    r = cli("batch", folder, "-o", tmp_path / "batch", "--jobs", "2", "--render-png",
            check=False)
    assert r.returncode == 1, r.stderr

    fail_once = tmp_path / "fail-once"
    fail_once.mkdir()
    env = dict(os.environ)
    r = subprocess.run([sys.executable, str(EXAMPLE), str(folder), "-o", str(tmp_path / "dask"),
                        "--workers", "2", "--render-png", "--fail-once", str(fail_once)],
                       capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 1, r.stderr
    assert f"dask_batch: {folder / 'broken.png'}: " in r.stderr
    # Every image was attempted twice: the first attempt failed on purpose, the retry ran.
    images = sorted(n for n in os.listdir(folder))
    assert sorted(os.listdir(fail_once)) == images

    batch_files = sorted(os.listdir(tmp_path / "batch"))
    assert batch_files == sorted(os.listdir(tmp_path / "dask"))
    assert len([n for n in batch_files if n.endswith(".svec")]) == len(images) - 1
    assert len([n for n in batch_files if n.endswith(".png")]) == len(images) - 1
    for name in batch_files:
        if name != "summary.csv":
            assert (tmp_path / "batch" / name).read_bytes() == \
                (tmp_path / "dask" / name).read_bytes(), name
    rows = summary(tmp_path / "batch")
    assert summary(tmp_path / "dask") == rows
    assert [row["status"] for row in rows].count("ok") == len(images) - 1
    assert next(r for r in rows if r["image"] == "broken.png")["status"] == "failed"

    # A second run resumes: everything is skipped, the summary is the same.
    r = subprocess.run([sys.executable, str(EXAMPLE), str(folder), "-o", str(tmp_path / "dask"),
                        "--workers", "2", "--render-png"],
                       capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 1, r.stderr
    again = summary(tmp_path / "dask")
    assert [row["status"] for row in again].count("skipped") == len(images) - 1
    for a, b in zip(again, rows):
        assert {**a, "status": ""} == {**b, "status": ""}
