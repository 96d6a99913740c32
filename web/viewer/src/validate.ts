// Validation of a vector image: a port of src/mesh/validate.cpp and of the checks of
// MeshTopology::build (src/mesh/topology.cpp), in the same order and with the same one-line
// messages, so that the viewer refuses exactly what the C++ reader refuses. Float64 throughout,
// as in C++.
//
// Order (each check may rely on the previous ones): the image's size; each level's rules, checked
// in WebAssembly (wasm/decode.c, check_level: finite values, positions in the image, index
// ranges; feature ids; topology: edges shared by one or two consistently oriented triangles,
// creases and features as chains of interior edges; positive areas; used vertices; border edges
// on the image rectangle and its corners present; tiling: angle sums, total area; the wedge color
// rules); then the pyramid records, strokes and metadata. (Counts are capped where they are read:
// decode.ts checks each against MAX_ELEMENTS before it sizes an array.)
import { SvecError, SvecImage, num } from './image';
import { checkLevel, checkObject, type Edges } from './wasm';

export const MAX_ELEMENTS = 2 ** 26;
export const MAX_LEVELS = 64;
export const MAX_DIMENSION = 65536;
export const MAX_OBJECTS = 4096;

/** A level's pyramid record (docs/format.md, "Levels and the pyramid"): the parent of each vertex
 * in the level before, and the collapses [removed, kept] that made the level, flattened. */
export interface PyramidRecord {
  parents: ArrayLike<number>;
  collapses: ArrayLike<number>;
}

export function fail(message: string): never {
  throw new SvecError(message);
}

// A JS string is valid UTF-8 when it has no lone surrogate (wasm.ts turns invalid bytes into one).
const invalid = (s: string) => /[\ud800-\udfff]/u.test(s);

const point = (x: number, y: number) => `(${num(x)}, ${num(y)})`;

/** Control characters as \xNN, for one-line messages. */
export const escape = (s: string) => s.replace(/[\x00-\x1f\x7f]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`);

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
 * of levels the decoder has already built; `objectRecords` what the objects' meshes name of a
 * pyramid record (nothing is allowed). */
export function validate(image: SvecImage, records: Array<PyramidRecord | undefined> = [], topologies: Edges[] = [],
  objectRecords: Array<PyramidRecord | undefined> = []): void {
  const { width, height, levels, objects, strokes, metadata } = image;
  for (const [name, v] of [['width', width], ['height', height]] as const) {
    if (v < 1) fail(`${name} ${v} is not positive`);
    if (v > MAX_DIMENSION) fail(`${name} ${v} is over the limit of ${MAX_DIMENSION}`);
  }
  if (width * height > 2 ** 30) fail(`image size ${width} x ${height} is over the limit of ${2 ** 30} pixels`);
  if (!levels.length) fail('the image has no levels');
  levels.forEach((m, l) => checkLevel(m, width, height, l, topologies[l]));
  levels.forEach((_, l) => validateLink(image, records[l], l));
  // Objects (validate_object of src/mesh/validate.cpp): the mesh's rules are checked in
  // WebAssembly (wasm/decode.c, check_object).
  if (objects.length > MAX_OBJECTS) fail(`${objects.length} objects is over the limit of ${MAX_OBJECTS}`);
  objects.forEach((o, i) => {
    const bad = (message: string): never => fail(`object ${i}: ${message}`), record = objectRecords[i];
    if (o.level < 0 || o.level >= levels.length) bad(`level ${o.level} is out of range (${levels.length} levels)`);
    if (invalid(o.name)) bad('name is not UTF-8');
    if (record && (record.parents.length || record.collapses.length)) bad('an object has no parent vertices or collapses');
    checkObject(o.mesh, i);
  });
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
  const keys = new Set<string>();
  metadata.forEach(([key, value], i) => {
    const where = `metadata entry ${i}`;
    if (invalid(key)) fail(`${where}: key is not valid UTF-8`);
    if (invalid(value)) fail(`${where} (${quoted(key)}): value is not valid UTF-8`);
    if (keys.has(key)) fail(`${where}: key ${quoted(key)} appears twice`);
    keys.add(key);
  });
}
