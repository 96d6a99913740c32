// Piecewise smooth Loop subdivision of a control mesh, as the C++ library refines it with
// OpenSubdiv (src/subdiv/subdivision.cpp): Loop's masks; creases, tears and the image border
// infinitely sharp (edge mask 1/2-1/2, vertex mask 1/8-6/8-1/8); corner vertices fixed; colors
// face-varying, each side of a tear refined on its own as if the tear were a border; then every
// point pushed to its limit position and color. Uniform refinement of a set of control faces plus
// the one-ring they need; only the selected faces' children are drawn.
//
// The rules, written once per level over flat arrays:
//   vertex rule: corner (tagged, or more than two sharp edges) keeps its value; exactly two sharp
//     edges: crease, 3/4 of itself and 1/8 of each sharp neighbour (per color value: the
//     neighbours' values on its own side); otherwise Loop's smooth mask over the one-ring.
//   edge rule: sharp: the midpoint (per side of a tear); smooth: 3/8 of the ends, 1/8 of the two
//     opposite corners.
//   limit: the same classes with the limit masks (crease 1/6-4/6-1/6, smooth Loop's limit).
// A sharp neighbour is found from the faces around a vertex: each face contributes the corner
// after it and the corner before it when the edge to them is sharp. Every sharp edge is seen the
// same number of times from one color value's faces (once per side of a tear, twice for a crease
// inside one wedge, once on the border), so the mean of the contributions is the mean of the two
// ends.
import type { Level } from './image';

export const SMOOTH = 0;
export const SHARP = 1; // crease: sharp, colors continuous
export const TEAR = 2; // sharp, colors discontinuous
export const BORDER = 3; // on the image border: sharp

/** One level of the refinement: triangles, their corners' color values, edges and tags. */
interface Mesh {
  numVertices: number;
  numValues: number;
  tri: Int32Array; // 3 vertex indices per face
  triValues: Int32Array; // 3 color value indices per face
  triEdges: Int32Array; // edge k runs from corner k to corner k + 1
  edgeVerts: Int32Array; // 2 per edge
  edgeTags: Uint8Array;
  corner: Uint8Array; // 1 for a vertex tagged corner
  valueVertex: Int32Array; // the vertex of each color value
}

/** A level's control topology, built once: edges, tags, vertex stars and ring boxes. */
export interface Topology {
  level: Level;
  numEdges: number;
  triEdges: Int32Array;
  edgeVerts: Int32Array;
  edgeTags: Uint8Array;
  corner: Uint8Array;
  /** faces around each vertex (CSR) */
  vertexFaceOffsets: Int32Array;
  vertexFaces: Int32Array;
  /** per face the bounding box (x0, y0, x1, y1) of the control points its limit patch depends on */
  ringBoxes: Float64Array;
}

/** The topology of a level of a `width` x `height` image; NaN for both: an object's mesh, which has
 * no image corners (its boundary vertices are creases, as in MeshTopology::build with kNoFrame). */
export function buildTopology(level: Level, width: number, height: number): Topology {
  const { positions: p, triangles: tri } = level;
  const nv = p.length / 2, nf = tri.length / 3;
  // Faces around each vertex.
  const vertexFaceOffsets = new Int32Array(nv + 1);
  for (let i = 0; i < 3 * nf; ++i) vertexFaceOffsets[tri[i] + 1]++;
  for (let v = 0; v < nv; ++v) vertexFaceOffsets[v + 1] += vertexFaceOffsets[v];
  const vertexFaces = new Int32Array(3 * nf);
  const fill = vertexFaceOffsets.slice(0, nv);
  for (let i = 0; i < 3 * nf; ++i) vertexFaces[fill[tri[i]]++] = (i / 3) | 0;
  // The corner index (3f + k) of the side a -> b, or -1: among the faces around a.
  const side = (a: number, b: number) => {
    for (let j = vertexFaceOffsets[a]; j < vertexFaceOffsets[a + 1]; ++j) {
      const f = 3 * vertexFaces[j];
      for (let k = 0; k < 3; ++k) if (tri[f + k] === a && tri[f + (k === 2 ? 0 : k + 1)] === b) return f + k;
    }
    return -1;
  };
  // Edges in order of first use; a side takes the edge of the opposite side seen before it.
  const triEdges = new Int32Array(3 * nf).fill(-1), twin = new Int32Array(3 * nf);
  const ends = new Int32Array(6 * nf);
  let ne = 0;
  for (let i = 0; i < 3 * nf; ++i) {
    const a = tri[i], b = tri[i - (i % 3) + ((i + 1) % 3)];
    const o = (twin[i] = side(b, a));
    if (o >= 0 && triEdges[o] >= 0) {
      triEdges[i] = triEdges[o];
    } else {
      (ends[2 * ne] = a), (ends[2 * ne + 1] = b), (triEdges[i] = ne++);
    }
  }
  const edgeVerts = ends.slice(0, 2 * ne);
  const edgeTags = new Uint8Array(ne);
  for (let i = 0; i < 3 * nf; ++i) if (twin[i] < 0) edgeTags[triEdges[i]] = BORDER;
  const tag = (a: number, b: number, t: number) => {
    const i = side(a, b) >= 0 ? side(a, b) : side(b, a);
    if (i >= 0) edgeTags[triEdges[i]] = t;
  };
  for (let i = 0; i < level.creases.length; i += 2) tag(level.creases[i], level.creases[i + 1], SHARP);
  const endpoint = new Uint8Array(nv);
  for (const f of level.features) {
    const v = f.vertices;
    for (let k = 0; k + 1 < v.length; ++k) tag(v[k], v[k + 1], TEAR);
    if (v[0] !== v[v.length - 1]) endpoint[v[0]] = endpoint[v[v.length - 1]] = 1;
  }
  // Vertex tags (docs/format.md, "Edges, features and creases"; src/mesh/topology.cpp).
  const creases = new Uint8Array(nv), tears = new Uint8Array(nv);
  for (let e = 0; e < ne; ++e) {
    if (edgeTags[e] === SMOOTH) continue;
    const count = edgeTags[e] === TEAR ? tears : creases;
    count[edgeVerts[2 * e]]++;
    count[edgeVerts[2 * e + 1]]++;
  }
  const corner = new Uint8Array(nv);
  for (let v = 0; v < nv; ++v) {
    const x = p[2 * v], y = p[2 * v + 1];
    const imageCorner = width >= 0 && (x === 0 || x === width) && (y === 0 || y === height);
    const c = creases[v], t = tears[v];
    corner[v] = imageCorner || endpoint[v] || !((c === 0 && t === 0) || (c === 2 && t === 0) || (t === 2 && c === 0)) ? 1 : 0;
  }
  // Ring boxes: the limit patch of a face lies in the hull of the control points of the faces
  // around its corners (every mask is a convex combination), as the C++ renderer bounds it.
  const star = new Float64Array(4 * nv);
  for (let v = 0; v < nv; ++v) {
    let x0 = p[2 * v], y0 = p[2 * v + 1], x1 = x0, y1 = y0;
    for (let j = vertexFaceOffsets[v]; j < vertexFaceOffsets[v + 1]; ++j) {
      const f = vertexFaces[j];
      for (let k = 0; k < 3; ++k) {
        const u = tri[3 * f + k], x = p[2 * u], y = p[2 * u + 1];
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
      }
    }
    (star[4 * v] = x0), (star[4 * v + 1] = y0), (star[4 * v + 2] = x1), (star[4 * v + 3] = y1);
  }
  const ringBoxes = new Float64Array(4 * nf);
  for (let f = 0; f < nf; ++f) {
    const a = 4 * tri[3 * f], b = 4 * tri[3 * f + 1], c = 4 * tri[3 * f + 2];
    ringBoxes[4 * f] = Math.min(star[a], star[b], star[c]);
    ringBoxes[4 * f + 1] = Math.min(star[a + 1], star[b + 1], star[c + 1]);
    ringBoxes[4 * f + 2] = Math.max(star[a + 2], star[b + 2], star[c + 2]);
    ringBoxes[4 * f + 3] = Math.max(star[a + 3], star[b + 3], star[c + 3]);
  }
  return { level, numEdges: ne, triEdges, edgeVerts, edgeTags, corner, vertexFaceOffsets, vertexFaces, ringBoxes };
}

/** The limit surface over the selected faces: one vertex per color value. */
export interface Refined {
  depth: number;
  /** x, y, r, g, b per color value of the last level (image pixels; 0-255 colors, unclamped) */
  vertices: Float32Array;
  /** the selected faces are the sub-mesh's faces 0 .. selected - 1 */
  selected: number;
  /**
   * Every level's triangles as color values (3 per face; a value keeps its number in later
   * levels, so they index `vertices` too; the children of face t are faces 4t .. 4t + 3 of the
   * next level, 4t + 3 the middle one) and the sub-mesh edge each side lies on (-1: inside a
   * control face).
   */
  levels: Array<{ values: Int32Array; sides: Int32Array }>;
  /** per sub-mesh edge: 1 when it is a tear or on the border */
  sharpEdges: Uint8Array;
  /** per sub-mesh edge its two sub-mesh faces (-1: none) */
  edgeFaces: Int32Array;
}

// Smooth (Loop) masks of OpenSubdiv's Sdc::Scheme<SCHEME_LOOP>: edge weight of a valence-n vertex
// for refinement and for the limit (valence 6: 1/16 and 1/12, in vertexPoints).
function loopEdgeWeight(n: number): number {
  const beta = 0.25 * Math.cos((Math.PI * 2) / n) + 0.375;
  return (0.625 - beta * beta) / n;
}
function loopLimitEdgeWeight(n: number): number {
  const beta = 0.25 * Math.cos((Math.PI * 2) / n) + 0.375;
  const gamma = (0.625 - beta * beta) / n;
  return 1 / (n + 3 / (8 * gamma));
}

// The vertex masks (refinement, or limit when `limit`) applied to the positions (2 per vertex) and
// colors (3 per color value) of level m, into outPos and outCol. Each vertex's rule: corner (tagged,
// or more than two sharp edges) keeps its value; exactly two sharp edges: crease; else smooth.
// The sums run over the faces around each vertex and each color value: the neighbour after each
// corner (the one-ring, for the smooth mask) and the sharp neighbours (for the crease mask).
function vertexPoints(m: Mesh, pos: Float64Array, col: Float64Array, limit: boolean, outPos: Float64Array, outCol: Float64Array): void {
  const nv = m.numVertices, nc = m.numValues, nf = m.tri.length / 3;
  const { tri, triValues: tv, triEdges: te, edgeTags: tags, edgeVerts: ev } = m;
  const sharpEdges = new Uint8Array(nv);
  for (let e = 0; e < tags.length; ++e) {
    if (tags[e] !== SMOOTH) sharpEdges[ev[2 * e]]++, sharpEdges[ev[2 * e + 1]]++;
  }
  const ringP = new Float64Array(2 * nv), sharpP = new Float64Array(2 * nv), ringC = new Float64Array(3 * nc), sharpC = new Float64Array(3 * nc);
  const ringN = new Int32Array(nv), sharpN = new Int32Array(nv), ringNC = new Int32Array(nc), sharpNC = new Int32Array(nc);
  for (let f = 0; f < nf; ++f) {
    for (let k = 0; k < 3; ++k) {
      const i = 3 * f + k, next = 3 * f + (k === 2 ? 0 : k + 1), prev = 3 * f + (k === 0 ? 2 : k - 1);
      const v = 2 * tri[i], n = 2 * tri[next], p = 2 * tri[prev];
      const c = 3 * tv[i], cn = 3 * tv[next], cp = 3 * tv[prev];
      ringN[tri[i]]++, ringNC[tv[i]]++;
      ringP[v] += pos[n], ringP[v + 1] += pos[n + 1];
      ringC[c] += col[cn], ringC[c + 1] += col[cn + 1], ringC[c + 2] += col[cn + 2];
      if (tags[te[i]] !== SMOOTH) {
        sharpN[tri[i]]++, sharpNC[tv[i]]++;
        sharpP[v] += pos[n], sharpP[v + 1] += pos[n + 1];
        sharpC[c] += col[cn], sharpC[c + 1] += col[cn + 1], sharpC[c + 2] += col[cn + 2];
      }
      if (tags[te[prev]] !== SMOOTH) {
        sharpN[tri[i]]++, sharpNC[tv[i]]++;
        sharpP[v] += pos[p], sharpP[v + 1] += pos[p + 1];
        sharpC[c] += col[cp], sharpC[c + 1] += col[cp + 1], sharpC[c + 2] += col[cp + 2];
      }
    }
  }
  // Per vertex the weights of itself and of the sums (crease: the sharp sum, smooth: the ring).
  const crease = limit ? 2 / 3 : 0.75, regular = limit ? 1 / 12 : 0.0625;
  const self = new Float64Array(nv), other = new Float64Array(nv), useRing = new Uint8Array(nv);
  for (let v = 0; v < nv; ++v) {
    const s = sharpEdges[v];
    if (m.corner[v] || s > 2 || (s === 2 && sharpN[v] === 0)) {
      self[v] = 1;
    } else if (s === 2) {
      self[v] = crease;
      other[v] = (1 - crease) / sharpN[v];
    } else {
      const n = ringN[v], w = n === 6 ? regular : limit ? loopLimitEdgeWeight(n) : loopEdgeWeight(n);
      self[v] = 1 - w * n;
      other[v] = w;
      useRing[v] = 1;
    }
  }
  for (let v = 0; v < nv; ++v) {
    const a = self[v], b = other[v], sum = useRing[v] ? ringP : sharpP;
    outPos[2 * v] = a * pos[2 * v] + b * sum[2 * v];
    outPos[2 * v + 1] = a * pos[2 * v + 1] + b * sum[2 * v + 1];
  }
  // A color value's crease mask counts its own side's sharp neighbours.
  for (let c = 0; c < nc; ++c) {
    const v = m.valueVertex[c], o = 3 * c;
    let a = self[v], b = other[v];
    const sum = useRing[v] ? ringC : sharpC;
    if (!useRing[v] && b !== 0) b = sharpNC[c] ? (1 - crease) / sharpNC[c] : ((a = 1), 0);
    else if (useRing[v] && ringNC[c] !== ringN[v]) {
      const n = ringNC[c], w = n === 6 ? regular : limit ? loopLimitEdgeWeight(n) : loopEdgeWeight(n);
      (a = 1 - w * n), (b = w);
    }
    outCol[o] = a * col[o] + b * sum[o];
    outCol[o + 1] = a * col[o + 1] + b * sum[o + 1];
    outCol[o + 2] = a * col[o + 2] + b * sum[o + 2];
  }
}

// One step of Loop subdivision: topology, positions and colors.
function refineOnce(m: Mesh, pos: Float64Array, col: Float64Array, sides: Int32Array): { mesh: Mesh; pos: Float64Array; col: Float64Array; sides: Int32Array } {
  const nv = m.numVertices, nc = m.numValues, nf = m.tri.length / 3, ne = m.edgeTags.length;
  const { tri, triValues: tv, triEdges: te, edgeVerts: ev, edgeTags: tags } = m;

  // Edge values: one per edge, two for a tear (side 0: the face that runs it edgeVerts[0] -> [1]).
  const edgeValue = new Int32Array(ne);
  let numValues = nc;
  for (let e = 0; e < ne; ++e) {
    edgeValue[e] = numValues;
    numValues += tags[e] === TEAR ? 2 : 1;
  }

  // Vertex points.
  const newPos = new Float64Array(2 * (nv + ne));
  const newCol = new Float64Array(3 * numValues);
  vertexPoints(m, pos, col, false, newPos, newCol);

  // Edge points: 1/8 of the opposite corners gathered per face, then the ends.
  const opposite = new Float64Array(2 * ne);
  for (let i = 0; i < 3 * nf; ++i) {
    const e = te[i], o = tri[i - (i % 3) + ((i + 2) % 3)];
    opposite[2 * e] += pos[2 * o];
    opposite[2 * e + 1] += pos[2 * o + 1];
  }
  for (let e = 0; e < ne; ++e) {
    const a = ev[2 * e], b = ev[2 * e + 1], out = 2 * (nv + e);
    for (let c = 0; c < 2; ++c) {
      const ends = pos[2 * a + c] + pos[2 * b + c];
      newPos[out + c] = tags[e] === SMOOTH ? 0.375 * ends + 0.125 * opposite[2 * e + c] : 0.5 * ends;
    }
  }
  // Edge colors: per face corner, its edge's value on its side.
  const done = new Uint8Array(numValues);
  for (let i = 0; i < 3 * nf; ++i) {
    const e = te[i], t = tags[e];
    const value = edgeValue[e] + (t === TEAR && tri[i] !== ev[2 * e] ? 1 : 0);
    const a = tv[i], b = tv[i - (i % 3) + ((i + 1) % 3)], o = tv[i - (i % 3) + ((i + 2) % 3)];
    const out = 3 * value;
    if (t !== SMOOTH) {
      if (done[value]) continue;
      done[value] = 1;
      for (let c = 0; c < 3; ++c) newCol[out + c] = 0.5 * (col[3 * a + c] + col[3 * b + c]);
    } else {
      // Both faces of a smooth edge add their opposite corner; the first also adds the ends.
      const first = !done[value];
      done[value] = 1;
      for (let c = 0; c < 3; ++c) {
        newCol[out + c] += 0.125 * col[3 * o + c] + (first ? 0.375 * (col[3 * a + c] + col[3 * b + c]) : 0);
      }
    }
  }

  // Child topology: corner k of face f keeps corner k in child 4f + k; child 4f + 3 joins the
  // edge points. Child edges: 2e and 2e + 1 halve edge e (from edgeVerts[0] and from [1]), then
  // three inner edges per face.
  const cnf = 4 * nf, cne = 2 * ne + 3 * nf;
  const ctri = new Int32Array(3 * cnf), cval = new Int32Array(3 * cnf), cte = new Int32Array(3 * cnf);
  const cev = new Int32Array(2 * cne), ctags = new Uint8Array(cne);
  for (let e = 0; e < ne; ++e) {
    cev[4 * e] = ev[2 * e];
    cev[4 * e + 1] = cev[4 * e + 2] = nv + e;
    cev[4 * e + 3] = ev[2 * e + 1];
    ctags[2 * e] = ctags[2 * e + 1] = tags[e];
  }
  const childSides = new Int32Array(3 * cnf).fill(-1); // the corner children keep two parent sides
  const mid = new Int32Array(3), midValue = new Int32Array(3), halfFrom = new Int32Array(3), halfTo = new Int32Array(3);
  for (let f = 0; f < nf; ++f) {
    const b3 = 3 * f, inner = 2 * ne + 3 * f; // inner edge j joins mid[j] and mid[j + 1]
    for (let k = 0; k < 3; ++k) {
      const e = te[b3 + k], forward = tri[b3 + k] === ev[2 * e];
      mid[k] = nv + e; // the point of edge k (corner k -> k + 1)
      midValue[k] = edgeValue[e] + (tags[e] === TEAR && !forward ? 1 : 0);
      halfFrom[k] = 2 * e + (forward ? 0 : 1); // the half of edge k at corner k
      halfTo[k] = 2 * e + (forward ? 1 : 0); // the half at corner k + 1
    }
    for (let k = 0; k < 3; ++k) {
      const prev = (k + 2) % 3, o = 3 * (4 * f + k);
      cev[2 * (inner + k)] = mid[k];
      cev[2 * (inner + k) + 1] = mid[(k + 1) % 3];
      ctri[o] = tri[b3 + k], ctri[o + 1] = mid[k], ctri[o + 2] = mid[prev];
      cval[o] = tv[b3 + k], cval[o + 1] = midValue[k], cval[o + 2] = midValue[prev];
      cte[o] = halfFrom[k], cte[o + 1] = inner + prev, cte[o + 2] = halfTo[prev];
      childSides[o] = sides[b3 + k], childSides[o + 2] = sides[b3 + prev];
      const c = 3 * (4 * f + 3) + k;
      ctri[c] = mid[k], cval[c] = midValue[k], cte[c] = inner + k;
    }
  }
  const corner = new Uint8Array(nv + ne);
  corner.set(m.corner);
  const valueVertex = new Int32Array(numValues);
  valueVertex.set(m.valueVertex);
  for (let e = 0; e < ne; ++e) {
    valueVertex[edgeValue[e]] = nv + e;
    if (tags[e] === TEAR) valueVertex[edgeValue[e] + 1] = nv + e;
  }
  const mesh: Mesh = {
    numVertices: nv + ne, numValues, tri: ctri, triValues: cval, triEdges: cte, edgeVerts: cev,
    edgeTags: ctags, corner, valueVertex,
  };
  return { mesh, pos: newPos, col: newCol, sides: childSides };
}

/**
 * Refines `faces` (control face indices; all faces when null) `depth` times and pushes the result
 * to the limit. The one-ring of the faces is refined with them so that their children are exact.
 */
export function refine(topo: Topology, faces: Int32Array | null, depth: number): Refined {
  const level = topo.level;
  const nf = level.triangles.length / 3;
  // Selected faces first, then the faces around their corners.
  let order: Int32Array;
  let selected: number;
  if (!faces) {
    order = new Int32Array(nf);
    for (let f = 0; f < nf; ++f) order[f] = f;
    selected = nf;
  } else {
    const mark = new Uint8Array(nf);
    const list: number[] = [];
    for (const f of faces) if (!mark[f]) (mark[f] = 1), list.push(f);
    selected = list.length;
    for (let i = 0; i < selected; ++i) {
      for (let k = 0; k < 3; ++k) {
        const v = level.triangles[3 * list[i] + k];
        for (let j = topo.vertexFaceOffsets[v]; j < topo.vertexFaceOffsets[v + 1]; ++j) {
          const g = topo.vertexFaces[j];
          if (!mark[g]) (mark[g] = 2), list.push(g);
        }
      }
    }
    order = Int32Array.from(list);
  }
  // The sub-mesh in local numbering (vertices, values and edges in order of first use).
  const nv = level.positions.length / 2, ncol = level.colors.length / 3, nsub = order.length;
  const vmap = new Int32Array(nv).fill(-1), cmap = new Int32Array(ncol).fill(-1), emap = new Int32Array(topo.numEdges).fill(-1);
  const tri = new Int32Array(3 * nsub), tv = new Int32Array(3 * nsub), te = new Int32Array(3 * nsub);
  const verts = new Int32Array(Math.min(nv, 3 * nsub)), values = new Int32Array(Math.min(ncol, 3 * nsub));
  const subEdges = new Int32Array(Math.min(topo.numEdges, 3 * nsub));
  let numVerts = 0, numValues = 0, numEdges = 0;
  for (let i = 0; i < nsub; ++i) {
    for (let k = 0; k < 3; ++k) {
      const g = 3 * order[i] + k;
      const v = level.triangles[g], c = level.triangleColors[g], e = topo.triEdges[g];
      if (vmap[v] < 0) (vmap[v] = numVerts), (verts[numVerts++] = v);
      if (cmap[c] < 0) (cmap[c] = numValues), (values[numValues++] = c);
      if (emap[e] < 0) (emap[e] = numEdges), (subEdges[numEdges++] = e);
      tri[3 * i + k] = vmap[v];
      tv[3 * i + k] = cmap[c];
      te[3 * i + k] = emap[e];
    }
  }
  const edgeVerts = new Int32Array(2 * numEdges), edgeTags = new Uint8Array(numEdges);
  for (let i = 0; i < numEdges; ++i) {
    const e = subEdges[i];
    edgeVerts[2 * i] = vmap[topo.edgeVerts[2 * e]];
    edgeVerts[2 * i + 1] = vmap[topo.edgeVerts[2 * e + 1]];
    edgeTags[i] = topo.edgeTags[e];
  }
  const corner = new Uint8Array(numVerts);
  let pos: Float64Array = new Float64Array(2 * numVerts);
  for (let i = 0; i < numVerts; ++i) {
    const v = verts[i];
    corner[i] = topo.corner[v];
    pos[2 * i] = level.positions[2 * v];
    pos[2 * i + 1] = level.positions[2 * v + 1];
  }
  let col: Float64Array = new Float64Array(3 * numValues);
  for (let i = 0; i < numValues; ++i) {
    for (let c = 0; c < 3; ++c) col[3 * i + c] = level.colors[3 * values[i] + c];
  }
  const valueVertex = new Int32Array(numValues);
  for (let i = 0; i < tri.length; ++i) valueVertex[tv[i]] = tri[i];
  let mesh: Mesh = {
    numVertices: numVerts, numValues, tri, triValues: tv, triEdges: te, edgeVerts, edgeTags, corner, valueVertex,
  };

  const sharpEdges = new Uint8Array(numEdges), edgeFaces = new Int32Array(2 * numEdges).fill(-1);
  for (let i = 0; i < 3 * nsub; ++i) {
    const e = te[i];
    sharpEdges[e] = edgeTags[e] === TEAR || edgeTags[e] === BORDER ? 1 : 0;
    edgeFaces[2 * e + (edgeFaces[2 * e] < 0 ? 0 : 1)] = (i / 3) | 0;
  }
  let sides: Int32Array = Int32Array.from(te);
  const levels: Refined['levels'] = [{ values: tv, sides }];
  for (let d = 0; d < depth; ++d) {
    ({ mesh, pos, col, sides } = refineOnce(mesh, pos, col, sides));
    levels.push({ values: mesh.triValues, sides });
  }

  // Limit positions and colors, one output vertex per color value.
  const limitPos = new Float64Array(pos.length), limitCol = new Float64Array(col.length);
  vertexPoints(mesh, pos, col, true, limitPos, limitCol);
  const vertices = new Float32Array(5 * mesh.numValues);
  for (let c = 0; c < mesh.numValues; ++c) {
    const v = mesh.valueVertex[c];
    vertices[5 * c] = limitPos[2 * v];
    vertices[5 * c + 1] = limitPos[2 * v + 1];
    vertices[5 * c + 2] = limitCol[3 * c];
    vertices[5 * c + 3] = limitCol[3 * c + 1];
    vertices[5 * c + 4] = limitCol[3 * c + 2];
  }
  return { depth, vertices, selected, levels, sharpEdges, edgeFaces };
}

/** The last level's triangles over the selected faces: the uniform refinement. */
export function uniformIndices(r: Refined): Uint32Array {
  return Uint32Array.from(r.levels[r.depth].values.subarray(0, 3 * r.selected * 4 ** r.depth));
}

/**
 * Triangles over the selected faces, each control face only as deep as it needs: the shallowest
 * level whose triangles are within `colorTolerance` (levels) of the next level's points, measured
 * where those points are drawn, and whose tear and border sides are within `positionTolerance`
 * output pixels of them (`scale` output pixels per image pixel). Faces that share an edge differ by
 * at most one level, and the coarser one takes the finer one's points on that edge (its triangles
 * there split in two, three or four): no cracks, no T-junctions, every point a limit point.
 */
export function adaptiveIndices(r: Refined, scale: number, colorTolerance: number, positionTolerance: number): Uint32Array {
  const V = r.vertices, D = r.depth, n = r.selected;
  // Error of level-d triangle t: its three sides against the midpoints of level d + 1.
  const fits = (d: number, t: number): boolean => {
    const { values, sides } = r.levels[d], mids = r.levels[d + 1].values;
    const a = 5 * values[3 * t], b = 5 * values[3 * t + 1], c = 5 * values[3 * t + 2];
    const area = (V[b] - V[a]) * (V[c + 1] - V[a + 1]) - (V[b + 1] - V[a + 1]) * (V[c] - V[a]);
    for (let k = 0; k < 3; ++k) {
      const m = 5 * mids[3 * (4 * t + 3) + k];
      // Barycentric weights of the midpoint's limit position in the coarse triangle.
      const wa = ((V[b] - V[m]) * (V[c + 1] - V[m + 1]) - (V[b + 1] - V[m + 1]) * (V[c] - V[m])) / area;
      const wb = ((V[c] - V[m]) * (V[a + 1] - V[m + 1]) - (V[c + 1] - V[m + 1]) * (V[a] - V[m])) / area;
      const wc = 1 - wa - wb;
      for (let j = 2; j < 5; ++j) {
        if (!(Math.abs(V[m + j] - wa * V[a + j] - wb * V[b + j] - wc * V[c + j]) <= colorTolerance)) return false;
      }
      const e = sides[3 * t + k];
      if (e >= 0 && r.sharpEdges[e]) {
        const p = 5 * values[3 * t + k], q = 5 * values[3 * t + ((k + 1) % 3)];
        const dx = V[q] - V[p], dy = V[q + 1] - V[p + 1];
        const off = Math.abs(dx * (V[m + 1] - V[p + 1]) - dy * (V[m] - V[p])) / Math.hypot(dx, dy);
        if (!(off * scale <= positionTolerance)) return false;
      }
    }
    return true;
  };
  const depthOf = new Int32Array(n);
  for (let f = 0; f < n; ++f) {
    let d = 0;
    for (; d < D; ++d) {
      let ok = true;
      for (let t = f * 4 ** d; ok && t < (f + 1) * 4 ** d; ++t) ok = fits(d, t);
      if (ok) break;
    }
    depthOf[f] = d;
  }
  // Neighbours within one level of each other.
  const neighbour = (f: number, e: number) => (r.edgeFaces[2 * e] === f ? r.edgeFaces[2 * e + 1] : r.edgeFaces[2 * e]);
  const sides0 = r.levels[0].sides;
  for (let changed = true; changed; ) {
    changed = false;
    for (let f = 0; f < n; ++f) {
      for (let k = 0; k < 3; ++k) {
        const g = neighbour(f, sides0[3 * f + k]);
        if (g >= 0 && g < n && depthOf[g] - 1 > depthOf[f]) (depthOf[f] = depthOf[g] - 1), (changed = true);
      }
    }
  }
  // A face at depth d < D gives at most 4 triangles per level-d triangle: at most the uniform count.
  const out = new Uint32Array(3 * n * 4 ** D);
  let size = 0;
  for (let f = 0; f < n; ++f) {
    const d = depthOf[f];
    const { values, sides } = r.levels[d];
    const child = d < D ? r.levels[d + 1].values : values;
    for (let t = f * 4 ** d; t < (f + 1) * 4 ** d; ++t) {
      // Sides whose neighbour across the control edge is a level deeper.
      let split = 0;
      for (let k = 0; k < 3; ++k) {
        const e = sides[3 * t + k], g = e >= 0 ? neighbour(f, e) : -1;
        if (g >= 0 && g < n && depthOf[g] > d) split |= 1 << k;
      }
      const v = 3 * t, m = 3 * (4 * t + 3);
      if (split === 0) {
        out[size++] = values[v], out[size++] = values[v + 1], out[size++] = values[v + 2];
      } else if (split === 7) {
        for (let i = 12 * t; i < 12 * t + 12; ++i) out[size++] = child[i];
      } else if (split === 1 || split === 2 || split === 4) {
        // the split side: corner k to k1; two triangles
        const k = split >> 1, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        out[size++] = values[v + k], out[size++] = child[m + k], out[size++] = values[v + k2];
        out[size++] = child[m + k], out[size++] = values[v + k1], out[size++] = values[v + k2];
      } else {
        // the whole side: corner j to j + 1; sides k and k1 split (corners k, k1, k2): three triangles
        const k = split === 6 ? 1 : split === 5 ? 2 : 0, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        out[size++] = values[v + k], out[size++] = child[m + k], out[size++] = values[v + k2];
        out[size++] = child[m + k], out[size++] = values[v + k1], out[size++] = child[m + k1];
        out[size++] = child[m + k], out[size++] = child[m + k1], out[size++] = values[v + k2];
      }
    }
  }
  return out.slice(0, size);
}
