"""The PEP 517 build backend of `pip install .` (pyproject.toml): no downloads, no setuptools.

It configures and builds the CMake project with the system's tools (only the library and the
Python module: tests and benchmarks off), then packs the package directory the build assembles
(<build>/python/subvec: __init__.py, the stubs and the extension) into a wheel for the running
interpreter.

Build directory: `build-wheel/` in the source tree, or the one given by
`--config-settings build-dir=DIR` (or SUBVEC_WHEEL_BUILD_DIR). A directory that CMake has already
configured (for instance `build/`) is built as it is and not reconfigured, so that its other
options stay; the backend then checks that its extension was built for this interpreter.
"""

import base64
import hashlib
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
NAME = "subvec"


def _version():
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(\s*subvec\s+VERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError("subvec_build: no 'project(subvec VERSION ...)' in CMakeLists.txt")
    return match.group(1)


def _metadata():
    return (
        "Metadata-Version: 2.1\n"
        f"Name: {NAME}\n"
        f"Version: {_version()}\n"
        "Summary: Vector images built on piecewise smooth Loop subdivision surfaces\n"
        "Requires-Python: >=3.9\n"
        "Requires-Dist: numpy\n"
    )


def _tag():
    impl = f"cp{sys.version_info.major}{sys.version_info.minor}"
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return f"{impl}-{impl}-{platform}"


def _dist_info():
    return f"{NAME}-{_version()}.dist-info"


def _setting(config_settings, key, env):
    value = (config_settings or {}).get(key) or os.environ.get(env)
    return value or None


def _build(config_settings):
    build_dir = pathlib.Path(
        _setting(config_settings, "build-dir", "SUBVEC_WHEEL_BUILD_DIR") or ROOT / "build-wheel")
    if not build_dir.is_absolute():
        build_dir = ROOT / build_dir
    jobs = _setting(config_settings, "jobs", "SUBVEC_JOBS") or str(os.cpu_count() or 1)
    cmake = shutil.which("cmake")
    if not cmake:
        raise RuntimeError("subvec_build: cmake not found (Debian: apt-get install cmake; "
                           "scripts/setup installs every dependency)")
    if not (build_dir / "CMakeCache.txt").exists():
        args = [cmake, "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                "-DSUBVEC_BUILD_TESTS=OFF", "-DSUBVEC_BUILD_BENCH=OFF", "-DSUBVEC_BUILD_PYTHON=ON",
                f"-DPython3_EXECUTABLE={sys.executable}"]
        if shutil.which("ninja"):
            args += ["-G", "Ninja"]
        subprocess.run(args, check=True, stdout=sys.stderr)
    subprocess.run([cmake, "--build", str(build_dir), "--target", "subvec_python",
                    "subvec_python_files", "-j", jobs], check=True, stdout=sys.stderr)
    package = build_dir / "python" / NAME
    suffix = sysconfig.get_config_var("EXT_SUFFIX")
    if not (package / f"_subvec{suffix}").exists():
        found = sorted(p.name for p in package.glob("_subvec*"))
        raise RuntimeError(f"subvec_build: {build_dir} holds {found or 'no extension'}, not "
                           f"_subvec{suffix} for {sys.executable}; use another build-dir")
    return package, suffix


def _record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    dist_info = pathlib.Path(metadata_directory) / _dist_info()
    dist_info.mkdir(parents=True, exist_ok=True)
    (dist_info / "METADATA").write_text(_metadata(), encoding="utf-8")
    return dist_info.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    package, suffix = _build(config_settings)
    wheel_name = f"{NAME}-{_version()}-{_tag()}.whl"
    files = []
    for path in sorted(package.iterdir()):
        # The extension for this interpreter, the Python sources, stubs and the py.typed marker.
        if path.is_file() and (path.name == f"_subvec{suffix}" or
                               path.suffix in (".py", ".pyi", ".typed")):
            files.append((f"{NAME}/{path.name}", path.read_bytes()))
    dist_info = _dist_info()
    files.append((f"{dist_info}/METADATA", _metadata().encode()))
    files.append((f"{dist_info}/WHEEL", (
        "Wheel-Version: 1.0\n"
        "Generator: subvec_build\n"
        "Root-Is-Purelib: false\n"
        f"Tag: {_tag()}\n").encode()))
    files.append((f"{dist_info}/top_level.txt", f"{NAME}\n".encode()))
    record = [_record_line(name, data) for name, data in files]
    record.append(f"{dist_info}/RECORD,,")
    files.append((f"{dist_info}/RECORD", ("\n".join(record) + "\n").encode()))

    out = pathlib.Path(wheel_directory)
    out.mkdir(parents=True, exist_ok=True)
    temp = out / (wheel_name + ".part")
    with zipfile.ZipFile(temp, "w", compression=zipfile.ZIP_DEFLATED) as wheel:
        for name, data in files:
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = (0o755 if name.endswith(suffix) else 0o644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            wheel.writestr(info, data)
    os.replace(temp, out / wheel_name)
    return wheel_name
