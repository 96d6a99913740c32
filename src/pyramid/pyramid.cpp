// The vector image pyramid (pyramid/pyramid.h, paper §6.4).
#include "subvec/pyramid/pyramid.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>
#include <unordered_map>

#include "mesh/coarsen_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec {
namespace {

using coarsen_detail::Coarsener;
using coarsen_detail::CollapseRecord;
using coarsen_detail::Kind;
using coarsen_detail::Rgb;

// One band: the step from level b - 1 (fine) to level b (coarse), with its details.
struct Band {
  std::vector<int32_t> merged_of;              // fine color -> merged color
  std::vector<Rgb> merge_detail;               // fine color minus its merged mean
  int num_merged = 0;
  std::vector<int32_t> parents;                // coarse vertex -> fine vertex
  std::vector<int32_t> coarse_color_merged;    // coarse color -> merged color
  std::vector<int32_t> merged_coarse;          // live merged color -> a coarse color, else -1
  // A kept vertex is the same vertex in both levels: what differs is only how each level expresses
  // it (the coarse level's colors were refitted for its coarser surface; positions may differ by the
  // file grid). These differences are applied in full, whatever eta: they are no band of detail.
  // (Scaling them would put control values fitted for the coarse surface under the fine one, whose
  // limit follows its control values more closely: ripples, not smoothing.)
  std::vector<Vec2> survivor_detail;           // fine position of a kept vertex minus its coarse one
  std::vector<Rgb> refit_detail;               // merged value of a kept color minus its refitted one
  std::vector<CollapseRecord> records;
  std::vector<std::array<double, 2>> position_detail;  // per record, in its local frame
  std::vector<std::vector<Rgb>> color_detail;          // per record, per wedge
  // A tear vertex of a kept feature: its two sides as a mean (predicted, detail scaled by eta) and
  // half the jump between them, which is kept as it is: a kept tear never fades nor sharpens.
  std::vector<uint8_t> tear_pair;                      // per record
  std::vector<Rgb> half_jump;                          // per record (zero unless tear_pair)
  std::vector<Rgb> merged_values;                      // merged colors as the step made them
  std::vector<Kind> kinds;                             // of every fine vertex
  std::vector<double> keep;                            // per fine vertex, see feature_keep
  std::vector<double> color_keep;                      // per fine color: its vertex's keep
  std::vector<double> merged_keep;                     // per merged color: its colors' largest keep
  std::vector<uint8_t> sides;                          // image sides of every fine vertex
};

[[noreturn]] void mismatch(int level, const std::string& what) {
  throw Error(ErrorCode::kInvalidMesh, "level " + std::to_string(level) +
                                           ": its pyramid record does not make it from level " +
                                           std::to_string(level - 1) + " (" + what + ")");
}

// Position prediction: Fujiwara weights taken at the ring's centroid. Returns R and the frame axis.
Vec2 predict_position(const std::vector<int32_t>& ring, const std::vector<Vec2>& pos) {
  double cx = 0, cy = 0;
  for (int32_t w : ring) cx += pos[w].x, cy += pos[w].y;
  const double n = static_cast<double>(ring.size());
  cx /= n, cy /= n;
  double sum = 0, x = 0, y = 0;
  for (int32_t w : ring) {
    const double wt = 1 / std::max(std::hypot(pos[w].x - cx, pos[w].y - cy), 1e-9);
    sum += wt, x += wt * pos[w].x, y += wt * pos[w].y;
  }
  return {x / sum, y / sum};
}

Vec2 frame_axis(Vec2 r, Vec2 kept) {
  const double dx = kept.x - r.x, dy = kept.y - r.y, len = std::hypot(dx, dy);
  if (len < 1e-12) return {1, 0};
  return {dx / len, dy / len};
}

// Color prediction: the value at `at` of the affine function that fits the wedge's neighbour
// colors best in the weighted least-squares sense, with eq. 3's Fujiwara weights 1 / |at - p_i|
// (paper: the weighted mean itself). It is still a fixed linear combination sum w~_i c_i of the
// neighbour colors, with w~_i summing to 1, but it reproduces linear color ramps exactly (linear
// precision), where the weighted mean bends them toward the nearer neighbours: at eta = 0 the
// pyramid then gives a smooth surface, not one with bumps at every removed vertex (docs/levels.md).
// A small ridge on the gradient makes collinear neighbours (a chain's two) a fit along their line
// and one neighbour its value.
Rgb predict_color(const CollapseRecord::Wedge& w, Vec2 at, const std::vector<Vec2>& pos,
                  const std::vector<Rgb>& merged) {
  const size_t n = w.neighbours.size();
  Rgb out{0, 0, 0};
  if (n == 0) return out;
  // Offsets from `at`, in units of their RMS length (the fit is scale-free), and the weights.
  double scale = 0;
  for (const auto& [v, c] : w.neighbours) scale += (pos[v].x - at.x) * (pos[v].x - at.x) + (pos[v].y - at.y) * (pos[v].y - at.y);
  scale = std::sqrt(scale / static_cast<double>(n));
  if (!(scale > 1e-12)) scale = 1;
  // Normal equations of [1 dx dy] with weights wt: M = sum wt X X^T, ridge on the gradient terms.
  double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  double wsum = 0;
  for (const auto& [v, c] : w.neighbours) {
    const double dx = (pos[v].x - at.x) / scale, dy = (pos[v].y - at.y) / scale;
    const double wt = 1 / std::max(std::hypot(dx, dy), 1e-9);
    const double x[3] = {1, dx, dy};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] += wt * x[i] * x[j];
    wsum += wt;
  }
  m[1][1] += 1e-2 * wsum, m[2][2] += 1e-2 * wsum;
  // First row of M^-1 (M is symmetric positive definite): the cofactors of its first column.
  const double c0 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c1 = -(m[1][0] * m[2][2] - m[1][2] * m[2][0]);
  const double c2 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double det = m[0][0] * c0 + m[0][1] * c1 + m[0][2] * c2;
  for (const auto& [v, c] : w.neighbours) {
    const double dx = (pos[v].x - at.x) / scale, dy = (pos[v].y - at.y) / scale;
    const double wt = 1 / std::max(std::hypot(dx, dy), 1e-9);
    const double coef = wt * (c0 + c1 * dx + c2 * dy) / det;
    for (int i = 0; i < 3; ++i) out[i] += coef * merged[c][i];
  }
  return out;
}

Rgb rgb(Color c) { return {c.r, c.g, c.b}; }

// The edge profile of a kept feature: how much of its color detail each fine vertex keeps whatever
// eta. All of it on the band's kept features and their one-ring, then a taper: two thirds on the
// second ring, a third on the third, none beyond. The rendered color within about a triangle of a
// feature is made of these vertices' control colors (a limit point depends on the control values
// within two rings, the second with a small weight): their details are the profile of the edge,
// not texture to take away. Smoothing them separately on each side (their predictions do not cross the tear)
// changed the rendered contrast 1.5 px out by up to 68 % on the shared photographs at eta = 0.3;
// keeping the one-ring left one feature (squirrel) at 5.7 %, a taper beyond it brings every
// feature within 5 %. The taper is gradual because a step from kept to smoothed detail at small
// eta is itself a ripple: with a quarter on the second ring and nothing beyond, squirrel's
// high-frequency energy was lower at eta = 0.3 than at 0; with a half and a fifth it rose from 0
// by 0.003 % (docs/levels.md, "Edge profiles").
constexpr double kProfileKeep[] = {1.0, 1.0, 2.0 / 3, 1.0 / 3};  // by ring from the feature out

std::vector<double> feature_keep(const ControlMesh& fine, const std::vector<int32_t>& kept_ids) {
  constexpr int kRings = static_cast<int>(std::size(kProfileKeep)) - 1;
  const int nv = fine.num_vertices();
  std::vector<double> keep(nv, 0);
  std::vector<int> dist(nv, -1);
  std::vector<int32_t> front;
  for (const Feature& f : fine.features) {
    if (std::find(kept_ids.begin(), kept_ids.end(), f.id) == kept_ids.end()) continue;
    for (int32_t v : f.vertices)
      if (dist[v] < 0) dist[v] = 0, front.push_back(v);
  }
  std::vector<std::vector<int32_t>> adj(nv);
  for (const Tri& t : fine.triangles)
    for (int k = 0; k < 3; ++k) adj[t[k]].push_back(t[(k + 1) % 3]), adj[t[(k + 1) % 3]].push_back(t[k]);
  for (int r = 0; r < kRings; ++r) {
    std::vector<int32_t> next;
    for (int32_t v : front)
      for (int32_t w : adj[v])
        if (dist[w] < 0) dist[w] = r + 1, next.push_back(w);
    front = std::move(next);
  }
  for (int v = 0; v < nv; ++v) keep[v] = dist[v] >= 0 ? kProfileKeep[dist[v]] : 0;
  return keep;
}

Band analyze(const ControlMesh& fine, const ControlMesh& coarse, int width, int height, int level) {
  Band b;
  std::vector<int32_t> kept_ids;
  for (const Feature& f : coarse.features) kept_ids.push_back(f.id);
  for (int32_t id : kept_ids) {
    if (std::none_of(fine.features.begin(), fine.features.end(), [&](const Feature& f) { return f.id == id; }))
      mismatch(level, "feature " + std::to_string(id) + " is not in the finer level");
  }
  Coarsener c(fine, width, height, kept_ids);
  const int nv = fine.num_vertices();
  b.merged_of = c.merged_of();
  b.num_merged = c.num_merged();
  b.kinds.resize(nv);
  b.sides.resize(nv);
  for (int v = 0; v < nv; ++v) {
    b.kinds[v] = c.kind(v);
    const Vec2 p = fine.positions[v];
    // (An object's mesh, MeshTopology::kNoFrame, has no sides: its boundary vertices stay.)
    b.sides[v] = width < 0 ? 0 : static_cast<uint8_t>((p.x == 0 ? 1 : 0) | (p.y == 0 ? 2 : 0) |
                                                      (p.x == width ? 4 : 0) | (p.y == height ? 8 : 0));
  }
  b.keep = feature_keep(fine, kept_ids);
  b.color_keep.assign(fine.colors.size(), 0);
  for (int32_t f = 0; f < fine.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) b.color_keep[fine.triangle_colors[f][k]] = b.keep[fine.triangles[f][k]];
  const std::vector<Rgb> merged = c.merged_colors();
  b.merged_values = merged;
  b.merged_keep.assign(merged.size(), 0);
  for (size_t k = 0; k < fine.colors.size(); ++k) {
    const int32_t m = b.merged_of[k];
    if (m >= 0) b.merged_keep[m] = std::max(b.merged_keep[m], b.color_keep[k]);
  }
  b.merge_detail.resize(fine.colors.size());
  for (size_t k = 0; k < fine.colors.size(); ++k) {
    const Rgb f = rgb(fine.colors[k]);
    const int32_t m = b.merged_of[k];
    for (int i = 0; i < 3; ++i) b.merge_detail[k][i] = m >= 0 ? f[i] - merged[m][i] : 0;
  }
  // Replay the collapses, recording each removed vertex's neighbourhood and detail.
  for (size_t i = 0; i < coarse.collapses.size(); ++i) {
    const auto [u, v] = coarse.collapses[i];
    if (u < 0 || u >= nv || v < 0 || v >= nv || !c.alive(u) || !c.alive(v))
      mismatch(level, "collapse " + std::to_string(i) + " names a removed vertex");
    std::vector<int32_t> nbrs;
    c.neighbours(u, nbrs);
    if (!std::binary_search(nbrs.begin(), nbrs.end(), v) || c.kind(u) == Kind::kCorner)
      mismatch(level, "collapse " + std::to_string(i) + " is not an edge collapse of a removable vertex");
    CollapseRecord r = c.collapse(u, v);
    if (r.position_ring.empty()) mismatch(level, "collapse " + std::to_string(i) + " has no neighbourhood");
    const Vec2 pr = predict_position(r.position_ring, fine.positions);
    const Vec2 e1 = frame_axis(pr, fine.positions[v]);
    const double dx = fine.positions[u].x - pr.x, dy = fine.positions[u].y - pr.y;
    b.position_detail.push_back({dx * e1.x + dy * e1.y, -dx * e1.y + dy * e1.x});
    std::vector<Rgb> cd;
    for (const auto& w : r.wedges) {
      const Rgb p = predict_color(w, fine.positions[u], fine.positions, merged);
      cd.push_back({merged[w.color][0] - p[0], merged[w.color][1] - p[1], merged[w.color][2] - p[2]});
    }
    const bool pair = c.kind(u) == Kind::kTear && r.wedges.size() == 2;
    Rgb half{0, 0, 0};
    if (pair) {
      // L = m + j + d, R = m - j + d with m the mean of the two side predictions.
      for (int ch = 0; ch < 3; ++ch) {
        const double l = merged[r.wedges[0].color][ch], rr = merged[r.wedges[1].color][ch];
        const double pred_l = l - cd[0][ch], pred_r = rr - cd[1][ch];
        half[ch] = (l - rr) / 2;
        cd[0][ch] = cd[1][ch] = (l + rr) / 2 - (pred_l + pred_r) / 2;
      }
    }
    b.tear_pair.push_back(pair ? 1 : 0);
    b.half_jump.push_back(half);
    b.color_detail.push_back(std::move(cd));
    b.records.push_back(std::move(r));
  }
  std::vector<int32_t> parents, color_merged;
  const ControlMesh replayed = c.result(parents, color_merged);
  if (coarse.parent_vertices.size() != static_cast<size_t>(coarse.num_vertices()) ||
      replayed.num_vertices() != coarse.num_vertices() || replayed.num_triangles() != coarse.num_triangles())
    mismatch(level, "vertex or triangle counts differ");
  // Match the coarse triangles to the replayed ones through the parents, corner by corner.
  auto canonical = [](std::array<int32_t, 3> t) {
    int k = 0;
    for (int i = 1; i < 3; ++i)
      if (t[i] < t[k]) k = i;
    return std::array<int32_t, 4>{t[k], t[(k + 1) % 3], t[(k + 2) % 3], k};
  };
  auto key = [](const std::array<int32_t, 4>& t) {
    return (uint64_t(uint32_t(t[0])) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(uint32_t(t[1])) << 21) ^ uint64_t(uint32_t(t[2]));
  };
  std::unordered_multimap<uint64_t, int32_t> faces;
  for (int32_t f = 0; f < replayed.num_triangles(); ++f) {
    std::array<int32_t, 3> t;
    for (int k = 0; k < 3; ++k) t[k] = parents[replayed.triangles[f][k]];
    faces.insert({key(canonical(t)), f});
  }
  b.parents = coarse.parent_vertices;
  b.coarse_color_merged.assign(coarse.colors.size(), -1);
  b.merged_coarse.assign(b.num_merged, -1);
  for (int32_t f = 0; f < coarse.num_triangles(); ++f) {
    std::array<int32_t, 3> t;
    for (int k = 0; k < 3; ++k) t[k] = b.parents[coarse.triangles[f][k]];
    const auto ct = canonical(t);
    int32_t g = -1;
    int kg = 0;
    for (auto [it, end] = faces.equal_range(key(ct)); it != end; ++it) {
      std::array<int32_t, 3> s;
      for (int k = 0; k < 3; ++k) s[k] = parents[replayed.triangles[it->second][k]];
      const auto cs = canonical(s);
      if (cs[0] == ct[0] && cs[1] == ct[1] && cs[2] == ct[2]) g = it->second, kg = cs[3];
    }
    if (g < 0) mismatch(level, "triangle " + std::to_string(f) + " is not made by the collapses");
    for (int i = 0; i < 3; ++i) {
      const int32_t cc = coarse.triangle_colors[f][(ct[3] + i) % 3];
      const int32_t m = color_merged[replayed.triangle_colors[g][(kg + i) % 3]];
      if (b.coarse_color_merged[cc] >= 0 && b.coarse_color_merged[cc] != m)
        mismatch(level, "color " + std::to_string(cc) + " spans two wedges");
      b.coarse_color_merged[cc] = m;
      if (b.merged_coarse[m] < 0) b.merged_coarse[m] = cc;
    }
  }
  for (int32_t m : color_merged)
    if (b.merged_coarse[m] < 0) mismatch(level, "a color of the replayed level has no value");
  for (int32_t i = 0; i < coarse.num_vertices(); ++i) {
    const Vec2 f = fine.positions[b.parents[i]], q = coarse.positions[i];
    b.survivor_detail.push_back({f.x - q.x, f.y - q.y});
  }
  b.refit_detail.resize(coarse.colors.size());
  for (size_t k = 0; k < coarse.colors.size(); ++k) {
    const Rgb q = rgb(coarse.colors[k]);
    const int32_t m = b.coarse_color_merged[k];
    for (int i = 0; i < 3; ++i) b.refit_detail[k][i] = m >= 0 ? merged[m][i] - q[i] : 0;
  }
  return b;
}

// Per color value of `mesh`: its limit value minus its control value (the limit surface's color
// at the vertex, on that side of a tear).
std::vector<Rgb> coarse_limit_shift(const ControlMesh& mesh, int width, int height) {
  const MeshTopology topology = MeshTopology::build(mesh, width, height);
  const Subdivision at_vertices(mesh, topology, 0);
  std::vector<float> limit(3 * static_cast<size_t>(at_vertices.num_colors()));
  at_vertices.evaluate_colors(mesh.colors, limit, 1);
  const RefinedMesh& out = at_vertices.topology();
  std::vector<Rgb> shift(mesh.colors.size(), Rgb{0, 0, 0});
  for (int32_t f = 0; f < mesh.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t c = mesh.triangle_colors[f][k], l = out.triangle_colors[f][k];
      const Rgb q = rgb(mesh.colors[c]);
      for (int i = 0; i < 3; ++i) shift[c][i] = double(limit[3 * l + i]) - q[i];
    }
  }
  return shift;
}

double eta_at(const std::vector<double>& etas, int band) {
  if (etas.empty()) return 1;
  return etas[std::min<size_t>(band - 1, etas.size() - 1)];
}

double signed_area(Vec2 a, Vec2 b, Vec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

// Reconstructs the fine level of band `b` from the (filtered) coarse one.
void reconstruct(const Band& b, const ControlMesh& coarse, double eta_g, double eta_c, ControlMesh& fine,
                 int width, int height, FilterReport& report) {
  const int nv = fine.num_vertices();
  const std::vector<Vec2> original = fine.positions;
  std::vector<Vec2> pos(nv);
  // (A merged value that neither a kept vertex nor a removed one carries keeps the step's value.)
  std::vector<Rgb> merged = b.merged_values;
  for (size_t i = 0; i < b.parents.size(); ++i) {
    pos[b.parents[i]] = {coarse.positions[i].x + b.survivor_detail[i].x,
                         coarse.positions[i].y + b.survivor_detail[i].y};
  }
  // A kept vertex's color at eta = 0 is the coarse surface's limit value there, not its control
  // value: the fine mesh then re-expresses the coarse surface (its limit follows its control values
  // more closely than the coarse mesh's does, so coarse control values under it would overshoot),
  // and the removed vertices' predictions interpolate that smooth surface. Between, the kept
  // vertex's own detail (its fine value minus that limit) is scaled like everyone's; at eta = 1 it
  // is its fine value exactly. Kept features' edge profiles keep their detail (`keep`).
  const std::vector<Rgb> limit_shift = coarse_limit_shift(coarse, width, height);
  for (size_t k = 0; k < coarse.colors.size(); ++k) {
    const int32_t m = b.coarse_color_merged[k];
    if (m < 0 || b.merged_coarse[m] != static_cast<int32_t>(k)) continue;
    const Rgb q = rgb(coarse.colors[k]);
    const double ek = eta_c + (1 - eta_c) * b.merged_keep[m];
    for (int i = 0; i < 3; ++i)
      merged[m][i] = q[i] + limit_shift[k][i] + ek * (b.refit_detail[k][i] - limit_shift[k][i]);
  }
  for (size_t i = b.records.size(); i-- > 0;) {
    const CollapseRecord& r = b.records[i];
    const Vec2 pr = predict_position(r.position_ring, pos);
    const Vec2 e1 = frame_axis(pr, pos[r.kept]);
    const auto& d = b.position_detail[i];
    Vec2 p{pr.x + eta_g * (d[0] * e1.x - d[1] * e1.y), pr.y + eta_g * (d[0] * e1.y + d[1] * e1.x)};
    // A border vertex stays exactly on its side.
    const uint8_t s = b.sides[r.removed];
    if (s & 1) p.x = 0;
    if (s & 4) p.x = width;
    if (s & 2) p.y = 0;
    if (s & 8) p.y = height;
    pos[r.removed] = p;
    const double ek = eta_c + (1 - eta_c) * b.keep[r.removed];
    if (b.tear_pair[i]) {
      const Rgb ql = predict_color(r.wedges[0], p, pos, merged), qr = predict_color(r.wedges[1], p, pos, merged);
      for (int c = 0; c < 3; ++c) {
        const double mean = (ql[c] + qr[c]) / 2 + ek * b.color_detail[i][0][c];
        merged[r.wedges[0].color][c] = mean + b.half_jump[i][c];
        merged[r.wedges[1].color][c] = mean - b.half_jump[i][c];
      }
      continue;
    }
    for (size_t w = 0; w < r.wedges.size(); ++w) {
      const Rgb q = predict_color(r.wedges[w], p, pos, merged);
      for (int c = 0; c < 3; ++c) merged[r.wedges[w].color][c] = q[c] + ek * b.color_detail[i][w][c];
    }
  }
  for (size_t k = 0; k < fine.colors.size(); ++k) {
    const int32_t m = b.merged_of[k];
    if (m < 0) continue;
    const double ek = eta_c + (1 - eta_c) * b.color_keep[k];
    fine.colors[k] = {static_cast<float>(merged[m][0] + ek * b.merge_detail[k][0]),
                      static_cast<float>(merged[m][1] + ek * b.merge_detail[k][1]),
                      static_cast<float>(merged[m][2] + ek * b.merge_detail[k][2])};
  }
  // Where a filtered position flips or flattens a triangle, its vertices move back toward their
  // unfiltered positions, halving the step until nothing flips (the unfiltered level is valid).
  constexpr double kMinArea = 1e-6;
  std::vector<uint8_t> moved(nv, 0);
  std::vector<double> share(nv, 1.0);
  std::vector<Vec2> filtered = pos;
  for (int round = 0; round < 60; ++round) {
    bool bad = false;
    for (const Tri& t : fine.triangles) {
      if (signed_area(pos[t[0]], pos[t[1]], pos[t[2]]) > kMinArea) continue;
      bad = true;
      for (int32_t v : t) {
        if (share[v] == 0) continue;
        share[v] = round >= 40 ? 0 : share[v] / 2;
        moved[v] = 1;
        pos[v] = {original[v].x + share[v] * (filtered[v].x - original[v].x),
                  original[v].y + share[v] * (filtered[v].y - original[v].y)};
      }
    }
    if (!bad) break;
    if (round == 59) pos = original, std::fill(moved.begin(), moved.end(), 1);
  }
  report.restored_vertices += static_cast<int>(std::count(moved.begin(), moved.end(), 1));
  fine.positions = pos;
}

// A pyramid of `mesh` made from itself: `bands` coarser meshes (fewer when nothing more can go),
// each made from the one before by removing half of its smooth vertices, shortest edge first
// (coarsen_detail::collapse_shortest_first), with its record. Boundary, crease, corner and tear
// vertices all stay, so the outline and the features are the fine mesh's at every eta; a coarser
// mesh's colors are its vertices' own (no refit: the details carry the rest).
std::vector<ControlMesh> own_pyramid(const ControlMesh& mesh, int width, int height, int bands) {
  std::vector<ControlMesh> levels{mesh};
  levels[0].parent_vertices.clear();
  levels[0].collapses.clear();
  std::vector<int32_t> ids;
  for (const Feature& f : mesh.features) ids.push_back(f.id);
  for (int b = 1; b <= bands; ++b) {
    const ControlMesh& fine = levels.back();
    Coarsener c(fine, width, height, ids);
    std::vector<uint8_t> removable(fine.num_vertices(), 0);
    int smooth = 0;
    for (int v = 0; v < fine.num_vertices(); ++v) smooth += removable[v] = c.kind(v) == Kind::kSmooth;
    std::vector<EdgeVerts> made = coarsen_detail::collapse_shortest_first(c, removable, smooth / 2);
    if (made.empty()) break;
    std::vector<int32_t> parents, color_merged;
    ControlMesh coarse = c.result(parents, color_merged);
    coarse.parent_vertices = std::move(parents);
    coarse.collapses = std::move(made);
    levels.push_back(std::move(coarse));
  }
  return levels;
}

// Reconstructs out[b - 1] from out[b] for the bands of `levels` (a pyramid: each level above 0
// with its record), coarsest first; band b takes the etas of band first_band + b - 1.
void filter_levels(const std::vector<ControlMesh>& levels, std::vector<ControlMesh>& out, int width,
                   int height, const FilterOptions& options, int first_band, FilterReport& r) {
  for (int band = static_cast<int>(levels.size()) - 1; band >= 1; --band) {
    const int eta_band = first_band + band - 1;
    const Band b = analyze(levels[band - 1], levels[band], width, height, eta_band);
    reconstruct(b, out[band], eta_at(options.geometry_eta, eta_band), eta_at(options.color_eta, eta_band),
                out[band - 1], width, height, r);
  }
}

// A mesh filtered through its own pyramid (own_pyramid) of `bands` bands from first_band on.
ControlMesh filter_own(const ControlMesh& mesh, int width, int height, int bands, const FilterOptions& options,
                       int first_band, FilterReport& r) {
  const std::vector<ControlMesh> levels = own_pyramid(mesh, width, height, bands);
  std::vector<ControlMesh> out = levels;
  filter_levels(levels, out, width, height, options, first_band, r);
  out[0].parent_vertices = mesh.parent_vertices;
  out[0].collapses = mesh.collapses;
  return std::move(out[0]);
}

}  // namespace

bool has_pyramid(const VectorImage& image) {
  if (image.levels.size() < 2) return false;
  for (size_t l = 1; l < image.levels.size(); ++l)
    if (image.levels[l].parent_vertices.empty()) return false;
  return true;
}

int filter_bands(const VectorImage& image, std::optional<int> object) {
  const int bands = static_cast<int>(image.levels.size()) - 1;
  return object ? std::max(bands, kObjectBands) : bands;
}

VectorImage filter(const VectorImage& image, const FilterOptions& options, FilterReport* report) {
  if (options.object && (*options.object < 0 || *options.object >= static_cast<int>(image.objects.size()))) {
    throw Error(ErrorCode::kInvalidArgument, "object " + std::to_string(*options.object) +
                                                 " is out of range (" + std::to_string(image.objects.size()) +
                                                 " objects)");
  }
  if (!options.object && image.levels.size() < 2) {
    throw Error(ErrorCode::kInvalidArgument,
                "the image has one level: a pyramid needs levels built by vectorize --levels");
  }
  const int bands = filter_bands(image, options.object);
  for (const auto* etas : {&options.geometry_eta, &options.color_eta}) {
    if (static_cast<int>(etas->size()) > bands) {
      throw Error(ErrorCode::kInvalidArgument, std::to_string(etas->size()) + " eta values for " +
                                                   std::to_string(bands) + " pyramid bands");
    }
    for (double e : *etas)
      if (!std::isfinite(e)) throw Error(ErrorCode::kInvalidArgument, "eta values must be finite");
  }
  FilterReport local;
  FilterReport& r = report ? *report : local;
  r = {};
  r.bands = bands;
  VectorImage out = image;
  if (options.object) {
    ControlMesh& mesh = out.objects[*options.object].mesh;
    mesh = filter_own(mesh, MeshTopology::kNoFrame, MeshTopology::kNoFrame, bands, options, 1, r);
    return out;
  }
  // Levels 0 .. top hold one pyramid when every one above the first has its record. Where an
  // edit dropped a record (make_object cuts its level), the level below the gap is filtered
  // through its own pyramid, with the bands from the gap up, and the levels under it as usual.
  int top = bands;
  while (top >= 1) {
    int low = top;
    while (low >= 1 && !image.levels[low].parent_vertices.empty()) --low;
    // Levels low .. top are one pyramid (low = top: a lone level).
    const std::vector<ControlMesh> levels(image.levels.begin() + low, image.levels.begin() + top + 1);
    std::vector<ControlMesh> part(out.levels.begin() + low, out.levels.begin() + top + 1);
    filter_levels(levels, part, image.width, image.height, options, low + 1, r);
    std::copy(part.begin(), part.end(), out.levels.begin() + low);
    if (low == 0) break;
    // Level low has no record: level low - 1 through its own pyramid, bands low .. bands.
    out.levels[low - 1] = filter_own(image.levels[low - 1], image.width, image.height, bands - low + 1, options,
                                     low, r);
    top = low - 1;
  }
  return out;
}

}  // namespace subvec
