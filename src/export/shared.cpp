// Strips of refined triangles (export_p.h) and the other pieces the PDF and SVG writers share.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <unordered_map>

#include "export/export_p.h"

namespace subvec::detail {
namespace {

uint64_t corner_key(const RefinedMesh& mesh, int32_t t, int k) {
  return (uint64_t{static_cast<uint32_t>(mesh.triangles[t][k])} << 32) |
         static_cast<uint32_t>(mesh.triangle_colors[t][k]);
}

struct PairHash {
  size_t operator()(const std::pair<uint64_t, uint64_t>& p) const {
    return std::hash<uint64_t>()(p.first * 0x9E3779B97F4A7C15ull ^ p.second);
  }
};

}  // namespace

Strips make_strips(const RefinedMesh& mesh) {
  const int32_t nt = mesh.num_triangles();
  // Directed corner edges -> (triangle, index of the edge's first corner).
  std::unordered_map<std::pair<uint64_t, uint64_t>, std::pair<int32_t, int>, PairHash> edges;
  edges.reserve(size_t(nt) * 3);
  for (int32_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      edges[{corner_key(mesh, t, k), corner_key(mesh, t, (k + 1) % 3)}] = {t, k};
  std::vector<char> done(nt, 0);
  // The unvisited triangle across the edge from corner (t, i) to corner (s, j): its third corner.
  auto across = [&](std::array<int32_t, 2> a, std::array<int32_t, 2> b) -> std::array<int32_t, 2> {
    const auto it = edges.find({corner_key(mesh, b[0], b[1]), corner_key(mesh, a[0], a[1])});
    if (it == edges.end() || done[it->second.first]) return {-1, -1};
    return {it->second.first, (it->second.second + 2) % 3};
  };
  Strips strips;
  for (int32_t t = 0; t < nt; ++t) {
    if (done[t]) continue;
    done[t] = 1;
    // Start rotated so that the edge (b, c) has a neighbor, when one does.
    int r = 0;
    for (int k = 0; k < 3; ++k) {
      if (across({t, (k + 1) % 3}, {t, (k + 2) % 3})[0] >= 0) {
        r = k;
        break;
      }
    }
    std::array<std::array<int32_t, 2>, 3> v = {{{t, r}, {t, (r + 1) % 3}, {t, (r + 2) % 3}}};
    for (const auto& c : v) {
      strips.corners.push_back(c);
      strips.flags.push_back(0);
    }
    for (;;) {
      // Continue across (b, c) (flag 1) or (a, c) (flag 2). The shared edge keeps its direction
      // in the previous triangle only up to orientation, so try both directions. Where both are
      // open, take the triangle with fewer open neighbours, so as to leave none of them alone.
      std::array<int32_t, 2> d1 = across(v[1], v[2]);
      if (d1[0] < 0) d1 = across(v[2], v[1]);
      std::array<int32_t, 2> d2 = across(v[0], v[2]);
      if (d2[0] < 0) d2 = across(v[2], v[0]);
      auto open_neighbours = [&](std::array<int32_t, 2> c) {
        int n = 0;
        for (int k = 0; k < 3; ++k) {
          const std::array<int32_t, 2> p{c[0], k}, q{c[0], (k + 1) % 3};
          const int32_t a = across(p, q)[0], b = across(q, p)[0];
          n += (a >= 0 && a != c[0]) || (b >= 0 && b != c[0]);
        }
        return n;
      };
      uint8_t flag = 1;
      std::array<int32_t, 2> d = d1;
      if (d1[0] < 0 || (d2[0] >= 0 && open_neighbours(d2) < open_neighbours(d1))) {
        d = d2;
        flag = 2;
      }
      if (d[0] < 0) break;
      done[d[0]] = 1;
      strips.corners.push_back(d);
      strips.flags.push_back(flag);
      v = flag == 1 ? std::array<std::array<int32_t, 2>, 3>{v[1], v[2], d}
                    : std::array<std::array<int32_t, 2>, 3>{v[0], v[2], d};
    }
  }
  return strips;
}

std::vector<Vec2> stroke_outline(const Stroke& stroke) {
  const std::vector<Vec2>& p = stroke.points;
  if (p.size() < 2) return {};
  // Clamped uniform cubic B-spline: the end points tripled.
  std::vector<Vec2> q = {p.front(), p.front()};
  q.insert(q.end(), p.begin(), p.end());
  q.push_back(p.back());
  q.push_back(p.back());
  constexpr int kSamples = 16;
  std::vector<Vec2> curve;
  for (size_t i = 0; i + 3 < q.size(); ++i) {
    for (int s = (i == 0 ? 0 : 1); s <= kSamples; ++s) {
      const double t = double(s) / kSamples, t2 = t * t, t3 = t2 * t;
      const double w[4] = {(1 - t) * (1 - t) * (1 - t) / 6, (3 * t3 - 6 * t2 + 4) / 6,
                           (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, t3 / 6};
      Vec2 c;
      for (int k = 0; k < 4; ++k) c.x += w[k] * q[i + k].x, c.y += w[k] * q[i + k].y;
      if (curve.empty() || std::hypot(c.x - curve.back().x, c.y - curve.back().y) > 1e-9)
        curve.push_back(c);
    }
  }
  if (curve.size() < 2) return {};
  std::vector<double> length(curve.size(), 0);
  for (size_t i = 1; i < curve.size(); ++i)
    length[i] = length[i - 1] + std::hypot(curve[i].x - curve[i - 1].x, curve[i].y - curve[i - 1].y);
  const double total = length.back();
  const double taper = std::clamp(double(stroke.taper), 0.0, 0.5) * total;
  std::vector<Vec2> left, right;
  for (size_t i = 0; i < curve.size(); ++i) {
    const Vec2& a = curve[i > 0 ? i - 1 : i];
    const Vec2& b = curve[i + 1 < curve.size() ? i + 1 : i];
    const double dx = b.x - a.x, dy = b.y - a.y, len = std::hypot(dx, dy);
    double half = 0.5 * stroke.width;
    if (taper > 0) half *= std::min({1.0, length[i] / taper, (total - length[i]) / taper});
    const double nx = len > 0 ? -dy / len * half : 0, ny = len > 0 ? dx / len * half : 0;
    left.push_back({curve[i].x + nx, curve[i].y + ny});
    right.push_back({curve[i].x - nx, curve[i].y - ny});
  }
  left.insert(left.end(), right.rbegin(), right.rend());
  return left;
}

std::vector<TearBand> tear_bands(const RefinedMesh& mesh, double width) {
  // Refined edge -> the (at most two) triangles on it.
  std::map<std::pair<int32_t, int32_t>, std::array<int32_t, 2>> sides;
  for (int32_t t = 0; t < mesh.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      auto [it, fresh] = sides.try_emplace({std::min(a, b), std::max(a, b)},
                                           std::array<int32_t, 2>{t, -1});
      if (!fresh) it->second[1] = t;
    }
  }
  std::vector<TearBand> bands;
  for (int side = 0; side < 2; ++side) {
    for (const EdgeVerts& e : mesh.tear_edges) {
      const auto it = sides.find({std::min(e[0], e[1]), std::max(e[0], e[1])});
      if (it == sides.end() || it->second[side] < 0) continue;
      const int32_t t = it->second[side];
      const Tri& v = mesh.triangles[t];
      int third = 0;  // corner of t off the edge
      for (int k = 0; k < 3; ++k)
        if (v[k] != e[0] && v[k] != e[1]) third = k;
      const double ax = mesh.positions[2 * e[0]], ay = mesh.positions[2 * e[0] + 1];
      const double bx = mesh.positions[2 * e[1]], by = mesh.positions[2 * e[1] + 1];
      const double cx = mesh.positions[2 * v[third]], cy = mesh.positions[2 * v[third] + 1];
      double nx = ay - by, ny = bx - ax;
      const double length = std::hypot(nx, ny);
      if (!(length > 0)) continue;
      nx /= length;
      ny /= length;
      double height = nx * (cx - ax) + ny * (cy - ay);  // of the third corner over the edge
      if (height < 0) {
        nx = -nx;
        ny = -ny;
        height = -height;
      }
      // The band's color: the triangle's (linear) color half a band width into the side, the
      // mean of what the band covers where the color changes fast next to the tear.
      const double toward_third = height > 0 ? std::min(1.0, 0.5 * width / height) : 0.0;
      TearBand band;
      band.edge = e;
      band.side = side;
      for (int ch = 0; ch < 3; ++ch) {
        double edge = 0;
        for (int k = 0; k < 3; ++k)
          if (k != third) edge += 0.5 * mesh.colors[3 * mesh.triangle_colors[t][k] + ch];
        const double corner = mesh.colors[3 * mesh.triangle_colors[t][third] + ch];
        band.color[ch] = edge + toward_third * (corner - edge);
      }
      // The first side's band reaches half a width across the tear, under the second side's: a
      // pixel on the tear is then fully covered by the first band, and the second one's
      // anti-aliased edge mixes the two by coverage, with nothing of the shading under them.
      const double across = side == 0 ? 0.5 * width : 0.0;
      band.corners = {Vec2{ax - across * nx, ay - across * ny}, Vec2{bx - across * nx, by - across * ny},
                      Vec2{bx + width * nx, by + width * ny}, Vec2{ax + width * nx, ay + width * ny}};
      bands.push_back(band);
    }
  }
  return bands;
}

std::vector<TearHint> tear_hints(const RefinedMesh& mesh, double width, double color_tolerance) {
  const std::vector<TearBand> bands = tear_bands(mesh, width);
  std::vector<TearHint> hints;
  for (size_t begin = 0; begin < bands.size();) {
    size_t end = begin + 1;
    auto near = [&](const TearBand& b) {
      for (int ch = 0; ch < 3; ++ch)
        if (std::abs(b.color[ch] - bands[begin].color[ch]) > color_tolerance) return false;
      return true;
    };
    while (end < bands.size() && bands[end].side == bands[begin].side &&
           bands[end].edge[0] == bands[end - 1].edge[1] && near(bands[end]))
      ++end;
    TearHint hint;
    auto mid = [](const Vec2& a, const Vec2& b) { return Vec2{0.5 * (a.x + b.x), 0.5 * (a.y + b.y)}; };
    // Along the tear (corners 0 and 1), then back along the offsets (corners 2 and 3).
    hint.polygon.push_back(bands[begin].corners[0]);
    for (size_t k = begin; k + 1 < end; ++k)
      hint.polygon.push_back(mid(bands[k].corners[1], bands[k + 1].corners[0]));
    hint.polygon.push_back(bands[end - 1].corners[1]);
    hint.polygon.push_back(bands[end - 1].corners[2]);
    for (size_t k = end - 1; k > begin; --k)
      hint.polygon.push_back(mid(bands[k].corners[3], bands[k - 1].corners[2]));
    hint.polygon.push_back(bands[begin].corners[3]);
    for (size_t k = begin; k < end; ++k)
      for (int ch = 0; ch < 3; ++ch) hint.color[ch] += bands[k].color[ch] / double(end - begin);
    hints.push_back(std::move(hint));
    begin = end;
  }
  return hints;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

}  // namespace subvec::detail
