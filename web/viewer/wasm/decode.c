// The compact levels of a .svec file (payload versions 2 and 3, docs/format.md) decoded in
// WebAssembly, and every level's validity rules checked: a port of the C++ reader
// (src/io/svec_compact.cpp, svec_range_p.h; src/mesh/validate.cpp and the checks of
// MeshTopology::build) with the same checks in the same order, as src/decode.ts and
// src/validate.ts had them in JavaScript. The reference is the C++ reader:
// web/tests/viewer-decode.mjs compares what the viewer decodes, and what it refuses, with
// `subvec`'s.
//
// Problems are reported through FAIL(code, ...) (message.c writes the messages), which throws the
// SvecError; it never returns. Numbers that the
// format lets exceed 32 bits are doubles, as in JavaScript: exact integers below 2^53, which
// every range check lies below.
#include "message.h"

IMPORT(mean) double js_mean(const double *terms, int32_t n);
IMPORT(exact) double js_exact(double a, double b, double c, double d);
IMPORT(atan2) double js_atan2(double, double);
static void *need(void *p) {
  if (!p) FAIL(E_OUT_OF_MEMORY);
  return p;
}
#define MAKE(type, count) ((type *)need(alloc_array(sizeof(type), (double)(count))))

enum { CONNECTIVITY, SPLITS, POSITIONS, FEATURES, STEPS, COLORS, HEADER_CONTEXT };
enum { OP_C, OP_L, OP_R, OP_E, OP_S };
enum { VIRTUAL = 0, SPLIT = 1, X = 2, STEP_FIRST = 4, STEP_NEXT = 5, ID = 6, LENGTH = 7, COLOR = 8 };
enum { CTX_OP_C = 1, CTX_OP_R = 9, CTX_OP_L = 17, SALIENCY = 25 + 170 * 23, CONTEXTS = SALIENCY + 8202 };
enum { TAG_CREASE = 1, TAG_TEAR = 2, TAG_BORDER = 3 };
static const double MAX_ELEMENTS = 67108864.0; // 2^26, Limits::kMaxElements

static double pow2(int k) {
  double v = 1;
  for (; k > 0; --k) v *= 2;
  for (; k < 0; ++k) v *= 0.5;
  return v;
}
static double fmin2(double a, double b) { return b < a ? b : a; }
static double fmax2(double a, double b) { return b > a ? b : a; }
static int32_t imin(int32_t a, int32_t b) { return a < b ? a : b; }
static int32_t next3(int32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
static int32_t prev3(int32_t h) { return h % 3 ? h - 1 : h + 2; }

// ---- sources: version 3's range decoder, version 2's varint sections ------------------------

typedef struct {
  const uint8_t *b;
  int32_t n, pos;
} Bytes;

typedef struct {
  int version;
  double ops; // the most connectivity operations the bytes can hold
  // version 3
  Bytes stream;
  uint32_t range, code;
  int32_t overread, context, vertexBits;
  uint16_t *p;
  uint8_t *seen;
  // version 2: the six sections, and what the features section is reading (-1: its name)
  Bytes section[6];
  int32_t featureWhat, numOps, packed;
} Source;

static uint32_t next_byte(Source *s) {
  if (s->stream.pos < s->stream.n) return s->stream.b[s->stream.pos++];
  if (++s->overread > 4) FAIL(E_ENDS_EARLY, s->context, s->stream.n);
  return 0;
}
static void renormalize(Source *s) {
  while (s->range < (1u << 24)) s->range <<= 8, s->code = (s->code << 8) | next_byte(s);
}
// A decision in context i; p adapts by 1/2^shift, shift = min(k + 2, 5) after k updates.
static int bit(Source *s, int32_t i) {
  uint32_t k = s->seen[i], bound = (s->range >> 12) * s->p[i];
  int b = 0;
  if (k < 3) s->seen[i] = (uint8_t)(k + 1);
  if (s->code >= bound) {
    s->code -= bound, s->range -= bound, s->p[i] = (uint16_t)(s->p[i] - (s->p[i] >> (k + 2))), b = 1;
  } else {
    s->range = bound, s->p[i] = (uint16_t)(s->p[i] + ((4096 - s->p[i]) >> (k + 2)));
  }
  renormalize(s);
  return b;
}
static double direct(Source *s, int k) {
  double v = 0;
  while (k--) {
    s->range >>= 1;
    int b = s->code >= s->range;
    if (b) s->code -= s->range;
    v = v * 2 + b;
    renormalize(s);
  }
  return v;
}

static void range_start(Source *s, const uint8_t *b, int32_t n, int32_t nv) {
  s->version = 3, s->stream = (Bytes){b, n, 0}, s->range = 0xffffffffu, s->code = 0, s->context = HEADER_CONTEXT;
  s->p = MAKE(uint16_t, CONTEXTS), s->seen = MAKE(uint8_t, CONTEXTS);
  for (int i = 0; i < CONTEXTS; ++i) s->p[i] = 2048;
  s->vertexBits = 32 - __builtin_clz((uint32_t)(nv - 1));
  s->ops = 1024.0 * (n + 8);
  for (int i = 0; i < 4; ++i) s->code = (s->code << 8) | next_byte(s);
  if (s->code >= s->range) FAIL(E_FIRST_BYTES);
}

// Version 2: a byte of section k, or the truncation message of its cursor.
static int32_t take(Source *s, int k, int32_t n) {
  Bytes *c = &s->section[k];
  int32_t p = c->pos, left = c->n - c->pos;
  if (n > left) FAIL(E_TRUNCATED, k, k == FEATURES ? s->featureWhat : -1, n, p, left);
  c->pos += n;
  return p;
}
static double varint(Source *s, int k) {
  double v = 0, scale = 1;
  for (int shift = 0;; shift += 7, scale *= 128) {
    uint32_t b = s->section[k].b[take(s, k, 1)];
    if (shift == 63 && b > 1) FAIL(E_MALFORMED_VARINT, k, k == FEATURES ? s->featureWhat : -1);
    v += (b & 0x7f) * scale;
    if (b < 128) return v;
  }
}
static double unzigzag(double v) {
  int odd = v < 9007199254740992.0 && ((uint64_t)v & 1);
  return odd ? -(v + 1) / 2 : v / 2;
}

static void begin(Source *s, int k) {
  if (s->version == 3) s->context = k;
}
static void end(Source *s, int k) {
  if (s->version == 2 && s->section[k].pos < s->section[k].n) FAIL(E_TRAILING_SECTION, s->section[k].n - s->section[k].pos, k);
}

// A number of model m (version 3: zero, sign, prefix[56], suffix[56][2]; Exp-Golomb over
// decisions), or the next varint of section k (version 2; `what` >= 0: feature `what` reads it).
static double read(Source *s, int k, int model, int is_signed, int32_t what) {
  if (s->version == 2) {
    if (what >= 0) s->featureWhat = what;
    double v = varint(s, k);
    return is_signed ? unzigzag(v) : v;
  }
  int32_t m = 25 + 170 * model;
  if (is_signed && !bit(s, m)) return 0;
  int negative = is_signed && bit(s, m + 1);
  int32_t n = 0;
  double v = 1;
  while (bit(s, m + 2 + n))
    if (++n == 56) FAIL(E_WIDE_NUMBER, s->context);
  for (int32_t j = 0; j < n; ++j) v = v * 2 + (j < 2 ? bit(s, m + 58 + 2 * n + j) : direct(s, 1));
  return !is_signed ? v - 1 : negative ? -v : v;
}

static int op(Source *s, int triangle, int fanU, int fanW) {
  if (s->version == 2) {
    if (s->numOps % 3 == 0 && (s->packed = s->section[CONNECTIVITY].b[take(s, CONNECTIVITY, 1)]) >= 125)
      FAIL(E_OPERATION_BYTE, s->numOps / 3);
    s->numOps++;
    int o = s->packed % 5;
    s->packed /= 5;
    return o;
  }
  if (triangle) return bit(s, 0) ? OP_E : OP_C;
  if (!bit(s, CTX_OP_C + fanW)) return OP_C;
  if (!bit(s, CTX_OP_R + fanW)) return OP_R;
  return bit(s, CTX_OP_L + fanU) ? OP_S : OP_L;
}

static double vertex(Source *s) { return s->version == 2 ? varint(s, FEATURES) : direct(s, s->vertexBits); }

static double saliency(Source *s, int32_t what) {
  union {
    uint32_t u;
    float f;
  } single;
  union {
    uint64_t u;
    double d;
  } wide;
  if (s->version == 2) {
    Bytes *c = &s->section[FEATURES];
    uint32_t tag = c->b[take(s, FEATURES, 1)];
    if (tag == 1) {
      int32_t at = take(s, FEATURES, 4);
      single.u = (uint32_t)c->b[at] | (uint32_t)c->b[at + 1] << 8 | (uint32_t)c->b[at + 2] << 16 | (uint32_t)c->b[at + 3] << 24;
      return single.f;
    }
    if (tag == 2) {
      int32_t at = take(s, FEATURES, 8);
      wide.u = 0;
      for (int i = 7; i >= 0; --i) wide.u = wide.u << 8 | c->b[at + i];
      return wide.d;
    }
    if (tag) FAIL(E_SALIENCY_TAG, what, tag);
    return 0;
  }
  if (!bit(s, SALIENCY)) return 0;
  int w = bit(s, SALIENCY + 1), top = w ? 12 : 9;
  uint32_t node = 1;
  for (int i = 0; i < top; ++i) node = 2 * node + (uint32_t)bit(s, SALIENCY + 2 + 4096 * w + (int32_t)node);
  uint32_t high = node - (1u << top);
  for (int k = 0; k < 4; ++k) high = 2 * high + (uint32_t)bit(s, SALIENCY + 8194 + 4 * w + k);
  if (!w) {
    single.u = high * (1u << 19) + (uint32_t)direct(s, 19);
    return single.f;
  }
  uint32_t hi = high * (1u << 16) + (uint32_t)direct(s, 16), lo = (uint32_t)direct(s, 32);
  wide.u = (uint64_t)hi << 32 | lo;
  return wide.d;
}

static double length(Source *s, int32_t what) {
  if (s->version == 3) return read(s, 0, LENGTH, 0, -1);
  double n = varint(s, FEATURES);
  if (n > s->section[STEPS].n - s->section[STEPS].pos) FAIL(E_FEW_STEP_BYTES, what, n + 2);
  return n;
}

static void finish(Source *s) {
  if (s->version == 2) return;
  int32_t left = s->stream.n - s->stream.pos;
  if (left > 0) FAIL(E_TRAILING_STREAM, left);
  if (s->code >= s->range) FAIL(E_LEAVES_INTERVAL);
}

// ---- connectivity -----------------------------------------------------------------------------

// traverse of the old decode.ts: the traversal of the mesh closed by the virtual vertex, 2V - 3
// operations after the seed (0, 1, 2). Fills the level's triangles (numbered without the virtual
// vertex), the gate u, w and apex each decode number was met across, and the virtual vertex.
static int32_t *traverse(Source *s, int32_t nv, int32_t ntriangles, int32_t **basisOut, int32_t *virtOut) {
  begin(s, CONNECTIVITY);
  begin(s, SPLITS);
  double vd = read(s, SPLITS, VIRTUAL, 0, -1);
  if (vd < 3 || vd > nv) FAIL(E_VIRTUAL, vd);
  int32_t virt = (int32_t)vd;
  // The arrays hold what the operations the bytes can code can make.
  int32_t nops = 2 * nv - 3, room = (int32_t)fmin2(nops, s->ops) + 3, nvisits = imin(nv + 1, room);
  int32_t *visits = MAKE(int32_t, nvisits), *basis = MAKE(int32_t, 3 * nvisits), *faces = MAKE(int32_t, 3 * room);
  int32_t *vtx = MAKE(int32_t, room), *next = MAKE(int32_t, room), *prev = MAKE(int32_t, room), *apex = MAKE(int32_t, room);
  int32_t *stack = MAKE(int32_t, 2 * room);
  for (int32_t i = 0; i < 3 * nvisits; ++i) basis[i] = -1;
  static const int32_t seed[5][3] = {{1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}, {0, 1, 2}};
  for (int k = 0; k < 3; ++k)
    vtx[k] = seed[0][k], next[k] = seed[1][k], prev[k] = seed[2][k], apex[k] = seed[3][k], faces[k] = seed[4][k], visits[k] = 1;
  int32_t gate = 0, size = 3, done = 0, nd = 3, entries = 3, top = 0;
  for (int32_t i = 0; i < nops; ++i) {
    if (done) FAIL(E_ENDS_BEFORE);
    if (i + 3 >= room) FAIL(E_OUTRUN);
    int32_t g = gate, n = next[g], u = vtx[g], w = vtx[n], x;
    int o = op(s, size == 3, u == virt ? 7 : imin(visits[u], 6), w == virt ? 7 : imin(visits[w], 6));
    if (o == OP_C) {
      // x new, between u and w
      if (nd > nv) FAIL(E_MORE_VERTICES, nv);
      x = nd++;
      basis[3 * x] = u, basis[3 * x + 1] = w, basis[3 * x + 2] = apex[g];
      apex[g] = w;
      vtx[entries] = x, next[entries] = n, prev[entries] = g, apex[entries] = u;
      gate = next[g] = prev[n] = entries++;
      size++;
    } else if (o == OP_E) {
      // the loop is u, w, x: done; continue with the one on top of the stack
      if (size != 3) FAIL(E_CLOSES_LOOP, i, size);
      x = vtx[next[n]];
      if (!(done = !top)) size = stack[--top], gate = stack[--top];
    } else if (o == OP_R || o == OP_L) {
      // x after w (w leaves the loop), or before u (u leaves)
      if (size <= 3) FAIL(E_LOOP_OF_3, i);
      int32_t p = prev[g], k = o == OP_R ? n : g;
      x = vtx[o == OP_R ? next[n] : p];
      apex[o == OP_R ? g : p] = o == OP_R ? w : u;
      next[prev[k]] = next[k];
      prev[next[k]] = prev[k];
      size--;
      if (o == OP_L) gate = p;
    } else {
      // x pos entries on: the loop splits into x, w, ... (current) and u, x, ... (put aside)
      double code = read(s, SPLITS, SPLIT, 0, -1), half = __builtin_floor(code / 2);
      double pos = unzigzag(code) != code / 2 ? size - 2 - half : half + 3;
      if (pos < 3 || pos > size - 2) FAIL(E_SPLIT_OFFSET);
      int32_t at = g, position = (int32_t)pos;
      if (position <= size / 2.0)
        for (int32_t k = 0; k < position; ++k) at = next[at];
      else
        for (int32_t k = position; k < size; ++k) at = prev[at];
      x = vtx[at];
      vtx[entries] = x, next[entries] = n, prev[entries] = prev[at], apex[entries] = u;
      gate = next[prev[at]] = prev[n] = entries++;
      next[g] = at;
      prev[at] = g;
      apex[g] = w;
      stack[top++] = g, stack[top++] = size - position + 1;
      size = position;
    }
    if (x == u || x == w) FAIL(E_DEGENERATE, i);
    visits[u]++, visits[w]++, visits[x]++;
    faces[3 * i + 3] = u, faces[3 * i + 4] = w, faces[3 * i + 5] = x;
  }
  if (!done) FAIL(E_UNVISITED);
  if (nd != nv + 1) FAIL(E_VERTEX_COUNT, nd - 1, nv);
  end(s, CONNECTIVITY);
  end(s, SPLITS);
  int32_t nh = 0;
  for (int32_t h = 0; h < 3 * nops + 3; h += 3)
    if (faces[h] != virt && faces[h + 1] != virt && faces[h + 2] != virt)
      for (int k = 0; k < 3; ++k) faces[nh++] = faces[h + k] - (faces[h + k] > virt);
  if (nh / 3 != ntriangles) FAIL(E_TRIANGLE_COUNT, nh / 3, ntriangles);
  *basisOut = basis, *virtOut = virt;
  return faces;
}

// sortBy of validate.ts: the items (default 0 .. m - 1) stably sorted by key[i] in [0, n); and
// where each key's run starts (run k is start[k] to start[k + 1]).
static int32_t *sort_by(const int32_t *key, int32_t m, int32_t n, const int32_t *items, int32_t **startOut) {
  int32_t *start = MAKE(int32_t, n + 2), *order = MAKE(int32_t, m);
  for (int32_t i = 0; i < m; ++i) start[key[i] + 2]++;
  for (int32_t k = 2; k < n + 2; ++k) start[k] += start[k - 1];
  for (int32_t j = 0; j < m; ++j) {
    int32_t i = items ? items[j] : j;
    order[start[key[i] + 1]++] = i;
  }
  if (startOut) *startOut = start;
  return order;
}

// The edges of triangles t (edges() of validate.ts): sorted by (a, b) with a < b, their triangles
// (g = -1 on the border), tags, and the twin of each half-edge. A problem is kept, not reported:
// the C++ reader finds it after the features.
typedef struct {
  int32_t numEdges;
  int32_t *a, *b, *f, *g;
  uint8_t *tag;
  int32_t *twin;
  int32_t problem;
  double args[4];
} Edges;

static void edges(const int32_t *t, int32_t nh, int32_t nv, Edges *E) {
  int32_t *lo = MAKE(int32_t, nh), *hi = MAKE(int32_t, nh);
  E->problem = -1;
  for (int32_t h = 0; h < nh; ++h) {
    int32_t x = t[h], y = t[next3(h)];
    if (x < 0 || x >= nv) {
      E->problem = E_TRIANGLE_VERTEX, E->args[0] = h / 3, E->args[1] = x, E->args[2] = nv;
      return;
    }
    if (x == y) {
      E->problem = E_REPEATS_VERTEX, E->args[0] = h / 3, E->args[1] = x;
      return;
    }
    lo[h] = x < y ? x : y;
    hi[h] = x < y ? y : x;
  }
  int32_t *order = sort_by(lo, nh, nv, sort_by(hi, nh, nv, 0, 0), 0);
  int32_t *a = E->a = MAKE(int32_t, nh), *b = E->b = MAKE(int32_t, nh), *f = E->f = MAKE(int32_t, nh), *g = E->g = MAKE(int32_t, nh);
  int32_t *twin = E->twin = MAKE(int32_t, nh);
  for (int32_t h = 0; h < nh; ++h) twin[h] = -1;
  int32_t ne = 0;
  for (int32_t i = 0; i < nh; ne++) {
    int32_t h = order[i], x = lo[h], y = hi[h];
    int pair = i + 1 < nh && lo[order[i + 1]] == x && hi[order[i + 1]] == y;
    int32_t k = pair ? order[i + 1] : -1;
    if (pair && i + 2 < nh && lo[order[i + 2]] == x && hi[order[i + 2]] == y) {
      E->problem = E_SHARED_EDGE, E->args[0] = x, E->args[1] = y;
      return;
    }
    a[ne] = x, b[ne] = y, f[ne] = h / 3, g[ne] = pair ? k / 3 : -1;
    if (pair && t[h] == t[k]) {
      E->problem = E_ORIENTATION, E->args[0] = f[ne], E->args[1] = g[ne], E->args[2] = x, E->args[3] = y;
      return;
    }
    if (pair) twin[h] = k, twin[k] = h;
    i += pair ? 2 : 1;
  }
  E->numEdges = ne;
  E->tag = MAKE(uint8_t, ne);
  for (int32_t e = 0; e < ne; ++e)
    if (g[e] < 0) E->tag[e] = TAG_BORDER;
}

// ---- positions --------------------------------------------------------------------------------

static double rounded_mean(double sum, double bound, const double *terms, int32_t n) {
  return bound < 1125899906842624.0 /* 2^50 */ ? __builtin_floor((2 * sum + n) / (2.0 * n)) : js_mean(terms, n);
}

// predict of the old decode.ts: positions on the 2^-p grid, by vertex in decode order, each
// predicted from those before it (the mean of the parallelograms a + b - c over triangles (x, a,
// b) and (b, a, c), else from the gate it was met across), clamped to [0, max].
static void predict(Source *s, const int32_t *t, const int32_t *corners, const int32_t *start, int32_t nv, const int32_t *twin,
                    const int32_t *basis, int32_t virt, double maxX, double maxY, double *px, double *py) {
  double *tx = MAKE(double, nv), *ty = MAKE(double, nv), previousX = 0, previousY = 0;
  begin(s, POSITIONS);
  for (int32_t v = 0; v < nv; ++v) {
    int32_t n = 0;
    double sx = 0, sy = 0, bx = 0, by = 0, qx, qy;
    for (int32_t i = start[v]; i < start[v + 1]; ++i) {
      int32_t h = corners[i], ab = next3(h), a = t[ab], b = t[prev3(h)], o = twin[ab];
      int32_t c = o < 0 ? v + 1 : t[prev3(o)];
      if (a > v || b > v || c > v) continue;
      double x = px[a] + px[b] - px[c], y = py[a] + py[b] - py[c];
      sx += tx[n] = x, sy += ty[n] = y, bx += __builtin_fabs(x), by += __builtin_fabs(y), n++;
    }
    int32_t d = v + (v >= virt), u = basis[3 * d], w = basis[3 * d + 1], a = basis[3 * d + 2];
    int32_t U = u - (u > virt), W = w - (w > virt), A = a - (a > virt);
    if (n) {
      qx = rounded_mean(sx, bx, tx, n);
      qy = rounded_mean(sy, by, ty, n);
    } else if (u < 0) {
      qx = previousX, qy = previousY;
    } else if (u == virt) {
      qx = px[W], qy = py[W];
    } else if (w == virt) {
      qx = px[U], qy = py[U];
    } else if (a == virt) {
      // Across a border edge: the apex of an equilateral triangle on its inner side.
      qx = __builtin_floor((px[U] + px[W]) / 2) - __builtin_floor(((py[W] - py[U]) * 7) / 8);
      qy = __builtin_floor((py[U] + py[W]) / 2) + __builtin_floor(((px[W] - px[U]) * 7) / 8);
    } else {
      qx = px[U] + px[W] - px[A], qy = py[U] + py[W] - py[A];
    }
    double rx = read(s, POSITIONS, X, 1, -1), ry = read(s, POSITIONS, X + 1, 1, -1);
    if (__builtin_fabs(rx) > 1099511627776.0 || __builtin_fabs(ry) > 1099511627776.0) FAIL(E_POSITION_RESIDUAL);
    previousX = px[v] = fmin2(fmax2(qx, 0), maxX) + rx;
    previousY = py[v] = fmin2(fmax2(qy, 0), maxY) + ry;
  }
  end(s, POSITIONS);
}

// ---- creases and features ---------------------------------------------------------------------

// a·b + c·d for integers, rounded once to a double (as C++ converts an exact int64).
static double exact(double a, double b, double c, double d) {
  return __builtin_fabs(a * b) + __builtin_fabs(c * d) < 9007199254740992.0 ? a * b + c * d : js_exact(a, b, c, d);
}

typedef struct {
  Source *s;
  const int32_t *t, *corners, *start;
  const double *px, *py;
  int32_t nv, stamps;
  int32_t *stamp, *ranked, *scratch;
  double *score;
} Steps;

// Straightest first (the lowest score), then by number.
static int before(const Steps *c, int32_t q, int32_t r, int byScore) {
  if (byScore && c->score[q] != c->score[r]) return c->score[q] < c->score[r];
  return q < r;
}
// A stable merge sort of ranked[0 .. n) (the order is total: every tie is broken by number).
static void sort_ranked(Steps *c, int32_t n, int byScore) {
  int32_t *x = c->ranked, *y = c->scratch;
  for (int32_t width = 1; width < n; width *= 2) {
    for (int32_t lo = 0; lo < n; lo += 2 * width) {
      int32_t mid = imin(lo + width, n), hi = imin(lo + 2 * width, n), i = lo, j = mid, k = lo;
      while (i < mid && j < hi) y[k++] = before(c, x[j], x[i], byScore) ? x[j++] : x[i++];
      while (i < mid) y[k++] = x[i++];
      while (j < hi) y[k++] = x[j++];
    }
    int32_t *swap = x;
    x = y, y = swap;
  }
  if (x != c->ranked) __builtin_memcpy(c->ranked, x, sizeof(int32_t) * (size_t)n);
}

static int32_t checked(Steps *c, double v, int isFeature, int32_t i) {
  if (v >= c->nv) FAIL(E_VERTEX_RANGE, isFeature, i, v);
  return (int32_t)v;
}

// The next vertex of a chain: the step's rank among the neighbours of `at` (by number for a
// chain's first step, after that straightest first: exact integer dot products, one rounding).
static int32_t step(Steps *c, int32_t from, int32_t at, int first, int isFeature, int32_t i) {
  int32_t n = 0;
  c->stamps++;
  for (int32_t j = c->start[at]; j < c->start[at + 1]; ++j)
    for (int k = 0; k < 2; ++k) {
      int32_t q = c->t[k ? prev3(c->corners[j]) : next3(c->corners[j])];
      if (c->stamp[q] != c->stamps) c->stamp[q] = c->stamps, c->ranked[n++] = q;
    }
  if (from >= 0) {
    double dx = c->px[at] - c->px[from], dy = c->py[at] - c->py[from];
    for (int32_t j = 0; j < n; ++j) {
      int32_t q = c->ranked[j];
      double ex = c->px[q] - c->px[at], ey = c->py[q] - c->py[at], len = __builtin_sqrt(exact(ex, ex, ey, ey));
      c->score[q] = len > 0 ? -exact(dx, ex, dy, ey) / len : 0;
    }
  }
  sort_ranked(c, n, from >= 0);
  double r = read(c->s, STEPS, first ? STEP_FIRST : STEP_NEXT, 0, -1);
  if (r >= n) FAIL(E_STEP_RANGE, isFeature, i, r);
  return c->ranked[(int32_t)r];
}

// ---- topology and wedges ----------------------------------------------------------------------

// Marks edge (x, y) as kind (topology() of validate.ts); `what`: crease i, or feature i (id).
static void mark(const Edges *E, int32_t nv, int32_t x, int32_t y, uint8_t kind, int32_t i, int32_t id) {
  double isFeature = kind == TAG_TEAR;
  if (x < 0 || x >= nv || y < 0 || y >= nv) FAIL(E_MARK_RANGE, isFeature, i, id, x < 0 || x >= nv ? x : y, nv);
  int32_t u = x < y ? x : y, v = x < y ? y : x, l = 0, r = E->numEdges;
  while (l < r) {
    int32_t mid = (l + r) >> 1;
    if (E->a[mid] < u || (E->a[mid] == u && E->b[mid] < v))
      l = mid + 1;
    else
      r = mid;
  }
  if (l == E->numEdges || E->a[l] != u || E->b[l] != v) FAIL(E_NOT_AN_EDGE, isFeature, i, id, x, y);
  if (E->tag[l] == TAG_BORDER) FAIL(E_ON_BORDER, isFeature, i, id, x, y);
  if (E->tag[l]) FAIL(E->tag[l] == TAG_TEAR ? E_ALREADY_TEAR : E_ALREADY_CREASE, isFeature, i, id, x, y);
  E->tag[l] = kind;
}

// MeshTopology::build's marking: the creases, then the features (chains of two or more).
static void mark_chains(const Edges *E, int32_t nv, const int32_t *creases, int32_t ncreases, const int32_t *ids,
                        const int32_t *offsets, const int32_t *verts, int32_t nfeatures) {
  for (int32_t i = 0; i < ncreases; ++i) mark(E, nv, creases[2 * i], creases[2 * i + 1], TAG_CREASE, i, 0);
  for (int32_t i = 0; i < nfeatures; ++i) {
    int32_t n = offsets[i + 1] - offsets[i];
    if (n < 2) FAIL(E_SHORT_FEATURE, i, ids[i]);
    for (int32_t k = 1; k < n; ++k) mark(E, nv, verts[offsets[i] + k - 1], verts[offsets[i] + k], TAG_TEAR, i, ids[i]);
  }
}

static int32_t find(int32_t *root, int32_t c) {
  while (root[c] != c) c = root[c] = root[root[c]];
  return c;
}
static int32_t corner_of(const int32_t *t, int32_t f, int32_t v) { return 3 * f + (t[3 * f] == v ? 0 : t[3 * f + 1] == v ? 1 : 2); }

// wedges() of validate.ts: one color index per wedge, numbered in order of first use.
static int32_t *wedges(const int32_t *t, int32_t nh, const Edges *E, int32_t *count) {
  int32_t *root = MAKE(int32_t, nh), *id = MAKE(int32_t, nh), *out = MAKE(int32_t, nh);
  for (int32_t c = 0; c < nh; ++c) root[c] = c, id[c] = -1;
  for (int32_t e = 0; e < E->numEdges; ++e)
    if (E->g[e] >= 0 && E->tag[e] != TAG_TEAR)
      for (int32_t v = E->a[e], k = 0; k < 2; k++, v = E->b[e]) root[find(root, corner_of(t, E->f[e], v))] = find(root, corner_of(t, E->g[e], v));
  int32_t n = 0;
  for (int32_t c = 0; c < nh; ++c) {
    int32_t r = find(root, c);
    if (id[r] < 0) id[r] = n++;
    out[c] = id[r];
  }
  *count = n;
  return out;
}

// ---- colors -----------------------------------------------------------------------------------

// decodeColors of the old decode.ts: one value per wedge, numbered canonically; each predicted by
// the rounded mean of the known values it shares a triangle with (else the previous one), coded as
// d_G, d_R - d_G, d_B - d_G in contexts of the neighbours' residuals; on the 2^-cb grid.
static float *colors(Source *s, const int32_t *tc, int32_t nh, int32_t nc, int32_t cb) {
  int32_t *start, *wedge = sort_by(tc, nh, nc, 0, &start);
  int32_t *adjacent = MAKE(int32_t, nc), *seen = MAKE(int32_t, nc);
  double *terms = MAKE(double, nc), *rgb = MAKE(double, 3 * nc), *activity = MAKE(double, 3 * nc);
  float *out = MAKE(float, 3 * nc);
  double unit = pow2(-cb), mid = 128 * pow2(cb) /* an integer: cb >= -4 */, last[3] = {mid, mid, mid}, q[3], d[3];
  begin(s, COLORS);
  for (int32_t ci = 0; ci < nc; ++ci) {
    int32_t n = 0;
    for (int32_t i = start[ci]; i < start[ci + 1]; ++i) {
      int32_t h = wedge[i], j = tc[next3(h)], k = tc[prev3(h)];
      if (j < ci && seen[j] <= ci) seen[j] = ci + 1, adjacent[n++] = j;
      if (k < ci && seen[k] <= ci) seen[k] = ci + 1, adjacent[n++] = k;
    }
    for (int ch = 0; ch < 3; ++ch) {
      double sum = 0, bound = 0, act = 0;
      for (int32_t k = 0; k < n; ++k) {
        int32_t j = 3 * adjacent[k] + ch;
        sum += terms[k] = rgb[j], bound += __builtin_fabs(rgb[j]), act += activity[j];
      }
      q[ch] = !n ? last[ch] : rounded_mean(sum, bound, terms, n);
      int context = 0;
      if (n) {
        uint32_t a = (uint32_t)__builtin_floor(act / n);
        int bits = 33 - (a ? __builtin_clz(a) : 32);
        context = (bits >> 1) < 4 ? bits >> 1 : 4;
      }
      d[ch] = read(s, COLORS, COLOR + 5 * ch + context, 1, -1);
    }
    for (int ch = 0; ch < 3; ++ch) {
      if (__builtin_fabs(d[ch]) > 281474976710656.0 /* 2^48 */) FAIL(E_COLOR_RESIDUAL);
      activity[3 * ci + ch] = fmin2(__builtin_fabs(d[ch]), 65535);
    }
    for (int ch = 0; ch < 3; ++ch) {
      last[ch] = rgb[3 * ci + ch] = q[ch] + (ch == 1 ? d[0] : d[ch ? ch : 1] + d[0]);
      // As the C++ reader: a float holds grid values up to 2^24 exactly.
      if (__builtin_fabs(last[ch]) > 16777216.0) FAIL(E_COLOR_VALUE);
      out[3 * ci + ch] = (float)(last[ch] * unit);
    }
  }
  end(s, COLORS);
  return out;
}

// ---- a level ----------------------------------------------------------------------------------

typedef struct {
  double *positions;
  float *colors;
  int32_t *triangles, *triangleColors, *creases;
  int32_t numFeatures;
  int32_t *featureIds, *featureOffsets, *featureVertices;
  double *featureSaliency;
  Edges edges;
} Level;

// src/wasm.ts reads the fields by position (of 32-bit pointers).
#ifdef __wasm__
_Static_assert(__builtin_offsetof(Level, featureSaliency) == 36 && __builtin_offsetof(Level, edges) == 40, "Level's layout");
_Static_assert(__builtin_offsetof(Edges, twin) == 24, "Edges' layout");
#endif

typedef struct {
  const uint8_t *bytes;
  int32_t length;
} Section;

// A compact level from its counts and precision (read by src/decode.ts): version 3 from one
// range-coded stream, version 2 from its six varint sections (ops: the most operations the rest
// of the payload can hold). Returns the level and its topology; 0 never (fail() throws).
EXPORT(compact)
Level *compact(int32_t version, const Section *sections, double ops, int32_t nv, int32_t ncolors, int32_t ntriangles,
               int32_t ncreases, int32_t nfeatures, int32_t pb, int32_t cb, double width, double height, int32_t level) {
  message_level = level, message_prefix = 0;
  Level *L = MAKE(Level, 1);
  Source *s = MAKE(Source, 1);
  if (version == 3) {
    range_start(s, sections[0].bytes, sections[0].length, nv);
  } else {
    s->version = 2, s->ops = ops, s->featureWhat = -1;
    for (int k = 0; k < 6; ++k) s->section[k] = (Bytes){sections[k].bytes, sections[k].length, 0};
  }
  int32_t *basis, virt;
  int32_t *t = L->triangles = traverse(s, nv, ntriangles, &basis, &virt), nh = 3 * ntriangles;
  // The corners by vertex; the edges (whose problems are reported after the features, as C++
  // finds them; until then, no twins).
  int32_t *start, *corners = sort_by(t, nh, nv, 0, &start);
  edges(t, nh, nv, &L->edges);
  int32_t *twin = L->edges.twin;
  if (L->edges.problem >= 0) {
    twin = MAKE(int32_t, nh);
    for (int32_t h = 0; h < nh; ++h) twin[h] = -1;
  }
  double *px = MAKE(double, nv), *py = MAKE(double, nv);
  predict(s, t, corners, start, nv, twin, basis, virt, width * pow2(pb), height * pow2(pb), px, py);
  double *positions = L->positions = MAKE(double, 2 * nv), unit = pow2(-pb);
  for (int32_t v = 0; v < nv; ++v) positions[2 * v] = px[v] * unit, positions[2 * v + 1] = py[v] * unit;

  // Creases and features: a first vertex, then each next one as its rank among the current
  // vertex's neighbours.
  begin(s, FEATURES);
  begin(s, STEPS);
  Steps c = {s, t, corners, start, px, py, nv, 0, MAKE(int32_t, nv), MAKE(int32_t, nh), MAKE(int32_t, nh), MAKE(double, nv)};
  int32_t *creases = L->creases = MAKE(int32_t, 2 * ncreases);
  for (int32_t i = 0; i < ncreases; ++i) {
    int32_t a = checked(&c, vertex(s), 0, i);
    creases[2 * i] = a, creases[2 * i + 1] = step(&c, -1, a, 1, 0, i);
  }
  // Feature vertices: their chains as they come (the arena grows with them).
  int32_t *ids = L->featureIds = MAKE(int32_t, nfeatures), *offsets = L->featureOffsets = MAKE(int32_t, nfeatures + 1);
  double *saliencies = L->featureSaliency = MAKE(double, nfeatures), previous = -1;
  int32_t **chains = MAKE(int32_t *, nfeatures);
  for (int32_t i = 0; i < nfeatures; ++i) {
    double id = previous += 1 + read(s, FEATURES, ID, 1, i);
    if (id < -2147483648.0 || id > 2147483647.0) FAIL(E_FEATURE_ID, i);
    ids[i] = (int32_t)id;
    saliencies[i] = saliency(s, i);
    double n = length(s, i);
    if (n > fmin2(nv, MAX_ELEMENTS - 2)) FAIL(E_FEATURE_LENGTH, i, n + 2);
    int32_t *v = chains[i] = MAKE(int32_t, n + 2);
    offsets[i + 1] = offsets[i] + (int32_t)n + 2;
    v[0] = checked(&c, vertex(s), 1, i);
    for (int32_t k = 0; k <= (int32_t)n; ++k) v[k + 1] = step(&c, k ? v[k - 1] : -1, v[k], !k, 1, i);
  }
  end(s, FEATURES);
  end(s, STEPS);
  int32_t *verts = L->featureVertices = MAKE(int32_t, offsets[nfeatures]);
  for (int32_t i = 0; i < nfeatures; ++i)
    __builtin_memcpy(verts + offsets[i], chains[i], sizeof(int32_t) * (size_t)(offsets[i + 1] - offsets[i]));
  L->numFeatures = nfeatures;

  // The topology: the edges' problem, then creases and features marked.
  Edges *E = &L->edges;
  if (E->problem >= 0) FAIL(E->problem, E->args[0], E->args[1], E->args[2], E->args[3]);
  mark_chains(E, nv, creases, ncreases, ids, offsets, verts, nfeatures);
  // The tears are known now: the wedges, and their colors.
  int32_t nc;
  int32_t *tc = L->triangleColors = wedges(t, nh, E, &nc);
  if (nc != ncolors) FAIL(E_COLOR_COUNT, nc, ncolors);
  L->colors = colors(s, tc, nh, nc, cb);
  finish(s);
  return L;
}

// ---- a level's validity rules -----------------------------------------------------------------

static const double PI = 3.141592653589793;

// The angle of triangle h / 3 at its corner h (corner_angle of src/mesh/validate.cpp).
static double corner_angle(const double *p, const int32_t *t, int32_t h) {
  int32_t u = t[h], v = t[next3(h)], w = t[prev3(h)];
  double ux = p[2 * v] - p[2 * u], uy = p[2 * v + 1] - p[2 * u + 1], vx = p[2 * w] - p[2 * u], vy = p[2 * w + 1] - p[2 * u + 1];
  return js_atan2(ux * vy - uy * vx, ux * vx + uy * vy);
}

// The image's frame (check_mesh, for a level): border edges on the image rectangle and its
// corners present; tiling (angle sums per vertex, the total area).
static void check_frame(int32_t nv, const double *p, int32_t nt, const int32_t *t, const double *area, const Edges *E, uint8_t *sides,
                        uint8_t *border, double *angles, double width, double height) {
  int32_t nh = 3 * nt;
  // Sides of the image rectangle each vertex lies on, exactly: 1 left, 2 right, 4 top, 8 bottom;
  // and the image corners: 1 (0, 0), 2 (W, 0), 4 (W, H), 8 (0, H).
  int corners = 0;
  for (int32_t v = 0; v < nv; ++v) {
    double x = p[2 * v], y = p[2 * v + 1];
    int s = sides[v] = (uint8_t)((x == 0) | (x == width) << 1 | (y == 0) << 2 | (y == height) << 3);
    corners |= s == 5 ? 1 : s == 6 ? 2 : s == 10 ? 4 : s == 9 ? 8 : 0;
  }
  for (int32_t e = 0; e < E->numEdges; ++e) {
    if (E->g[e] >= 0) continue;
    int32_t u = E->a[e], v = E->b[e];
    if (!(sides[u] & sides[v])) FAIL(V_GAP_EDGE, u, v, u, v);
    border[u] = border[v] = 1;
  }
  for (int k = 0; k < 4; ++k)
    if (!(corners & (1 << k))) FAIL(V_NO_CORNER, k % 3 ? width : 0, k > 1 ? height : 0);

  // Tiling: angle sums per vertex, then the total area (summed compensated, as C++ sums it in
  // long double).
  double total = 0, lost = 0;
  for (int32_t h = 0; h < nh; ++h) angles[t[h]] += corner_angle(p, t, h);
  for (int32_t f = 0; f < nt; ++f) {
    double s = area[f], sum = total + s;
    lost += __builtin_fabs(total) >= __builtin_fabs(s) ? total - sum + s : s - sum + total;
    total = sum;
  }
  total += lost;
  for (int32_t v = 0; v < nv; ++v) {
    int corner = border[v] && sides[v] & 3 && sides[v] & 12, kind = corner ? 0 : border[v] ? 1 : 2;
    double expected = corner ? PI / 2 : border[v] ? PI : 2 * PI;
    if (__builtin_fabs(angles[v] - expected) > 1e-6) FAIL(V_ANGLES, angles[v] > expected ? W_OVERLAP : W_GAP, v, v, angles[v] / PI, W_CORNER + kind, expected / PI);
  }
  double image = width * height;
  if (__builtin_fabs(total - image) > 1e-9 * image) FAIL(V_AREA, total, width * height, width, height);
}

// validateLevel of the old validate.ts (src/mesh/validate.cpp), in its order: finite positions in
// the image; (*) finite colors and indices in range; unique feature ids, finite saliencies;
// (*) the topology; positive areas; used vertices; border edges on the image rectangle and its
// corners present; tiling (angle sums per vertex, the total area); (*) the wedge color rules.
// `built`: the topology of a level this module decoded (compact), which makes the checks marked *
// true by construction; 0 for the others (JSON, version 1). `object`: an object's mesh
// (validate_object), which need not tile the image: positions within 2^24 pixels instead of in
// the image, and instead of the border and tiling, its boundary made of closed loops (two
// boundary edges at each boundary vertex) and the triangles around each vertex making one turn
// (less at a boundary vertex). Returns 1; problems go to fail().
static int32_t check_mesh(int32_t nv, const double *p, int32_t nc, const float *c, int32_t nt, const int32_t *t, const int32_t *tc,
                          int32_t ncreases, const int32_t *creases, int32_t nfeatures, const int32_t *ids, const double *saliency,
                          const int32_t *offsets, const int32_t *verts, double width, double height, const Edges *built,
                          int32_t object) {
  int32_t nh = 3 * nt;
  for (int32_t v = 0; v < nv; ++v) {
    double x = p[2 * v], y = p[2 * v + 1];
    if (!__builtin_isfinite(x) || !__builtin_isfinite(y)) FAIL(V_POSITION_NOT_FINITE, v, v);
    if (object) {
      if (__builtin_fabs(x) > 16777216.0 || __builtin_fabs(y) > 16777216.0) FAIL(V_POSITION_FAR, v, v);
    } else if (x < 0 || x > width || y < 0 || y > height) FAIL(V_POSITION_OUTSIDE, v, v, width, height);
  }
  if (!built) {
    for (int32_t i = 0; i < 3 * nc; ++i)
      if (!__builtin_isfinite(c[i])) FAIL(V_COLOR_NOT_FINITE, i / 3, c[i - i % 3], c[i - i % 3 + 1], c[i - i % 3 + 2]);
    // Vertex indices before color indices: without triangle_colors (JSON) these are copies of them.
    for (int32_t h = 0; h < nh; ++h)
      if (t[h] < 0 || t[h] >= nv) FAIL(E_TRIANGLE_VERTEX, h / 3, t[h], nv);
    for (int32_t h = 0; h < nh; ++h)
      if (tc[h] < 0 || tc[h] >= nc) FAIL(V_TRIANGLE_COLOR, h / 3, tc[h], nc);
  }
  // Feature ids: the first feature that repeats an earlier id, or whose saliency is not finite.
  {
    int32_t *order = MAKE(int32_t, nfeatures), *scratch = MAKE(int32_t, nfeatures), repeat = nfeatures;
    for (int32_t i = 0; i < nfeatures; ++i) order[i] = i;
    for (int32_t width2 = 1; width2 < nfeatures; width2 *= 2) { // merge sort by (id, index)
      for (int32_t lo = 0; lo < nfeatures; lo += 2 * width2) {
        int32_t mid = imin(lo + width2, nfeatures), hi = imin(lo + 2 * width2, nfeatures), i = lo, j = mid, k = lo;
        while (i < mid && j < hi) scratch[k++] = ids[order[j]] < ids[order[i]] ? order[j++] : order[i++];
        while (i < mid) scratch[k++] = order[i++];
        while (j < hi) scratch[k++] = order[j++];
      }
      int32_t *swap = order;
      order = scratch, scratch = swap;
    }
    for (int32_t k = 1; k < nfeatures; ++k)
      if (ids[order[k]] == ids[order[k - 1]] && (k == 1 || ids[order[k - 2]] != ids[order[k]]) && order[k] < repeat) repeat = order[k];
    for (int32_t i = 0; i < nfeatures; ++i) {
      if (i == repeat) FAIL(V_REPEATED_ID, i, ids[i]);
      if (!__builtin_isfinite(saliency[i])) FAIL(V_SALIENCY, i, ids[i], saliency[i]);
    }
  }
  Edges own;
  const Edges *E = built;
  if (!built) {
    edges(t, nh, nv, &own);
    if (own.problem >= 0) FAIL(own.problem, own.args[0], own.args[1], own.args[2], own.args[3]);
    mark_chains(&own, nv, creases, ncreases, ids, offsets, verts, nfeatures);
    E = &own;
  }

  // Signed areas, and the used vertices.
  double *area = MAKE(double, nt);
  uint8_t *used = MAKE(uint8_t, nv), *sides = MAKE(uint8_t, nv), *border = MAKE(uint8_t, nv);
  for (int32_t f = 0; f < nt; ++f) {
    int32_t u = t[3 * f], v = t[3 * f + 1], w = t[3 * f + 2];
    double s = area[f] = 0.5 * ((p[2 * v] - p[2 * u]) * (p[2 * w + 1] - p[2 * u + 1]) - (p[2 * v + 1] - p[2 * u + 1]) * (p[2 * w] - p[2 * u]));
    if (!(s > 0)) FAIL(V_FLIPPED, f, u, v, w, s);
    used[u] = used[v] = used[w] = 1;
  }
  for (int32_t v = 0; v < nv; ++v)
    if (!used[v]) FAIL(V_UNUSED_VERTEX, v, v);
  double *angles = MAKE(double, nv);
  if (object) {
    // The boundary (counted in bytes, as C++ counts it), then the turns around each vertex.
    if (!nt) FAIL(V_NO_TRIANGLES);
    for (int32_t e = 0; e < E->numEdges; ++e)
      if (E->g[e] < 0) border[E->a[e]]++, border[E->b[e]]++;
    for (int32_t v = 0; v < nv; ++v)
      if (border[v] != 0 && border[v] != 2) FAIL(V_BOUNDARY_EDGES, v, v, border[v]);
    for (int32_t h = 0; h < nh; ++h) angles[t[h]] += corner_angle(p, t, h);
    for (int32_t v = 0; v < nv; ++v)
      if (border[v] ? !(angles[v] < 2 * PI - 1e-6) : __builtin_fabs(angles[v] - 2 * PI) > 1e-6) FAIL(V_TURNS, v, v, angles[v] / PI);
  } else
    check_frame(nv, p, nt, t, area, E, sides, border, angles, width, height);
  if (built) return 1;

  // Colors: each value belongs to one vertex and is used; across an edge that is not a tear, both
  // triangles use the same value at each end.
  int32_t *owner = MAKE(int32_t, nc), *first = MAKE(int32_t, nc);
  for (int32_t i = 0; i < nc; ++i) owner[i] = -1;
  for (int32_t h = 0; h < nh; ++h) {
    int32_t v = t[h], i = tc[h], f = h / 3;
    if (owner[i] < 0)
      owner[i] = v, first[i] = f;
    else if (owner[i] != v)
      FAIL(V_COLOR_OWNER, i, owner[i], first[i], v, f);
  }
  for (int32_t i = 0; i < nc; ++i)
    if (owner[i] < 0) FAIL(V_UNUSED_COLOR, i);
  for (int32_t e = 0; e < E->numEdges; ++e) {
    int32_t f = E->f[e], g = E->g[e];
    if (g >= 0 && E->tag[e] != TAG_TEAR)
      for (int32_t v = E->a[e], k = 0; k < 2; k++, v = E->b[e]) {
        int32_t cf = tc[corner_of(t, f, v)], cg = tc[corner_of(t, g, v)];
        if (cf != cg) FAIL(V_COLOR_EDGE, E->a[e], E->b[e], f, g, v, cf, cg);
      }
  }
  return 1;
}

// A level's rules (check_mesh), its messages prefixed "level L: " (validate.c calls it).
int32_t check_level(int32_t nv, const double *p, int32_t nc, const float *c, int32_t nt, const int32_t *t, const int32_t *tc,
                    int32_t ncreases, const int32_t *creases, int32_t nfeatures, const int32_t *ids, const double *saliency,
                    const int32_t *offsets, const int32_t *verts, double width, double height, const Edges *built,
                    int32_t level) {
  message_level = level, message_prefix = 1, message_positions = p;
  return check_mesh(nv, p, nc, c, nt, t, tc, ncreases, creases, nfeatures, ids, saliency, offsets, verts, width, height, built, 0);
}

// Object `index`'s mesh (check_mesh), its messages prefixed "object N: ".
int32_t check_object(int32_t nv, const double *p, int32_t nc, const float *c, int32_t nt, const int32_t *t, const int32_t *tc,
                     int32_t ncreases, const int32_t *creases, int32_t nfeatures, const int32_t *ids, const double *saliency,
                     const int32_t *offsets, const int32_t *verts, int32_t index) {
  message_level = index, message_prefix = 2, message_positions = p;
  return check_mesh(nv, p, nc, c, nt, t, tc, ncreases, creases, nfeatures, ids, saliency, offsets, verts, 0, 0, 0, 1);
}
