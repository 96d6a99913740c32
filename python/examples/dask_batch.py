#!/usr/bin/env python3
"""Vectorize a folder of images on a Dask distributed cluster: `subvec batch` beyond one machine.

    python3 dask_batch.py IN_DIR -o OUT_DIR [--workers N | --scheduler ADDRESS]
                          [--ratio R | --vertices N] [--render-png]

One task per image, each on one thread of a worker: read the image, vectorize it through the
`subvec` Python module, write OUT_DIR/<name>.svec (and <name>.png with --render-png) atomically,
measure the MAE of what was written. The rows stream back to this process as the tasks finish
(dask.distributed.as_completed) and are written to OUT_DIR/summary.csv, in the same format as
`subvec batch` writes it. A task that fails is retried once (on any worker); an image that fails
twice is listed on stderr and in the summary, and the others still run; the exit status is then 1.
Outputs that exist and read back as valid are kept, so an interrupted run resumes. The outputs are
byte-identical to those of `subvec batch` with the same options (tests/python/test_dask.py).

--workers N (default 2) starts a LocalCluster of N single-threaded worker processes on this
machine; --scheduler tcp://HOST:8786 uses a running cluster instead (`dask-scheduler` on one
machine, `dask-worker tcp://HOST:8786 --nthreads 1` on each of the others). The workers then need
the `subvec` module and must see IN_DIR and OUT_DIR at the same paths (a shared file system).
docs/python.md, "Beyond one machine".
"""

import argparse
import csv
import io
import os
import sys
import tempfile
import time

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".webp", ".tif", ".tiff", ".bmp")
COLUMNS = ["image", "output", "width", "height", "vertices", "triangles", "mae", "seconds",
           "status", "error"]
MAX_PIXELS = 1 << 25  # as `subvec batch --max-pixels` (subvec::kDefaultMaxInputPixels)
_UMASK = os.umask(0)  # read once (the call sets it), so outputs get the usual mode, as the CLI's
os.umask(_UMASK)


def list_images(in_dir):
    """The images of in_dir (not its subfolders) by name, and the .svec stem each one maps to."""
    if not os.path.isdir(in_dir):
        raise SystemExit(f"dask_batch: '{in_dir}' is not a directory")
    names = sorted(n for n in os.listdir(in_dir)
                   if n.lower().endswith(IMAGE_EXTENSIONS) and
                   os.path.isfile(os.path.join(in_dir, n)))
    if not names:
        raise SystemExit(f"dask_batch: no images ({', '.join(IMAGE_EXTENSIONS)}) in '{in_dir}'")
    return names


def write_atomic(path, data):
    """To a temporary file beside `path`, then renamed: never a partial output."""
    fd, temp = tempfile.mkstemp(dir=os.path.dirname(path) or ".",
                                prefix=os.path.basename(path) + ".tmp-")
    try:
        os.chmod(temp, 0o666 & ~_UMASK)  # mkstemp makes it 0600
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, path)
    except BaseException:
        os.unlink(temp)
        raise


def previous_output(svec_path, png_path, render_png, subvec):
    """The vector image a previous run wrote, when its outputs exist and read back as valid."""
    if not os.path.isfile(svec_path) or (render_png and not os.path.isfile(png_path)):
        return None
    try:
        saved = subvec.load(svec_path)
        if render_png:
            png = subvec.read_image(png_path)
            if png.shape[:2] != (saved.height, saved.width):
                return None
        return saved
    except subvec.Error:
        return None


def vectorize_one(in_path, out_dir, conflict, ratio, vertices, levels, render_png,
                  fail_once_dir=None):
    """The task: one image, as `subvec batch` does it (apps/cli/batch.cpp). Returns its row."""
    import subvec  # on the worker

    start = time.monotonic()
    name = os.path.basename(in_path)
    if fail_once_dir:  # for the test of retries: the first attempt at each image fails
        marker = os.path.join(fail_once_dir, name)
        if not os.path.exists(marker):
            open(marker, "w").close()
            raise RuntimeError(f"{name}: failing once on purpose (--fail-once)")
    if conflict:
        raise subvec.InvalidArgumentError(conflict)
    stem = os.path.splitext(name)[0]
    svec_path = os.path.join(out_dir, stem + ".svec")
    png_path = os.path.join(out_dir, stem + ".png")
    photo = subvec.read_image(in_path, max_pixels=MAX_PIXELS)
    height, width = photo.shape[:2]

    saved = previous_output(svec_path, png_path, render_png, subvec)
    skipped = saved is not None
    if saved is not None and (saved.width, saved.height) != (width, height):
        saved = None
    data = None
    if saved is None:
        # Only the options given: the defaults and their ranges are the library's.
        given = {"ratio": ratio, "vertices": vertices, "levels": levels}
        options = {key: value for key, value in given.items() if value is not None}
        data = subvec.vectorize(photo, threads=1, **options).to_bytes()
        saved = subvec.from_bytes(data)  # what the file holds, measured and drawn below
    rendered = saved.render(threads=1)
    mae = subvec.compare(photo, rendered)["mae_mean"]
    if data is not None:
        if render_png:
            subvec.write_png(png_path, rendered)  # atomic in the library
        write_atomic(svec_path, data)
    level = saved.info()["levels"][0]
    return {"image": name, "output": stem + ".svec", "width": width, "height": height,
            "vertices": level["vertices"], "triangles": level["triangles"], "mae": f"{mae:.4f}",
            "seconds": f"{time.monotonic() - start:.3f}",
            "status": "skipped" if skipped and data is None else "ok", "error": ""}


def failed_row(name, seconds, error):
    return {"image": name, "output": "", "width": "", "height": "", "vertices": "",
            "triangles": "", "mae": "", "seconds": f"{seconds:.3f}", "status": "failed",
            "error": " ".join(str(error).splitlines())}


def summary_csv(rows):
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    for row in sorted(rows, key=lambda r: r["image"]):
        writer.writerow(row)
    return out.getvalue()


def run(client, in_dir, out_dir, ratio=None, vertices=None, levels=None, render_png=False,
        fail_once_dir=None,
        log=sys.stderr):
    """Vectorizes in_dir into out_dir on `client`'s cluster; returns the summary rows."""
    from dask.distributed import as_completed

    names = list_images(in_dir)
    os.makedirs(out_dir, exist_ok=True)
    first_with_stem, futures = {}, {}
    start = time.monotonic()
    for name in names:
        stem = os.path.splitext(name)[0]
        owner = first_with_stem.setdefault(stem, name)
        conflict = "" if owner == name else \
            f"its output {stem}.svec would be the output of {owner}"
        future = client.submit(vectorize_one, os.path.join(in_dir, name), out_dir, conflict,
                               ratio, vertices, levels, render_png, fail_once_dir,
                               key=f"vectorize-{name}", retries=1, pure=False)
        futures[future] = name
    rows = []
    for done, future in enumerate(as_completed(futures), 1):
        name = futures[future]
        if future.status == "finished":
            row = future.result()
        else:
            row = failed_row(name, time.monotonic() - start, future.exception())
        rows.append(row)
        print(f"[{done}/{len(names)}] {name}: {row['status']}"
              f"{' (' + row['error'] + ')' if row['error'] else ''}", file=log, flush=True)
    write_atomic(os.path.join(out_dir, "summary.csv"), summary_csv(rows).encode())
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input", help="folder of images (PNG, JPEG, WebP, TIFF, BMP)")
    parser.add_argument("-o", "--output", required=True, help="output folder (created)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=2,
                       help="worker processes of a LocalCluster on this machine (default 2)")
    where.add_argument("--scheduler", help="address of a running Dask scheduler")
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--ratio", type=float,
                      help="control vertices as a fraction of the pixel count (default: subvec.vectorize's)")
    size.add_argument("--vertices", type=int, help="control vertex count instead")
    parser.add_argument("--levels", type=int,
                        help="levels of abstraction (default: subvec.vectorize's), as subvec vectorize")
    parser.add_argument("--render-png", action="store_true", help="also write NAME.png")
    parser.add_argument("--fail-once", metavar="DIR", help=argparse.SUPPRESS)  # tests: retries
    args = parser.parse_args(argv)

    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        client = Client(args.scheduler)
        cluster = None
    else:
        if args.workers < 1:
            parser.error("--workers must be at least 1")
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        rows = run(client, args.input, args.output, ratio=args.ratio, vertices=args.vertices,
                   levels=args.levels,
                   render_png=args.render_png, fail_once_dir=args.fail_once)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    failed = [r for r in rows if r["status"] == "failed"]
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "skipped", "failed")}
    print(f"{len(rows)} images: {counts['ok']} vectorized, {counts['skipped']} skipped, "
          f"{counts['failed']} failed; summary in {os.path.join(args.output, 'summary.csv')}")
    for row in sorted(failed, key=lambda r: r["image"]):
        print(f"dask_batch: {os.path.join(args.input, row['image'])}: {row['error']}",
              file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
