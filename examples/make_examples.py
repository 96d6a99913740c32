#!/usr/bin/env python3
"""Writes the hand-made example images examples/0N-*.svec.json (docs/format.md describes the form).

Run from anywhere: python3 examples/make_examples.py. Standard library only. The output is
deterministic and uses the same layout as subvec's own writer, so `subvec convert` of an example
back to .svec.json reproduces the file byte for byte (a unit test checks this).

Each example is built the same way:
  1. place vertices (the 4 image corners included; border vertices exactly on the border);
  2. add triangles, each tagged with the region it belongs to (orientation is fixed up here);
  3. list the tear features as vertex chains;
  4. give every region a color function color(x, y).
Colors are then assigned per *wedge*: the triangle corners around a vertex that are connected
through edges that are not tears share one color value (that is the validity rule of the format),
so a vertex gets one color per side of a tear, and a single color where a tear ends.
"""
import json
import math
import os

WIDTH_LIMIT = 100  # columns, as in subvec's writer


class Mesh:
    def __init__(self, width, height):
        self.width, self.height = width, height
        self.vertices = []   # (x, y)
        self.triangles = []  # (a, b, c), positive signed area in image coordinates (y down)
        self.regions = []    # region name of each triangle
        self.features = []   # vertex chains

    def vertex(self, x, y):
        # Snap to the border when within rounding, then keep 3 decimals: short, exact text.
        x = min(max(round(x, 3), 0), self.width)
        y = min(max(round(y, 3), 0), self.height)
        self.vertices.append((x, y))
        return len(self.vertices) - 1

    def triangle(self, a, b, c, region):
        (ax, ay), (bx, by), (cx, cy) = (self.vertices[v] for v in (a, b, c))
        area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        assert area != 0, f"degenerate triangle {(a, b, c)}"
        self.triangles.append((a, b, c) if area > 0 else (a, c, b))
        self.regions.append(region)

    def colorize(self, color_of_region):
        """Per-corner colors from region color functions, one color value per wedge."""
        tears = set()
        for chain in self.features:
            for a, b in zip(chain, chain[1:]):
                tears.add(frozenset((a, b)))
        corner_color = [[None] * 3 for _ in self.triangles]
        colors = []
        faces_of = [[] for _ in self.vertices]
        for f, tri in enumerate(self.triangles):
            for v in tri:
                faces_of[v].append(f)
        for v, faces in enumerate(faces_of):
            # Union the faces around v that share a non-tear edge (v, w).
            parent = {f: f for f in faces}

            def root(f):
                while parent[f] != f:
                    f = parent[f]
                return f

            for i, f in enumerate(faces):
                for g in faces[i + 1:]:
                    shared = set(self.triangles[f]) & set(self.triangles[g])
                    if len(shared) == 2 and frozenset(shared) not in tears:
                        parent[root(f)] = root(g)
            wedge_color = {}
            x, y = self.vertices[v]
            for f in faces:
                r = root(f)
                value = tuple(clamp_round(c) for c in color_of_region[self.regions[f]](x, y))
                if r not in wedge_color:
                    wedge_color[r] = len(colors)
                    colors.append(value)
                else:
                    # A wedge spanning two regions (a tear ends here): their colors must agree.
                    assert all(abs(p - q) <= 0.11 for p, q in zip(colors[wedge_color[r]], value)), (
                        f"vertex {v}: regions disagree inside one wedge")
                corner_color[f][self.triangles[f].index(v)] = wedge_color[r]
        return colors, [tuple(c) for c in corner_color]


def clamp_round(c):
    return round(min(max(c, 0.0), 255.0), 1)


def lerp(a, b, t):
    return tuple(p + (q - p) * t for p, q in zip(a, b))


# ---------------------------------------------------------------------------------------------
# Writing, in the layout of subvec's writer.

def num(v):
    return str(int(v)) if float(v).is_integer() else repr(float(v))


def items_text(items):
    return ["[" + ", ".join(num(c) for c in item) + "]" for item in items]


def write_list(lines, indent, key, items, comma):
    head, tail = f'"{key}": [', "]," if comma else "]"
    one_line = "  " * indent + head + ", ".join(items) + tail
    if len(one_line) <= WIDTH_LIMIT:
        lines.append(one_line)
        return
    lines.append("  " * indent + head)
    room = WIDTH_LIMIT - 2 * (indent + 1)
    current = ""
    for i, item in enumerate(items):
        piece = item + ("," if i + 1 < len(items) else "")
        if current and len(current) + 1 + len(piece) > room:
            lines.append("  " * (indent + 1) + current)
            current = ""
        current += (" " if current else "") + piece
    if current:
        lines.append("  " * (indent + 1) + current)
    lines.append("  " * indent + tail)


def write_image(path, mesh, colors, triangle_colors, metadata):
    lines = ["{", '  "format": "subvec",', '  "version": 1,',f'  "width": {mesh.width},', f'  "height": {mesh.height},', '  "levels": [', "    {"]
    write_list(lines, 3, "vertices", items_text(mesh.vertices), True)
    write_list(lines, 3, "colors", items_text(colors), True)
    write_list(lines, 3, "triangles", items_text(mesh.triangles), True)
    write_list(lines, 3, "triangle_colors", items_text(triangle_colors), bool(mesh.features))
    if mesh.features:
        lines.append('      "features": [')
        for i, chain in enumerate(mesh.features):
            end = "}," if i + 1 < len(mesh.features) else "}"
            text = f'{{"id": {i}, "saliency": 0, "vertices": [' + ", ".join(map(str, chain)) + "]" + end
            if 8 + len(text) <= WIDTH_LIMIT:
                lines.append("        " + text)
            else:
                lines += ["        {", f'          "id": {i},', '          "saliency": 0,']
                write_list(lines, 5, "vertices", [str(v) for v in chain], False)
                lines.append("        " + end)
        lines.append("      ]")
    lines += ["    }", "  ],", '  "metadata": {']
    for i, (key, value) in enumerate(metadata):
        text = json.dumps(key, ensure_ascii=False) + ": " + json.dumps(value, ensure_ascii=False)
        lines.append("    " + text + ("," if i + 1 < len(metadata) else ""))
    lines += ["  }", "}"]
    with open(path, "w", encoding="utf-8") as out:
        out.write("\n".join(lines) + "\n")


# ---------------------------------------------------------------------------------------------
# Shared construction: rings of vertices around a center, joined by strips of triangles.

def ray_to_border(mesh, cx, cy, angle):
    """Distance from (cx, cy) along `angle` to the image border."""
    dx, dy = math.cos(angle), math.sin(angle)
    ts = []
    if dx > 1e-12: ts.append((mesh.width - cx) / dx)
    if dx < -1e-12: ts.append(-cx / dx)
    if dy > 1e-12: ts.append((mesh.height - cy) / dy)
    if dy < -1e-12: ts.append(-cy / dy)
    return min(ts)


def border_point(mesh, cx, cy, angle):
    d = ray_to_border(mesh, cx, cy, angle)
    x, y = cx + d * math.cos(angle), cy + d * math.sin(angle)
    # Land exactly on the border (and exactly on a corner at 45 degrees).
    snap = lambda v, limit: 0 if abs(v) < 1e-9 else limit if abs(v - limit) < 1e-9 else v
    return snap(x, mesh.width), snap(y, mesh.height)


def strip(mesh, inner, outer, region_of):
    """Triangles between two closed rings with the same number of vertices (shorter diagonal)."""
    n = len(inner)
    for k in range(n):
        a, b, c, d = inner[k], inner[(k + 1) % n], outer[(k + 1) % n], outer[k]
        pa, pb, pc, pd = (mesh.vertices[v] for v in (a, b, c, d))
        if math.dist(pa, pc) <= math.dist(pb, pd):
            mesh.triangle(a, b, c, region_of(k))
            mesh.triangle(a, c, d, region_of(k))
        else:
            mesh.triangle(a, b, d, region_of(k))
            mesh.triangle(b, c, d, region_of(k))


# ---------------------------------------------------------------------------------------------
# 01: a disk whose boundary is a closed tear, on a smooth gradient.

def make_disk():
    W = H = 96
    cx, cy, R = 48.0, 48.0, 28.0
    mesh = Mesh(W, H)
    n = 16
    angle = lambda k: 2 * math.pi * k / n
    center = mesh.vertex(cx, cy)
    inner = [mesh.vertex(cx + 13 * math.cos(angle(2 * i + 1)), cy + 13 * math.sin(angle(2 * i + 1)))
             for i in range(n // 2)]
    circle = [mesh.vertex(cx + R * math.cos(angle(k)), cy + R * math.sin(angle(k))) for k in range(n)]
    border = [border_point(mesh, cx, cy, angle(k)) for k in range(n)]
    middle = [mesh.vertex((cx + R * math.cos(angle(k)) + bx) / 2, (cy + R * math.sin(angle(k)) + by) / 2)
              for k, (bx, by) in enumerate(border)]
    border = [mesh.vertex(bx, by) for bx, by in border]

    for i in range(n // 2):  # center fan over the inner ring
        mesh.triangle(center, inner[i], inner[(i + 1) % (n // 2)], "disk")
    for i in range(n // 2):  # inner ring (8) to circle (16): inner[i] sits at circle[2i+1]
        a, b = inner[i], inner[(i + 1) % (n // 2)]
        c1, c2, c3 = circle[2 * i + 1], circle[(2 * i + 2) % n], circle[(2 * i + 3) % n]
        mesh.triangle(a, c1, c2, "disk")
        mesh.triangle(a, c2, b, "disk")
        mesh.triangle(b, c2, c3, "disk")
    strip(mesh, circle, middle, lambda k: "background")
    strip(mesh, middle, border, lambda k: "background")
    mesh.features.append(circle + [circle[0]])  # closed: first vertex repeated

    def background(x, y):  # linear: renders exactly as this gradient
        return lerp(lerp((246, 226, 190), (150, 190, 230), x / W), (60, 90, 150), 0.55 * y / H)

    def disk(x, y):  # a lit ball: highlight up-left, darker rim
        d = math.dist((x, y), (cx - 10, cy - 11)) / (1.5 * R)
        return lerp((255, 236, 214), (178, 24, 43), min(d, 1) ** 0.8)

    return mesh, mesh.colorize({"disk": disk, "background": background})


# ---------------------------------------------------------------------------------------------
# 02: a tear that ends inside the image: the color jump fades to nothing at its end.

def make_open_tear():
    W, H = 128, 96
    nx, ny = 8, 6
    tear_row, tear_end = 3, 5  # the tear runs along grid row 3 from the left border to column 5
    mesh = Mesh(W, H)
    bend = lambda x: -9 * math.sin(math.pi * x / W)        # the tear's shape (0 on both borders)
    falloff = {0: 0, 1: 0.25, 2: 0.6, 3: 1, 4: 0.6, 5: 0.25, 6: 0}
    grid = [[mesh.vertex(W * i / nx, H * j / ny + falloff[j] * bend(W * i / nx))
             for i in range(nx + 1)] for j in range(ny + 1)]
    for j in range(ny):
        for i in range(nx):
            region = "above" if j < tear_row else "below"
            a, b, c, d = grid[j][i], grid[j][i + 1], grid[j + 1][i + 1], grid[j + 1][i]
            mesh.triangle(a, b, c, region)
            mesh.triangle(a, c, d, region)
    mesh.features.append([grid[tear_row][i] for i in range(tear_end + 1)])
    x_end = W * tear_end / nx

    def base(x, y):  # a sandy gradient
        return lerp(lerp((236, 206, 150), (205, 160, 112), x / W), (150, 110, 86), y / H)

    def jump(x, y):  # full strength at the left border, zero from the tear's end on
        along = max(0.0, 1 - x / x_end)
        across = max(0.0, 1 - abs(y - H / 2) / (H / 2))
        return along * across

    def above(x, y):
        return tuple(c + 38 * jump(x, y) * w for c, w in zip(base(x, y), (0.5, 0.9, 1.2)))

    def below(x, y):
        return tuple(c - 70 * jump(x, y) * w for c, w in zip(base(x, y), (1.0, 0.9, 0.6)))

    return mesh, mesh.colorize({"above": above, "below": below})


# ---------------------------------------------------------------------------------------------
# 03: three features meeting at a junction: three colored sectors.

def make_junction():
    W = H = 96
    cx, cy = 48.0, 48.0
    mesh = Mesh(W, H)
    n = 24                                 # spokes every 15 degrees (45-degree spokes hit corners)
    arms = (2, 10, 18)                     # spokes at 30, 150 and 270 degrees (y down: 270 is up)
    radii, twists = (9, 20, 33), (16, 10, 5)  # inner rings; twists (degrees) curve the arms
    center = mesh.vertex(cx, cy)
    rings = []
    for r, twist in zip(radii, twists):
        rings.append([mesh.vertex(cx + r * math.cos(math.radians(15 * k + twist)),
                                  cy + r * math.sin(math.radians(15 * k + twist))) for k in range(n)])
    last = radii[-1]
    border = [border_point(mesh, cx, cy, math.radians(15 * k)) for k in range(n)]
    rings.append([mesh.vertex((cx + last * math.cos(math.radians(15 * k + 2)) + bx) / 2,
                              (cy + last * math.sin(math.radians(15 * k + 2)) + by) / 2)
                  for k, (bx, by) in enumerate(border)])
    rings.append([mesh.vertex(bx, by) for bx, by in border])

    def sector(k):  # the spokes k..k+1 lie in sector 0, 1 or 2
        k = (k - arms[0]) % n
        return "abc"[sum(k >= (a - arms[0]) % n for a in arms) - 1]

    for k in range(n):
        mesh.triangle(center, rings[0][k], rings[0][(k + 1) % n], sector(k))
    for inner, outer in zip(rings, rings[1:]):
        strip(mesh, inner, outer, sector)
    for a in arms:
        mesh.features.append([center] + [ring[a] for ring in rings])

    def shade(light, dark):
        return lambda x, y: lerp(light, dark, min(1.0, math.dist((x, y), (cx, cy)) / 60))

    return mesh, mesh.colorize({
        "a": shade((255, 214, 120), (214, 84, 36)),    # lower sector: amber to burnt orange
        "b": shade((150, 226, 210), (18, 120, 128)),   # left sector: mint to teal
        "c": shade((222, 196, 250), (92, 52, 150)),    # right sector: lavender to violet
    })


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    examples = [
        ("01-disk", make_disk, "A disk whose boundary is a closed tear, on a smooth gradient."),
        ("02-open-tear", make_open_tear, "A tear that ends inside the image: the color jump "
         "along it fades to nothing at its end."),
        ("03-junction", make_junction, "Three tear features meeting at a junction: three "
         "colored sectors."),
    ]
    for name, make, description in examples:
        mesh, (colors, triangle_colors) = make()
        metadata = [("title", name), ("description", description),
                    ("license", "CC0-1.0"), ("generator", "examples/make_examples.py")]
        path = os.path.join(here, name + ".svec.json")
        write_image(path, mesh, colors, triangle_colors, metadata)
        print(f"{path}: {len(mesh.vertices)} vertices, {len(colors)} colors, "
              f"{len(mesh.triangles)} triangles, {len(mesh.features)} features")


if __name__ == "__main__":
    main()
