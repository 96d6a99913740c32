// Validation of a vector image: a port of src/mesh/validate.cpp and of the checks of
// MeshTopology::build (src/mesh/topology.cpp), in the same order and with the same one-line
// messages, so that the viewer refuses exactly what the C++ reader refuses. Float64 throughout,
// as in C++.
//
// Order (each check may rely on the previous ones): sizes; finite values, positions in the image,
// index ranges; feature ids; topology (edges shared by one or two consistently oriented
// triangles, creases and features as chains of interior edges); positive areas; used vertices;
// border edges on the image rectangle and its corners present; tiling (angle sums, total area);
// the wedge color rules. Then the pyramid records, strokes and metadata.
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
  if (v === 0) return Object.is(v, -0) ? '-0' : '0';
  const exponent = +v.toExponential(5).split('e')[1];
  const trim = (s: string) => (s.includes('.') ? s.replace(/\.?0+$/, '') : s);
  if (exponent >= -4 && exponent < 6) return trim(v.toFixed(5 - exponent));
  const [mantissa] = v.toExponential(5).split('e');
  return `${trim(mantissa)}e${exponent < 0 ? '-' : '+'}${String(Math.abs(exponent)).padStart(2, '0')}`;
}

const point = (x: number, y: number) => `(${num(x)}, ${num(y)})`;

// Edge tags.
const CREASE = 1, TEAR = 2, BORDER = 3;

/** Indices 0..n-1 of the pairs (a[i], b[i]) ordered by (a, b, i), and where each value of a
 * (0 <= a < nv) starts: a counting sort on a, then each run by b, stably (MeshTopology::build). */
export function sortPairs(a: Int32Array, b: Int32Array, nv: number): [Int32Array, Int32Array] {
  const start = new Int32Array(nv + 1), order = new Int32Array(a.length);
  for (const x of a) start[x + 1]++;
  for (let v = 0; v < nv; v++) start[v + 1] += start[v];
  const fill = start.slice(0, nv);
  a.forEach((x, i) => (order[fill[x]++] = i));
  for (let v = 0; v < nv; v++) {
    const run = order.subarray(start[v], start[v + 1]);
    // Runs are a vertex's few edges; a long one (a fan) gets the library sort.
    if (run.length > 16) run.sort((x, y) => b[x] - b[y] || x - y);
    else
      for (let i = 1; i < run.length; i++) {
        const h = run[i];
        let j = i;
        for (; j > 0 && b[run[j - 1]] > b[h]; j--) run[j] = run[j - 1];
        run[j] = h;
      }
  }
  return [order, start];
}

/** The edges of a level, sorted by (a, b) with a < b: their triangles (g = -1 on the border) and
 * tags (0 smooth, 1 crease, 2 tear, 3 border). */
export interface Topology {
  a: Int32Array;
  b: Int32Array;
  f: Int32Array;
  g: Int32Array;
  tag: Uint8Array;
}

/** MeshTopology::build without the vertex tags. Messages have no "level L: " prefix. */
export function topology(m: Level, nv: number): Topology {
  const t = m.triangles, nh = t.length;
  const lo = new Int32Array(nh), hi = new Int32Array(nh);
  for (let h = 0; h < nh; h++) {
    const x = t[h], y = t[h - (h % 3) + ((h + 1) % 3)], f = (h / 3) | 0;
    if (x < 0 || x >= nv) fail(`triangle ${f} refers to vertex ${x}, out of range (${nv} vertices)`);
    if (x === y) fail(`triangle ${f} repeats vertex ${x}`);
    lo[h] = Math.min(x, y);
    hi[h] = Math.max(x, y);
  }
  // Each undirected edge occurs once (border) or twice in opposite directions (interior).
  const [order] = sortPairs(lo, hi, nv);
  const ea = new Int32Array(nh), eb = new Int32Array(nh), ef = new Int32Array(nh), eg = new Int32Array(nh);
  let ne = 0;
  for (let i = 0; i < nh; ne++) {
    const h = order[i];
    let j = i + 1;
    while (j < nh && lo[order[j]] === lo[h] && hi[order[j]] === hi[h]) j++;
    const x = lo[h], y = hi[h], f = (h / 3) | 0, g = j - i === 2 ? (order[i + 1] / 3) | 0 : -1;
    if (j - i > 2) fail(`edge (${x}, ${y}) is shared by more than two triangles`);
    if (g >= 0 && t[h] === t[order[i + 1]])
      fail(`triangles ${f} and ${g} are oriented inconsistently across edge (${x}, ${y})`);
    ea[ne] = x, eb[ne] = y, ef[ne] = f, eg[ne] = g;
    i = j;
  }
  const tag = new Uint8Array(ne);
  for (let e = 0; e < ne; e++) if (eg[e] < 0) tag[e] = BORDER;
  const find = (x: number, y: number) => {
    if (x > y) [x, y] = [y, x];
    let l = 0, r = ne;
    while (l < r) {
      const mid = (l + r) >> 1;
      if (ea[mid] < x || (ea[mid] === x && eb[mid] < y)) l = mid + 1;
      else r = mid;
    }
    return l < ne && ea[l] === x && eb[l] === y ? l : -1;
  };
  const mark = (x: number, y: number, kind: number, what: string) => {
    if (x < 0 || x >= nv || y < 0 || y >= nv)
      fail(`${what} refers to vertex ${x < 0 || x >= nv ? x : y}, out of range (${nv} vertices)`);
    const e = find(x, y);
    if (e < 0) fail(`${what}: (${x}, ${y}) is not an edge of the mesh`);
    if (tag[e] === BORDER) fail(`${what}: (${x}, ${y}) lies on the image border`);
    if (tag[e]) fail(`${what}: edge (${x}, ${y}) is already a ${tag[e] === TEAR ? 'feature edge' : 'crease'}`);
    tag[e] = kind;
  };
  for (let i = 0; i < m.creases.length; i += 2) mark(m.creases[i], m.creases[i + 1], CREASE, `crease ${i / 2}`);
  m.features.forEach((feature, i) => {
    const what = `feature ${i} (id ${feature.id})`, v = feature.vertices;
    if (v.length < 2) fail(`${what} has fewer than two vertices`);
    for (let k = 0; k + 1 < v.length; k++) mark(v[k], v[k + 1], TEAR, what);
  });
  return { a: ea.subarray(0, ne), b: eb.subarray(0, ne), f: ef.subarray(0, ne), g: eg.subarray(0, ne), tag };
}

/** face_varying_indices: one color index per wedge (corners of a vertex joined across edges
 * that are not tears), numbered in order of first use; and their count. */
export function wedges(m: Level, topo: Topology): [Int32Array, number] {
  const t = m.triangles, root = Int32Array.from(t, (_, i) => i);
  const find = (c: number) => {
    while (root[c] !== c) c = root[c] = root[root[c]];
    return c;
  };
  const corner = (f: number, v: number) => 3 * f + (t[3 * f] === v ? 0 : t[3 * f + 1] === v ? 1 : 2);
  for (let e = 0; e < topo.a.length; e++) {
    if (topo.g[e] < 0 || topo.tag[e] === TEAR) continue;
    for (const v of [topo.a[e], topo.b[e]]) root[find(corner(topo.f[e], v))] = find(corner(topo.g[e], v));
  }
  const id = new Int32Array(t.length).fill(-1), out = new Int32Array(t.length);
  let n = 0;
  for (let c = 0; c < t.length; c++) {
    const r = find(c);
    if (id[r] < 0) id[r] = n++;
    out[c] = id[r];
  }
  return [out, n];
}

function validateLevel(m: Level, width: number, height: number, level: number): void {
  const bad = (message: string): never => fail(`level ${level}: ${message}`);
  const p = m.positions, t = m.triangles, tc = m.triangleColors, c = m.colors;
  const nv = p.length / 2, nc = c.length / 3, nf = t.length / 3;
  const sizes: Array<[string, number]> = [['vertices', nv], ['colors', nc], ['triangles', nf], ['creases', m.creases.length / 2], ['features', m.features.length]];
  for (const f of m.features) sizes.push(['feature vertices', f.vertices.length]);
  for (const [what, n] of sizes) if (n > MAX_ELEMENTS) bad(`${n} ${what} is over the limit of ${MAX_ELEMENTS}`);
  if (tc.length !== t.length) bad(`${nf} triangles but ${tc.length / 3} triangle_colors entries (one per triangle needed)`);

  for (let v = 0; v < nv; v++) {
    const x = p[2 * v], y = p[2 * v + 1];
    if (!isFinite(x) || !isFinite(y)) bad(`vertex ${v} position ${point(x, y)} is not finite`);
    if (x < 0 || x > width || y < 0 || y > height)
      bad(`vertex ${v} position ${point(x, y)} is outside the image [0, ${width}] x [0, ${height}]`);
  }
  for (let i = 0; i < nc; i++)
    if (!c.subarray(3 * i, 3 * i + 3).every(isFinite)) bad(`color ${i} (${Array.from(c.subarray(3 * i, 3 * i + 3), num).join(', ')}) is not finite`);
  // Vertex indices before color indices: without triangle_colors (JSON) these are copies of them.
  t.forEach((v, h) => (v < 0 || v >= nv) && bad(`triangle ${(h / 3) | 0} refers to vertex ${v}, out of range (${nv} vertices)`));
  tc.forEach((i, h) => (i < 0 || i >= nc) && bad(`triangle_colors ${(h / 3) | 0} refers to color ${i}, out of range (${nc} colors)`));
  const ids = new Set<number>();
  m.features.forEach((f, i) => {
    if (ids.has(f.id)) bad(`feature ${i} repeats id ${f.id} (ids must be unique within a level)`);
    ids.add(f.id);
    if (!isFinite(f.saliency)) bad(`feature ${i} (id ${f.id}) saliency ${num(f.saliency)} is not finite`);
  });

  let topo: Topology;
  try {
    topo = topology(m, nv);
  } catch (e) {
    return bad((e as Error).message);
  }

  const area = (a: number, b: number, c: number) =>
    0.5 * ((p[2 * b] - p[2 * a]) * (p[2 * c + 1] - p[2 * a + 1]) - (p[2 * b + 1] - p[2 * a + 1]) * (p[2 * c] - p[2 * a]));
  for (let f = 0; f < nf; f++) {
    const s = area(t[3 * f], t[3 * f + 1], t[3 * f + 2]);
    if (!(s > 0)) bad(`triangle ${f} (${t[3 * f]}, ${t[3 * f + 1]}, ${t[3 * f + 2]}) is flipped or degenerate (signed area ${num(s)})`);
  }
  const used = new Uint8Array(nv);
  for (const v of t) used[v] = 1;
  for (let v = 0; v < nv; v++) if (!used[v]) bad(`vertex ${v} ${point(p[2 * v], p[2 * v + 1])} is used by no triangle`);

  // Sides of the image rectangle a vertex lies on, exactly: 1 left, 2 right, 4 top, 8 bottom.
  const sides = (v: number) => {
    const x = p[2 * v], y = p[2 * v + 1];
    return +(x === 0) | (+(x === width) << 1) | (+(y === 0) << 2) | (+(y === height) << 3);
  };
  const border = new Uint8Array(nv);
  for (let e = 0; e < topo.a.length; e++) {
    if (topo.g[e] >= 0) continue;
    const a = topo.a[e], b = topo.b[e];
    if (!(sides(a) & sides(b)))
      bad(`edge (${a}, ${b}) from ${point(p[2 * a], p[2 * a + 1])} to ${point(p[2 * b], p[2 * b + 1])} has a triangle on one side only but does not lie on the image border (a gap or a hole in the mesh)`);
    border[a] = border[b] = 1;
  }
  for (const [x, y] of [[0, 0], [width, 0], [width, height], [0, height]]) {
    let found = false;
    for (let v = 0; v < nv && !found; v++) found = p[2 * v] === x && p[2 * v + 1] === y;
    if (!found) bad(`no vertex at the image corner ${point(x, y)}`);
  }

  // Tiling: angle sums per vertex, then the total area (summed compensated, as C++ sums it in
  // long double).
  const angles = new Float64Array(nv);
  let total = 0, lost = 0;
  for (let f = 0; f < nf; f++) {
    for (let k = 0; k < 3; k++) {
      const a = t[3 * f + k], b = t[3 * f + ((k + 1) % 3)], c = t[3 * f + ((k + 2) % 3)];
      const ux = p[2 * b] - p[2 * a], uy = p[2 * b + 1] - p[2 * a + 1], vx = p[2 * c] - p[2 * a], vy = p[2 * c + 1] - p[2 * a + 1];
      angles[a] += Math.atan2(ux * vy - uy * vx, ux * vx + uy * vy);
    }
    const s = area(t[3 * f], t[3 * f + 1], t[3 * f + 2]), sum = total + s;
    lost += Math.abs(total) >= Math.abs(s) ? total - sum + s : s - sum + total;
    total = sum;
  }
  total += lost;
  for (let v = 0; v < nv; v++) {
    const s = sides(v), corner = border[v] && s & 3 && s & 12;
    const expected = corner ? Math.PI / 2 : border[v] ? Math.PI : 2 * Math.PI;
    if (Math.abs(angles[v] - expected) > 1e-6)
      bad(`triangles ${angles[v] > expected ? 'overlap' : 'leave a gap'} around vertex ${v} ${point(p[2 * v], p[2 * v + 1])}: their angles there sum to ${num(angles[v] / Math.PI)}*pi, ${corner ? 'an image corner' : border[v] ? 'a border vertex' : 'an interior vertex'} needs ${num(expected / Math.PI)}*pi`);
  }
  const image = width * height;
  if (Math.abs(total - image) > 1e-9 * image)
    bad(`the triangles cover an area of ${num(total)} but the image has ${num(image)} (${width} x ${height}): they overlap or leave a gap`);

  // Colors: each value belongs to one vertex and is used; across an edge that is not a tear,
  // both triangles use the same value at each end.
  const owner = new Int32Array(nc).fill(-1), first = new Int32Array(nc);
  for (let h = 0; h < t.length; h++) {
    const v = t[h], i = tc[h], f = (h / 3) | 0;
    if (owner[i] < 0) (owner[i] = v), (first[i] = f);
    else if (owner[i] !== v)
      bad(`color ${i} is used at vertex ${owner[i]} (triangle ${first[i]}) and at vertex ${v} (triangle ${f}); a color value belongs to one vertex`);
  }
  owner.forEach((v, i) => v < 0 && bad(`color ${i} is used by no triangle corner`));
  const cornerColor = (f: number, v: number) => tc[3 * f + (t[3 * f] === v ? 0 : t[3 * f + 1] === v ? 1 : 2)];
  for (let e = 0; e < topo.a.length; e++) {
    const f = topo.f[e], g = topo.g[e];
    if (g < 0 || topo.tag[e] === TEAR) continue;
    for (const v of [topo.a[e], topo.b[e]]) {
      const cf = cornerColor(f, v), cg = cornerColor(g, v);
      if (cf !== cg)
        bad(`edge (${topo.a[e]}, ${topo.b[e]}) is not a tear but triangles ${f} and ${g} use different colors at vertex ${v} (${cf} and ${cg})`);
    }
  }
}

// The pyramid link of level l: one parent per vertex, parents distinct and in range, the
// collapses removing exactly the other vertices of level l - 1.
function validateLink(image: SvecImage, record: PyramidRecord | undefined, l: number): void {
  if (!record || (!record.parents.length && !record.collapses.length)) return;
  const bad = (message: string): never => fail(`level ${l}: ${message}`);
  if (l === 0) bad('level 0 has no level before it, but names parent vertices or collapses');
  const nv = image.levels[l].positions.length / 2, fine = image.levels[l - 1].positions.length / 2;
  const { parents, collapses } = record, n = collapses.length / 2;
  if (parents.length !== nv) bad(`${parents.length} parent vertices for ${nv} vertices`);
  if (n + nv !== fine) bad(`${n} collapses do not take level ${l - 1}'s ${fine} vertices to ${nv}`);
  const state = new Uint8Array(fine); // 1 parent, 2 removed
  for (let i = 0; i < parents.length; i++) {
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
const quoted = (s: string) =>
  `"${s.slice(0, 60).replace(/["\\]/g, '\\$&').replace(/[\x00-\x1f\x7f]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`)}${s.length > 60 ? '..."' : '"'}`;

/** Throws a SvecError naming the first rule of docs/format.md ("Validity rules") that the image
 * breaks. `records` are the pyramid records by level, where the file has them. */
export function validate(image: SvecImage, records: Array<PyramidRecord | undefined> = []): void {
  const { width, height, levels } = image;
  for (const [name, v] of [['width', width], ['height', height]] as const) {
    if (v < 1) fail(`${name} ${v} is not positive`);
    if (v > MAX_DIMENSION) fail(`${name} ${v} is over the limit of ${MAX_DIMENSION}`);
  }
  if (width * height > 2 ** 30) fail(`image size ${width} x ${height} is over the limit of ${2 ** 30} pixels`);
  if (!levels.length) fail('the image has no levels');
  if (levels.length > MAX_LEVELS) fail(`${levels.length} levels is over the limit of ${MAX_LEVELS}`);
  levels.forEach((m, l) => validateLevel(m, width, height, l));
  levels.forEach((_, l) => validateLink(image, records[l], l));
  if (image.strokes.length > MAX_ELEMENTS) fail(`${image.strokes.length} strokes is over the limit of ${MAX_ELEMENTS}`);
  image.strokes.forEach((s, i) => {
    const bad = (message: string): never => fail(`stroke ${i}: ${message}`);
    const n = s.points.length / 2;
    if (s.level < 0 || s.level >= levels.length) bad(`level ${s.level} is out of range (${levels.length} levels)`);
    if (n > MAX_ELEMENTS) bad(`${n} points is over the limit of ${MAX_ELEMENTS}`);
    if (n < 2) bad('has fewer than two points');
    for (let k = 0; k < n; k++) {
      const x = s.points[2 * k], y = s.points[2 * k + 1];
      if (!isFinite(x) || !isFinite(y)) bad(`point ${k} ${point(x, y)} is not finite`);
    }
    if (!(isFinite(s.width) && s.width > 0)) bad(`width ${num(s.width)} is not a positive number`);
    if (!s.color.every(isFinite)) bad(`color (${s.color.map(num).join(', ')}) is not finite`);
    if (!(s.taper >= 0 && s.taper <= 0.5)) bad(`taper ${num(s.taper)} is outside [0, 0.5]`);
  });
  if (image.metadata.length > MAX_ELEMENTS)
    fail(`${image.metadata.length} metadata entries is over the limit of ${MAX_ELEMENTS}`);
  // A JS string is valid UTF-8 when it has no lone surrogate (decode.ts turns invalid bytes into one).
  const keys = new Set<string>(), valid = (s: string) => !/[\ud800-\udfff]/u.test(s);
  image.metadata.forEach(([key, value], i) => {
    const where = `metadata entry ${i}`;
    if (!valid(key)) fail(`${where}: key is not valid UTF-8`);
    if (!valid(value)) fail(`${where} (${quoted(key)}): value is not valid UTF-8`);
    if (keys.has(key)) fail(`${where}: key ${quoted(key)} appears twice`);
    keys.add(key);
  });
}
