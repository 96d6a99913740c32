// Validation of a vector image: a port of src/mesh/validate.cpp and of the checks of
// MeshTopology::build (src/mesh/topology.cpp), in the same order and with the same one-line
// messages, so that the viewer refuses exactly what the C++ reader refuses. Float64 throughout,
// as in C++. Plain loops over typed arrays: this runs on every file a page opens.
//
// Order (each check may rely on the previous ones): finite values, positions in the image, index
// ranges; feature ids; topology (edges shared by one or two consistently oriented triangles,
// creases and features as chains of interior edges); positive areas; used vertices; border edges
// on the image rectangle and its corners present; tiling (angle sums, total area); the wedge
// color rules. Then the pyramid records, strokes and metadata. (Counts are capped where they are
// read: decode.ts checks each against MAX_ELEMENTS before it sizes an array.)
import { Level, SvecError, SvecImage } from './image';

export const MAX_ELEMENTS = 2 ** 26;
export const MAX_LEVELS = 64;
export const MAX_DIMENSION = 65536;

/** A level's pyramid record (docs/format.md, "Levels and the pyramid"): the parent of each vertex
 * in the level before, and the collapses [removed, kept] that made the level, flattened. */
export interface PyramidRecord {
  parents: ArrayLike<number>;
  collapses: ArrayLike<number>;
}

export function fail(message: string): never {
  throw new SvecError(message);
}

/** v as printf's "%g" writes it (6 significant digits), as the C++ messages print numbers. */
export function num(v: number): string {
  if (!isFinite(v)) return isNaN(v) ? 'nan' : v < 0 ? '-inf' : 'inf';
  if (!v) return 1 / v < 0 ? '-0' : '0';
  const [mantissa, e] = v.toExponential(5).split('e'), exponent = +e;
  const trim = (s: string) => (s.includes('.') ? s.replace(/\.?0+$/, '') : s);
  if (exponent >= -4 && exponent < 6) return trim(v.toFixed(5 - exponent));
  return `${trim(mantissa)}e${exponent < 0 ? '-' : '+'}${String(Math.abs(exponent)).padStart(2, '0')}`;
}

const point = (x: number, y: number) => `(${num(x)}, ${num(y)})`;

/** Control characters as \xNN, for one-line messages. */
export const escape = (s: string) => s.replace(/[\x00-\x1f\x7f]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`);

/** The corner after h in its triangle, and the one before. */
export const next3 = (h: number) => (h % 3 === 2 ? h - 2 : h + 1);
export const prev3 = (h: number) => (h % 3 ? h - 1 : h + 2);

/** A stable counting sort of `items` (default 0..key.length-1) by key[i], 0 <= key[i] < n: the
 * items in order, and where each key's run starts (run k is start[k] to start[k + 1]). */
export function sortBy(key: ArrayLike<number>, n: number, items?: Int32Array): [Int32Array, Int32Array] {
  const m = key.length, start = new Int32Array(n + 2), order = new Int32Array(m);
  for (let i = 0; i < m; i++) start[key[i] + 2]++;
  for (let k = 2; k < n + 2; k++) start[k] += start[k - 1];
  for (let j = 0; j < m; j++) {
    const i = items ? items[j] : j;
    order[start[key[i] + 1]++] = i;
  }
  return [order, start];
}

// Edge tags.
const CREASE = 1, TEAR = 2, BORDER = 3;

/** The edges of a level, sorted by (a, b) with a < b: their triangles (g = -1 on the border) and
 * tags (0 smooth, 1 crease, 2 tear, 3 border); and the twin of each half-edge (corner h stands
 * for the half-edge from t[h] to t[next3(h)]), -1 on the border. */
export interface Topology {
  a: Int32Array;
  b: Int32Array;
  f: Int32Array;
  g: Int32Array;
  tag: Uint8Array;
  twin: Int32Array;
}

/** The edges of triangles t over nv vertices (MeshTopology::build without the creases and
 * features), or the message of the first problem. */
export function edges(t: Int32Array, nv: number): Topology | string {
  const nh = t.length, lo = new Int32Array(nh), hi = new Int32Array(nh);
  for (let h = 0; h < nh; h++) {
    const x = t[h], y = t[next3(h)];
    if (x < 0 || x >= nv) return `triangle ${(h / 3) | 0} refers to vertex ${x}, out of range (${nv} vertices)`;
    if (x === y) return `triangle ${(h / 3) | 0} repeats vertex ${x}`;
    lo[h] = x < y ? x : y;
    hi[h] = x < y ? y : x;
  }
  // The half-edges by (lo, hi, index): each undirected edge occurs once (border) or twice in
  // opposite directions (interior).
  const [order] = sortBy(lo, nv, sortBy(hi, nv)[0]);
  const a = new Int32Array(nh), b = new Int32Array(nh), f = new Int32Array(nh), g = new Int32Array(nh), twin = new Int32Array(nh).fill(-1);
  let ne = 0;
  for (let i = 0; i < nh; ne++) {
    const h = order[i], k = order[i + 1], x = lo[h], y = hi[h], pair = i + 1 < nh && lo[k] === x && hi[k] === y;
    if (pair && i + 2 < nh && lo[order[i + 2]] === x && hi[order[i + 2]] === y) return `edge (${x}, ${y}) is shared by more than two triangles`;
    (a[ne] = x), (b[ne] = y), (f[ne] = (h / 3) | 0), (g[ne] = pair ? (k / 3) | 0 : -1);
    if (pair && t[h] === t[k]) return `triangles ${f[ne]} and ${g[ne]} are oriented inconsistently across edge (${x}, ${y})`;
    if (pair) (twin[h] = k), (twin[k] = h);
    i += pair ? 2 : 1;
  }
  const tag = new Uint8Array(ne);
  for (let e = 0; e < ne; e++) if (g[e] < 0) tag[e] = BORDER;
  return { a: a.subarray(0, ne), b: b.subarray(0, ne), f: f.subarray(0, ne), g: g.subarray(0, ne), tag, twin };
}

/** MeshTopology::build without the vertex tags: the edges (given, or found), creases and
 * features marked; `prefix` starts its messages. */
export function topology(m: Level, nv: number, prefix = '', found = edges(m.triangles, nv)): Topology {
  const bad = (message: string): never => fail(prefix + message);
  const topo = typeof found === 'string' ? bad(found) : found, { a, b, tag } = topo, ne = a.length;
  const mark = (x: number, y: number, kind: number, what: string) => {
    if (x < 0 || x >= nv || y < 0 || y >= nv) bad(`${what} refers to vertex ${x < 0 || x >= nv ? x : y}, out of range (${nv} vertices)`);
    // Binary search for (min, max).
    const u = Math.min(x, y), v = Math.max(x, y);
    let l = 0, r = ne;
    while (l < r) {
      const mid = (l + r) >> 1;
      if (a[mid] < u || (a[mid] === u && b[mid] < v)) l = mid + 1;
      else r = mid;
    }
    if (l === ne || a[l] !== u || b[l] !== v) bad(`${what}: (${x}, ${y}) is not an edge of the mesh`);
    if (tag[l] === BORDER) bad(`${what}: (${x}, ${y}) lies on the image border`);
    if (tag[l]) bad(`${what}: edge (${x}, ${y}) is already a ${tag[l] === TEAR ? 'feature edge' : 'crease'}`);
    tag[l] = kind;
  };
  for (let i = 0; i < m.creases.length; i += 2) mark(m.creases[i], m.creases[i + 1], CREASE, `crease ${i / 2}`);
  m.features.forEach(({ id, vertices: v }, i) => {
    const what = `feature ${i} (id ${id})`;
    if (v.length < 2) bad(`${what} has fewer than two vertices`);
    for (let k = 1; k < v.length; k++) mark(v[k - 1], v[k], TEAR, what);
  });
  return topo;
}

/** The root of c in a union-find forest (halving the path on the way). */
function find(root: Int32Array, c: number) {
  while (root[c] !== c) c = root[c] = root[root[c]];
  return c;
}

/** The corner of triangle f at vertex v. */
const corner = (t: Int32Array, f: number, v: number) => 3 * f + (t[3 * f] === v ? 0 : t[3 * f + 1] === v ? 1 : 2);

/** face_varying_indices: one color index per wedge (corners of a vertex joined across edges
 * that are not tears), numbered in order of first use; and their count. */
export function wedges(m: Level, { a, b, f, g, tag }: Topology): [Int32Array, number] {
  const t = m.triangles, root = new Int32Array(t.length);
  for (let c = 0; c < t.length; c++) root[c] = c;
  for (let e = 0; e < a.length; e++)
    if (g[e] >= 0 && tag[e] !== TEAR)
      for (let v = a[e], k = 0; k < 2; k++, v = b[e]) root[find(root, corner(t, f[e], v))] = find(root, corner(t, g[e], v));
  const id = new Int32Array(t.length).fill(-1), out = new Int32Array(t.length);
  let n = 0;
  for (let c = 0; c < t.length; c++) {
    const r = find(root, c);
    if (id[r] < 0) id[r] = n++;
    out[c] = id[r];
  }
  return [out, n];
}

function validateLevel(m: Level, width: number, height: number, level: number, topo?: Topology): void {
  const prefix = `level ${level}: `, bad = (message: string): never => fail(prefix + message);
  const p = m.positions, t = m.triangles, tc = m.triangleColors, c = m.colors;
  const nv = p.length / 2, nc = c.length / 3, nf = t.length / 3;
  const at = (v: number) => point(p[2 * v], p[2 * v + 1]);

  for (let v = 0; v < nv; v++) {
    const x = p[2 * v], y = p[2 * v + 1];
    if (!isFinite(x) || !isFinite(y)) bad(`vertex ${v} position ${at(v)} is not finite`);
    if (x < 0 || x > width || y < 0 || y > height) bad(`vertex ${v} position ${at(v)} is outside the image [0, ${width}] x [0, ${height}]`);
  }
  // A level the decoder built (with its topology) has finite colors, indices in range and wedge
  // colors by construction: the checks marked * are for the others.
  const built = !!topo;
  for (let i = 0; i < 3 * nc && !built; i++) // *
    if (!isFinite(c[i])) bad(`color ${(i / 3) | 0} (${Array.from(c.subarray(i - (i % 3), i - (i % 3) + 3), num).join(', ')}) is not finite`);
  // Vertex indices before color indices: without triangle_colors (JSON) these are copies of them.
  for (let h = 0; h < t.length && !built; h++) // *
    if (t[h] < 0 || t[h] >= nv) bad(`triangle ${(h / 3) | 0} refers to vertex ${t[h]}, out of range (${nv} vertices)`);
  for (let h = 0; h < t.length && !built; h++) // *
    if (tc[h] < 0 || tc[h] >= nc) bad(`triangle_colors ${(h / 3) | 0} refers to color ${tc[h]}, out of range (${nc} colors)`);
  const ids = new Set<number>();
  m.features.forEach(({ id, saliency }, i) => {
    if (ids.has(id)) bad(`feature ${i} repeats id ${id} (ids must be unique within a level)`);
    ids.add(id);
    if (!isFinite(saliency)) bad(`feature ${i} (id ${id}) saliency ${num(saliency)} is not finite`);
  });
  const { a, b, f: ef, g: eg, tag } = topo ?? topology(m, nv, prefix);

  // Signed areas, and the used vertices.
  const area = new Float64Array(nf), used = new Uint8Array(nv);
  for (let f = 0; f < nf; f++) {
    const u = t[3 * f], v = t[3 * f + 1], w = t[3 * f + 2];
    const s = (area[f] = 0.5 * ((p[2 * v] - p[2 * u]) * (p[2 * w + 1] - p[2 * u + 1]) - (p[2 * v + 1] - p[2 * u + 1]) * (p[2 * w] - p[2 * u])));
    if (!(s > 0)) bad(`triangle ${f} (${u}, ${v}, ${w}) is flipped or degenerate (signed area ${num(s)})`);
    used[u] = used[v] = used[w] = 1;
  }
  for (let v = 0; v < nv; v++) if (!used[v]) bad(`vertex ${v} ${at(v)} is used by no triangle`);

  // Sides of the image rectangle each vertex lies on, exactly: 1 left, 2 right, 4 top, 8 bottom;
  // and the image corners.
  const sides = new Uint8Array(nv), border = new Uint8Array(nv);
  let corners = 0;
  for (let v = 0; v < nv; v++) {
    const x = p[2 * v], y = p[2 * v + 1];
    const s = (sides[v] = +(x === 0) | (+(x === width) << 1) | (+(y === 0) << 2) | (+(y === height) << 3));
    // corners: 1 (0, 0), 2 (W, 0), 4 (W, H), 8 (0, H)
    corners |= s === 5 ? 1 : s === 6 ? 2 : s === 10 ? 4 : s === 9 ? 8 : 0;
  }
  for (let e = 0; e < a.length; e++) {
    if (eg[e] >= 0) continue;
    const u = a[e], v = b[e];
    if (!(sides[u] & sides[v]))
      bad(`edge (${u}, ${v}) from ${at(u)} to ${at(v)} has a triangle on one side only but does not lie on the image border (a gap or a hole in the mesh)`);
    border[u] = border[v] = 1;
  }
  for (let k = 0; k < 4; k++)
    if (!(corners & (1 << k))) bad(`no vertex at the image corner ${point(k % 3 ? width : 0, k > 1 ? height : 0)}`);

  // Tiling: angle sums per vertex, then the total area (summed compensated, as C++ sums it in
  // long double).
  const angles = new Float64Array(nv);
  let total = 0, lost = 0;
  for (let h = 0; h < t.length; h++) {
    const u = t[h], v = t[next3(h)], w = t[prev3(h)];
    const ux = p[2 * v] - p[2 * u], uy = p[2 * v + 1] - p[2 * u + 1], vx = p[2 * w] - p[2 * u], vy = p[2 * w + 1] - p[2 * u + 1];
    angles[u] += Math.atan2(ux * vy - uy * vx, ux * vx + uy * vy);
  }
  for (let f = 0; f < nf; f++) {
    const s = area[f], sum = total + s;
    lost += Math.abs(total) >= Math.abs(s) ? total - sum + s : s - sum + total;
    total = sum;
  }
  total += lost;
  for (let v = 0; v < nv; v++) {
    const corner = border[v] && sides[v] & 3 && sides[v] & 12;
    const expected = corner ? Math.PI / 2 : border[v] ? Math.PI : 2 * Math.PI;
    if (Math.abs(angles[v] - expected) > 1e-6)
      bad(`triangles ${angles[v] > expected ? 'overlap' : 'leave a gap'} around vertex ${v} ${at(v)}: their angles there sum to ${num(angles[v] / Math.PI)}*pi, ${corner ? 'an image corner' : border[v] ? 'a border vertex' : 'an interior vertex'} needs ${num(expected / Math.PI)}*pi`);
  }
  const image = width * height;
  if (Math.abs(total - image) > 1e-9 * image)
    bad(`the triangles cover an area of ${num(total)} but the image has ${num(image)} (${width} x ${height}): they overlap or leave a gap`);

  // Colors (*): each value belongs to one vertex and is used; across an edge that is not a tear,
  // both triangles use the same value at each end.
  if (built) return;
  const owner = new Int32Array(nc).fill(-1), first = new Int32Array(nc);
  for (let h = 0; h < t.length; h++) {
    const v = t[h], i = tc[h], f = (h / 3) | 0;
    if (owner[i] < 0) owner[i] = v, first[i] = f;
    else if (owner[i] !== v)
      bad(`color ${i} is used at vertex ${owner[i]} (triangle ${first[i]}) and at vertex ${v} (triangle ${f}); a color value belongs to one vertex`);
  }
  for (let i = 0; i < nc; i++) if (owner[i] < 0) bad(`color ${i} is used by no triangle corner`);
  for (let e = 0; e < a.length; e++) {
    const f = ef[e], g = eg[e];
    if (g >= 0 && tag[e] !== TEAR)
      for (let v = a[e], k = 0; k < 2; k++, v = b[e]) {
        const cf = tc[corner(t, f, v)], cg = tc[corner(t, g, v)];
        if (cf !== cg) bad(`edge (${a[e]}, ${b[e]}) is not a tear but triangles ${f} and ${g} use different colors at vertex ${v} (${cf} and ${cg})`);
      }
  }
}

// The pyramid link of level l: one parent per vertex, parents distinct and in range, the
// collapses removing exactly the other vertices of level l - 1.
function validateLink(image: SvecImage, record: PyramidRecord | undefined, l: number): void {
  if (!record || (!record.parents.length && !record.collapses.length)) return;
  const bad = (message: string): never => fail(`level ${l}: ${message}`);
  if (!l) bad('level 0 has no level before it, but names parent vertices or collapses');
  const nv = image.levels[l].positions.length / 2, fine = image.levels[l - 1].positions.length / 2;
  const { parents, collapses } = record, n = collapses.length / 2;
  if (parents.length !== nv) bad(`${parents.length} parent vertices for ${nv} vertices`);
  if (n + nv !== fine) bad(`${n} collapses do not take level ${l - 1}'s ${fine} vertices to ${nv}`);
  const state = new Uint8Array(fine); // 1 parent, 2 removed
  for (let i = 0; i < nv; i++) {
    const v = parents[i];
    if (v < 0 || v >= fine) bad(`parent vertex ${i} is ${v}, out of range`);
    if (state[v]) bad(`parent vertex ${v} appears twice`);
    state[v] = 1;
  }
  for (let i = 0; i < n; i++) {
    const u = collapses[2 * i], v = collapses[2 * i + 1];
    if (u < 0 || u >= fine || v < 0 || v >= fine || u === v) bad(`collapse ${i} (${u}, ${v}) is out of range`);
    if (state[u]) bad(`collapse ${i} removes vertex ${u}, which is kept or already removed`);
    state[u] = 2;
  }
}

// A string for a one-line message: quoted, control characters and quotes escaped, cut at 60.
const quoted = (s: string) => `"${escape(s.slice(0, 60).replace(/["\\]/g, '\\$&'))}${s.length > 60 ? '..."' : '"'}`;

/** Throws a SvecError naming the first rule of docs/format.md ("Validity rules") that the image
 * breaks. `records` are the pyramid records by level, where the file has them; `topologies` those
 * of levels the decoder has already built. */
export function validate(image: SvecImage, records: Array<PyramidRecord | undefined> = [], topologies: Topology[] = []): void {
  const { width, height, levels, strokes, metadata } = image;
  for (const [name, v] of [['width', width], ['height', height]] as const) {
    if (v < 1) fail(`${name} ${v} is not positive`);
    if (v > MAX_DIMENSION) fail(`${name} ${v} is over the limit of ${MAX_DIMENSION}`);
  }
  if (width * height > 2 ** 30) fail(`image size ${width} x ${height} is over the limit of ${2 ** 30} pixels`);
  if (!levels.length) fail('the image has no levels');
  levels.forEach((m, l) => validateLevel(m, width, height, l, topologies[l]));
  levels.forEach((_, l) => validateLink(image, records[l], l));
  strokes.forEach((s, i) => {
    const bad = (message: string): never => fail(`stroke ${i}: ${message}`), n = s.points.length / 2;
    if (s.level < 0 || s.level >= levels.length) bad(`level ${s.level} is out of range (${levels.length} levels)`);
    if (n < 2) bad('has fewer than two points');
    for (let k = 0; k < n; k++) {
      const x = s.points[2 * k], y = s.points[2 * k + 1];
      if (!isFinite(x) || !isFinite(y)) bad(`point ${k} ${point(x, y)} is not finite`);
    }
    if (!(isFinite(s.width) && s.width > 0)) bad(`width ${num(s.width)} is not a positive number`);
    if (!s.color.every(isFinite)) bad(`color (${s.color.map(num).join(', ')}) is not finite`);
    if (!(s.taper >= 0 && s.taper <= 0.5)) bad(`taper ${num(s.taper)} is outside [0, 0.5]`);
  });
  if (metadata.length > MAX_ELEMENTS) fail(`${metadata.length} metadata entries is over the limit of ${MAX_ELEMENTS}`);
  // A JS string is valid UTF-8 when it has no lone surrogate (decode.ts turns invalid bytes into one).
  const keys = new Set<string>(), invalid = (s: string) => /[\ud800-\udfff]/u.test(s);
  metadata.forEach(([key, value], i) => {
    const where = `metadata entry ${i}`;
    if (invalid(key)) fail(`${where}: key is not valid UTF-8`);
    if (invalid(value)) fail(`${where} (${quoted(key)}): value is not valid UTF-8`);
    if (keys.has(key)) fail(`${where}: key ${quoted(key)} appears twice`);
    keys.add(key);
  });
}
