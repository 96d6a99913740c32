"""`pip install .` with no index: the in-tree build backend (python/build_backend) packs the
module built by CMake into a wheel, and the installed package imports outside the source tree.
The test reuses the CMake build the tests run from (build-dir), so it only packs and installs."""

import os
import subprocess
import sys
import zipfile

from conftest import BUILD, ROOT


def test_pip_install_from_the_source_tree_offline(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                   check=True)
    python = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([str(python), "-m", "pip", "install", "--no-index", "--no-deps",
                        "--no-cache-dir", "--config-settings", f"build-dir={BUILD}", str(ROOT)],
                       capture_output=True, text=True, env=env, cwd=tmp_path, timeout=900)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([str(python), "-c",
                        "import subvec, numpy; "
                        "img = subvec.load('" + str(ROOT / "examples" / "01-disk.svec.json") +
                        "'); print(subvec.__file__); print(img.render().shape)"],
                       capture_output=True, text=True, env=env, cwd=tmp_path, check=True)
    location, shape = r.stdout.split("\n")[:2]
    assert location.startswith(str(venv)), location
    assert shape.startswith("(")
    site = os.path.dirname(os.path.dirname(location))
    assert os.path.exists(os.path.join(site, "subvec", "__init__.pyi"))
    assert os.path.exists(os.path.join(site, "subvec", "py.typed"))


def test_wheel_contents(tmp_path):
    sys.path.insert(0, str(ROOT / "python" / "build_backend"))
    try:
        import subvec_build
    finally:
        sys.path.pop(0)
    name = subvec_build.build_wheel(str(tmp_path), {"build-dir": str(BUILD)})
    with zipfile.ZipFile(tmp_path / name) as wheel:
        names = wheel.namelist()
        record = wheel.read(next(n for n in names if n.endswith("RECORD"))).decode()
    assert "subvec/__init__.py" in names and "subvec/__init__.pyi" in names
    assert any(n.startswith("subvec/_subvec") and n.endswith(".so") for n in names)
    assert all(n in record for n in names)
    assert name.startswith("subvec-0.1.0-cp3")
