// Triangle rasterization with a top-left fill rule, Gouraud shading, tear anti-aliasing and
// overlays. See raster_p.h for the design; this file is organised as
//   fixed point and the triangle setup (edge functions, fill rule),
//   coverage traversal: which samples a triangle owns (shared with the sample_coverage test hook),
//   shading, the marks of pixels to supersample, the two passes of a band, overlays, rasterize().
#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "render/raster_p.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/parallel_p.h"

namespace subvec::detail {
namespace {

// 24.8 fixed point: 8 subpixel bits. Coordinates are clamped to a guard band of +-2^21 output
// pixels, so edge-function products stay below 2^61 in int64.
constexpr int kSubpixelBits = 8;
constexpr int64_t kOne = int64_t{1} << kSubpixelBits;
constexpr int64_t kHalf = kOne / 2;
constexpr double kGuard = double(int64_t{1} << (21 + kSubpixelBits));

// 4x4 subsamples per marked pixel at offsets (k + 0.5) / 4: 32 + 64 k in fixed point.
constexpr int kSubGrid = 4;
constexpr int kSubsamples = kSubGrid * kSubGrid;
constexpr int64_t kSubStep = kOne / kSubGrid;
constexpr int64_t kSubOffset = kSubStep / 2;

// Marks live in 8x8-pixel tiles; bands are a power of two of at least the tile height.
constexpr int kTileBits = 3;
constexpr int kTile = 1 << kTileBits;

// Output pixels to fixed point (snap_range() does the same two coordinates at a time).
[[maybe_unused]] int32_t to_fixed(double v) {
  v *= double(kOne);
  v = v > -kGuard ? v : -kGuard;  // also maps NaN to the guard band
  v = v < kGuard ? v : kGuard;
  // Round half up: floor(v + 0.5), as a truncation of a non-negative value.
  return static_cast<int32_t>(static_cast<int64_t>(v + (kGuard + 0.5)) -
                              static_cast<int64_t>(kGuard));
}

// Floor division of a fixed-point value by one pixel (arithmetic shift floors negatives).
int pixel_floor(int32_t v) { return v >> kSubpixelBits; }
// First pixel index whose centre is >= v, and last whose centre is <= v.
int first_centre(int32_t v) { return (v + int32_t{kHalf} - 1) >> kSubpixelBits; }
int last_centre(int32_t v) { return (v - int32_t{kHalf}) >> kSubpixelBits; }

// Edge k runs from corner k+1 to corner k+2 (opposite corner k). Its function
//   E_k(P) = dx_k (P.y - y_{k+1}) - dy_k (P.x - x_{k+1})
// equals cross(v_{k+2} - v_{k+1}, P - v_{k+1}): positive inside a triangle of positive signed area
// (cross(b - a, c - a) > 0), and E_0 + E_1 + E_2 = twice the area, so E_k / area2 are the
// barycentric weights. Fill rule: a sample with E_k == 0 belongs to the triangle iff
// dy_k > 0, or dy_k == 0 and dx_k > 0. This is the sign of E_k at the sample nudged by (-e, e^2),
// the same nudge for every triangle, so the two triangles sharing an edge (which run it in
// opposite directions) split its samples exactly, and a vertex sample goes to exactly one
// triangle of its fan. The rule is folded in as a bias of 0 or -1 on the integer E_k.
struct TriangleSetup {
  Fixed v0, v1, v2;
  int64_t dx0, dy0, dx1, dy1, dx2, dy2;
  int64_t b0, b1, b2;  // fill-rule biases
  int64_t area2 = 0;
  int32_t min_x = 0, max_x = 0, min_y = 0, max_y = 0;

  static int32_t min3(int32_t a, int32_t b, int32_t c) { return std::min(std::min(a, b), c); }
  static int32_t max3(int32_t a, int32_t b, int32_t c) { return std::max(std::max(a, b), c); }
  // 0 when dy > 0 or (dy == 0 and dx > 0), else -1: the sign of the lexicographic key
  // dy 2^32 + dx (|dx|, |dy| < 2^31), minus one, shifted down.
  static int64_t bias(int64_t dx, int64_t dy) { return (dy * (int64_t{1} << 32) + dx - 1) >> 63; }

  // Corners and bounding box.
  void init(Fixed a, Fixed b, Fixed c) {
    v0 = a, v1 = b, v2 = c;
    min_x = min3(a.x, b.x, c.x), max_x = max3(a.x, b.x, c.x);
    min_y = min3(a.y, b.y, c.y), max_y = max3(a.y, b.y, c.y);
  }
  // Edges and area; returns false for a degenerate or back-facing triangle (drawn by no one).
  bool init_edges() {
    dx0 = int64_t(v2.x) - v1.x, dy0 = int64_t(v2.y) - v1.y;
    dx1 = int64_t(v0.x) - v2.x, dy1 = int64_t(v0.y) - v2.y;
    dx2 = int64_t(v1.x) - v0.x, dy2 = int64_t(v1.y) - v0.y;
    area2 = dx2 * (int64_t(v2.y) - v0.y) - dy2 * (int64_t(v2.x) - v0.x);
    b0 = bias(dx0, dy0), b1 = bias(dx1, dy1), b2 = bias(dx2, dy2);
    return area2 > 0;
  }
  // Biased edge functions at (x, y): the sample is inside iff all three are >= 0.
  int64_t edge0(int64_t x, int64_t y) const { return dx0 * (y - v1.y) - dy0 * (x - v1.x) + b0; }
  int64_t edge1(int64_t x, int64_t y) const { return dx1 * (y - v2.y) - dy1 * (x - v2.x) + b1; }
  int64_t edge2(int64_t x, int64_t y) const { return dx2 * (y - v0.y) - dy2 * (x - v0.x) + b2; }
};

// ---- Coverage traversal ------------------------------------------------------------------------
// Every path below decides coverage exactly by the fill rule above; they differ only in speed.
// Visitors get the unbiased edge functions 1 and 2 as floats (enough for the barycentrics).

#if defined(__SSE2__)
// Triangles less than 8 pixels across are tested with SSE2 float lanes, 4 samples at a time. The
// edge functions at samples within a few pixels of such a triangle are integers below 2^24 in
// magnitude, which floats hold exactly, so the float tests are the integer tests.
constexpr int32_t kSmall = 8 << kSubpixelBits;

bool is_small(const TriangleSetup& t) {
  return (t.max_x - t.min_x < kSmall) & (t.max_y - t.min_y < kSmall);
}

// Tests `rows` rows of 4 samples starting at (x, y) (fixed point), sample pitch `step`; returns a
// mask with bit 4 j + i set for covered sample (i, j) and fills e1, e2 (unbiased) for all lanes.
[[gnu::always_inline]] inline unsigned test_rows(const TriangleSetup& t, int64_t x, int64_t y,
                                                 int64_t step, int rows, float* e1s, float* e2s) {
  const __m128 lane = _mm_setr_ps(0.f, 1.f, 2.f, 3.f), zero = _mm_setzero_ps();
  __m128 e0 = _mm_add_ps(_mm_set1_ps(float(t.edge0(x, y))),
                         _mm_mul_ps(lane, _mm_set1_ps(float(-t.dy0 * step))));
  __m128 e1 = _mm_add_ps(_mm_set1_ps(float(t.edge1(x, y))),
                         _mm_mul_ps(lane, _mm_set1_ps(float(-t.dy1 * step))));
  __m128 e2 = _mm_add_ps(_mm_set1_ps(float(t.edge2(x, y))),
                         _mm_mul_ps(lane, _mm_set1_ps(float(-t.dy2 * step))));
  const __m128 s0 = _mm_set1_ps(float(t.dx0 * step)), s1 = _mm_set1_ps(float(t.dx1 * step));
  const __m128 s2 = _mm_set1_ps(float(t.dx2 * step));
  const __m128 b1 = _mm_set1_ps(float(t.b1)), b2 = _mm_set1_ps(float(t.b2));
  unsigned mask = 0;
  for (int j = 0; j < rows; ++j) {
    const __m128 outside = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(e0, zero), _mm_cmplt_ps(e1, zero)),
                                     _mm_cmplt_ps(e2, zero));
    mask |= (~unsigned(_mm_movemask_ps(outside)) & 0xfu) << (4 * j);
    _mm_store_ps(e1s + 4 * j, _mm_sub_ps(e1, b1));
    _mm_store_ps(e2s + 4 * j, _mm_sub_ps(e2, b2));
    e0 = _mm_add_ps(e0, s0);
    e1 = _mm_add_ps(e1, s1);
    e2 = _mm_add_ps(e2, s2);
  }
  return mask;
}
#endif

#if defined(__SSE2__)
// ---- Small triangles, four at a time ------------------------------------------------------------
// Nearly all refined triangles have at most 4 x 2 candidate pixel centres (1-3 pixel edges), and
// their cost is the per-triangle work, so these run four at a time with one triangle per SSE2
// lane: gather, candidate range, edge functions, the fill-rule test of all 8 candidates, the choice
// of the owned ones and the shading of the first two, without data-dependent branches. Relative
// to its first candidate centre, such a triangle's corners are less than 5 pixels (2^11 fixed-point
// units) away, so its edge functions at the candidates are integers below 2^24 in magnitude:
// exact in int32 lanes and in float lanes alike, so the test is the integer test of the fill rule
// and the shading gets the same floats as Shader::shade() does.

// Coverage of four triangles, one per lane. Candidate c = 4 j + i (i < 4, j < 2) of a lane is its
// pixel centre (px0 + i, py0 + j).
struct QuadCoverage {
  static constexpr int kNone = 8;  // candidate index meaning "none"
  __m128i owned;                   // per lane: bit c set for each owned candidate
  __m128i px0, py0;                // first candidate per lane
  __m128 e1, e2;                   // unbiased E_1, E_2 at the first candidate
  __m128 e1_x, e1_y, e2_x, e2_y;   // their steps per column and per row
  __m128 area2;                    // twice the area
  unsigned large;                  // lanes (bits) with more candidates: for for_each_centre()

  // E_1 and E_2 at candidate c of every lane (any finite value for kNone).
  void edges_at(__m128i c, __m128& f1, __m128& f2) const {
    const __m128 i = _mm_cvtepi32_ps(_mm_and_si128(c, _mm_set1_epi32(3)));
    const __m128 j = _mm_cvtepi32_ps(_mm_srli_epi32(c, 2));
    f1 = _mm_add_ps(_mm_add_ps(e1, _mm_mul_ps(i, e1_x)), _mm_mul_ps(j, e1_y));
    f2 = _mm_add_ps(_mm_add_ps(e2, _mm_mul_ps(i, e2_x)), _mm_mul_ps(j, e2_y));
  }
};

template <class T>
T lane_of(__m128i v, int lane) {
  alignas(16) T a[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(a), v);
  return a[lane];
}
inline float lane_of(__m128 v, int lane) {
  alignas(16) float a[4];
  _mm_store_ps(a, v);
  return a[lane];
}

// min and max of int32 lanes whose difference is below 2^31 (SSE2 has neither).
inline __m128i min_epi32(__m128i a, __m128i b) {
  const __m128i d = _mm_sub_epi32(a, b);
  return _mm_add_epi32(b, _mm_and_si128(d, _mm_srai_epi32(d, 31)));
}
inline __m128i max_epi32(__m128i a, __m128i b) {
  const __m128i d = _mm_sub_epi32(a, b);
  return _mm_sub_epi32(a, _mm_and_si128(d, _mm_srai_epi32(d, 31)));
}

// Index of the lowest set bit of each lane (lanes of at most 24 bits, not zero): the exponent of
// the lowest bit converted to float.
inline __m128i lowest_bit(__m128i v) {
  const __m128i low = _mm_and_si128(v, _mm_sub_epi32(_mm_setzero_si128(), v));
  return _mm_sub_epi32(_mm_srli_epi32(_mm_castps_si128(_mm_cvtepi32_ps(low)), 23),
                       _mm_set1_epi32(127));
}

// Covers the pixel centres in columns [0, last_x] and rows [first_y, last_y] with triangles
// tris[0 .. 4), of which the first n in 1..4 count (lanes n..3 own nothing). Lanes with more than
// 4 x 2 candidates in that window are flagged in q.large and own nothing here. Coordinates are
// within the +-2^29 guard band of to_fixed(), so differences fit in int32.
[[gnu::always_inline]] inline void cover_quad(const Fixed* fixed, const Tri* tris, int n,
                                              int first_x, int last_x, int first_y, int last_y,
                                              QuadCoverage& q) {
  // Corners k of the four triangles as (x, y) vectors over the lanes.
  __m128i xs[3], ys[3];
  for (int k = 0; k < 3; ++k) {
    auto corner = [&](int lane) {
      return _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&fixed[tris[lane][k]]));
    };
    const __m128i lo = _mm_unpacklo_epi32(corner(0), corner(1));  // x0 x1 y0 y1
    const __m128i hi = _mm_unpacklo_epi32(corner(2), corner(3));  // x2 x3 y2 y3
    xs[k] = _mm_unpacklo_epi64(lo, hi);
    ys[k] = _mm_unpackhi_epi64(lo, hi);
  }
  // Candidate range: first_centre() of the minimum, last_centre() of the maximum.
  auto first = [](const __m128i* v) {
    return _mm_srai_epi32(
        _mm_add_epi32(min_epi32(min_epi32(v[0], v[1]), v[2]), _mm_set1_epi32(kHalf - 1)),
        kSubpixelBits);
  };
  auto last = [](const __m128i* v) {
    return _mm_srai_epi32(
        _mm_sub_epi32(max_epi32(max_epi32(v[0], v[1]), v[2]), _mm_set1_epi32(kHalf)),
        kSubpixelBits);
  };
  const __m128i cx0 = first(xs), cx1 = last(xs), cy0 = first(ys), cy1 = last(ys);
  // Small: at most 4 x 2 candidates before clipping to the window. The triangle is then less than
  // 5 x 3 pixels across, and its corners less than 5 pixels from any of its candidates.
  const __m128i small =
      _mm_and_si128(_mm_cmplt_epi32(_mm_sub_epi32(cx1, cx0), _mm_set1_epi32(4)),
                    _mm_cmplt_epi32(_mm_sub_epi32(cy1, cy0), _mm_set1_epi32(2)));
  q.px0 = max_epi32(cx0, _mm_set1_epi32(first_x));
  q.py0 = max_epi32(cy0, _mm_set1_epi32(first_y));
  const __m128i columns = _mm_sub_epi32(min_epi32(cx1, _mm_set1_epi32(last_x)), q.px0);  // - 1
  const __m128i rows = _mm_sub_epi32(min_epi32(cy1, _mm_set1_epi32(last_y)), q.py0);     // - 1
  const __m128i present = _mm_cmplt_epi32(_mm_set1_epi32(3 - n), _mm_setr_epi32(3, 2, 1, 0));
  const __m128i any = _mm_and_si128(
      present, _mm_cmpgt_epi32(_mm_or_si128(columns, rows), _mm_set1_epi32(-1)));
  q.large = unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_andnot_si128(small, any))));
  // The candidates in the clipped range, in the lanes drawn here: 2^(columns + 1) - 1 (from the
  // exponent of a float) in row 0, the same in row 1 if there are two rows.
  const __m128i row_bits = _mm_sub_epi32(
      _mm_cvttps_epi32(_mm_castsi128_ps(
          _mm_slli_epi32(_mm_add_epi32(columns, _mm_set1_epi32(128)), 23))),
      _mm_set1_epi32(1));
  const __m128i valid = _mm_and_si128(
      _mm_and_si128(small, any),
      _mm_or_si128(row_bits, _mm_and_si128(_mm_slli_epi32(row_bits, 4),
                                           _mm_cmpgt_epi32(rows, _mm_setzero_si128()))));

  // Corners relative to the first candidate (small integers in the lanes that are used).
  const __m128i ox = _mm_add_epi32(_mm_slli_epi32(q.px0, kSubpixelBits), _mm_set1_epi32(kHalf));
  const __m128i oy = _mm_add_epi32(_mm_slli_epi32(q.py0, kSubpixelBits), _mm_set1_epi32(kHalf));
  for (int k = 0; k < 3; ++k) {
    xs[k] = _mm_sub_epi32(xs[k], ox);
    ys[k] = _mm_sub_epi32(ys[k], oy);
  }
  // Edge k runs from corner k+1 to corner k+2; its function at the first candidate is
  // dy_k x_{k+1} - dx_k y_{k+1} (products in float: exact), and it steps by -dy_k per column and
  // dx_k per row (in pixels). With the fill rule's bias (TriangleSetup) added, a candidate is inside
  // iff the three biased values are >= 0: iff their OR has no sign bit.
  const __m128i zero = _mm_setzero_si128();
  __m128i h[3], step_x[3], step_y[3];
  __m128 e[3];
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const __m128i dx = _mm_sub_epi32(xs[b], xs[a]), dy = _mm_sub_epi32(ys[b], ys[a]);
    e[k] = _mm_sub_ps(_mm_mul_ps(_mm_cvtepi32_ps(dy), _mm_cvtepi32_ps(xs[a])),
                      _mm_mul_ps(_mm_cvtepi32_ps(dx), _mm_cvtepi32_ps(ys[a])));
    const __m128i owns = _mm_or_si128(
        _mm_cmpgt_epi32(dy, zero), _mm_and_si128(_mm_cmpeq_epi32(dy, zero), _mm_cmpgt_epi32(dx, zero)));
    h[k] = _mm_add_epi32(_mm_cvttps_epi32(e[k]), _mm_andnot_si128(owns, _mm_set1_epi32(-1)));
    step_x[k] = _mm_slli_epi32(_mm_sub_epi32(zero, dy), kSubpixelBits);
    step_y[k] = _mm_slli_epi32(dx, kSubpixelBits);
  }
  q.e1 = e[1], q.e2 = e[2];
  q.e1_x = _mm_cvtepi32_ps(step_x[1]), q.e1_y = _mm_cvtepi32_ps(step_y[1]);
  q.e2_x = _mm_cvtepi32_ps(step_x[2]), q.e2_y = _mm_cvtepi32_ps(step_y[2]);
  q.area2 = _mm_add_ps(_mm_add_ps(e[0], e[1]), e[2]);

  __m128i owned = zero;
  for (int j = 0; j < 2; ++j) {
    __m128i f0 = h[0], f1 = h[1], f2 = h[2];
    for (int i = 0; i < 4; ++i) {
      const __m128i outside = _mm_srai_epi32(_mm_or_si128(_mm_or_si128(f0, f1), f2), 31);
      owned = _mm_or_si128(owned, _mm_andnot_si128(outside, _mm_set1_epi32(1 << (4 * j + i))));
      if (i < 3) {
        f0 = _mm_add_epi32(f0, step_x[0]);
        f1 = _mm_add_epi32(f1, step_x[1]);
        f2 = _mm_add_epi32(f2, step_x[2]);
      }
    }
    if (j == 0) {
      h[0] = _mm_add_epi32(h[0], step_y[0]);
      h[1] = _mm_add_epi32(h[1], step_y[1]);
      h[2] = _mm_add_epi32(h[2], step_y[2]);
    }
  }
  q.owned = _mm_and_si128(owned, valid);
}
#endif

// The pixel centres of rows [py0, py1] x columns [px0, px1] (a non-empty range inside the
// triangle's bounding box) that the triangle owns: visit(px, py, e1, e2). Sets t.area2.
template <class Visit>
void for_each_centre(TriangleSetup& t, int px0, int px1, int py0, int py1, Visit&& visit) {
  if ((px0 == px1) & (py0 == py1)) {
    // A single candidate (most refined triangles): the biases only matter for a sample on an
    // edge, so test without them first. A sample inside all three edges implies a positive area
    // (the E_k sum to it), so back-facing and degenerate triangles fall out here too.
    const int64_t x = int64_t(px0) * kOne + kHalf, y = int64_t(py0) * kOne + kHalf;
    const Fixed a = t.v0, b = t.v1, c = t.v2;
    const int64_t e0 = (int64_t(c.x) - b.x) * (y - b.y) - (int64_t(c.y) - b.y) * (x - b.x);
    const int64_t e1 = (int64_t(a.x) - c.x) * (y - c.y) - (int64_t(a.y) - c.y) * (x - c.x);
    const int64_t e2 = (int64_t(b.x) - a.x) * (y - a.y) - (int64_t(b.y) - a.y) * (x - a.x);
    if ((e0 | e1 | e2) < 0) return;
    if ((e0 == 0) | (e1 == 0) | (e2 == 0)) {
      t.init_edges();
      if (((e0 + t.b0) | (e1 + t.b1) | (e2 + t.b2)) < 0) return;
    }
    t.area2 = e0 + e1 + e2;
    visit(px0, py0, float(e1), float(e2));
    return;
  }
  if (!t.init_edges()) return;
  const int64_t x = int64_t(px0) * kOne + kHalf, y = int64_t(py0) * kOne + kHalf;
#if defined(__SSE2__)
  if ((px1 - px0 < 4) & (py1 - py0 < 4) & is_small(t)) {
    alignas(16) float e1s[16], e2s[16];
    unsigned mask = test_rows(t, x, y, kOne, py1 - py0 + 1, e1s, e2s);
    const unsigned columns = (1u << (px1 - px0 + 1)) - 1;
    mask &= columns * 0x1111u;  // lanes beyond px1
    while (mask) {
      const int k = std::countr_zero(mask);
      mask &= mask - 1;
      visit(px0 + (k & 3), py0 + (k >> 2), e1s[k], e2s[k]);
    }
    return;
  }
#endif
  // General case: int64 edge functions stepped across the box.
  int64_t r0 = t.edge0(x, y), r1 = t.edge1(x, y), r2 = t.edge2(x, y);
  const int64_t sx0 = -t.dy0 * kOne, sx1 = -t.dy1 * kOne, sx2 = -t.dy2 * kOne;
  const int64_t sy0 = t.dx0 * kOne, sy1 = t.dx1 * kOne, sy2 = t.dx2 * kOne;
  for (int py = py0; py <= py1; ++py) {
    int64_t e0 = r0, e1 = r1, e2 = r2;
    for (int px = px0; px <= px1; ++px) {
      if ((e0 | e1 | e2) >= 0) visit(px, py, float(e1 - t.b1), float(e2 - t.b2));
      e0 += sx0;
      e1 += sx1;
      e2 += sx2;
    }
    r0 += sy0;
    r1 += sy1;
    r2 += sy2;
  }
}

// The 4x4 subsamples of pixel (px, py) that the triangle owns: visit(k, e1, e2), k = 4 row +
// column. Needs t.init_edges() done (and true).
template <class Visit>
void for_each_subsample(const TriangleSetup& t, int px, int py, Visit&& visit) {
  const int64_t x = int64_t(px) * kOne + kSubOffset, y = int64_t(py) * kOne + kSubOffset;
#if defined(__SSE2__)
  if (is_small(t)) {
    alignas(16) float e1s[16], e2s[16];
    unsigned mask = test_rows(t, x, y, kSubStep, kSubGrid, e1s, e2s);
    while (mask) {
      const int k = std::countr_zero(mask);
      mask &= mask - 1;
      visit(k, e1s[k], e2s[k]);
    }
    return;
  }
#endif
  int64_t r0 = t.edge0(x, y), r1 = t.edge1(x, y), r2 = t.edge2(x, y);
  for (int j = 0; j < kSubGrid; ++j) {
    int64_t e0 = r0, e1 = r1, e2 = r2;
    for (int i = 0; i < kSubGrid; ++i) {
      if ((e0 | e1 | e2) >= 0) visit(j * kSubGrid + i, float(e1 - t.b1), float(e2 - t.b2));
      e0 -= t.dy0 * kSubStep;
      e1 -= t.dy1 * kSubStep;
      e2 -= t.dy2 * kSubStep;
    }
    r0 += t.dx0 * kSubStep;
    r1 += t.dx1 * kSubStep;
    r2 += t.dx2 * kSubStep;
  }
}

// ---- Shading -----------------------------------------------------------------------------------

uint8_t to_u8(float v) {
  v = v > 0.f ? v : 0.f;  // NaN -> 0
  v = v < 255.f ? v : 255.f;
  return static_cast<uint8_t>(static_cast<int>(v + 0.5f));
}

// Gouraud color of a sample from its edge functions: c0 + (w1 (c1 - c0) + w2 (c2 - c0)) with the
// barycentric weights w_k = E_k / area2, rounded and clamped to 0..255 (NaN -> 0). Returns the
// color packed as r | g << 8 | b << 16.
struct Shader {
#if defined(__SSE2__)
  __m128 base = _mm_setzero_ps(), d1 = base, d2 = base;  // c0 + 0.5 (rounding), c1 - c0, c2 - c0
  float inv_area = 0;

  static __m128 load_rgb(const float* c) {  // (r, g, b, 0)
    return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(c)),
                         _mm_load_ss(c + 2));
  }
  void init(const float* c0, const float* c1, const float* c2, float area2) {
    const __m128 a = load_rgb(c0);
    base = _mm_add_ps(a, _mm_set1_ps(0.5f));
    d1 = _mm_sub_ps(load_rgb(c1), a);
    d2 = _mm_sub_ps(load_rgb(c2), a);
    inv_area = 1.f / area2;
  }
  uint32_t shade(float e1, float e2) const {
    const __m128 w1 = _mm_set1_ps(e1 * inv_area), w2 = _mm_set1_ps(e2 * inv_area);
    __m128 v = _mm_add_ps(base, _mm_add_ps(_mm_mul_ps(w1, d1), _mm_mul_ps(w2, d2)));
    // max returns its second operand (0) for NaN; 255.25 truncates to 255.
    v = _mm_min_ps(_mm_max_ps(v, _mm_setzero_ps()), _mm_set1_ps(255.25f));
    __m128i i = _mm_cvttps_epi32(v);
    i = _mm_packs_epi32(i, i);
    i = _mm_packus_epi16(i, i);
    return static_cast<uint32_t>(_mm_cvtsi128_si32(i)) & 0xffffffu;
  }
#else
  float base[3] = {}, d1[3] = {}, d2[3] = {};
  float inv_area = 0;

  void init(const float* c0, const float* c1, const float* c2, float area2) {
    for (int c = 0; c < 3; ++c) {
      base[c] = c0[c] + 0.5f;
      d1[c] = c1[c] - c0[c];
      d2[c] = c2[c] - c0[c];
    }
    inv_area = 1.f / area2;
  }
  uint32_t shade(float e1, float e2) const {
    const float w1 = e1 * inv_area, w2 = e2 * inv_area;
    uint32_t rgb = 0;
    for (int c = 0; c < 3; ++c) {
      float v = base[c] + (w1 * d1[c] + w2 * d2[c]);
      v = v > 0.f ? v : 0.f;
      v = v < 255.25f ? v : 255.25f;
      rgb |= static_cast<uint32_t>(v) << (8 * c);
    }
    return rgb;
  }
#endif
};

// Sets up `shader` for triangle ti (at its first covered sample: many tiny triangles cover none).
void init_shader(Shader& shader, const RefinedMesh& mesh, int32_t ti, float area2) {
  const Tri& tc = mesh.triangle_colors[ti];
  const float* colors = mesh.colors.data();
  shader.init(colors + size_t(tc[0]) * 3, colors + size_t(tc[1]) * 3, colors + size_t(tc[2]) * 3,
              area2);
}

#if defined(__SSE2__)
// The Gouraud colors of candidates c[r] (any color for kNone) of the four lanes of `q`, packed as
// Shader::shade() packs them and computed with the same operations in the same order, so they
// are the same bytes; the four triangles share the vector instructions. `corners`: the color
// indices of the four triangles.
template <int kRounds>
[[gnu::always_inline]] inline void shade_quad(const float* colors, const Tri* corners,
                                              const QuadCoverage& q, const __m128i (&c)[kRounds],
                                              __m128i (&rgb)[kRounds]) {
  __m128 base[3], d1[3], d2[3];  // per channel, over the lanes
  {
    __m128 v[3][4];  // corner k: (r, g, b, 0) per lane, then transposed to r, g, b, 0
    for (int k = 0; k < 3; ++k) {
      for (int lane = 0; lane < 4; ++lane)
        v[k][lane] = Shader::load_rgb(colors + size_t(corners[lane][k]) * 3);
      _MM_TRANSPOSE4_PS(v[k][0], v[k][1], v[k][2], v[k][3]);
    }
    for (int ch = 0; ch < 3; ++ch) {
      base[ch] = _mm_add_ps(v[0][ch], _mm_set1_ps(0.5f));
      d1[ch] = _mm_sub_ps(v[1][ch], v[0][ch]);
      d2[ch] = _mm_sub_ps(v[2][ch], v[0][ch]);
    }
  }
  const __m128 inv_area = _mm_div_ps(_mm_set1_ps(1.f), q.area2);
  for (int r = 0; r < kRounds; ++r) {
    __m128 e1, e2;
    q.edges_at(c[r], e1, e2);
    const __m128 w1 = _mm_mul_ps(e1, inv_area), w2 = _mm_mul_ps(e2, inv_area);
    __m128i packed = _mm_setzero_si128();
    for (int ch = 0; ch < 3; ++ch) {
      __m128 v = _mm_add_ps(base[ch], _mm_add_ps(_mm_mul_ps(w1, d1[ch]), _mm_mul_ps(w2, d2[ch])));
      v = _mm_min_ps(_mm_max_ps(v, _mm_setzero_ps()), _mm_set1_ps(255.25f));
      packed = _mm_or_si128(packed, _mm_slli_epi32(_mm_cvttps_epi32(v), 8 * ch));
    }
    rgb[r] = packed;
  }
}
#endif

// ---- Pixels marked for supersampling ----------------------------------------------------------

// Marked pixels in 8x8 tiles: a tile holds a 64-bit mask of its marked pixels and, per pixel, the
// slot of its 16 subsamples (RGBA8 words, alpha 255 once written).
class MarkTiles {
 public:
  // Marks for rows [row0, row1) of a view `width` pixels wide; row0 is a multiple of the tile
  // height. Coordinates below are the view's.
  MarkTiles(int width, int row0, int row1)
      : width_(width),
        row0_(row0),
        height_(row1),
        tiles_x_((width + kTile - 1) / kTile),
        tile_(size_t(tiles_x_) * ((row1 - row0 + kTile - 1) / kTile), -1) {}

  bool empty() const { return masks_.empty(); }

  void mark(int x, int y) {
    int32_t& t = tile_[size_t((y - row0_) >> kTileBits) * tiles_x_ + (x >> kTileBits)];
    if (t < 0) {
      t = static_cast<int32_t>(masks_.size());
      masks_.push_back(0);
    }
    masks_[t] |= uint64_t{1} << bit(x, y);
  }

  // Marks every pixel that the segment a-b touches (conservatively, a little more).
  void mark_segment(Fixed a, Fixed b) {
    if (a.y > b.y) std::swap(a, b);
    const int r0 = std::max(pixel_floor(a.y), row0_),
              r1 = std::min(pixel_floor(b.y), height_ - 1);
    if (std::max(a.x, b.x) < 0 || pixel_floor(std::min(a.x, b.x)) >= width_) return;
    const double dy = double(b.y) - a.y;
    for (int r = r0; r <= r1; ++r) {
      // The part of the segment inside row r, widened by one subpixel unit for rounding.
      const double ya = std::max<double>(a.y, double(r) * kOne);
      const double yb = std::min<double>(b.y, double(r + 1) * kOne);
      double xa = a.x, xb = b.x;
      if (dy > 0) {
        xa = a.x + (double(b.x) - a.x) * (ya - a.y) / dy;
        xb = a.x + (double(b.x) - a.x) * (yb - a.y) / dy;
      }
      const int c0 = std::max(static_cast<int>(std::floor((std::min(xa, xb) - 1) / kOne)), 0);
      const int c1 =
          std::min(static_cast<int>(std::floor((std::max(xa, xb) + 1) / kOne)), width_ - 1);
      for (int c = c0; c <= c1; ++c) mark(c, r);
    }
  }

  // Numbers the marked pixels and allocates their subsamples once marking is complete.
  void finish_marking() {
    slots_.assign(masks_.size() * kTile * kTile, -1);
    int32_t total = 0;
    for (size_t t = 0; t < masks_.size(); ++t) {
      for (int b = 0; b < kTile * kTile; ++b) {
        if ((masks_[t] >> b) & 1) slots_[t * kTile * kTile + b] = total++;
      }
    }
    samples_.assign(size_t(total) * kSubsamples, 0);
  }

  // Whether any pixel in [x0, x1] x [y0, y1] (clipped to the output) may be marked: a tile test.
  bool any_tile(int x0, int x1, int y0, int y1) const {
    x0 = std::max(x0, 0) >> kTileBits;
    x1 = std::min(x1, width_ - 1) >> kTileBits;
    y0 = (std::max(y0, row0_) - row0_) >> kTileBits;
    y1 = (std::min(y1, height_ - 1) - row0_) >> kTileBits;
    if (x0 > x1 || y0 > y1) return false;
    if (x1 - x0 <= 1 && y1 - y0 <= 1) {  // small boxes: the (at most) four tiles at the corners
      const int32_t* r0 = tile_.data() + size_t(y0) * tiles_x_;
      const int32_t* r1 = tile_.data() + size_t(y1) * tiles_x_;
      return (r0[x0] & r0[x1] & r1[x0] & r1[x1]) >= 0;  // unmarked tiles hold -1
    }
    for (int ty = y0; ty <= y1; ++ty) {
      for (int tx = x0; tx <= x1; ++tx) {
        if (tile_[size_t(ty) * tiles_x_ + tx] >= 0) return true;
      }
    }
    return false;
  }

  // Calls visit(x, y, samples) for each marked pixel in [x0, x1] x [y0, y1] (clipped), walking
  // the set bits of the tile masks.
  template <class Visit>
  void for_each_marked(int x0, int x1, int y0, int y1, Visit&& visit) {
    x0 = std::max(x0, 0), x1 = std::min(x1, width_ - 1), y0 = std::max(y0, row0_) - row0_,
    y1 = std::min(y1, height_ - 1) - row0_;
    if (x0 > x1 || y0 > y1) return;
    for (int ty = y0 >> kTileBits; ty <= y1 >> kTileBits; ++ty) {
      // Rows of this tile inside [y0, y1], as a byte selector.
      const int ly0 = std::max(y0 - (ty << kTileBits), 0),
                ly1 = std::min(y1 - (ty << kTileBits), kTile - 1);
      const uint64_t rows = (~uint64_t{0} >> (8 * (kTile - 1 - ly1))) & (~uint64_t{0} << (8 * ly0));
      for (int tx = x0 >> kTileBits; tx <= x1 >> kTileBits; ++tx) {
        const int32_t t = tile_[size_t(ty) * tiles_x_ + tx];
        if (t < 0) continue;
        const int lx0 = std::max(x0 - (tx << kTileBits), 0),
                  lx1 = std::min(x1 - (tx << kTileBits), kTile - 1);
        const uint64_t columns =
            ((uint64_t{2} << lx1) - (uint64_t{1} << lx0)) * 0x0101010101010101ull;
        uint64_t mask = masks_[t] & rows & columns;
        while (mask) {
          const int b = std::countr_zero(mask);
          mask &= mask - 1;
          visit((tx << kTileBits) + (b & (kTile - 1)), row0_ + (ty << kTileBits) + (b >> kTileBits),
                samples_.data() + size_t(slots_[size_t(t) * kTile * kTile + b]) * kSubsamples);
        }
      }
    }
  }

  // Replaces each marked pixel of columns [x0, x1) and rows [y0, y1) by the mean of its written
  // subsamples; alpha is the covered fraction. Row 0 of `out` is row row0.
  void resolve(Image8& out, int x0, int x1, int y0, int y1) {
    for_each_marked(x0, x1 - 1, y0, y1 - 1, [&](int x, int y, const uint32_t* s) {
      uint32_t sum[3] = {0, 0, 0}, count = 0;
      for (int i = 0; i < kSubsamples; ++i) {
        if ((s[i] >> 24) == 0) continue;
        sum[0] += s[i] & 0xff;
        sum[1] += (s[i] >> 8) & 0xff;
        sum[2] += (s[i] >> 16) & 0xff;
        ++count;
      }
      uint8_t* p = out.row(y - row0_) + size_t(x) * out.channels;
      if (count == 0) {
        if (out.channels == 4) std::memset(p, 0, 4);
        return;
      }
      for (int c = 0; c < 3; ++c) p[c] = static_cast<uint8_t>((sum[c] + count / 2) / count);
      if (out.channels == 4)
        p[3] = static_cast<uint8_t>((count * 255 + kSubsamples / 2) / kSubsamples);
    });
  }

 private:
  static int bit(int x, int y) { return ((y & (kTile - 1)) << kTileBits) | (x & (kTile - 1)); }

  int width_, row0_, height_, tiles_x_;  // height_: the end row
  std::vector<int32_t> tile_;      // per tile: index into masks_, or -1
  std::vector<uint64_t> masks_;    // per marked tile
  std::vector<int32_t> slots_;     // per marked tile, 64 pixels: slot in samples_, or -1
  std::vector<uint32_t> samples_;  // 16 RGBA8 words per marked pixel
};

// ---- The passes of a band ----------------------------------------------------------------------

struct Frame {
  const RefinedMesh* mesh;
  const Fixed* fixed;  // #N output positions
  int width, height;
  MarkTiles* marks;  // nullptr without marked pixels
  PixelRect clip;    // the pixels drawn; row 0 of the output is row clip.y0
};

// Pass 1: the pixel-centre samples of the band's blocks, rows [band_y0, band_y1). The triangles
// whose bounding box meets a marked tile are collected for pass 2 into `near` (when not null).
template <int kChannels>
void draw_centres(const Frame& f, std::span<const int32_t> units, const Unit* unit_data,
                  Image8& out, int band_y0, int band_y1, std::vector<int32_t>* near) {
  const RefinedMesh& mesh = *f.mesh;
  const Tri* tris = mesh.triangles.data();
  const int first_x = f.clip.x0, last_x = f.clip.x1 - 1, last_y = band_y1 - 1;
  const size_t stride = size_t(out.width) * kChannels;
  // Row py of the view is row py - clip.y0 of `out` (unsigned arithmetic: the origin may lie
  // before the buffer; every pixel written lies in it).
  const uintptr_t pixels = uintptr_t(out.pixels.data()) - uintptr_t(f.clip.y0) * stride;
  auto at = [&](int px, int py) {
    return reinterpret_cast<uint8_t*>(pixels + uintptr_t(py) * stride + uintptr_t(px) * kChannels);
  };
  TriangleSetup t;
  Shader shader;
  auto draw = [&](uint8_t* p, uint32_t rgb) {
    p[0] = static_cast<uint8_t>(rgb);
    p[1] = static_cast<uint8_t>(rgb >> 8);
    p[2] = static_cast<uint8_t>(rgb >> 16);
    if constexpr (kChannels == 4) p[3] = 255;
  };
  // Any triangle, through for_each_centre().
  auto draw_triangle = [&](int32_t ti) {
    const Tri& tri = tris[ti];
    t.init(f.fixed[tri[0]], f.fixed[tri[1]], f.fixed[tri[2]]);
    const int px0 = std::max(first_centre(t.min_x), first_x),
              px1 = std::min(last_centre(t.max_x), last_x);
    const int py0 = std::max(first_centre(t.min_y), band_y0),
              py1 = std::min(last_centre(t.max_y), last_y);
    if ((px0 > px1) | (py0 > py1)) return;
    bool shaded = false;
    for_each_centre(t, px0, px1, py0, py1, [&](int px, int py, float e1, float e2) {
      if (!shaded) init_shader(shader, mesh, ti, float(t.area2)), shaded = true;
      draw(at(px, py), shader.shade(e1, e2));
    });
  };
#if defined(__SSE2__)
  QuadCoverage q;
  uint8_t dummy[4];
  // Candidate c relative to the first; the last entry (kNone) leads to `dummy`.
  uintptr_t offsets[QuadCoverage::kNone + 1];
  for (int c = 0; c < QuadCoverage::kNone; ++c)
    offsets[c] = uintptr_t(c >> 2) * stride + uintptr_t(c & 3) * kChannels;
#endif
  for (const int32_t u : units) {
    const Unit& unit = unit_data[u];
    if (near && f.marks->any_tile(unit.x0, unit.x1, std::max(unit.y0, band_y0),
                                  std::min(unit.y1, last_y))) {
      for (int32_t ti = unit.begin; ti < unit.end; ++ti) {
        const Tri& tri = tris[ti];
        t.init(f.fixed[tri[0]], f.fixed[tri[1]], f.fixed[tri[2]]);
        if (f.marks->any_tile(pixel_floor(t.min_x), pixel_floor(t.max_x),
                              std::max(pixel_floor(t.min_y), band_y0),
                              std::min(pixel_floor(t.max_y), last_y))) {
          near->push_back(ti);
        }
      }
    }
#if defined(__SSE2__)
    for (int32_t ti = unit.begin; ti < unit.end; ti += 4) {
      const int n = std::min(4, unit.end - ti);
      const Tri* quad = tris + ti;
      const Tri* quad_colors = mesh.triangle_colors.data() + ti;
      Tri tail[4], tail_colors[4];
      if (n < 4) {  // pad with the first triangle
        for (int lane = 0; lane < 4; ++lane) {
          tail[lane] = quad[lane < n ? lane : 0];
          tail_colors[lane] = quad_colors[lane < n ? lane : 0];
        }
        quad = tail;
        quad_colors = tail_colors;
      }
      cover_quad(f.fixed, quad, n, first_x, last_x, band_y0, last_y, q);
      // A triangle owns 0, 1 or 2 of its candidates, unpredictably: the first (two) are shaded and
      // drawn without branches (a missing one, kNone, to a dummy pixel), only the rare others
      // one by one.
      const __m128i none = _mm_set1_epi32(1 << QuadCoverage::kNone);
      const __m128i second = _mm_and_si128(q.owned, _mm_sub_epi32(q.owned, _mm_set1_epi32(1)));
      const __m128i rest = _mm_and_si128(second, _mm_sub_epi32(second, _mm_set1_epi32(1)));
      const __m128i zero = _mm_setzero_si128();
      const unsigned more =
          ~unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(rest, zero)))) & 0xfu;
      alignas(16) int32_t px0[4], py0[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(px0), q.px0);
      _mm_store_si128(reinterpret_cast<__m128i*>(py0), q.py0);
      // Rounds: 1 when no lane owns a second candidate (most quads at 1-pixel edges), else 2.
      auto draw_quad = [&]<int kRounds>() {
        __m128i which[kRounds], rgb_v[kRounds];
        which[0] = lowest_bit(_mm_or_si128(q.owned, none));
        if constexpr (kRounds == 2) which[1] = lowest_bit(_mm_or_si128(second, none));
        shade_quad<kRounds>(mesh.colors.data(), quad_colors, q, which, rgb_v);
        alignas(16) int32_t c[kRounds][4];
        alignas(16) uint32_t rgb[kRounds][4];
        for (int r = 0; r < kRounds; ++r) {
          _mm_store_si128(reinterpret_cast<__m128i*>(c[r]), which[r]);
          _mm_store_si128(reinterpret_cast<__m128i*>(rgb[r]), rgb_v[r]);
        }
        auto draw_lane = [&](int lane) {
          // (Unsigned arithmetic: a lane without candidates may have its origin off the output.)
          const uintptr_t origin = uintptr_t(at(px0[lane], py0[lane]));
          offsets[QuadCoverage::kNone] = uintptr_t(dummy) - origin;
          for (int r = 0; r < kRounds; ++r)
            draw(reinterpret_cast<uint8_t*>(origin + offsets[c[r][lane]]), rgb[r][lane]);
        };
        if ((n == 4) & (q.large == 0)) {
          draw_lane(0), draw_lane(1), draw_lane(2), draw_lane(3);
        } else {
          for (int lane = 0; lane < n; ++lane) {
            if ((q.large >> lane) & 1) {
              draw_triangle(ti + lane);
            } else {
              draw_lane(lane);
            }
          }
        }
      };
      if (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(second, zero))) == 0xf) {
        draw_quad.template operator()<1>();
      } else {
        draw_quad.template operator()<2>();
      }
      for (unsigned lanes = more; lanes; lanes &= lanes - 1) {  // owning 3 or more
        const int lane = std::countr_zero(lanes);
        init_shader(shader, mesh, ti + lane, lane_of(q.area2, lane));
        const float e1 = lane_of(q.e1, lane), e1_x = lane_of(q.e1_x, lane),
                    e1_y = lane_of(q.e1_y, lane), e2 = lane_of(q.e2, lane),
                    e2_x = lane_of(q.e2_x, lane), e2_y = lane_of(q.e2_y, lane);
        for (uint32_t owned = lane_of<uint32_t>(rest, lane); owned; owned &= owned - 1) {
          const int c = std::countr_zero(owned);
          const float i = float(c & 3), j = float(c >> 2);
          draw(at(px0[lane] + (c & 3), py0[lane] + (c >> 2)),
               shader.shade(e1 + i * e1_x + j * e1_y, e2 + i * e2_x + j * e2_y));
        }
      }
    }
#else
    for (int32_t ti = unit.begin; ti < unit.end; ++ti) draw_triangle(ti);
#endif
  }
}

// Pass 2: the subsamples of the marked pixels in rows [band_y0, band_y1) that the given
// triangles own.
void draw_subsamples(const Frame& f, std::span<const int32_t> triangles, int band_y0, int band_y1) {
  const RefinedMesh& mesh = *f.mesh;
  MarkTiles& marks = *f.marks;
  const int last_x = f.clip.x1 - 1, last_y = band_y1 - 1;
  TriangleSetup t;
  Shader shader;
  for (const int32_t ti : triangles) {
    const Tri& tri = mesh.triangles[ti];
    t.init(f.fixed[tri[0]], f.fixed[tri[1]], f.fixed[tri[2]]);
    const int ax0 = std::max(pixel_floor(t.min_x), f.clip.x0), ax1 = std::min(pixel_floor(t.max_x), last_x);
    const int ay0 = std::max(pixel_floor(t.min_y), band_y0),
              ay1 = std::min(pixel_floor(t.max_y), last_y);
    if (!t.init_edges()) continue;
    bool shaded = false;
    marks.for_each_marked(ax0, ax1, ay0, ay1, [&](int px, int py, uint32_t* samples) {
      for_each_subsample(t, px, py, [&](int k, float e1, float e2) {
        if (!shaded) init_shader(shader, mesh, ti, float(t.area2)), shaded = true;
        samples[k] = shader.shade(e1, e2) | 0xff000000u;
      });
    });
  }
}

// ---- Overlays ----------------------------------------------------------------------------------

// Anti-aliased overlay primitives: coverage of a pixel centre at distance d from a primitive of
// half width w is clamp(w + 0.5 - d, 0, 1), a box-filtered edge. Columns [x0, x1) and rows
// [y0, y1) of the view only; row 0 of `out` is view row `row0`.
void draw_overlay_band(Image8& out, int x0, int x1, int y0, int y1, int row0,
                       std::span<const OverlayLayer> layers, std::vector<float>& coverage) {
  const int w = x1 - x0;
  coverage.assign(size_t(y1 - y0) * w, 0.f);
  auto pixel = [](float v, int lo, int hi) {  // floor, clamped (also for huge or NaN values)
    const float f = std::floor(v);
    return f > float(lo) ? (f < float(hi) ? static_cast<int>(f) : hi) : lo;
  };
  for (const OverlayLayer& layer : layers) {
    int bx0 = x1, bx1 = x0 - 1, by0 = y1, by1 = y0 - 1;  // touched region
    auto splat = [&](float minx, float maxx, float miny, float maxy, auto&& cov) {
      const int px0 = pixel(minx, x0, x1), px1 = pixel(maxx, x0 - 1, x1 - 1);
      const int py0 = pixel(miny, y0, y1), py1 = pixel(maxy, y0 - 1, y1 - 1);
      if (px0 > px1 || py0 > py1) return;
      bx0 = std::min(bx0, px0), bx1 = std::max(bx1, px1), by0 = std::min(by0, py0),
      by1 = std::max(by1, py1);
      for (int py = py0; py <= py1; ++py) {
        float* row = coverage.data() + size_t(py - y0) * w;
        for (int px = px0; px <= px1; ++px)
          row[px - x0] = std::max(row[px - x0], cov(float(px) + 0.5f, float(py) + 0.5f));
      }
    };
    const float reach = layer.half_width + 1.f;
    for (const auto& s : layer.segments) {
      const float ax = s[0], ay = s[1], dx = s[2] - s[0], dy = s[3] - s[1];
      const float len2 = dx * dx + dy * dy;
      splat(std::min(s[0], s[2]) - reach, std::max(s[0], s[2]) + reach,
            std::min(s[1], s[3]) - reach, std::max(s[1], s[3]) + reach, [&](float x, float y) {
              float u = len2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / len2 : 0.f;
              u = std::clamp(u, 0.f, 1.f);
              const float ex = x - (ax + u * dx), ey = y - (ay + u * dy);
              return std::clamp(layer.half_width + 0.5f - std::sqrt(ex * ex + ey * ey), 0.f, 1.f);
            });
    }
    for (const auto& d : layer.dots) {
      const float r = d[2] + 1.f;
      splat(d[0] - r, d[0] + r, d[1] - r, d[1] + r, [&](float x, float y) {
        const float ex = x - d[0], ey = y - d[1];
        return std::clamp(d[2] + 0.5f - std::sqrt(ex * ex + ey * ey), 0.f, 1.f);
      });
    }
    // Source-over compositing with straight alpha.
    for (int py = by0; py <= by1; ++py) {
      float* row = coverage.data() + size_t(py - y0) * w;
      uint8_t* dst = out.row(py - row0);
      for (int px = bx0; px <= bx1; ++px) {
        const float a = row[px - x0] * layer.opacity;
        row[px - x0] = 0.f;
        if (a <= 0.f) continue;
        uint8_t* p = dst + size_t(px) * out.channels;
        const float da = out.channels == 4 ? p[3] / 255.f : 1.f;
        const float oa = a + da * (1.f - a);
        for (int c = 0; c < 3; ++c) p[c] = to_u8((layer.color[c] * a + p[c] * da * (1.f - a)) / oa);
        if (out.channels == 4) p[3] = to_u8(oa * 255.f);
      }
    }
  }
}

// ---- Frame setup -------------------------------------------------------------------------------

// Snaps vertices [begin, end) to fixed point: to_fixed(view.to_output(...)), two at a time.
void snap_range(const RefinedMesh& mesh, const ViewTransform& view, int begin, int end,
                Fixed* fixed) {
  const float* positions = mesh.positions.data();
#if defined(__SSE2__)
  // The same double operations as to_output() and to_fixed(), with x and y in the two lanes:
  // max() and min() are the clamps (NaN, the first operand, goes to the lower bound) and the
  // biased value truncates to int32 (it lies in [0.5, 2^30 + 0.5]).
  const __m128d origin = _mm_setr_pd(view.x0, view.y0), scale = _mm_setr_pd(view.sx, view.sy);
  const __m128d one = _mm_set1_pd(double(kOne)), lo = _mm_set1_pd(-kGuard),
                hi = _mm_set1_pd(kGuard), bias = _mm_set1_pd(kGuard + 0.5);
  const __m128i guard = _mm_set1_epi32(static_cast<int32_t>(kGuard));
  for (int i = begin; i < end; ++i) {
    const __m128 p =
        _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(positions + 2 * size_t(i)));
    __m128d v = _mm_mul_pd(_mm_mul_pd(_mm_sub_pd(_mm_cvtps_pd(p), origin), scale), one);
    v = _mm_add_pd(_mm_min_pd(_mm_max_pd(v, lo), hi), bias);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(fixed + i),
                     _mm_sub_epi32(_mm_cvttpd_epi32(v), guard));
  }
#else
  for (int i = begin; i < end; ++i) {
    const auto o = view.to_output(positions[2 * size_t(i)], positions[2 * size_t(i) + 1]);
    fixed[i] = {to_fixed(o[0]), to_fixed(o[1])};
  }
#endif
}

void snap_vertices(const RefinedMesh& mesh, const ViewTransform& view, int threads,
                   std::vector<Fixed>& fixed) {
  const int n = mesh.num_vertices();
  fixed.resize(n);
  constexpr int kChunk = 1 << 16;
  parallel_for((n + kChunk - 1) / kChunk, threads, [&](int chunk) {
    snap_range(mesh, view, chunk * kChunk, std::min(n, (chunk + 1) * kChunk), fixed.data());
  });
}

// Band height: a power of two, at least the tile height, several bands per thread for load balance.
int band_shift(int height, int threads) {
  const int target = height / std::max(1, 4 * threads);
  int shift = kTileBits;
  while (shift < 6 && (2 << shift) <= target) ++shift;
  return shift;
}

// Bounds unit u for the frame: the pixel columns and rows of its bounding box.
void bound_unit(const RefinedMesh& mesh, const Frame& f, const ViewTransform& view,
                std::span<const TriangleBlock> blocks, int u, Unit& unit) {
  constexpr int kBlock = 64;
  int x0, x1, y0, y1;
  if (!blocks.empty()) {
    const TriangleBlock& b = blocks[u];
    unit.begin = b.begin;
    unit.end = b.end;
    // Snapping moves a vertex by at most half a subpixel unit: widen the box by one unit.
    constexpr double kMargin = 1.0 / kOne;
    const auto lo = view.to_output(b.x0, b.y0), hi = view.to_output(b.x1, b.y1);
    auto floor_px = [](double v) {  // floor, clamped (NaN -> -1e9)
      v = v > -1e9 ? v : -1e9;
      return static_cast<int>(std::floor(v < 1e9 ? v : 1e9));
    };
    x0 = floor_px(lo[0] - kMargin), x1 = floor_px(hi[0] + kMargin);
    y0 = floor_px(lo[1] - kMargin), y1 = floor_px(hi[1] + kMargin);
  } else {
    unit.begin = u * kBlock;
    unit.end = std::min(mesh.num_triangles(), unit.begin + kBlock);
    int32_t bx0 = INT32_MAX, bx1 = INT32_MIN, by0 = INT32_MAX, by1 = INT32_MIN;
    for (int32_t i = unit.begin; i < unit.end; ++i) {
      const Tri& tri = mesh.triangles[i];
      const Fixed a = f.fixed[tri[0]], b = f.fixed[tri[1]], c = f.fixed[tri[2]];
      bx0 = std::min(bx0, TriangleSetup::min3(a.x, b.x, c.x));
      bx1 = std::max(bx1, TriangleSetup::max3(a.x, b.x, c.x));
      by0 = std::min(by0, TriangleSetup::min3(a.y, b.y, c.y));
      by1 = std::max(by1, TriangleSetup::max3(a.y, b.y, c.y));
    }
    x0 = pixel_floor(bx0), x1 = pixel_floor(bx1), y0 = pixel_floor(by0), y1 = pixel_floor(by1);
  }
  unit.x0 = x0, unit.x1 = x1;
  unit.y0 = std::max(y0, f.clip.y0);
  unit.y1 = std::min(y1, f.clip.y1 - 1);
  if (x1 < f.clip.x0 || x0 >= f.clip.x1 || unit.begin >= unit.end) unit.y1 = unit.y0 - 1;  // culled
}

}  // namespace

Image8 rasterize(const RefinedMesh& mesh, const ViewTransform& view, const RasterOptions& options,
                 std::span<const OverlayLayer> overlay, RasterScratch* scratch) {
  Image8 out;
  rasterize_into(mesh, view, options, overlay, scratch, out);
  return out;
}

void rasterize_into(const RefinedMesh& mesh, const ViewTransform& view, const RasterOptions& options,
                    std::span<const OverlayLayer> overlay, RasterScratch* scratch, Image8& out) {
  const int width = view.width, height = view.height, threads = std::max(options.threads, 1);
  const PixelRect clip = options.clip.value_or(PixelRect{0, 0, width, height});
  if (clip.x0 < 0 || clip.y0 < 0 || clip.x1 > width || clip.y1 > height || clip.x0 >= clip.x1 ||
      clip.y0 >= clip.y1 || clip.y0 % kTile != 0 ||
      (options.clip && (out.width != width || out.height != clip.y1 - clip.y0 ||
                        out.channels != options.channels))) {
    throw std::logic_error("rasterize_into: bad clip");
  }
  // A reused frame is cleared band by band just before the band is drawn, so that the drawing
  // finds its rows in cache (clearing a 4K frame up front costs a cache miss per line later).
  // A clipped frame is the caller's, cleared by it.
  const bool reused = !options.clip && out.width == width && out.height == height &&
                      out.channels == options.channels;
  if (!reused && !options.clip) out = Image8(width, height, options.channels);
  RasterScratch local;
  RasterScratch& work = scratch ? *scratch : local;
  Frame f{&mesh, nullptr, width, height, nullptr, clip};

  // Snap the vertices and bound the blocks of triangles. Blocks come from the caller with
  // image-space boxes (then both run as one parallel loop), or are cut here, 64 triangles each,
  // and bounded from the snapped vertices afterwards.
  const int num_vertices = mesh.num_vertices();
  work.fixed.resize(num_vertices);
  f.fixed = work.fixed.data();
  const bool given = !options.blocks.empty();
  const int num_units =
      given ? static_cast<int>(options.blocks.size()) : (mesh.num_triangles() + 63) / 64;
  work.units.resize(num_units);
  constexpr int kVerticesPerJob = 1 << 16, kUnitsPerJob = 1024;
  const int vertex_jobs = (num_vertices + kVerticesPerJob - 1) / kVerticesPerJob;
  const int unit_jobs = (num_units + kUnitsPerJob - 1) / kUnitsPerJob;
  auto bound_units = [&](int job) {
    const int end = std::min(num_units, (job + 1) * kUnitsPerJob);
    for (int u = job * kUnitsPerJob; u < end; ++u)
      bound_unit(mesh, f, view, options.blocks, u, work.units[u]);
  };
  parallel_for(vertex_jobs + (given ? unit_jobs : 0), threads, [&](int job) {
    if (job >= vertex_jobs) return bound_units(job - vertex_jobs);
    snap_range(mesh, view, job * kVerticesPerJob,
               std::min(num_vertices, (job + 1) * kVerticesPerJob), work.fixed.data());
  });
  if (!given) parallel_for(unit_jobs, threads, bound_units);

  // Mark the pixels crossed by discontinuities (serial: cheap, and keeps the tile order fixed).
  MarkTiles marks(width, clip.y0, clip.y1);
  if (options.antialias) {
    for (const EdgeVerts& e : mesh.tear_edges) marks.mark_segment(f.fixed[e[0]], f.fixed[e[1]]);
    if (options.antialias_border) {
      for (const EdgeVerts& e : mesh.border_edges) marks.mark_segment(f.fixed[e[0]], f.fixed[e[1]]);
    }
    marks.finish_marking();
    if (!marks.empty()) f.marks = &marks;
  }

  // Bin the blocks by band: a block goes to every band that its bounding box's pixel rows meet
  // (the band pass culls each triangle further). Serial and in block order, so each band's list
  // is in triangle order whatever the thread count.
  const int shift = band_shift(clip.y1 - clip.y0, threads), band_h = 1 << shift;
  const int num_bands = (clip.y1 - clip.y0 + band_h - 1) / band_h;
  work.band_begin.assign(num_bands + 2, 0);
  int64_t* begin = work.band_begin.data() + 1;  // count into begin[band + 1], then prefix
  for (const Unit& unit : work.units) {
    for (int band = (unit.y0 - clip.y0) >> shift;
         unit.y0 <= unit.y1 && band <= (unit.y1 - clip.y0) >> shift; ++band)
      ++begin[band + 1];
  }
  for (int band = 0; band < num_bands; ++band) begin[band + 1] += begin[band];
  work.binned.resize(begin[num_bands]);
  for (int u = 0; u < num_units; ++u) {
    const Unit& unit = work.units[u];
    for (int band = (unit.y0 - clip.y0) >> shift;
         unit.y0 <= unit.y1 && band <= (unit.y1 - clip.y0) >> shift; ++band) {
      work.binned[begin[band]++] = u;
    }
  }
  // begin[band] now ends band `band`, i.e. band_begin[band + 1]: the lists start at band_begin.

  // Each band: centres, then subsamples and their resolve, then overlays; one writer per pixel.
  // Bands are handed out heaviest first (by triangles binned) to balance the threads; the order
  // does not change the output.
  std::vector<std::pair<int64_t, int>> order(num_bands);
  for (int band = 0; band < num_bands; ++band) {
    int64_t load = 0;
    for (int64_t i = work.band_begin[band]; i < work.band_begin[band + 1]; ++i) {
      const Unit& unit = work.units[work.binned[i]];
      load += unit.end - unit.begin;
    }
    order[band] = {-load, band};
  }
  std::sort(order.begin(), order.end());
  parallel_for(num_bands, threads, [&](int job) {
    const int band = order[job].second;
    const int y0 = clip.y0 + band * band_h, y1 = std::min(clip.y1, y0 + band_h);
    if (reused) std::fill(out.row(y0), out.row(y0) + size_t(y1 - y0) * width * out.channels, 0);
    const std::span<const int32_t> list(work.binned.data() + work.band_begin[band],
                                        work.binned.data() + work.band_begin[band + 1]);
    thread_local std::vector<int32_t> near_list;
    near_list.clear();
    std::vector<int32_t>* near =
        f.marks && marks.any_tile(clip.x0, clip.x1 - 1, y0, y1 - 1) ? &near_list : nullptr;
    if (options.channels == 4) {
      draw_centres<4>(f, list, work.units.data(), out, y0, y1, near);
    } else {
      draw_centres<3>(f, list, work.units.data(), out, y0, y1, near);
    }
    if (near) {
      draw_subsamples(f, near_list, y0, y1);
      marks.resolve(out, clip.x0, clip.x1, y0, y1);
    }
    if (!overlay.empty()) {
      thread_local std::vector<float> coverage;
      draw_overlay_band(out, clip.x0, clip.x1, y0, y1, clip.y0, overlay, coverage);
    }
  });
}

void draw_overlay(Image8& out, std::span<const OverlayLayer> overlay, int threads) {
  if (overlay.empty()) return;
  constexpr int kBand = 64;
  parallel_for((out.height + kBand - 1) / kBand, std::max(threads, 1), [&](int band) {
    thread_local std::vector<float> coverage;
    draw_overlay_band(out, 0, out.width, band * kBand, std::min(out.height, (band + 1) * kBand), 0,
                      overlay, coverage);
  });
}

void draw_overlay_clipped(Image8& out, const PixelRect& clip, std::span<const OverlayLayer> overlay) {
  if (overlay.empty()) return;
  std::vector<float> coverage;
  draw_overlay_band(out, clip.x0, clip.x1, clip.y0, clip.y1, clip.y0, overlay, coverage);
}

std::vector<int32_t> sample_coverage(const RefinedMesh& mesh, const ViewTransform& view,
                                     bool subsamples) {
  const int width = view.width, height = view.height;
  std::vector<Fixed> fixed;
  snap_vertices(mesh, view, 1, fixed);
  std::vector<int32_t> counts(size_t(width) * height * (subsamples ? kSubsamples : 1), 0);
  TriangleSetup t;
  auto count_centres = [&](const Tri& tri) {
    t.init(fixed[tri[0]], fixed[tri[1]], fixed[tri[2]]);
    const int px0 = std::max(first_centre(t.min_x), 0),
              px1 = std::min(last_centre(t.max_x), width - 1);
    const int py0 = std::max(first_centre(t.min_y), 0),
              py1 = std::min(last_centre(t.max_y), height - 1);
    if (px0 > px1 || py0 > py1) return;
    for_each_centre(t, px0, px1, py0, py1,
                    [&](int px, int py, float, float) { ++counts[size_t(py) * width + px]; });
  };
  if (!subsamples) {  // the traversal of draw_centres()
    const Tri* tris = mesh.triangles.data();
    for (int ti = 0; ti < mesh.num_triangles(); ti += 4) {
      const int n = std::min(4, mesh.num_triangles() - ti);
#if defined(__SSE2__)
      Tri quad[4];
      for (int lane = 0; lane < 4; ++lane) quad[lane] = tris[ti + (lane < n ? lane : 0)];
      QuadCoverage q;
      cover_quad(fixed.data(), quad, n, 0, width - 1, 0, height - 1, q);
      for (int lane = 0; lane < n; ++lane) {
        if ((q.large >> lane) & 1) count_centres(tris[ti + lane]);
        const int px0 = lane_of<int32_t>(q.px0, lane), py0 = lane_of<int32_t>(q.py0, lane);
        for (uint32_t owned = lane_of<uint32_t>(q.owned, lane); owned; owned &= owned - 1) {
          const int c = std::countr_zero(owned);
          ++counts[size_t(py0 + (c >> 2)) * width + size_t(px0 + (c & 3))];
        }
      }
#else
      for (int lane = 0; lane < n; ++lane) count_centres(tris[ti + lane]);
#endif
    }
    return counts;
  }
  for (const Tri& tri : mesh.triangles) {
    t.init(fixed[tri[0]], fixed[tri[1]], fixed[tri[2]]);
    if (!t.init_edges()) continue;
    const int ax0 = std::max(pixel_floor(t.min_x), 0),
              ax1 = std::min(pixel_floor(t.max_x), width - 1);
    const int ay0 = std::max(pixel_floor(t.min_y), 0),
              ay1 = std::min(pixel_floor(t.max_y), height - 1);
    for (int py = ay0; py <= ay1; ++py) {
      for (int px = ax0; px <= ax1; ++px) {
        for_each_subsample(t, px, py, [&](int k, float, float) {
          ++counts[(size_t(py) * width + px) * kSubsamples + k];
        });
      }
    }
  }
  return counts;
}

}  // namespace subvec::detail
