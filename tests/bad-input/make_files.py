#!/usr/bin/env python3
"""Writes both corpora of bad inputs: the command line's, tests/bad-input/files/*, and the
library's, tests/data/bad/*.

Run: python3 tests/bad-input/make_files.py [--library]

- tests/bad-input/files/: what a stranger may hand `subvec`. cases.txt says what the command line
  must answer for each file (tests/unit/cli/bad_input_test.cpp); README.md describes the format.
  Needs cjpeg and cwebp (Debian packages libjpeg-turbo-progs and webp) for the two valid images
  the JPEG and WebP cases start from, zstd, and build/bin/subvec (or $SUBVEC) for the binary
  .svec cases. Every file is small (under 10 kB): decompression bombs declare absurd sizes in
  their headers rather than holding the pixels.
- tests/data/bad/: each file breaks exactly one rule of docs/format.md;
  tests/unit/io/bad_files_test.cpp lists, for every file, the error code and the words its message
  must contain, and cases.txt runs each through the command line too. Standard library only (the
  binary files hold their payload in stored, uncompressed zstd blocks); `--library` writes only
  these. Most start from the 4 x 4 worked example of docs/format.md (corners 0-3, center 4).

The written files are committed, so the tests need none of the tools. Some files are also seeds of
the fuzzers (fuzz/corpus/*/, the command line's with a "bad-input-" prefix).
"""
import copy
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "files")
LIBRARY = os.path.join(HERE, "..", "data", "bad")


def write(name, data, folder=OUT):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(folder, name), mode) as out:
        out.write(data)


# ---- PNG -----------------------------------------------------------------------------------------

def chunk(kind, payload):
    body = kind + payload
    return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png(width, height, rows=None, color_type=2, depth=8, idat=None):
    """An RGB (color_type 2) or gray (0) PNG; `rows` are bytes per row without the filter byte."""
    channels = {0: 1, 2: 3, 6: 4}[color_type]
    if idat is None:
        if rows is None:
            rows = [bytes((x * 4 + y * 2 + c * 60) % 256 for x in range(width) for c in range(channels))
                    for y in range(height)]
        idat = zlib.compress(b"".join(b"\0" + r for r in rows), 9)
    ihdr = struct.pack(">IIBBBBB", width, height, depth, color_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def png_files():
    good = png(64, 48)
    write("valid-64x48.png", good)
    write("valid-32x24.png", png(32, 24))
    write("png-truncated.png", good[: len(good) // 2])
    write("png-only-signature.png", good[:8])
    # One byte of the compressed pixels changed: the chunk's CRC no longer matches.
    bad = bytearray(good)
    bad[60] ^= 0x55
    write("png-bad-crc.png", bytes(bad))
    # Garbage in place of the zlib stream, with a correct CRC: only the decoder can tell.
    write("png-bad-zlib.png", png(64, 48, idat=bytes(range(7, 250))))
    # A valid zlib stream that holds only half of the rows.
    half = [bytes(64 * 3)] * 24
    write("png-short-data.png", png(64, 48, idat=zlib.compress(b"".join(b"\0" + r for r in half))))
    # A valid zlib stream with a filter type byte of 9 (there are five filters).
    rows = b"".join(b"\x09" + bytes(32 * 3) for _ in range(24))
    write("png-bad-filter.png", png(32, 24, idat=zlib.compress(rows)))
    # No IDAT at all.
    ihdr = struct.pack(">IIBBBBB", 8, 8, 8, 2, 0, 0, 0)
    write("png-no-idat.png", b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IEND", b""))
    # An invalid bit depth for RGB.
    write("png-bad-depth.png", png(8, 8, idat=zlib.compress(bytes(8 * 25)), depth=3))
    # Zero-size images.
    write("png-zero-width.png", png(0, 16, idat=zlib.compress(b"\0" * 16)))
    write("png-zero-height.png", png(16, 0, idat=zlib.compress(b"")))
    # Decompression bombs: absurd sizes declared in IHDR, a few bytes of data.
    tiny = zlib.compress(bytes(1000))
    write("png-bomb-100000x100000.png", png(100000, 100000, idat=tiny))
    write("png-bomb-2^31x2^31.png", png(2**31 - 1, 2**31 - 1, idat=tiny))
    write("png-bomb-4000x4000.png", png(4000, 4000, idat=tiny))  # over --max-pixels 1000000
    # A 20000 x 20000 gray image of zeros, deflated: 400 MB of pixels in a 400 kB stream would be
    # a real bomb; this one holds only 50 rows (the rest missing), so the header check must act.
    rows = zlib.compress(b"".join(b"\0" + bytes(20000) for _ in range(50)), 9)
    write("png-bomb-gray-20000x20000.png", png(20000, 20000, color_type=0, idat=rows))
    # Tiny but valid images.
    write("png-1x1.png", png(1, 1))
    write("png-2x2.png", png(2, 2))
    write("png-1x64.png", png(1, 64))
    write("png-64x1.png", png(64, 1))


# ---- JPEG ----------------------------------------------------------------------------------------

def tool_output(command, data):
    return subprocess.run(command, input=data, stdout=subprocess.PIPE, check=True).stdout


def ppm(width, height):
    pixels = bytes((x * 4 + y * 2 + c * 60) % 256 for y in range(height) for x in range(width)
                   for c in range(3))
    return b"P6\n%d %d\n255\n" % (width, height) + pixels


def jpeg_segments(data):
    """(marker, offset) of each marker segment up to the start of scan."""
    out, i = [], 2
    while i < len(data):
        marker = data[i + 1]
        out.append((marker, i))
        if marker == 0xDA:
            break
        i += 2 + struct.unpack(">H", data[i + 2:i + 4])[0]
    return out


def jpeg_files():
    good = tool_output(["cjpeg", "-quality", "90"], ppm(64, 48))
    write("valid-64x48.jpg", good)
    segments = dict(jpeg_segments(good))
    sof, sos, dht = segments[0xC0], segments[0xDA], segments[0xC4]
    write("jpeg-truncated.jpg", good[: len(good) // 2])
    write("jpeg-only-soi.jpg", good[:3])
    # No end-of-image marker.
    write("jpeg-no-eoi.jpg", good[:-2])

    def with_size(width, height):
        b = bytearray(good)
        struct.pack_into(">HH", b, sof + 5, height, width)
        return bytes(b)

    write("jpeg-zero-height.jpg", with_size(64, 0))
    write("jpeg-zero-width.jpg", with_size(0, 48))
    write("jpeg-bomb-65500x65500.jpg", with_size(65500, 65500))
    write("jpeg-bomb-4000x4000.jpg", with_size(4000, 4000))  # over --max-pixels 1000000
    # A Huffman table whose code counts overflow.
    b = bytearray(good)
    for k in range(16):
        b[dht + 5 + k] = 0xFF
    write("jpeg-bad-huffman.jpg", bytes(b))
    # The frame header says 7 components.
    b = bytearray(good)
    b[sof + 9] = 7
    write("jpeg-bad-components.jpg", bytes(b))
    # The scan starts before any frame header.
    write("jpeg-no-frame.jpg", good[:sof] + good[sos:])
    # Random bytes after a valid start of image.
    write("jpeg-garbage.jpg", b"\xff\xd8\xff" + bytes((k * 37 + 11) % 256 for k in range(400)))


# ---- BMP, TIFF, WebP, others ---------------------------------------------------------------------

def bmp(width, height, pixels=None, bits=24):
    row = (bits * abs(width) + 31) // 32 * 4
    if pixels is None:
        pixels = bytes(row * abs(height))
    header = struct.pack("<2sIHHI", b"BM", 54 + len(pixels), 0, 0, 54)
    dib = struct.pack("<IiiHHIIiiII", 40, width, height, 1, bits, 0, len(pixels), 2835, 2835, 0, 0)
    return header + dib + pixels


def tiff(width, height, strip=None, big_endian=False):
    """A baseline RGB TIFF with one uncompressed strip."""
    e = ">" if big_endian else "<"
    if strip is None:
        strip = bytes(width * height * 3)
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 8), (259, 3, 1, 1),
               (262, 3, 1, 2), (273, 4, 1, 0), (277, 3, 1, 3), (278, 4, 1, height),
               (279, 4, 1, len(strip))]
    ifd_at = 8
    data_at = ifd_at + 2 + 12 * len(entries) + 4
    out = (b"MM" if big_endian else b"II") + struct.pack(e + "HI", 42, ifd_at)
    out += struct.pack(e + "H", len(entries))
    for tag, kind, count, value in entries:
        if tag == 273:
            value = data_at
        if kind == 3:
            out += struct.pack(e + "HHIHH", tag, kind, count, value, 0)
        else:
            out += struct.pack(e + "HHII", tag, kind, count, value)
    out += struct.pack(e + "I", 0)
    return out + strip


def bigtiff(width, height):
    """A BigTIFF (version 43) header and directory declaring a width x height RGB image."""
    entries = [(256, 16, 1, width), (257, 16, 1, height), (258, 3, 1, 8), (259, 3, 1, 1),
               (262, 3, 1, 2), (273, 16, 1, 0), (277, 3, 1, 3), (278, 16, 1, height),
               (279, 16, 1, 3000)]
    out = b"II" + struct.pack("<HHHQ", 43, 8, 0, 16)
    out += struct.pack("<Q", len(entries))
    data_at = 16 + 8 + 20 * len(entries) + 8
    for tag, kind, count, value in entries:
        if tag == 273:
            value = data_at
        if kind == 3:
            out += struct.pack("<HHQH6x", tag, kind, count, value)
        else:
            out += struct.pack("<HHQQ", tag, kind, count, value)
    out += struct.pack("<Q", 0)
    return out + bytes(3000)


def other_files():
    write("empty.png", b"")
    write("text.png", "this is not an image\n")
    write("gif.gif", b"GIF89a\x01\x00\x01\x00\x00\x00\x00;")
    write("bmp-truncated.bmp", bmp(64, 48)[:2000])
    write("bmp-bomb-100000x100000.bmp", bmp(100000, 100000, pixels=bytes(64)))
    write("bmp-bomb-negative.bmp", bmp(-2**31, -2**31, pixels=bytes(64)))
    write("bmp-zero.bmp", bmp(0, 0, pixels=b""))
    write("bmp-bad-bits.bmp", bmp(8, 8, pixels=bytes(256), bits=13))
    write("tiff-truncated.tiff", tiff(32, 24)[:500])
    write("tiff-bomb-100000x100000.tiff", tiff(100000, 100000, strip=bytes(3000)))
    write("tiff-bomb-big-endian.tiff", tiff(100000, 100000, strip=bytes(3000), big_endian=True))
    write("bigtiff-bomb.tiff", bigtiff(100000, 100000))
    write("tiff-zero.tiff", tiff(0, 0, strip=bytes(16)))
    # A directory offset past the end of the file.
    b = bytearray(tiff(8, 8))
    struct.pack_into("<I", b, 4, 0x7FFFFFF0)
    write("tiff-bad-offset.tiff", bytes(b))
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "in.ppm")
        dst = os.path.join(tmp, "out.webp")
        with open(src, "wb") as f:
            f.write(ppm(64, 48))
        subprocess.run(["cwebp", "-quiet", src, "-o", dst], check=True)
        with open(dst, "rb") as f:
            good_webp = f.read()
    write("webp-truncated.webp", good_webp[: len(good_webp) // 2])
    # VP8X (extended) header declaring a 16777216 x 16777216 canvas.
    vp8x = b"VP8X" + struct.pack("<I", 10) + bytes([0, 0, 0, 0]) + b"\xff\xff\xff\xff\xff\xff"
    write("webp-bomb.webp", b"RIFF" + struct.pack("<I", 4 + len(vp8x)) + b"WEBP" + vp8x)


# ---- vector images -------------------------------------------------------------------------------

# The 4 x 4 worked example of docs/format.md, which both corpora start from.
SQUARE = {
    "format": "subvec", "version": 1, "width": 4, "height": 4,
    "levels": [{
        "vertices": [[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]],
        "colors": [[255, 0, 0], [255, 0, 0], [0, 0, 255], [0, 0, 255], [127.5, 0, 127.5]],
        "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    }],
}


def square(top=None, **level):
    image = json.loads(json.dumps(SQUARE))
    image["levels"][0].update(level)
    image.update(top or {})
    return json.dumps(image) + "\n"


def svec_json_files():
    write("svec-valid.svec.json", square())
    write("svec-negative-width.svec.json", square({"width": -4}))
    write("svec-zero-size.svec.json", square({"width": 0, "height": 0}))
    write("svec-fractional-width.svec.json", square({"width": 4.5}))
    write("svec-no-levels.svec.json", square({"levels": []}))
    write("svec-65-levels.svec.json", square({"levels": [SQUARE["levels"][0]] * 65}))
    write("svec-negative-index.svec.json", square(triangles=[[0, 1, 4], [1, 2, -1], [2, 3, 4], [3, 0, 4]]))
    write("svec-index-2^40.svec.json", square(triangles=[[0, 1, 4], [1, 2, 2**40], [2, 3, 4], [3, 0, 4]]))
    write("svec-fractional-index.svec.json", square(triangles=[[0, 1, 4], [1, 2, 4.5], [2, 3, 4], [3, 0, 4]]))
    write("svec-repeated-vertex.svec.json", square(triangles=[[0, 1, 4], [1, 1, 4], [2, 3, 4], [3, 0, 4]]))
    write("svec-two-triangles-missing.svec.json", square(triangles=[[0, 1, 4], [2, 3, 4]]))
    write("svec-infinity.svec.json", square().replace("[2, 2]", "[Infinity, 2]"))
    write("svec-nan.svec.json", square().replace("[2, 2]", "[NaN, 2]"))
    write("svec-1e308-position.svec.json", square(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [1e308, 2]]))
    write("svec-1e400-color.svec.json", square().replace("127.5, 0, 127.5", "1e400, 0, 127.5"))
    # Finite but huge colors, and a saliency and a stroke with absurd values: all must be refused
    # or drawn without overflow.
    write("svec-huge-color.svec.json", square(colors=[[1e308, 0, 0], [-1e308, 0, 0], [0, 0, 255],
                                                      [0, 0, 255], [127.5, 0, 127.5]]))
    # The largest 32-bit floats: valid, must render without overflow.
    write("svec-color-3e38.svec.json", square(colors=[[3e38, 0, 0], [-3e38, 0, 0], [0, 3e38, 255],
                                                      [0, 0, -3e38], [3e38, 3e38, 3e38]]))
    stroke = {"points": [[1, 1], [3, 3]], "width": 1, "color": [0, 0, 0]}
    write("svec-stroke-huge-width.svec.json", square({"strokes": [dict(stroke, width=1e300)]}))
    write("svec-stroke-width-3e38.svec.json", square({"strokes": [dict(stroke, width=3e38)]}))
    write("svec-stroke-points-3e38.svec.json",
          square({"strokes": [dict(stroke, points=[[-3e38, -3e38], [3e38, 3e38], [1, 3e38]])]}))
    write("svec-stroke-color-3e38.svec.json", square({"strokes": [dict(stroke, color=[3e38, -3e38, 0])]}))
    write("svec-stroke-huge-points.svec.json",
          square({"strokes": [dict(stroke, points=[[-1e300, -1e300], [1e300, 1e300]])]}))
    write("svec-stroke-one-point.svec.json", square({"strokes": [dict(stroke, points=[[1, 1]])]}))
    write("svec-stroke-level-5.svec.json", square({"strokes": [dict(stroke, level=5)]}))
    write("svec-stroke-huge-color.svec.json", square({"strokes": [dict(stroke, color=[1e308, 0, 0])]}))
    # Features: not along mesh edges, repeated, of one vertex, crossing the border.
    write("svec-feature-not-edge.svec.json", square(features=[{"id": 0, "vertices": [0, 2]}]))
    write("svec-feature-one-vertex.svec.json", square(features=[{"id": 0, "vertices": [4]}]))
    write("svec-feature-repeated-edge.svec.json", square(features=[{"id": 0, "vertices": [0, 4, 0]}]))
    write("svec-feature-duplicate-id.svec.json",
          square(features=[{"id": 0, "vertices": [0, 4]}, {"id": 0, "vertices": [4, 2]}],
                 triangle_colors=[[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    write("svec-feature-huge-saliency.svec.json",
          square(features=[{"id": 0, "vertices": [0, 4, 2], "saliency": 1e400}]))
    write("svec-crease-not-edge.svec.json", square(creases=[[0, 2]]))
    # The mesh: flipped, overlapping, not covering, degenerate.
    write("svec-flipped.svec.json", square(triangles=[[0, 4, 1], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    write("svec-all-flipped.svec.json", square(triangles=[[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]]))
    write("svec-not-covering.svec.json",
          square(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]],
                 triangles=[[0, 1, 4], [1, 2, 4], [2, 3, 4]]))
    write("svec-degenerate.svec.json",
          square(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [2, 0]],
                 triangles=[[0, 4, 3], [4, 1, 2], [4, 2, 3], [0, 1, 4]]))
    write("svec-overlap.svec.json",
          square(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [2, 2], [3, 1]],
                 colors=[[0, 0, 0]] * 6,
                 triangles=[[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 1, 5]]))
    # A big declared size with a tiny mesh: rendering at 1x would be 2^30 pixels.
    big = {"width": 32768, "height": 32768}
    scaled = json.loads(square())
    scaled.update(big)
    scaled["levels"][0]["vertices"] = [[0, 0], [32768, 0], [32768, 32768], [0, 32768], [16384, 16384]]
    write("svec-32768x32768.svec.json", json.dumps(scaled) + "\n")
    # Structure: deep nesting, wrong top-level types.
    write("svec-deep-nesting.svec.json", "[" * 5000 + "]" * 5000 + "\n")
    write("svec-array.svec.json", "[]\n")
    write("svec-empty.svec.json", "")
    write("svec-bom.svec.json", "\ufeff" + square())
    write("svec-metadata-bad-utf8.svec.json",
          square({"metadata": {"title": "x"}}).encode().replace(b'"x"', b'"\xff\xfe"'))


# ---- edit operations -----------------------------------------------------------------------------

def ops_files():
    def ops(name, value):
        write(name, value if isinstance(value, str) else json.dumps(value) + "\n")

    ops("ops-empty.json", [])
    ops("ops-not-json.json", "drag it over there\n")
    ops("ops-object.json", {"op": "drag"})
    ops("ops-unknown-op.json", [{"op": "explode", "at": [10, 10]}])
    ops("ops-feature-nowhere.json",
        [{"op": "drag", "select": "feature", "from": [48, 48], "to": [50, 50]}])
    ops("ops-move-feature-nowhere.json", [{"op": "move-feature", "at": [2, 2], "translate": [1, 1]}])
    ops("ops-level-5.json", [{"op": "drag", "select": "vertex", "from": [48, 48], "to": [50, 50],
                              "level": 5}])
    ops("ops-negative-level.json", [{"op": "drag", "select": "vertex", "from": [48, 48],
                                     "to": [50, 50], "level": -1}])
    ops("ops-outside.json", [{"op": "drag", "select": "vertex", "from": [1e9, 48], "to": [50, 50]}])
    ops("ops-to-huge.json", [{"op": "drag", "select": "vertex", "from": [48, 48], "to": [1e308, 1e308]}])
    ops("ops-sigma-zero.json", [{"op": "drag", "select": "feature", "from": [20, 48], "to": [22, 48],
                                 "sigma": 0}])
    ops("ops-sigma-negative.json", [{"op": "drag", "select": "feature", "from": [20, 48],
                                     "to": [22, 48], "sigma": -5}])
    ops("ops-rotate-huge.json", [{"op": "move-feature", "at": [20, 48], "translate": [0, 0],
                                  "rotate": 1e308}])
    ops("ops-translate-huge.json", [{"op": "move-feature", "at": [20, 48], "translate": [1e300, 0]}])
    ops("ops-radius-negative.json", [{"op": "color", "mode": "blend", "at": [48, 48], "radius": -3,
                                      "color": [0, 0, 0], "amount": 0.5}])
    ops("ops-amount-huge.json", [{"op": "color", "mode": "blend", "at": [48, 48], "radius": 3,
                                  "color": [0, 0, 0], "amount": 1e308}])
    ops("ops-color-huge.json", [{"op": "color", "mode": "blend", "at": [48, 48], "radius": 3,
                                 "color": [1e308, 0, 0], "amount": 0.5}])
    ops("ops-color-wrong-length.json", [{"op": "color", "mode": "blend", "at": [48, 48],
                                         "radius": 3, "color": [0, 0], "amount": 0.5}])
    ops("ops-infinity.json", '[{"op": "drag", "select": "vertex", "from": [48, 48], "to": [Infinity, 1]}]\n')
    ops("ops-number-overflow.json", '[{"op": "drag", "select": "vertex", "from": [48, 48], "to": [1e400, 1]}]\n')
    ops("ops-add-feature-one-point.json", [{"op": "add-feature", "points": [[10, 10]]}])
    ops("ops-add-feature-kind.json", [{"op": "add-feature", "points": [[10, 10], [20, 30]], "kind": "fold"}])
    ops("ops-add-feature-crossing.json", [{"op": "add-feature", "points": [[5, 47.3], [91, 47.3]]}])
    ops("ops-add-feature-outside.json", [{"op": "add-feature", "points": [[10, 10], [10, 1e9]]}])
    ops("ops-delete-feature-outside.json", [{"op": "delete-feature", "at": [-3, 10]}])
    # Objects (edit/objects.h): the example disk made an object, then edited as one.
    ops("ops-objects.json", [
        {"op": "make-object", "at": [48, 48], "name": "disk"},
        {"op": "move-object", "object": 0, "translate": [20, -5], "rotate": 15, "scale": 0.8},
        {"op": "hide-object", "object": 0},
        {"op": "show-object", "object": 0},
        {"op": "order-object", "object": 0, "to": 0}])
    ops("ops-make-object-nowhere.json", [{"op": "make-object", "at": [3, 3]}])
    ops("ops-move-object-missing.json", [{"op": "move-object", "object": 0, "translate": [5, 5]}])
    ops("ops-move-object-scale-zero.json", [{"op": "move-object", "object": 0, "scale": 0}])
    ops("ops-move-object-nothing.json", [{"op": "move-object", "object": 0}])
    ops("ops-order-object-to-far.json", [{"op": "make-object", "at": [48, 48]},
                                         {"op": "order-object", "object": 0, "to": 3}])
    ops("ops-deep-nesting.json", "[" * 5000 + "]" * 5000 + "\n")
    ops("ops-duplicate-key.json", '[{"op": "drag", "op": "drag", "select": "vertex", "from": [1, 1], "to": [2, 2]}]\n')


# ---- binary .svec from the examples (needs build/bin/subvec) -------------------------------------

def svec_binary_files():
    subvec = os.environ.get("SUBVEC", os.path.join(HERE, "..", "..", "build", "bin", "subvec"))
    example = os.path.join(HERE, "..", "..", "examples", "03-junction.svec.json")
    with tempfile.TemporaryDirectory() as tmp:
        # svec-v2-*.svec were written the same way by the version 2 writer (before version 3
        # became the default); main() keeps them.
        for version, extra in (("v1", ["--lossless"]), ("v3", [])):
            path = os.path.join(tmp, version + ".svec")
            subprocess.run([subvec, "convert", example, "-o", path] + extra, check=True)
            with open(path, "rb") as f:
                good = f.read()
            write(f"svec-{version}-truncated-half.svec", good[: len(good) // 2])
            write(f"svec-{version}-truncated-last-byte.svec", good[:-1])
            # A byte inside the zstd frame flipped, one in the first block and one near the end.
            for name, at in (("early", 40), ("late", len(good) - 12)):
                b = bytearray(good)
                b[at] ^= 0xA5
                write(f"svec-{version}-flipped-{name}.svec", bytes(b))
            write(f"svec-{version}-doubled.svec", good + good)
            if version == "v3":
                v3_stream_files(good)


def v3_stream_files(good):
    """Version 3 files whose zstd frame is sound but whose level stream is damaged."""
    import struct
    payload = subprocess.run(["zstd", "-d", "-q", "-c"], input=good[32:], check=True,
                             stdout=subprocess.PIPE).stdout
    # The level's stream length follows 12 bytes of size and level count, 20 of counts, 2 of grids.
    n = struct.unpack_from("<I", payload, 34)[0]

    def wrap(p):
        frame = subprocess.run(["zstd", "-q", "-c", "-9"], input=p, check=True,
                               stdout=subprocess.PIPE).stdout
        return good[:16] + struct.pack("<QQ", len(p), len(frame)) + frame

    flipped = bytearray(payload)
    flipped[38 + n // 2] ^= 0x5A
    write("svec-v3-stream-flipped.svec", wrap(bytes(flipped)))
    cut = payload[:34] + struct.pack("<I", n - 8) + payload[38:38 + n - 8] + payload[38 + n:]
    write("svec-v3-stream-cut.svec", wrap(cut))


# ---- the library's corpus, tests/data/bad ------------------------------------------------------------

def text_of(image):
    """One line per top-level key and per level key: small and readable."""
    lines = []
    for key, value in image.items():
        if key == "levels":
            levels = []
            for level in value:
                inner = ",\n".join(f"    {json.dumps(k)}: {json.dumps(v)}" for k, v in level.items())
                levels.append("  {\n" + inner + "\n  }")
            lines.append('"levels": [\n' + ",\n".join(levels) + "\n]")
        else:
            lines.append(f"{json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def square_image(**level_changes):
    image = copy.deepcopy(SQUARE)
    image["levels"][0].update(level_changes)
    return image


def write_library(name, data):
    write(name, data, LIBRARY)


def library_json_files():
    files = {}
    # Indices out of range.
    files["index-triangle"] = square_image(triangles=[[0, 1, 4], [1, 2, 9], [2, 3, 4], [3, 0, 4]])
    files["index-triangle-colors"] = square_image(triangle_colors=[[0, 1, 4], [1, 2, 4], [2, 3, 7], [3, 0, 4]])
    files["index-feature"] = square_image(features=[{"id": 3, "vertices": [4, 12]}])
    # Non-covering: triangle (1, 2, 4) removed, leaving a hole at the right.
    files["gap"] = square_image(triangles=[[0, 1, 4], [2, 3, 4], [3, 0, 4]])
    # Self-overlapping: a fan around the center that winds twice around it, over a second copy of
    # the four corners (vertices 5-8): every triangle is positive, every border edge on the border.
    files["overlap"] = square_image(
        vertices=[[2, 2], [0, 0], [4, 0], [4, 4], [0, 4], [0, 0], [4, 0], [4, 4], [0, 4]],
        colors=[[0, 0, 0]] * 9,
        triangles=[[1, 2, 0], [2, 3, 0], [3, 4, 0], [4, 5, 0], [5, 6, 0], [6, 7, 0], [7, 8, 0], [8, 1, 0]])
    # Two complete copies of the mesh on top of each other.
    files["double-cover"] = square_image(
        vertices=SQUARE["levels"][0]["vertices"] * 2, colors=SQUARE["levels"][0]["colors"] * 2,
        triangles=SQUARE["levels"][0]["triangles"] + [[a + 5, b + 5, c + 5] for a, b, c in
                                                      SQUARE["levels"][0]["triangles"]])
    # Flipped: vertex 5 splits triangle (0, 1, 4) but sits below the center, folding its fan over.
    files["flipped"] = square_image(
        vertices=SQUARE["levels"][0]["vertices"] + [[2, 3]],
        colors=SQUARE["levels"][0]["colors"] + [[0, 0, 0]],
        triangles=[[0, 1, 5], [1, 4, 5], [4, 0, 5], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    files["inconsistent-orientation"] = square_image(triangles=[[0, 1, 4], [1, 4, 2], [2, 3, 4], [3, 0, 4]])
    files["outside"] = square_image(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [2, 4.5]])
    files["unused-vertex"] = square_image(vertices=SQUARE["levels"][0]["vertices"] + [[1, 1]],
                                    colors=SQUARE["levels"][0]["colors"] + [[0, 0, 0]])
    # Features that are not chains of interior mesh edges.
    files["not-a-chain"] = square_image(features=[{"id": 0, "vertices": [1, 3]}])
    files["feature-on-border"] = square_image(features=[{"id": 0, "vertices": [0, 1]}])
    # A color jump across edge (0, 4), which is not a tear.
    files["color-jump-without-tear"] = square_image(
        colors=SQUARE["levels"][0]["colors"] + [[0, 255, 0]],
        triangle_colors=[[5, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    # Structure.
    bad_key = square_image()
    bad_key["levels"][0]["triangle_color"] = bad_key["levels"][0].pop("triangles")
    files["unknown-key"] = bad_key
    files["wrong-type"] = dict(SQUARE, width="4")
    files["absurd-size"] = dict(SQUARE, width=100000000, height=100000000)
    files["wrong-version"] = dict(SQUARE, version=3)
    for name, image in files.items():
        write_library(name + ".svec.json", text_of(image))

    square_text = text_of(SQUARE)
    write_library("nan.svec.json", square_text.replace("[2, 2]", "[NaN, 2]"))
    write_library("huge-number.svec.json", square_text.replace("[2, 2]", "[2, 1e400]"))
    write_library("duplicate-key.svec.json", square_text.replace('"height": 4', '"height": 4,\n"height": 5'))
    write_library("truncated.svec.json", square_text[:len(square_text) // 2])


# Binary files.

def raw_zstd_frame(data):
    """A zstd frame (RFC 8878) with the content size and one stored block per 128 KiB."""
    out = bytearray(b"\x28\xb5\x2f\xfd\xe0") + struct.pack("<Q", len(data))
    pos = 0
    while True:
        n = min(len(data) - pos, 1 << 17)
        last = pos + n == len(data)
        out += struct.pack("<I", (n << 3) | int(last))[:3] + data[pos:pos + n]
        pos += n
        if last:
            return bytes(out)


def svec(payload, version=1, flags=0, payload_size=None, frame=None):
    frame = raw_zstd_frame(payload) if frame is None else frame
    size = len(payload) if payload_size is None else payload_size
    return b"SUBVEC\x00\x1a" + struct.pack("<IIQQ", version, flags, size, len(frame)) + frame


def square_payload(x1=4.0, tri_vertex=4):
    p = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 5, 4, 0, 0)
    for x, y in [(0, 0), (x1, 0), (4, 4), (0, 4), (2, 2)]:
        p += struct.pack("<dd", x, y)
    for rgb in [(255, 0, 0), (255, 0, 0), (0, 0, 255), (0, 0, 255), (127.5, 0, 127.5)]:
        p += struct.pack("<fff", *rgb)
    triangles = [(0, 1, 4), (1, 2, 4), (2, 3, tri_vertex), (3, 0, 4)]
    for a, b, c in triangles:
        p += struct.pack("<iii", a, b, c)
    for a, b, c in [(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]:
        p += struct.pack("<iii", a, b, c)
    return p + struct.pack("<II", 0, 0)


def library_binary_files():
    good = svec(square_payload())
    write_library("wrong-magic.svec", b"SUBVEX" + good[6:])
    write_library("wrong-version.svec", svec(square_payload(), version=7))
    write_library("unknown-flags.svec", svec(square_payload(), flags=4))
    write_library("object-strokes-without-objects.svec", svec(square_payload(), flags=2))
    write_library("truncated-header.svec", good[:20])
    write_library("truncated.svec", good[:len(good) - 30])
    write_library("truncated-zstd.svec", svec(square_payload(), frame=raw_zstd_frame(square_payload())[:-30]))
    write_library("absurd-payload-size.svec", svec(square_payload(), payload_size=1 << 50))
    absurd_count = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 5, 0xFFFFFFF0, 0, 0)
    write_library("absurd-count.svec", svec(absurd_count + bytes(64)))
    write_library("truncated-payload.svec", svec(square_payload()[:-40]))
    write_library("trailing-payload-bytes.svec", svec(square_payload() + b"\x00\x00"))
    write_library("trailing-file-bytes.svec", good + b"\x00")
    write_library("nan-position.svec", svec(square_payload(x1=math.nan)))
    write_library("index-out-of-range.svec", svec(square_payload(tri_vertex=-7)))


# The compact (version 2) payload of the square, as laid out in docs/format.md ("Worked example,
# version 2"), in pieces so that one field at a time can be broken.
COMPACT_HEAD = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 5, 4, 0, 0)
COMPACT_SECTIONS = [bytes([0x32, 0x3C, 0x03]), bytes([0x03]),
                    bytes.fromhex("0000 2000 0f10 0010 0000"), b"", b"",
                    bytes.fromhex("7f8002 000100 007f8001 00bf01be01 007f8001")]


def compact_payload(head=COMPACT_HEAD, precision=b"\x02\xff", sections=COMPACT_SECTIONS):
    body = b"".join(struct.pack("<I", len(s)) + s for s in sections)
    return head + precision + body + struct.pack("<II", 0, 0)


def library_compact_files():
    sections = list(COMPACT_SECTIONS)
    sections[0] = bytes([0x7F, 0x3C, 0x03])  # 127: not three operations in base 5
    write_library("compact-bad-operations.svec", svec(compact_payload(sections=sections), version=2))
    write_library("compact-bad-precision.svec", svec(compact_payload(precision=b"\x0d\xff"), version=2))
    head = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 6, 4, 0, 0)  # 6 colors declared
    write_library("compact-color-count.svec", svec(compact_payload(head=head), version=2))
    sections = list(COMPACT_SECTIONS)
    sections[2] = sections[2] + b"\x00"
    write_library("compact-trailing-section-bytes.svec", svec(compact_payload(sections=sections), version=2))


def main():
    library_only = sys.argv[1:] == ["--library"]
    if sys.argv[1:] and not library_only:
        sys.exit("usage: make_files.py [--library]")
    library_json_files()
    library_binary_files()
    library_compact_files()
    if library_only:
        return
    os.makedirs(OUT, exist_ok=True)
    for name in os.listdir(OUT):
        if not name.startswith("svec-v2-"):
            os.remove(os.path.join(OUT, name))
    png_files()
    jpeg_files()
    other_files()
    svec_json_files()
    ops_files()
    svec_binary_files()


if __name__ == "__main__":
    main()
