"""The installed Python module (tests/install/run.cmake): imported from PREFIX_SITE (argv[1]), not
from the build tree, and working: loads examples/01-disk.svec.json (argv[2]) and renders it."""
import sys

site, example = sys.argv[1], sys.argv[2]
sys.path.insert(0, site)
import subvec  # noqa: E402

where = getattr(subvec, "__file__", None) or ""
if not where.startswith(site + "/"):
    sys.exit(f"check_module: subvec imported from {where or 'a namespace package'}, not {site}")
frame = subvec.load(example).render(scale=2)
if frame.shape[:2] != (192, 192):
    sys.exit(f"check_module: render shape {frame.shape}")
print(f"check_module: {where}, rendered {frame.shape[1]}x{frame.shape[0]}")
