// The viewer's WebAssembly (web/viewer/wasm): the compact levels' decoder (wasm/decode.c, whose
// reference is the C++ reader) and the refinement (wasm/subdivide.c, behind the interface of
// subdivide.ts, which is its reference: the same arithmetic, operation for operation, checked to
// the bit by web/tests/viewer-subdivision.mjs). Why: a page decodes and refines its file once,
// cold, and JavaScript's first tiers box every double they compute; WebAssembly runs compiled
// from the start (docs/viewer.md, "Why WebAssembly").
//
// The module is small (compiled synchronously on first use, 2-3 ms) and keeps no state between
// calls: each call resets its arena, copies the inputs in and the outputs out.
import { Decompress } from 'fzstd';
import type { Feature, Level } from './image';
import { SvecError } from './image';
import type { Topology as Edges } from './validate';
import type { Refined, Topology } from './subdivide';
import { WASM } from './wasm-binary';

export { uniformIndices, type Refined, type Topology } from './subdivide';

interface Exports {
  memory: WebAssembly.Memory;
  reset(): void;
  alloc(bytes: number): number;
  topology(...args: number[]): number;
  refine(...args: number[]): number;
  adaptive(...args: number[]): number;
  compact(...args: number[]): number;
  xxh64(bytes: number, length: number): number;
}

let instance: Exports | null = null;
const MAX_KEPT = 64 * 2 ** 20; // an arena grown past this is dropped after the call

function module(): Exports {
  if (instance) return instance;
  const packed = Uint8Array.from(atob(WASM), (c) => c.charCodeAt(0));
  const parts: Uint8Array[] = [];
  new Decompress((part) => parts.push(part)).push(packed, true);
  const bytes = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  parts.reduce((at, p) => (bytes.set(p, at), at + p.length), 0);
  const env = { cos: Math.cos, hypot: Math.hypot, fail: failed, mean, exact };
  instance = new WebAssembly.Instance(new WebAssembly.Module(bytes), { env }).exports as unknown as Exports;
  return instance;
}

type Typed = Int32Array | Uint32Array | Uint8Array | Float32Array | Float64Array;
type TypedClass<T extends Typed> = { new (buffer: ArrayBuffer, offset: number, length: number): T; BYTES_PER_ELEMENT: number };

// One call: the arena reset, `run` copying in with put() and calling (a function that returns a
// pointer returns 0 when the arena cannot grow), then the outputs read with get() (copies); the
// arena dropped when it grew large.
function call<R>(run: (put: (a: Typed) => number, m: Exports) => number, read: (at: number, get: <T extends Typed>(c: TypedClass<T>, at: number, n: number) => T, i32: (at: number) => number) => R): R {
  const m = module();
  m.reset();
  try {
    const put = (a: Typed) => {
      const at = m.alloc(a.byteLength);
      if (!at) outOfMemory();
      new Uint8Array(m.memory.buffer, at, a.byteLength).set(new Uint8Array(a.buffer, a.byteOffset, a.byteLength));
      return at;
    };
    const at = run(put, m);
    const buffer = m.memory.buffer;
    const get = <T extends Typed>(c: TypedClass<T>, p: number, n: number): T => new c(buffer, p, n).slice() as T;
    return read(at, get, (p: number) => new Int32Array(buffer, p, 1)[0]);
  } finally {
    if (m.memory.buffer.byteLength > MAX_KEPT) instance = null;
  }
}

function outOfMemory(): never {
  throw new SvecError('out of memory: the image needs more than WebAssembly can hold');
}
const pointer = (at: number) => at || outOfMemory();

// A Topology in the module's memory: the C struct's fields in order.
function putTopology(t: Topology, put: (a: Typed) => number): number {
  const fields = [t.triEdges, t.edgeVerts, t.edgeTags, t.corner, t.vertexFaceOffsets, t.vertexFaces, t.ringBoxes].map(put);
  return put(Int32Array.of(t.numEdges, ...fields));
}

/** buildTopology of subdivide.ts. */
export function buildTopology(level: Level, width: number, height: number): Topology {
  const { positions: p, triangles: tri } = level;
  const offsets = new Int32Array(level.features.length + 1);
  level.features.forEach((f, i) => (offsets[i + 1] = offsets[i] + f.vertices.length));
  const verts = new Int32Array(offsets[level.features.length]);
  level.features.forEach((f, i) => verts.set(f.vertices, offsets[i]));
  const nv = p.length / 2, nf = tri.length / 3;
  return call(
    (put, m) => pointer(m.topology(nv, put(p), nf, put(tri), level.creases.length / 2, put(level.creases), level.features.length, put(offsets), put(verts), width, height)),
    (at, get, i32) => {
      const ne = i32(at), field = (k: number) => i32(at + 4 * k);
      return {
        level, numEdges: ne, triEdges: get(Int32Array, field(1), 3 * nf), edgeVerts: get(Int32Array, field(2), 2 * ne),
        edgeTags: get(Uint8Array, field(3), ne), corner: get(Uint8Array, field(4), nv),
        vertexFaceOffsets: get(Int32Array, field(5), nv + 1), vertexFaces: get(Int32Array, field(6), 3 * nf),
        ringBoxes: get(Float64Array, field(7), 4 * nf),
      };
    },
  );
}

/** refine of subdivide.ts. */
export function refine(topo: Topology, faces: Int32Array | null, depth: number): Refined {
  const L = topo.level, nf = L.triangles.length / 3;
  if (!(depth >= 0 && depth < 16)) throw new RangeError(`depth ${depth} is not in 0..15`);
  if (faces) for (const f of faces) if (!(f >= 0 && f < nf)) throw new RangeError(`face ${f} is not one of the level's ${nf}`);
  return call(
    (put, m) => pointer(m.refine(putTopology(topo, put), L.positions.length / 2, put(L.positions), L.colors.length / 3, put(L.colors),
      nf, put(L.triangles), put(L.triangleColors), faces ? put(faces) : 0, faces ? faces.length : 0, depth)),
    (at, get, i32) => {
      const [selected, numFaces, numValues, numEdges, vertices, sharpEdges, edgeFaces] = [0, 1, 2, 3, 4, 5, 6].map((k) => i32(at + 4 * k));
      const levels: Refined['levels'] = [];
      for (let d = 0; d <= depth; ++d) {
        const n = 3 * numFaces * 4 ** d;
        levels.push({ values: get(Int32Array, i32(at + 28 + 4 * d), n), sides: get(Int32Array, i32(at + 92 + 4 * d), n) });
      }
      return {
        depth, selected, levels, vertices: get(Float32Array, vertices, 5 * numValues),
        sharpEdges: get(Uint8Array, sharpEdges, numEdges), edgeFaces: get(Int32Array, edgeFaces, 2 * numEdges),
      };
    },
  );
}

/** adaptiveIndices of subdivide.ts. */
export function adaptiveIndices(r: Refined, scale: number, colorTolerance: number, positionTolerance: number): Uint32Array {
  const numEdges = r.sharpEdges.length, numValues = r.vertices.length / 5, numFaces = r.levels[0].values.length / 3;
  return call(
    (put, m) => {
      const values = new Int32Array(16), sides = new Int32Array(16);
      r.levels.forEach((l, d) => ((values[d] = put(l.values)), (sides[d] = put(l.sides))));
      const head = [r.selected, numFaces, numValues, numEdges, put(r.vertices), put(r.sharpEdges), put(r.edgeFaces)];
      return pointer(m.adaptive(put(Int32Array.from([...head, ...values, ...sides])), r.depth, scale, colorTolerance, positionTolerance));
    },
    (at, get, i32) => get(Uint32Array, i32(at + 4), i32(at)),
  );
}

/** zstd's content checksum of b: the low 32 bits of XXH64, seed 0 (wasm/checksum.c). */
export function checksum(b: Uint8Array): number {
  return call((put, m) => m.xxh64(put(b), b.length) >>> 0, (sum) => sum);
}

// ---------------------------------------------------------------------------------------------
// Compact levels (wasm/decode.c).

/** A compact level's counts, precision and bytes (one stream, or six sections), as decode.ts read them. */
export interface CompactInput {
  version: number;
  sections: Uint8Array[];
  ops: number;
  nv: number;
  ncolors: number;
  ntriangles: number;
  ncreases: number;
  nfeatures: number;
  pb: number;
  cb: number;
  width: number;
  height: number;
  /** "level L ", which starts most messages */
  name: string;
}

// The level being decoded, for the messages.
let current: CompactInput | null = null;

const SECTION = ['connectivity', 'split offsets', 'positions', 'features', 'feature steps', 'colors', 'header'];
const chain = (feature: number, i: number, id?: number) => (feature ? `feature ${i}${id === undefined ? '' : ` (id ${id})`}` : `crease ${i}`);
// The messages of wasm/decode.c's codes, in their order: n is the level's name, then its numbers.
type Message = (n: string, a: number, b: number, c: number, d: number, e: number) => string;
const connectivity = (m: (a: number, b: number) => string): Message => (n, a, b) => `${n}connectivity: ${m(a, b)}`;
const MESSAGES: Message[] = [
  () => 'out of memory: the image needs more than WebAssembly can hold',
  (n) => `${n}stream: corrupt coded data (bad first bytes)`,
  (n, k, length) => `${n}stream ${SECTION[k]}: the coded data ends early (${length} bytes)`,
  (n, k) => `${n}stream ${SECTION[k]}: a number of more than 56 bits`,
  (n, left) => `${left} unexpected bytes at the end of ${n}stream`,
  (n) => `${n}stream: corrupt coded data (the code leaves its interval)`,
  (n, k, w, need, at, left) => `truncated payload while reading ${n}${w < 0 ? SECTION[k] : chain(1, w)} (needs ${need} bytes at offset ${at}, ${left} left)`,
  (n, k, w) => `malformed varint while reading ${n}${w < 0 ? SECTION[k] : chain(1, w)}`,
  (n, i) => `${n}connectivity: byte ${i} is not three operations`,
  (n, left, k) => `${left} unexpected bytes at the end of ${n}${SECTION[k]}`,
  (n, i, tag) => `${n}feature ${i}: unknown saliency tag ${tag}`,
  (n, i, length) => `${n}feature ${i}: ${length + 2} vertices, too few bytes`,
  connectivity((v) => `virtual vertex ${v} out of range`),
  connectivity(() => 'the traversal ends before the last operation'),
  connectivity(() => 'the operations outrun the stream'),
  connectivity((nv) => `more vertices than the ${nv} declared`),
  connectivity((i, size) => `operation ${i} closes a loop of ${size} edges`),
  connectivity((i) => `operation ${i} on a loop of 3 edges`),
  connectivity(() => 'split offset out of range'),
  connectivity((i) => `operation ${i} makes a degenerate triangle`),
  connectivity(() => 'the traversal leaves triangles unvisited'),
  connectivity((n, nv) => `${n} vertices, but ${nv} are declared`),
  connectivity((n, nt) => `${n} triangles, but ${nt} are declared`),
  (n) => `${n}positions: residual out of range`,
  (n, f, i, v) => `${n}${chain(f, i)}: vertex ${v} out of range`,
  (n, f, i, r) => `${n}${chain(f, i)}: step ${r} out of range`,
  (n, i) => `${n}feature ${i}: id out of range`,
  (n, i, length) => `${n}feature ${i}: ${length + 2} vertices, more than the level has`,
  // The topology's messages (MeshTopology::build's, without the level's name).
  (_, f, x, nv) => `triangle ${f} refers to vertex ${x}, out of range (${nv} vertices)`,
  (_, f, x) => `triangle ${f} repeats vertex ${x}`,
  (_, x, y) => `edge (${x}, ${y}) is shared by more than two triangles`,
  (_, f, g, x, y) => `triangles ${f} and ${g} are oriented inconsistently across edge (${x}, ${y})`,
  (_, f, i, id, v) => `${chain(f, i, id)} refers to vertex ${v}, out of range (${current!.nv} vertices)`,
  (_, f, i, id, x, y) => `${chain(f, i, id)}: (${x}, ${y}) is not an edge of the mesh`,
  (_, f, i, id, x, y) => `${chain(f, i, id)}: (${x}, ${y}) lies on the image border`,
  (_, f, i, id, x, y) => `${chain(f, i, id)}: edge (${x}, ${y}) is already a crease`,
  (_, f, i, id, x, y) => `${chain(f, i, id)}: edge (${x}, ${y}) is already a feature edge`,
  (_, i, id) => `${chain(1, i, id)} has fewer than two vertices`,
  (n, nc, declared) => `${n}colors: the tears give ${nc} color values, but ${declared} are declared`,
  (n) => `${n}colors: residual out of range`,
  (n) => `${n}colors: value out of range`,
];

function failed(code: number, a: number, b: number, c: number, d: number, e: number): never {
  throw new SvecError(MESSAGES[code]?.(current?.name ?? '', a, b, c, d, e) ?? `corrupt compact level (code ${code})`);
}

// ⌊(2·s + n) / (2·n)⌋, the rounded mean of the n integers at `terms` (doubles in the module's
// memory) in BigInt: for terms of 2^50 and more in all, where doubles could round.
function mean(terms: number, n: number): number {
  const t = new Float64Array(instance!.memory.buffer, terms, n);
  let sum = 0n;
  for (let i = 0; i < n; i++) sum += BigInt(t[i]);
  const num = 2n * sum + BigInt(n), den = BigInt(2 * n), q = num / den;
  return Number(num % den && num < 0n ? q - 1n : q);
}

// a·b + c·d for integers too large for doubles, rounded once (as C++ converts an exact int64).
const exact = (a: number, b: number, c: number, d: number) => Number(BigInt(a) * BigInt(b) + BigInt(c) * BigInt(d));

/** A compact level and its topology (edges, twins, tags), or a SvecError naming the problem. */
export function decodeCompact(input: CompactInput): [Level, Edges] {
  const { nv, ntriangles: nt, ncreases, nfeatures } = input;
  current = input;
  try {
    return call(
      (put, m) => {
        const sections = new Int32Array(12);
        input.sections.forEach((s, k) => ((sections[2 * k] = put(s)), (sections[2 * k + 1] = s.length)));
        return m.compact(input.version, put(sections), input.ops, nv, input.ncolors, nt, ncreases, nfeatures, input.pb, input.cb, input.width, input.height);
      },
      (at, get, i32) => {
        const field = (k: number) => i32(at + 4 * k);
        const offsets = get(Int32Array, field(7), nfeatures + 1), ids = get(Int32Array, field(6), nfeatures);
        const saliency = get(Float64Array, field(9), nfeatures), vertices = get(Int32Array, field(8), offsets[nfeatures]);
        const features: Feature[] = [];
        for (let i = 0; i < nfeatures; i++) features.push({ id: ids[i], saliency: saliency[i], vertices: vertices.subarray(offsets[i], offsets[i + 1]) });
        const triangles = get(Int32Array, field(2), 3 * nt);
        const level: Level = {
          positions: get(Float64Array, field(0), 2 * nv), colors: get(Float32Array, field(1), 3 * input.ncolors), triangles,
          triangleColors: get(Int32Array, field(3), 3 * nt), creases: get(Int32Array, field(4), 2 * ncreases), features,
        };
        const ne = field(10), edge = (k: number) => get(Int32Array, field(11 + k), ne);
        return [level, { a: edge(0), b: edge(1), f: edge(2), g: edge(3), tag: get(Uint8Array, field(15), ne), twin: get(Int32Array, field(16), 3 * nt) }];
      },
    );
  } finally {
    current = null;
  }
}
