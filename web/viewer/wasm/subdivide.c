// The viewer's refinement in WebAssembly (docs/viewer.md, "Why WebAssembly"): the same rules and
// the same arithmetic, operation for operation, as web/viewer/src/subdivide.ts, which stays the
// reference (web/tests/viewer-subdivision.mjs compares the two bit for bit). A page's first frame runs
// this code once, cold: JavaScript's first tiers box every double they compute (about 46 MB of
// garbage for a 3,000-vertex file), while WebAssembly is compiled before it runs.
//
// Every function returns 0 when the arena cannot grow (memory.h).
#include "memory.h"

// Math.cos and Math.hypot, so that the results are JavaScript's to the bit.
IMPORT(cos) double js_cos(double);
IMPORT(hypot) double js_hypot(double, double);

enum { SMOOTH = 0, SHARP = 1, TEAR = 2, BORDER = 3 };
static const double PI = 3.141592653589793;

// ---- topology ---------------------------------------------------------------------------------

typedef struct {
  int32_t numEdges;
  int32_t *triEdges, *edgeVerts;
  uint8_t *edgeTags, *corner;
  int32_t *vertexFaceOffsets, *vertexFaces;
  double *ringBoxes;
} Topology;

// The corner index (3f + k) of the side a -> b among the faces around a, or -1.
static int32_t side(const int32_t *tri, const int32_t *vfo, const int32_t *vf, int32_t a, int32_t b) {
  for (int32_t j = vfo[a]; j < vfo[a + 1]; ++j) {
    int32_t f = 3 * vf[j];
    for (int k = 0; k < 3; ++k)
      if (tri[f + k] == a && tri[f + (k == 2 ? 0 : k + 1)] == b) return f + k;
  }
  return -1;
}

static void tag(const int32_t *tri, const Topology *t, int32_t a, int32_t b, uint8_t value) {
  int32_t i = side(tri, t->vertexFaceOffsets, t->vertexFaces, a, b);
  if (i < 0) i = side(tri, t->vertexFaceOffsets, t->vertexFaces, b, a);
  if (i >= 0) t->edgeTags[t->triEdges[i]] = value;
}

static double min3(double a, double b, double c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
static double max3(double a, double b, double c) { return a > b ? (a > c ? a : c) : (b > c ? b : c); }

// buildTopology of subdivide.ts. Features are given as offsets (numFeatures + 1) into their vertices;
// width and height NaN (an object's mesh): no vertex is an image corner.
EXPORT(topology)
Topology *topology(int32_t nv, const double *p, int32_t nf, const int32_t *tri, int32_t numCreases, const int32_t *creaseEnds,
                   int32_t numFeatures, const int32_t *featureOffsets, const int32_t *featureVerts, double width, double height) {
  Topology *t = NEW(Topology, 1);
  CHECK(t);
  int32_t *vfo = t->vertexFaceOffsets = NEW(int32_t, nv + 1);
  int32_t *vf = t->vertexFaces = NEW(int32_t, 3 * nf);
  int32_t *fill = NEW(int32_t, nv);
  CHECK(vfo && vf && fill);
  for (int32_t i = 0; i < 3 * nf; ++i) vfo[tri[i] + 1]++;
  for (int32_t v = 0; v < nv; ++v) vfo[v + 1] += vfo[v];
  for (int32_t v = 0; v < nv; ++v) fill[v] = vfo[v];
  for (int32_t i = 0; i < 3 * nf; ++i) vf[fill[tri[i]]++] = i / 3;

  // Edges in order of first use; a side takes the edge of the opposite side seen before it.
  int32_t *te = t->triEdges = NEW(int32_t, 3 * nf), *twin = NEW(int32_t, 3 * nf), *ends = NEW(int32_t, 6 * nf);
  CHECK(te && twin && ends);
  for (int32_t i = 0; i < 3 * nf; ++i) te[i] = -1;
  int32_t ne = 0;
  for (int32_t i = 0; i < 3 * nf; ++i) {
    int32_t a = tri[i], b = tri[i - i % 3 + (i + 1) % 3];
    int32_t o = twin[i] = side(tri, vfo, vf, b, a);
    if (o >= 0 && te[o] >= 0) {
      te[i] = te[o];
    } else {
      ends[2 * ne] = a, ends[2 * ne + 1] = b, te[i] = ne++;
    }
  }
  t->numEdges = ne;
  t->edgeVerts = ends;
  uint8_t *tags = t->edgeTags = NEW(uint8_t, ne);
  CHECK(tags);
  for (int32_t i = 0; i < 3 * nf; ++i)
    if (twin[i] < 0) tags[te[i]] = BORDER;
  for (int32_t i = 0; i < numCreases; ++i) tag(tri, t, creaseEnds[2 * i], creaseEnds[2 * i + 1], SHARP);
  uint8_t *endpoint = NEW(uint8_t, nv);
  CHECK(endpoint);
  for (int32_t f = 0; f < numFeatures; ++f) {
    const int32_t *v = featureVerts + featureOffsets[f];
    int32_t n = featureOffsets[f + 1] - featureOffsets[f];
    for (int32_t k = 0; k + 1 < n; ++k) tag(tri, t, v[k], v[k + 1], TEAR);
    if (n > 0 && v[0] != v[n - 1]) endpoint[v[0]] = endpoint[v[n - 1]] = 1;
  }
  // Vertex tags (docs/format.md, "Edges, features and creases"; src/mesh/topology.cpp).
  uint8_t *creases = NEW(uint8_t, nv), *tears = NEW(uint8_t, nv), *corner = t->corner = NEW(uint8_t, nv);
  CHECK(creases && tears && corner);
  for (int32_t e = 0; e < ne; ++e) {
    if (tags[e] == SMOOTH) continue;
    uint8_t *count = tags[e] == TEAR ? tears : creases;
    count[ends[2 * e]]++;
    count[ends[2 * e + 1]]++;
  }
  for (int32_t v = 0; v < nv; ++v) {
    double x = p[2 * v], y = p[2 * v + 1];
    int imageCorner = width >= 0 && (x == 0 || x == width) && (y == 0 || y == height);
    int c = creases[v], s = tears[v];
    corner[v] = imageCorner || endpoint[v] || !((c == 0 && s == 0) || (c == 2 && s == 0) || (s == 2 && c == 0));
  }
  // Ring boxes: the hull of the control points of the faces around a face's corners.
  double *star = NEW(double, 4 * nv), *boxes = t->ringBoxes = NEW(double, 4 * nf);
  CHECK(star && boxes);
  for (int32_t v = 0; v < nv; ++v) {
    double x0 = p[2 * v], y0 = p[2 * v + 1], x1 = x0, y1 = y0;
    for (int32_t j = vfo[v]; j < vfo[v + 1]; ++j) {
      for (int k = 0; k < 3; ++k) {
        int32_t u = tri[3 * vf[j] + k];
        double x = p[2 * u], y = p[2 * u + 1];
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
      }
    }
    star[4 * v] = x0, star[4 * v + 1] = y0, star[4 * v + 2] = x1, star[4 * v + 3] = y1;
  }
  for (int32_t f = 0; f < nf; ++f) {
    int32_t a = 4 * tri[3 * f], b = 4 * tri[3 * f + 1], c = 4 * tri[3 * f + 2];
    boxes[4 * f] = min3(star[a], star[b], star[c]);
    boxes[4 * f + 1] = min3(star[a + 1], star[b + 1], star[c + 1]);
    boxes[4 * f + 2] = max3(star[a + 2], star[b + 2], star[c + 2]);
    boxes[4 * f + 3] = max3(star[a + 3], star[b + 3], star[c + 3]);
  }
  return t;
}

// ---- refinement -------------------------------------------------------------------------------

typedef struct {
  int32_t numVertices, numValues, numFaces, numEdges;
  int32_t *tri, *triValues, *triEdges, *edgeVerts;
  uint8_t *edgeTags, *corner;
  int32_t *valueVertex;
} Mesh;

// Smooth (Loop) masks of OpenSubdiv's Sdc::Scheme<SCHEME_LOOP>.
static double loopEdgeWeight(int32_t n) {
  double beta = 0.25 * js_cos((PI * 2) / n) + 0.375;
  return (0.625 - beta * beta) / n;
}
static double loopLimitEdgeWeight(int32_t n) {
  double beta = 0.25 * js_cos((PI * 2) / n) + 0.375;
  double gamma = (0.625 - beta * beta) / n;
  return 1 / (n + 3 / (8 * gamma));
}

// vertexPoints of subdivide.ts: the vertex masks (refinement, or limit) into outPos and outCol.
static int vertexPoints(const Mesh *m, const double *pos, const double *col, int limit, double *outPos, double *outCol) {
  int32_t nv = m->numVertices, nc = m->numValues, nf = m->numFaces;
  const int32_t *tri = m->tri, *tv = m->triValues, *te = m->triEdges, *ev = m->edgeVerts;
  const uint8_t *tags = m->edgeTags;
  uint8_t *sharpEdges = NEW(uint8_t, nv);
  double *ringP = NEW(double, 2 * nv), *sharpP = NEW(double, 2 * nv), *ringC = NEW(double, 3 * nc), *sharpC = NEW(double, 3 * nc);
  int32_t *ringN = NEW(int32_t, nv), *sharpN = NEW(int32_t, nv), *ringNC = NEW(int32_t, nc), *sharpNC = NEW(int32_t, nc);
  double *self = NEW(double, nv), *other = NEW(double, nv);
  uint8_t *useRing = NEW(uint8_t, nv);
  CHECK(sharpEdges && ringP && sharpP && ringC && sharpC && ringN && sharpN && ringNC && sharpNC && self && other && useRing);
  for (int32_t e = 0; e < m->numEdges; ++e)
    if (tags[e] != SMOOTH) sharpEdges[ev[2 * e]]++, sharpEdges[ev[2 * e + 1]]++;
  for (int32_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      int32_t i = 3 * f + k, next = 3 * f + (k == 2 ? 0 : k + 1), prev = 3 * f + (k == 0 ? 2 : k - 1);
      int32_t v = 2 * tri[i], n = 2 * tri[next], p = 2 * tri[prev];
      int32_t c = 3 * tv[i], cn = 3 * tv[next], cp = 3 * tv[prev];
      ringN[tri[i]]++, ringNC[tv[i]]++;
      ringP[v] += pos[n], ringP[v + 1] += pos[n + 1];
      ringC[c] += col[cn], ringC[c + 1] += col[cn + 1], ringC[c + 2] += col[cn + 2];
      if (tags[te[i]] != SMOOTH) {
        sharpN[tri[i]]++, sharpNC[tv[i]]++;
        sharpP[v] += pos[n], sharpP[v + 1] += pos[n + 1];
        sharpC[c] += col[cn], sharpC[c + 1] += col[cn + 1], sharpC[c + 2] += col[cn + 2];
      }
      if (tags[te[prev]] != SMOOTH) {
        sharpN[tri[i]]++, sharpNC[tv[i]]++;
        sharpP[v] += pos[p], sharpP[v + 1] += pos[p + 1];
        sharpC[c] += col[cp], sharpC[c + 1] += col[cp + 1], sharpC[c + 2] += col[cp + 2];
      }
    }
  }
  double crease = limit ? 2.0 / 3.0 : 0.75, regular = limit ? 1.0 / 12.0 : 0.0625;
  for (int32_t v = 0; v < nv; ++v) {
    int s = sharpEdges[v];
    if (m->corner[v] || s > 2 || (s == 2 && sharpN[v] == 0)) {
      self[v] = 1;
    } else if (s == 2) {
      self[v] = crease;
      other[v] = (1 - crease) / sharpN[v];
    } else {
      int32_t n = ringN[v];
      double w = n == 6 ? regular : limit ? loopLimitEdgeWeight(n) : loopEdgeWeight(n);
      self[v] = 1 - w * n;
      other[v] = w;
      useRing[v] = 1;
    }
  }
  for (int32_t v = 0; v < nv; ++v) {
    double a = self[v], b = other[v];
    const double *sum = useRing[v] ? ringP : sharpP;
    outPos[2 * v] = a * pos[2 * v] + b * sum[2 * v];
    outPos[2 * v + 1] = a * pos[2 * v + 1] + b * sum[2 * v + 1];
  }
  // A color value's crease mask counts its own side's sharp neighbours.
  for (int32_t c = 0; c < nc; ++c) {
    int32_t v = m->valueVertex[c], o = 3 * c;
    double a = self[v], b = other[v];
    const double *sum = useRing[v] ? ringC : sharpC;
    if (!useRing[v] && b != 0) {
      if (sharpNC[c]) {
        b = (1 - crease) / sharpNC[c];
      } else {
        a = 1, b = 0;
      }
    } else if (useRing[v] && ringNC[c] != ringN[v]) {
      int32_t n = ringNC[c];
      double w = n == 6 ? regular : limit ? loopLimitEdgeWeight(n) : loopEdgeWeight(n);
      a = 1 - w * n, b = w;
    }
    outCol[o] = a * col[o] + b * sum[o];
    outCol[o + 1] = a * col[o + 1] + b * sum[o + 1];
    outCol[o + 2] = a * col[o + 2] + b * sum[o + 2];
  }
  return 1;
}

// refineOnce of subdivide.ts: one step of Loop subdivision of m into *out.
static int refineOnce(const Mesh *m, const double *pos, const double *col, const int32_t *sides, Mesh *out, double **outPos,
                      double **outCol, int32_t **outSides) {
  int32_t nv = m->numVertices, nc = m->numValues, nf = m->numFaces, ne = m->numEdges;
  const int32_t *tri = m->tri, *tv = m->triValues, *te = m->triEdges, *ev = m->edgeVerts;
  const uint8_t *tags = m->edgeTags;

  // Edge values: one per edge, two for a tear (side 0: the face that runs it edgeVerts[0] -> [1]).
  int32_t *edgeValue = NEW(int32_t, ne);
  CHECK(edgeValue);
  int32_t numValues = nc;
  for (int32_t e = 0; e < ne; ++e) {
    edgeValue[e] = numValues;
    numValues += tags[e] == TEAR ? 2 : 1;
  }
  double *newPos = NEW(double, 2 * (nv + ne)), *newCol = NEW(double, 3 * numValues);
  CHECK(newPos && newCol);
  CHECK(vertexPoints(m, pos, col, 0, newPos, newCol));

  // Edge points: 1/8 of the opposite corners gathered per face, then the ends.
  double *opposite = NEW(double, 2 * ne);
  CHECK(opposite);
  for (int32_t i = 0; i < 3 * nf; ++i) {
    int32_t e = te[i], o = tri[i - i % 3 + (i + 2) % 3];
    opposite[2 * e] += pos[2 * o];
    opposite[2 * e + 1] += pos[2 * o + 1];
  }
  for (int32_t e = 0; e < ne; ++e) {
    int32_t a = ev[2 * e], b = ev[2 * e + 1], at = 2 * (nv + e);
    for (int c = 0; c < 2; ++c) {
      double ends = pos[2 * a + c] + pos[2 * b + c];
      newPos[at + c] = tags[e] == SMOOTH ? 0.375 * ends + 0.125 * opposite[2 * e + c] : 0.5 * ends;
    }
  }
  // Edge colors: per face corner, its edge's value on its side.
  uint8_t *done = NEW(uint8_t, numValues);
  CHECK(done);
  for (int32_t i = 0; i < 3 * nf; ++i) {
    int32_t e = te[i], t = tags[e];
    int32_t value = edgeValue[e] + (t == TEAR && tri[i] != ev[2 * e] ? 1 : 0);
    int32_t a = tv[i], b = tv[i - i % 3 + (i + 1) % 3], o = tv[i - i % 3 + (i + 2) % 3];
    int32_t at = 3 * value;
    if (t != SMOOTH) {
      if (done[value]) continue;
      done[value] = 1;
      for (int c = 0; c < 3; ++c) newCol[at + c] = 0.5 * (col[3 * a + c] + col[3 * b + c]);
    } else {
      // Both faces of a smooth edge add their opposite corner; the first also adds the ends.
      int first = !done[value];
      done[value] = 1;
      for (int c = 0; c < 3; ++c)
        newCol[at + c] += 0.125 * col[3 * o + c] + (first ? 0.375 * (col[3 * a + c] + col[3 * b + c]) : 0.0);
    }
  }

  // Child topology: corner k of face f keeps corner k in child 4f + k; child 4f + 3 joins the
  // edge points. Child edges 2e and 2e + 1 halve edge e, then three inner edges per face.
  int32_t cnf = 4 * nf, cne = 2 * ne + 3 * nf;
  int32_t *ctri = NEW(int32_t, 3 * cnf), *cval = NEW(int32_t, 3 * cnf), *cte = NEW(int32_t, 3 * cnf);
  int32_t *cev = NEW(int32_t, 2 * cne), *childSides = NEW(int32_t, 3 * cnf);
  uint8_t *ctags = NEW(uint8_t, cne);
  CHECK(ctri && cval && cte && cev && childSides && ctags);
  for (int32_t e = 0; e < ne; ++e) {
    cev[4 * e] = ev[2 * e];
    cev[4 * e + 1] = cev[4 * e + 2] = nv + e;
    cev[4 * e + 3] = ev[2 * e + 1];
    ctags[2 * e] = ctags[2 * e + 1] = tags[e];
  }
  for (int32_t i = 0; i < 3 * cnf; ++i) childSides[i] = -1;
  int32_t mid[3], midValue[3], halfFrom[3], halfTo[3];
  for (int32_t f = 0; f < nf; ++f) {
    int32_t b3 = 3 * f, inner = 2 * ne + 3 * f;
    for (int k = 0; k < 3; ++k) {
      int32_t e = te[b3 + k];
      int forward = tri[b3 + k] == ev[2 * e];
      mid[k] = nv + e;
      midValue[k] = edgeValue[e] + (tags[e] == TEAR && !forward ? 1 : 0);
      halfFrom[k] = 2 * e + (forward ? 0 : 1);
      halfTo[k] = 2 * e + (forward ? 1 : 0);
    }
    for (int k = 0; k < 3; ++k) {
      int prev = (k + 2) % 3;
      int32_t o = 3 * (4 * f + k);
      cev[2 * (inner + k)] = mid[k];
      cev[2 * (inner + k) + 1] = mid[(k + 1) % 3];
      ctri[o] = tri[b3 + k], ctri[o + 1] = mid[k], ctri[o + 2] = mid[prev];
      cval[o] = tv[b3 + k], cval[o + 1] = midValue[k], cval[o + 2] = midValue[prev];
      cte[o] = halfFrom[k], cte[o + 1] = inner + prev, cte[o + 2] = halfTo[prev];
      childSides[o] = sides[b3 + k], childSides[o + 2] = sides[b3 + prev];
      int32_t c = 3 * (4 * f + 3) + k;
      ctri[c] = mid[k], cval[c] = midValue[k], cte[c] = inner + k;
    }
  }
  uint8_t *corner = NEW(uint8_t, nv + ne);
  int32_t *valueVertex = NEW(int32_t, numValues);
  CHECK(corner && valueVertex);
  __builtin_memcpy(corner, m->corner, (size_t)nv);
  __builtin_memcpy(valueVertex, m->valueVertex, sizeof(int32_t) * (size_t)nc);
  for (int32_t e = 0; e < ne; ++e) {
    valueVertex[edgeValue[e]] = nv + e;
    if (tags[e] == TEAR) valueVertex[edgeValue[e] + 1] = nv + e;
  }
  *out = (Mesh){nv + ne, numValues, cnf, cne, ctri, cval, cte, cev, ctags, corner, valueVertex};
  *outPos = newPos, *outCol = newCol, *outSides = childSides;
  return 1;
}

// What refine returns: per level d its triangles' color values and sides (3 per face, nsub * 4^d
// faces), then the limit vertices and the sub-mesh edges' flags and faces.
typedef struct {
  int32_t selected, numFaces, numValues, numEdges;
  float *vertices;
  uint8_t *sharpEdges;
  int32_t *edgeFaces;
  int32_t *values[16], *sides[16];
} Refined;

// refine of subdivide.ts: faces (numFaces of them, or all when faces is 0) refined depth times
// (depth <= 15) and pushed to the limit, with their one-ring. Colors are the level's (float32).
EXPORT(refine)
Refined *refine(const Topology *topo, int32_t nv, const double *positions, int32_t ncol, const float *colors, int32_t nf,
                const int32_t *triangles, const int32_t *triangleColors, const int32_t *faces, int32_t numFaces, int32_t depth) {
  Refined *r = NEW(Refined, 1);
  CHECK(r && depth >= 0 && depth < 16);
  // Selected faces first, then the faces around their corners.
  int32_t *order, selected, nsub;
  if (!faces) {
    order = NEW(int32_t, nf);
    CHECK(order);
    for (int32_t f = 0; f < nf; ++f) order[f] = f;
    selected = nsub = nf;
  } else {
    uint8_t *mark = NEW(uint8_t, nf);
    order = NEW(int32_t, nf);
    CHECK(mark && order);
    nsub = 0;
    for (int32_t i = 0; i < numFaces; ++i)
      if (!mark[faces[i]]) mark[faces[i]] = 1, order[nsub++] = faces[i];
    selected = nsub;
    for (int32_t i = 0; i < selected; ++i) {
      for (int k = 0; k < 3; ++k) {
        int32_t v = triangles[3 * order[i] + k];
        for (int32_t j = topo->vertexFaceOffsets[v]; j < topo->vertexFaceOffsets[v + 1]; ++j) {
          int32_t g = topo->vertexFaces[j];
          if (!mark[g]) mark[g] = 2, order[nsub++] = g;
        }
      }
    }
  }
  // The sub-mesh in local numbering (vertices, values and edges in order of first use).
  int32_t *vmap = NEW(int32_t, nv), *cmap = NEW(int32_t, ncol), *emap = NEW(int32_t, topo->numEdges);
  int32_t *tri = NEW(int32_t, 3 * nsub), *tv = NEW(int32_t, 3 * nsub), *te = NEW(int32_t, 3 * nsub);
  int32_t *verts = NEW(int32_t, nv), *values = NEW(int32_t, ncol), *subEdges = NEW(int32_t, topo->numEdges);
  CHECK(vmap && cmap && emap && tri && tv && te && verts && values && subEdges);
  for (int32_t i = 0; i < nv; ++i) vmap[i] = -1;
  for (int32_t i = 0; i < ncol; ++i) cmap[i] = -1;
  for (int32_t i = 0; i < topo->numEdges; ++i) emap[i] = -1;
  int32_t numVerts = 0, numValues = 0, numEdges = 0;
  for (int32_t i = 0; i < nsub; ++i) {
    for (int k = 0; k < 3; ++k) {
      int32_t g = 3 * order[i] + k;
      int32_t v = triangles[g], c = triangleColors[g], e = topo->triEdges[g];
      if (vmap[v] < 0) vmap[v] = numVerts, verts[numVerts++] = v;
      if (cmap[c] < 0) cmap[c] = numValues, values[numValues++] = c;
      if (emap[e] < 0) emap[e] = numEdges, subEdges[numEdges++] = e;
      tri[3 * i + k] = vmap[v];
      tv[3 * i + k] = cmap[c];
      te[3 * i + k] = emap[e];
    }
  }
  int32_t *edgeVerts = NEW(int32_t, 2 * numEdges);
  uint8_t *edgeTags = NEW(uint8_t, numEdges), *corner = NEW(uint8_t, numVerts);
  double *pos = NEW(double, 2 * numVerts), *col = NEW(double, 3 * numValues);
  int32_t *valueVertex = NEW(int32_t, numValues);
  CHECK(edgeVerts && edgeTags && corner && pos && col && valueVertex);
  for (int32_t i = 0; i < numEdges; ++i) {
    int32_t e = subEdges[i];
    edgeVerts[2 * i] = vmap[topo->edgeVerts[2 * e]];
    edgeVerts[2 * i + 1] = vmap[topo->edgeVerts[2 * e + 1]];
    edgeTags[i] = topo->edgeTags[e];
  }
  for (int32_t i = 0; i < numVerts; ++i) {
    int32_t v = verts[i];
    corner[i] = topo->corner[v];
    pos[2 * i] = positions[2 * v];
    pos[2 * i + 1] = positions[2 * v + 1];
  }
  for (int32_t i = 0; i < numValues; ++i)
    for (int c = 0; c < 3; ++c) col[3 * i + c] = colors[3 * values[i] + c];
  for (int32_t i = 0; i < 3 * nsub; ++i) valueVertex[tv[i]] = tri[i];
  Mesh mesh = {numVerts, numValues, nsub, numEdges, tri, tv, te, edgeVerts, edgeTags, corner, valueVertex};

  uint8_t *sharpEdges = r->sharpEdges = NEW(uint8_t, numEdges);
  int32_t *edgeFaces = r->edgeFaces = NEW(int32_t, 2 * numEdges), *sides = NEW(int32_t, 3 * nsub);
  CHECK(sharpEdges && edgeFaces && sides);
  for (int32_t i = 0; i < 2 * numEdges; ++i) edgeFaces[i] = -1;
  for (int32_t i = 0; i < 3 * nsub; ++i) {
    int32_t e = te[i];
    sharpEdges[e] = edgeTags[e] == TEAR || edgeTags[e] == BORDER;
    edgeFaces[2 * e + (edgeFaces[2 * e] < 0 ? 0 : 1)] = i / 3;
    sides[i] = te[i];
  }
  r->values[0] = tv, r->sides[0] = sides;
  for (int32_t d = 0; d < depth; ++d) {
    Mesh child;
    CHECK(refineOnce(&mesh, pos, col, sides, &child, &pos, &col, &sides));
    mesh = child;
    r->values[d + 1] = mesh.triValues, r->sides[d + 1] = sides;
  }

  // Limit positions and colors, one output vertex per color value.
  double *limitPos = NEW(double, 2 * mesh.numVertices), *limitCol = NEW(double, 3 * mesh.numValues);
  float *vertices = r->vertices = NEW(float, 5 * mesh.numValues);
  CHECK(limitPos && limitCol && vertices);
  CHECK(vertexPoints(&mesh, pos, col, 1, limitPos, limitCol));
  for (int32_t c = 0; c < mesh.numValues; ++c) {
    int32_t v = mesh.valueVertex[c];
    vertices[5 * c] = (float)limitPos[2 * v];
    vertices[5 * c + 1] = (float)limitPos[2 * v + 1];
    vertices[5 * c + 2] = (float)limitCol[3 * c];
    vertices[5 * c + 3] = (float)limitCol[3 * c + 1];
    vertices[5 * c + 4] = (float)limitCol[3 * c + 2];
  }
  r->selected = selected, r->numFaces = nsub, r->numValues = mesh.numValues, r->numEdges = numEdges;
  return r;
}

// ---- adaptive triangles -----------------------------------------------------------------------

static double absolute(double x) { return __builtin_fabs(x); }

// fits of adaptiveIndices: level-d triangle t against the midpoints of level d + 1.
static int fits(const Refined *r, int32_t d, int32_t t, double scale, double colorTolerance, double positionTolerance) {
  const float *V = r->vertices;
  const int32_t *values = r->values[d], *sides = r->sides[d], *mids = r->values[d + 1];
  int32_t a = 5 * values[3 * t], b = 5 * values[3 * t + 1], c = 5 * values[3 * t + 2];
  double ax = V[a], ay = V[a + 1], bx = V[b], by = V[b + 1], cx = V[c], cy = V[c + 1];
  double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  for (int k = 0; k < 3; ++k) {
    int32_t m = 5 * mids[3 * (4 * t + 3) + k];
    double mx = V[m], my = V[m + 1];
    double wa = ((bx - mx) * (cy - my) - (by - my) * (cx - mx)) / area;
    double wb = ((cx - mx) * (ay - my) - (cy - my) * (ax - mx)) / area;
    double wc = 1 - wa - wb;
    for (int j = 2; j < 5; ++j) {
      double e = (double)V[m + j] - wa * (double)V[a + j] - wb * (double)V[b + j] - wc * (double)V[c + j];
      if (!(absolute(e) <= colorTolerance)) return 0;
    }
    int32_t e = sides[3 * t + k];
    if (e >= 0 && r->sharpEdges[e]) {
      int32_t p = 5 * values[3 * t + k], q = 5 * values[3 * t + (k + 1) % 3];
      double px = V[p], py = V[p + 1], dx = (double)V[q] - px, dy = (double)V[q + 1] - py;
      double off = absolute(dx * (my - py) - dy * (mx - px)) / js_hypot(dx, dy);
      if (!(off * scale <= positionTolerance)) return 0;
    }
  }
  return 1;
}

static int32_t neighbour(const Refined *r, int32_t f, int32_t e) {
  return r->edgeFaces[2 * e] == f ? r->edgeFaces[2 * e + 1] : r->edgeFaces[2 * e];
}

typedef struct {
  int32_t count;
  uint32_t *indices;
} Indices;

// adaptiveIndices of subdivide.ts: the triangles, 3 color values each.
EXPORT(adaptive)
Indices *adaptive(const Refined *r, int32_t depth, double scale, double colorTolerance, double positionTolerance) {
  int32_t D = depth, n = r->selected;
  int32_t *depthOf = NEW(int32_t, n);
  Indices *result = NEW(Indices, 1);
  uint32_t *out = NEW(uint32_t, 3 * (size_t)n << (2 * D));
  CHECK(depthOf && result && out);
  for (int32_t f = 0; f < n; ++f) {
    int32_t d = 0;
    for (; d < D; ++d) {
      int ok = 1;
      for (int32_t t = f << (2 * d); ok && t < (f + 1) << (2 * d); ++t) ok = fits(r, d, t, scale, colorTolerance, positionTolerance);
      if (ok) break;
    }
    depthOf[f] = d;
  }
  // Neighbours within one level of each other.
  const int32_t *sides0 = r->sides[0];
  for (int changed = 1; changed;) {
    changed = 0;
    for (int32_t f = 0; f < n; ++f) {
      for (int k = 0; k < 3; ++k) {
        int32_t g = neighbour(r, f, sides0[3 * f + k]);
        if (g >= 0 && g < n && depthOf[g] - 1 > depthOf[f]) depthOf[f] = depthOf[g] - 1, changed = 1;
      }
    }
  }
  int32_t size = 0;
  for (int32_t f = 0; f < n; ++f) {
    int32_t d = depthOf[f];
    const int32_t *values = r->values[d], *sides = r->sides[d];
    const int32_t *child = d < D ? r->values[d + 1] : values;
    for (int32_t t = f << (2 * d); t < (f + 1) << (2 * d); ++t) {
      // Sides whose neighbour across the control edge is a level deeper.
      int split = 0;
      for (int k = 0; k < 3; ++k) {
        int32_t e = sides[3 * t + k], g = e >= 0 ? neighbour(r, f, e) : -1;
        if (g >= 0 && g < n && depthOf[g] > d) split |= 1 << k;
      }
      int32_t v = 3 * t, m = 3 * (4 * t + 3);
      if (split == 0) {
        out[size++] = (uint32_t)values[v], out[size++] = (uint32_t)values[v + 1], out[size++] = (uint32_t)values[v + 2];
      } else if (split == 7) {
        for (int32_t i = 12 * t; i < 12 * t + 12; ++i) out[size++] = (uint32_t)child[i];
      } else if (split == 1 || split == 2 || split == 4) {
        int k = split >> 1, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        out[size++] = (uint32_t)values[v + k], out[size++] = (uint32_t)child[m + k], out[size++] = (uint32_t)values[v + k2];
        out[size++] = (uint32_t)child[m + k], out[size++] = (uint32_t)values[v + k1], out[size++] = (uint32_t)values[v + k2];
      } else {
        int k = split == 6 ? 1 : split == 5 ? 2 : 0, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        out[size++] = (uint32_t)values[v + k], out[size++] = (uint32_t)child[m + k], out[size++] = (uint32_t)values[v + k2];
        out[size++] = (uint32_t)child[m + k], out[size++] = (uint32_t)values[v + k1], out[size++] = (uint32_t)child[m + k1];
        out[size++] = (uint32_t)child[m + k], out[size++] = (uint32_t)child[m + k1], out[size++] = (uint32_t)values[v + k2];
      }
    }
  }
  result->count = size, result->indices = out;
  return result;
}
