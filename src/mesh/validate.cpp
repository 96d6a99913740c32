// Validation of a vector image (mesh/validate.h).
//
// Design note. MeshTopology::build already rejects what is wrong combinatorially (indices out of
// range, edges shared by three triangles, inconsistent orientation, creases and features that are
// not chains of interior edges). This file adds what needs geometry or colors, in an order where
// each check may rely on the previous ones:
//   1. sizes, finite values, positions inside the closed image rectangle, index ranges;
//   2. topology (MeshTopology::build);
//   3. every triangle has positive signed area; every vertex is used;
//   4. every boundary edge lies on one side of the image rectangle, the 4 image corners are
//   vertices;
//   5. tiling: at every vertex the triangle angles sum to 2*pi (interior), pi (border) or pi/2
//      (image corner), and the total area is W*H. With 3 and 4 this makes the mesh a local
//      homeomorphism onto the rectangle that is one-to-one on the border, hence a covering of the
//      rectangle, and the area makes it a single sheet: no gap and no overlap;
//   6. colors: each color value belongs to one vertex and is used; across an edge that is not a
//      tear both triangles use the same color values at both ends.
// Messages are one line, "level L: <element> <index> <problem>".
#include "subvec/mesh/validate.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <unordered_set>

#include "core/messages_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

using detail::num;

std::string str(int64_t v) { return std::to_string(v); }

// (Strings are built by appending: GCC 12 warns falsely (-Wrestrict) on "literal" + temporary.)
std::string point(Vec2 p) {
  std::string s = "(";
  return s.append(num(p.x)).append(", ").append(num(p.y)).append(")");
}

// A string for a one-line message: quoted, control characters and quotes escaped, cut at 60 bytes.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (size_t i = 0; i < s.size() && i < 60; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      if (c == '"' || c == '\\') out += '\\';
      out += static_cast<char>(c);
    }
  }
  return out + (s.size() > 60 ? "...\"" : "\"");
}

std::string edge_name(int a, int b) {
  std::string s = "(";
  return s.append(str(a)).append(", ").append(str(b)).append(")");
}

// Signed area of triangle (a, b, c); positive in image coordinates (y down) for the orientation
// subvec uses: cross(b - a, c - a) / 2.
double signed_area(Vec2 a, Vec2 b, Vec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

// Interior angle at a of a positively oriented triangle (a, b, c), in (0, pi).
double corner_angle(Vec2 a, Vec2 b, Vec2 c) {
  const double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - a.x, vy = c.y - a.y;
  return std::atan2(ux * vy - uy * vx, ux * vx + uy * vy);
}

bool valid_utf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = 0;
    uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      extra = 1, cp = c & 0x1Fu;
    } else if ((c & 0xF0) == 0xE0) {
      extra = 2, cp = c & 0x0Fu;
    } else if ((c & 0xF8) == 0xF0) {
      extra = 3, cp = c & 0x07u;
    } else {
      return false;
    }
    if (i + extra >= s.size()) return false;
    for (int k = 1; k <= extra; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3Fu);
    }
    // Reject overlong forms, surrogates and code points past U+10FFFF.
    static constexpr uint32_t kMin[4] = {0, 0x80, 0x800, 0x10000};
    if (cp < kMin[extra] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += size_t(extra) + 1;
  }
  return true;
}

class LevelValidator {
 public:
  LevelValidator(const ControlMesh& mesh, int width, int height, int level)
      : mesh_(mesh), width_(width), height_(height), prefix_("level " + str(level) + ": ") {}
  // An object's mesh (validate_object): no frame to tile.
  LevelValidator(const ControlMesh& mesh, int width, int height, const std::string& prefix)
      : mesh_(mesh), width_(width), height_(height), prefix_(prefix), object_(true) {}

  MeshTopology run() {
    check_sizes();
    check_values();
    check_features();
    try {
      topo_ = object_ ? MeshTopology::build(mesh_, MeshTopology::kNoFrame, MeshTopology::kNoFrame)
                      : MeshTopology::build(mesh_, width_, height_);
    } catch (const Error& e) {
      throw Error(e.code(), prefix_ + e.what());
    }
    check_triangle_areas();
    check_unused_vertices();
    if (object_) {
      check_object_boundary();
      check_object_turns();
    } else {
      check_boundary();
      check_tiling();
    }
    check_colors();
    return std::move(topo_);
  }

 private:
  [[noreturn]] void fail(const std::string& message,
                         ErrorCode code = ErrorCode::kInvalidMesh) const {
    throw Error(code, prefix_ + message);
  }

  void check_count(const char* what, size_t n) const {
    if (static_cast<int64_t>(n) > Limits::kMaxElements) {
      fail(str(static_cast<int64_t>(n)) + " " + what + " is over the limit of " +
               str(Limits::kMaxElements),
           ErrorCode::kLimit);
    }
  }

  void check_sizes() const {
    check_count("vertices", mesh_.positions.size());
    check_count("colors", mesh_.colors.size());
    check_count("triangles", mesh_.triangles.size());
    check_count("creases", mesh_.creases.size());
    check_count("features", mesh_.features.size());
    for (size_t i = 0; i < mesh_.features.size(); ++i)
      check_count("feature vertices", mesh_.features[i].vertices.size());
    if (mesh_.triangle_colors.size() != mesh_.triangles.size()) {
      fail(str(mesh_.num_triangles()) + " triangles but " +
           str(static_cast<int64_t>(mesh_.triangle_colors.size())) +
           " triangle_colors entries (one per triangle needed)");
    }
  }

  void check_values() const {
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      const Vec2 p = mesh_.positions[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        fail("vertex " + str(v) + " position " + point(p) + " is not finite");
      }
      if (object_) {
        constexpr double kFar = double(1 << 24);
        if (std::abs(p.x) > kFar || std::abs(p.y) > kFar) {
          fail("vertex " + str(v) + " position " + point(p) + " is more than 2^24 pixels away");
        }
      } else if (p.x < 0 || p.x > width_ || p.y < 0 || p.y > height_) {
        fail("vertex " + str(v) + " position " + point(p) + " is outside the image [0, " +
             str(width_) + "] x [0, " + str(height_) + "]");
      }
    }
    for (int c = 0; c < mesh_.num_colors(); ++c) {
      const Color k = mesh_.colors[c];
      if (!std::isfinite(k.r) || !std::isfinite(k.g) || !std::isfinite(k.b)) {
        fail("color " + str(c) + " (" + num(k.r) + ", " + num(k.g) + ", " + num(k.b) +
             ") is not finite");
      }
    }
    // Vertex indices before color indices: without triangle_colors in a .svec.json file the
    // color indices are copies of the vertex indices, and the vertex is what the author wrote.
    const int nv = mesh_.num_vertices(), nc = mesh_.num_colors();
    for (int f = 0; f < mesh_.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.triangles[f][k];
        if (v < 0 || v >= nv) {
          fail("triangle " + str(f) + " refers to vertex " + str(v) + ", out of range (" + str(nv) +
               " vertices)");
        }
      }
    }
    for (int f = 0; f < mesh_.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int c = mesh_.triangle_colors[f][k];
        if (c < 0 || c >= nc) {
          fail("triangle_colors " + str(f) + " refers to color " + str(c) + ", out of range (" +
               str(nc) + " colors)");
        }
      }
    }
  }

  void check_features() const {
    std::unordered_set<int32_t> ids;
    for (size_t i = 0; i < mesh_.features.size(); ++i) {
      const Feature& feature = mesh_.features[i];
      if (!ids.insert(feature.id).second) {
        fail("feature " + str(int64_t(i)) + " repeats id " + str(feature.id) +
             " (ids must be unique within a level)");
      }
      if (!std::isfinite(feature.saliency)) {
        fail("feature " + str(int64_t(i)) + " (id " + str(feature.id) + ") saliency " +
             num(feature.saliency) + " is not finite");
      }
    }
  }

  void check_triangle_areas() const {
    for (int f = 0; f < mesh_.num_triangles(); ++f) {
      const Tri& t = mesh_.triangles[f];
      const double area = signed_area(pos(t[0]), pos(t[1]), pos(t[2]));
      if (!(area > 0)) {
        fail("triangle " + str(f) + " " + tri_name(t) + " is flipped or degenerate (signed area " +
             num(area) + ")");
      }
    }
  }

  void check_unused_vertices() const {
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      auto [begin, end] = topo_.faces_of(v);
      if (begin == end) fail("vertex " + str(v) + " " + point(pos(v)) + " is used by no triangle");
    }
  }

  // Which sides of the image rectangle a position lies on (exactly): bit 0 left, 1 right, 2 top,
  // 3 bottom.
  unsigned sides(Vec2 p) const {
    return (p.x == 0 ? 1u : 0u) | (p.x == width_ ? 2u : 0u) | (p.y == 0 ? 4u : 0u) |
           (p.y == height_ ? 8u : 0u);
  }

  void check_boundary() {
    on_boundary_.assign(mesh_.positions.size(), 0);
    for (int e = 0; e < topo_.num_edges(); ++e) {
      if (topo_.edge_faces[e][1] >= 0) continue;
      const auto [a, b] = topo_.edges[e];
      if ((sides(pos(a)) & sides(pos(b))) == 0) {
        fail("edge " + edge_name(a, b) + " from " + point(pos(a)) + " to " + point(pos(b)) +
             " has a triangle on one side only but does not lie on the image border (a gap or a "
             "hole in the mesh)");
      }
      on_boundary_[a] = on_boundary_[b] = 1;
    }
    const Vec2 corners[4] = {
        {0, 0}, {double(width_), 0}, {double(width_), double(height_)}, {0, double(height_)}};
    for (const Vec2& corner : corners) {
      bool found = false;
      for (int v = 0; v < mesh_.num_vertices() && !found; ++v) found = pos(v) == corner;
      if (!found) fail("no vertex at the image corner " + point(corner));
    }
  }

  // An object: its boundary edges make closed loops, two at each boundary vertex (no pinch).
  void check_object_boundary() {
    if (mesh_.triangles.empty()) fail("has no triangles");
    on_boundary_.assign(mesh_.positions.size(), 0);
    for (int e = 0; e < topo_.num_edges(); ++e) {
      if (topo_.edge_faces[e][1] >= 0) continue;
      for (const int v : topo_.edges[e]) ++on_boundary_[v];
    }
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      if (on_boundary_[v] != 0 && on_boundary_[v] != 2) {
        fail("vertex " + str(v) + " " + point(pos(v)) + " is on " + str(int(on_boundary_[v])) +
             " boundary edges (an object's boundary is made of closed loops, two edges at each "
             "vertex)");
      }
    }
  }

  // An object: the triangles around an interior vertex make exactly one turn (no fold), and those
  // around a boundary vertex less than one.
  void check_object_turns() const {
    std::vector<double> angle_sum(mesh_.positions.size(), 0.0);
    for (const Tri& t : mesh_.triangles) {
      const Vec2 a = pos(t[0]), b = pos(t[1]), c = pos(t[2]);
      angle_sum[t[0]] += corner_angle(a, b, c);
      angle_sum[t[1]] += corner_angle(b, c, a);
      angle_sum[t[2]] += corner_angle(c, a, b);
    }
    constexpr double kTurn = 2 * std::numbers::pi, kAngleTolerance = 1e-6;
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      const double sum = angle_sum[v];
      const bool bad = on_boundary_[v] ? !(sum < kTurn - kAngleTolerance)
                                       : std::abs(sum - kTurn) > kAngleTolerance;
      if (bad) {
        fail("triangles overlap around vertex " + str(v) + " " + point(pos(v)) +
             ": their angles there sum to " + num(sum / std::numbers::pi) + "*pi");
      }
    }
  }

  void check_tiling() const {
    const int nv = mesh_.num_vertices();
    std::vector<double> angle_sum(nv, 0.0);
    long double total_area = 0;
    for (const Tri& t : mesh_.triangles) {
      const Vec2 a = pos(t[0]), b = pos(t[1]), c = pos(t[2]);
      angle_sum[t[0]] += corner_angle(a, b, c);
      angle_sum[t[1]] += corner_angle(b, c, a);
      angle_sum[t[2]] += corner_angle(c, a, b);
      total_area += signed_area(a, b, c);
    }
    constexpr double kPi = std::numbers::pi;
    constexpr double kAngleTolerance = 1e-6;  // radians; a fold changes a sum by at least pi/2
    for (int v = 0; v < nv; ++v) {
      double expected = 2 * kPi;
      const char* where = "an interior vertex";
      if (on_boundary_[v]) {
        const unsigned s = sides(pos(v));
        const bool image_corner = (s & 3u) != 0 && (s & 12u) != 0;
        expected = image_corner ? kPi / 2 : kPi;
        where = image_corner ? "an image corner" : "a border vertex";
      }
      const double sum = angle_sum[v];
      if (std::abs(sum - expected) > kAngleTolerance) {
        fail("triangles " + std::string(sum > expected ? "overlap" : "leave a gap") +
             " around vertex " + str(v) + " " + point(pos(v)) + ": their angles there sum to " +
             num(sum / kPi) + "*pi, " + where + " needs " + num(expected / kPi) + "*pi");
      }
    }
    const double image_area = double(width_) * double(height_);
    if (std::abs(double(total_area) - image_area) > 1e-9 * image_area) {
      fail("the triangles cover an area of " + num(double(total_area)) + " but the image has " +
           num(image_area) + " (" + str(width_) + " x " + str(height_) +
           "): they overlap or leave a gap");
    }
  }

  // Color index that triangle f uses at its corner on vertex v.
  int corner_color(int f, int v) const {
    const Tri& t = mesh_.triangles[f];
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    return mesh_.triangle_colors[f][k];
  }

  void check_colors() const {
    const int nc = mesh_.num_colors();
    std::vector<int32_t> owner(nc, -1), first_triangle(nc, -1);
    for (int f = 0; f < mesh_.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.triangles[f][k], c = mesh_.triangle_colors[f][k];
        if (owner[c] < 0) {
          owner[c] = v;
          first_triangle[c] = f;
        } else if (owner[c] != v) {
          fail("color " + str(c) + " is used at vertex " + str(owner[c]) + " (triangle " +
               str(first_triangle[c]) + ") and at vertex " + str(v) + " (triangle " + str(f) +
               "); a color value belongs to one vertex");
        }
      }
    }
    for (int c = 0; c < nc; ++c) {
      if (owner[c] < 0) fail("color " + str(c) + " is used by no triangle corner");
    }
    for (int e = 0; e < topo_.num_edges(); ++e) {
      const auto [f, g] = topo_.edge_faces[e];
      if (g < 0 || topo_.edge_tags[e] == EdgeTag::kTear) continue;
      for (int v : topo_.edges[e]) {
        const int cf = corner_color(f, v), cg = corner_color(g, v);
        if (cf != cg) {
          fail("edge " + edge_name(topo_.edges[e][0], topo_.edges[e][1]) +
               " is not a tear but triangles " + str(f) + " and " + str(g) +
               " use different colors at vertex " + str(v) + " (" + str(cf) + " and " + str(cg) +
               ")");
        }
      }
    }
  }

  Vec2 pos(int v) const { return mesh_.positions[v]; }
  static std::string tri_name(const Tri& t) {
    return "(" + str(t[0]) + ", " + str(t[1]) + ", " + str(t[2]) + ")";
  }

  const ControlMesh& mesh_;
  const int width_, height_;
  const std::string prefix_;
  MeshTopology topo_;
  std::vector<uint8_t> on_boundary_;
  const bool object_ = false;
};

// `owner`: "" for the image's strokes, "object N " for an object's.
void validate_stroke(const Stroke& stroke, size_t index, int num_levels, const std::string& owner = {}) {
  const std::string prefix = owner + "stroke " + str(int64_t(index)) + ": ";
  auto fail = [&](const std::string& message, ErrorCode code = ErrorCode::kInvalidMesh) {
    throw Error(code, prefix + message);
  };
  if (stroke.level < 0 || stroke.level >= num_levels) {
    fail("level " + str(stroke.level) + " is out of range (" + str(num_levels) + " levels)");
  }
  if (static_cast<int64_t>(stroke.points.size()) > Limits::kMaxElements) {
    fail(str(int64_t(stroke.points.size())) + " points is over the limit of " +
             str(Limits::kMaxElements),
         ErrorCode::kLimit);
  }
  if (stroke.points.size() < 2) fail("has fewer than two points");
  for (size_t i = 0; i < stroke.points.size(); ++i) {
    const Vec2 p = stroke.points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      fail("point " + str(int64_t(i)) + " " + point(p) + " is not finite");
    }
  }
  if (!std::isfinite(stroke.width) || !(stroke.width > 0)) {
    fail("width " + num(stroke.width) + " is not a positive number");
  }
  const Color c = stroke.color;
  if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b)) {
    fail("color (" + num(c.r) + ", " + num(c.g) + ", " + num(c.b) + ") is not finite");
  }
  if (!(stroke.taper >= 0 && stroke.taper <= 0.5f)) {
    fail("taper " + num(stroke.taper) + " is outside [0, 0.5]");
  }
}

// The pyramid link of level l (ControlMesh::parent_vertices, collapses): indices in range, parents
// distinct, none of them removed. Whether the collapses really make this level is checked where
// the pyramid replays them (pyramid/pyramid.h).
void validate_level_link(const VectorImage& image, int l) {
  const ControlMesh& m = image.levels[l];
  const std::string where = "level " + str(l) + ": ";
  auto fail = [&](const std::string& message) { throw Error(ErrorCode::kInvalidMesh, where + message); };
  if (m.parent_vertices.empty() && m.collapses.empty()) return;
  if (l == 0) fail("level 0 has no level before it, but names parent vertices or collapses");
  const int64_t fine = image.levels[l - 1].num_vertices();
  if (static_cast<int64_t>(m.parent_vertices.size()) != m.num_vertices()) {
    fail(str(int64_t(m.parent_vertices.size())) + " parent vertices for " + str(m.num_vertices()) +
         " vertices");
  }
  if (static_cast<int64_t>(m.collapses.size()) + m.num_vertices() != fine) {
    fail(str(int64_t(m.collapses.size())) + " collapses do not take level " + str(l - 1) + "'s " +
         str(fine) + " vertices to " + str(m.num_vertices()));
  }
  std::vector<uint8_t> state(static_cast<size_t>(fine), 0);  // 1 parent, 2 removed
  for (size_t i = 0; i < m.parent_vertices.size(); ++i) {
    const int32_t p = m.parent_vertices[i];
    if (p < 0 || p >= fine) fail("parent vertex " + str(int64_t(i)) + " is " + str(p) + ", out of range");
    if (state[p]) fail("parent vertex " + str(p) + " appears twice");
    state[p] = 1;
  }
  for (size_t i = 0; i < m.collapses.size(); ++i) {
    const auto [u, v] = m.collapses[i];
    if (u < 0 || u >= fine || v < 0 || v >= fine || u == v) {
      fail("collapse " + str(int64_t(i)) + " (" + str(u) + ", " + str(v) + ") is out of range");
    }
    if (state[u]) fail("collapse " + str(int64_t(i)) + " removes vertex " + str(u) + ", which is kept or already removed");
    state[u] = 2;
  }
}

}  // namespace

MeshTopology validate_level(const ControlMesh& mesh, int width, int height, int level_index) {
  return LevelValidator(mesh, width, height, level_index).run();
}

MeshTopology validate_object(const Object& object, int width, int height, int num_levels, int index) {
  const std::string prefix = "object " + str(index) + ": ";
  if (object.level < 0 || object.level >= num_levels) {
    throw Error(ErrorCode::kInvalidMesh, prefix + "level " + str(object.level) +
                                             " is out of range (" + str(num_levels) + " levels)");
  }
  if (!valid_utf8(object.name)) throw Error(ErrorCode::kInvalidMesh, prefix + "name is not UTF-8");
  if (!object.mesh.parent_vertices.empty() || !object.mesh.collapses.empty()) {
    throw Error(ErrorCode::kInvalidMesh, prefix + "an object has no parent vertices or collapses");
  }
  MeshTopology topology = LevelValidator(object.mesh, width, height, prefix).run();
  if (static_cast<int64_t>(object.strokes.size()) > Limits::kMaxElements) {
    throw Error(ErrorCode::kLimit, prefix + str(int64_t(object.strokes.size())) +
                                       " strokes is over the limit of " + str(Limits::kMaxElements));
  }
  for (size_t s = 0; s < object.strokes.size(); ++s) {
    const Stroke& stroke = object.strokes[s];
    validate_stroke(stroke, s, num_levels, "object " + str(index) + " ");
    if (stroke.level != object.level) {
      throw Error(ErrorCode::kInvalidMesh, prefix + "stroke " + str(int64_t(s)) + ": level " +
                                               str(stroke.level) + " is not the object's level " +
                                               str(object.level));
    }
  }
  return topology;
}

std::vector<ObjectTopology> visible_objects(const VectorImage& image, int level) {
  std::vector<ObjectTopology> out;
  for (size_t o = 0; o < image.objects.size(); ++o) {
    const Object& object = image.objects[o];
    if (object.level != level || !object.visible) continue;
    out.push_back({static_cast<int>(o), validate_object(object, image.width, image.height,
                                                        static_cast<int>(image.levels.size()),
                                                        static_cast<int>(o))});
  }
  return out;
}

void validate(const VectorImage& image) {
  for (const auto& [name, value] : {std::pair{"width", image.width}, {"height", image.height}}) {
    if (value < 1)
      throw Error(ErrorCode::kInvalidMesh,
                  std::string(name) + " " + str(value) + " is not positive");
    if (value > Limits::kMaxDimension) {
      throw Error(ErrorCode::kLimit, std::string(name) + " " + str(value) +
                                         " is over the limit of " + str(Limits::kMaxDimension));
    }
  }
  const int64_t pixels = int64_t{image.width} * image.height;
  if (pixels > Limits::kMaxPixels) {
    throw Error(ErrorCode::kLimit, "image size " + str(image.width) + " x " + str(image.height) +
                                       " is over the limit of " + str(Limits::kMaxPixels) +
                                       " pixels");
  }
  if (image.levels.empty()) throw Error(ErrorCode::kInvalidMesh, "the image has no levels");
  if (static_cast<int64_t>(image.levels.size()) > Limits::kMaxLevels) {
    throw Error(ErrorCode::kLimit, str(int64_t(image.levels.size())) +
                                       " levels is over the limit of " + str(Limits::kMaxLevels));
  }
  for (size_t l = 0; l < image.levels.size(); ++l)
    validate_level(image.levels[l], image.width, image.height, static_cast<int>(l));
  for (size_t l = 0; l < image.levels.size(); ++l)
    validate_level_link(image, static_cast<int>(l));
  if (static_cast<int64_t>(image.objects.size()) > Limits::kMaxObjects) {
    throw Error(ErrorCode::kLimit, str(int64_t(image.objects.size())) +
                                       " objects is over the limit of " + str(Limits::kMaxObjects));
  }
  for (size_t o = 0; o < image.objects.size(); ++o) {
    validate_object(image.objects[o], image.width, image.height,
                    static_cast<int>(image.levels.size()), static_cast<int>(o));
  }
  if (static_cast<int64_t>(image.strokes.size()) > Limits::kMaxElements) {
    throw Error(ErrorCode::kLimit, str(int64_t(image.strokes.size())) +
                                       " strokes is over the limit of " +
                                       str(Limits::kMaxElements));
  }
  for (size_t s = 0; s < image.strokes.size(); ++s)
    validate_stroke(image.strokes[s], s, static_cast<int>(image.levels.size()));
  if (static_cast<int64_t>(image.metadata.size()) > Limits::kMaxElements) {
    throw Error(ErrorCode::kLimit, str(int64_t(image.metadata.size())) +
                                       " metadata entries is over the limit of " +
                                       str(Limits::kMaxElements));
  }
  std::unordered_set<std::string> keys;
  for (size_t i = 0; i < image.metadata.size(); ++i) {
    const auto& [key, value] = image.metadata[i];
    const std::string where = "metadata entry " + str(int64_t(i));
    if (!valid_utf8(key)) throw Error(ErrorCode::kInvalidMesh, where + ": key is not valid UTF-8");
    if (!valid_utf8(value)) {
      throw Error(ErrorCode::kInvalidMesh,
                  where + " (" + quoted(key) + "): value is not valid UTF-8");
    }
    if (!keys.insert(key).second) {
      throw Error(ErrorCode::kInvalidMesh, where + ": key " + quoted(key) + " appears twice");
    }
  }
}

}  // namespace subvec
