#!/usr/bin/env python3
"""Writes the bad-file corpus tests/data/bad/*: each file breaks exactly one rule of docs/format.md.

Run: python3 tests/data/bad/make_bad_files.py. Standard library only. tests/unit/io/bad_files_test.cpp
lists, for every file here, the error code and the words its message must contain.

Most files start from the 4 x 4 worked example of docs/format.md (corners 0-3, center 4). Binary
files hold their payload in stored (uncompressed) zstd blocks, so no zstd module is needed.
"""
import copy
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

SQUARE = {
    "format": "subvec", "version": 1, "width": 4, "height": 4,
    "levels": [{
        "vertices": [[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]],
        "colors": [[255, 0, 0], [255, 0, 0], [0, 0, 255], [0, 0, 255], [127.5, 0, 127.5]],
        "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    }],
}


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


def square(**level_changes):
    image = copy.deepcopy(SQUARE)
    image["levels"][0].update(level_changes)
    return image


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(HERE, name), mode) as out:
        out.write(data)


def json_files():
    files = {}
    # Indices out of range.
    files["index-triangle"] = square(triangles=[[0, 1, 4], [1, 2, 9], [2, 3, 4], [3, 0, 4]])
    files["index-triangle-colors"] = square(triangle_colors=[[0, 1, 4], [1, 2, 4], [2, 3, 7], [3, 0, 4]])
    files["index-feature"] = square(features=[{"id": 3, "vertices": [4, 12]}])
    # Non-covering: triangle (1, 2, 4) removed, leaving a hole at the right.
    files["gap"] = square(triangles=[[0, 1, 4], [2, 3, 4], [3, 0, 4]])
    # Self-overlapping: a fan around the center that winds twice around it, over a second copy of
    # the four corners (vertices 5-8): every triangle is positive, every border edge on the border.
    files["overlap"] = square(
        vertices=[[2, 2], [0, 0], [4, 0], [4, 4], [0, 4], [0, 0], [4, 0], [4, 4], [0, 4]],
        colors=[[0, 0, 0]] * 9,
        triangles=[[1, 2, 0], [2, 3, 0], [3, 4, 0], [4, 5, 0], [5, 6, 0], [6, 7, 0], [7, 8, 0], [8, 1, 0]])
    # Two complete copies of the mesh on top of each other.
    files["double-cover"] = square(
        vertices=SQUARE["levels"][0]["vertices"] * 2, colors=SQUARE["levels"][0]["colors"] * 2,
        triangles=SQUARE["levels"][0]["triangles"] + [[a + 5, b + 5, c + 5] for a, b, c in
                                                      SQUARE["levels"][0]["triangles"]])
    # Flipped: vertex 5 splits triangle (0, 1, 4) but sits below the center, folding its fan over.
    files["flipped"] = square(
        vertices=SQUARE["levels"][0]["vertices"] + [[2, 3]],
        colors=SQUARE["levels"][0]["colors"] + [[0, 0, 0]],
        triangles=[[0, 1, 5], [1, 4, 5], [4, 0, 5], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    files["inconsistent-orientation"] = square(triangles=[[0, 1, 4], [1, 4, 2], [2, 3, 4], [3, 0, 4]])
    files["outside"] = square(vertices=[[0, 0], [4, 0], [4, 4], [0, 4], [2, 4.5]])
    files["unused-vertex"] = square(vertices=SQUARE["levels"][0]["vertices"] + [[1, 1]],
                                    colors=SQUARE["levels"][0]["colors"] + [[0, 0, 0]])
    # Features that are not chains of interior mesh edges.
    files["not-a-chain"] = square(features=[{"id": 0, "vertices": [1, 3]}])
    files["feature-on-border"] = square(features=[{"id": 0, "vertices": [0, 1]}])
    # A color jump across edge (0, 4), which is not a tear.
    files["color-jump-without-tear"] = square(
        colors=SQUARE["levels"][0]["colors"] + [[0, 255, 0]],
        triangle_colors=[[5, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    # Structure.
    bad_key = square()
    bad_key["levels"][0]["triangle_color"] = bad_key["levels"][0].pop("triangles")
    files["unknown-key"] = bad_key
    files["wrong-type"] = dict(SQUARE, width="4")
    files["absurd-size"] = dict(SQUARE, width=100000000, height=100000000)
    files["wrong-version"] = dict(SQUARE, version=3)
    for name, image in files.items():
        write(name + ".svec.json", text_of(image))

    square_text = text_of(SQUARE)
    write("nan.svec.json", square_text.replace("[2, 2]", "[NaN, 2]"))
    write("huge-number.svec.json", square_text.replace("[2, 2]", "[2, 1e400]"))
    write("duplicate-key.svec.json", square_text.replace('"height": 4', '"height": 4,\n"height": 5'))
    write("truncated.svec.json", square_text[:len(square_text) // 2])


# ---------------------------------------------------------------------------------------------
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


def binary_files():
    good = svec(square_payload())
    write("wrong-magic.svec", b"SUBVEX" + good[6:])
    write("wrong-version.svec", svec(square_payload(), version=7))
    write("unknown-flags.svec", svec(square_payload(), flags=1))
    write("truncated-header.svec", good[:20])
    write("truncated.svec", good[:len(good) - 30])
    write("truncated-zstd.svec", svec(square_payload(), frame=raw_zstd_frame(square_payload())[:-30]))
    write("absurd-payload-size.svec", svec(square_payload(), payload_size=1 << 50))
    absurd_count = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 5, 0xFFFFFFF0, 0, 0)
    write("absurd-count.svec", svec(absurd_count + bytes(64)))
    write("truncated-payload.svec", svec(square_payload()[:-40]))
    write("trailing-payload-bytes.svec", svec(square_payload() + b"\x00\x00"))
    write("trailing-file-bytes.svec", good + b"\x00")
    write("nan-position.svec", svec(square_payload(x1=math.nan)))
    write("index-out-of-range.svec", svec(square_payload(tri_vertex=-7)))


# The compact (version 2) payload of the square, as laid out in docs/format.md ("Worked example,
# version 2"), in pieces so that one field at a time can be broken.
COMPACT_HEAD = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 5, 4, 0, 0)
COMPACT_SECTIONS = [bytes([0x32, 0x3C, 0x03]), bytes([0x03]),
                    bytes.fromhex("0000 2000 0f10 0010 0000"), b"", b"",
                    bytes.fromhex("7f8002 000100 007f8001 00bf01be01 007f8001")]


def compact_payload(head=COMPACT_HEAD, precision=b"\x02\xff", sections=COMPACT_SECTIONS):
    body = b"".join(struct.pack("<I", len(s)) + s for s in sections)
    return head + precision + body + struct.pack("<II", 0, 0)


def compact_files():
    sections = list(COMPACT_SECTIONS)
    sections[0] = bytes([0x7F, 0x3C, 0x03])  # 127: not three operations in base 5
    write("compact-bad-operations.svec", svec(compact_payload(sections=sections), version=2))
    write("compact-bad-precision.svec", svec(compact_payload(precision=b"\x0d\xff"), version=2))
    head = struct.pack("<iiI", 4, 4, 1) + struct.pack("<5I", 5, 6, 4, 0, 0)  # 6 colors declared
    write("compact-color-count.svec", svec(compact_payload(head=head), version=2))
    sections = list(COMPACT_SECTIONS)
    sections[2] = sections[2] + b"\x00"
    write("compact-trailing-section-bytes.svec", svec(compact_payload(sections=sections), version=2))


if __name__ == "__main__":
    json_files()
    binary_files()
    compact_files()
