"""Shared fixtures of the Python tests (ctest runs them with PYTHONPATH=<build>/python and
SUBVEC_CLI=<build>/bin/subvec; by hand: PYTHONPATH=build/python python3 -m pytest tests/python)."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("SUBVEC_BUILD_DIR", ROOT / "build"))
SHARED_IMAGES = ROOT.parent / "shared" / "images"


@pytest.fixture(scope="session")
def cli():
    """Runs the built `subvec` command; returns the CompletedProcess (text mode)."""
    path = os.environ.get("SUBVEC_CLI", str(BUILD / "bin" / "subvec"))
    if not os.path.exists(path):
        pytest.fail(f"no subvec command at {path} (build first, or set SUBVEC_CLI)")

    def run(*args, check=True, **kwargs):
        result = subprocess.run([path, *map(str, args)], capture_output=True, text=True, **kwargs)
        if check and result.returncode != 0:
            raise AssertionError(f"subvec {' '.join(map(str, args))} exited "
                                 f"{result.returncode}: {result.stderr}")
        return result

    run.path = path
    return run


@pytest.fixture(scope="session")
def shared_images():
    if not SHARED_IMAGES.is_dir():
        pytest.skip(f"no {SHARED_IMAGES}: shared photographs not present")
    return SHARED_IMAGES


def disk_image(width=96, height=72, cx=40.3, cy=33.6, r=21.4, hue=0):
    """A disk over a gradient, anti-aliased by 4x4 supersampling: H x W x 3 uint8."""
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    inside = np.zeros((height, width))
    for sy in range(4):
        for sx in range(4):
            inside += (np.hypot(xs + (sx + 0.5) / 4 - cx, ys + (sy + 0.5) / 4 - cy) < r) / 16
    bg = np.stack([40 + 120 * xs / width, 60 + 0 * xs + hue, 200 - 100 * xs / width], axis=-1)
    fg = np.stack([230 + 0 * ys, 200 - 60 * ys / height, 40 + 0 * ys + hue], axis=-1)
    img = inside[..., None] * fg + (1 - inside[..., None]) * bg
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)
