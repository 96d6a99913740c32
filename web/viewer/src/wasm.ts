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
import type { Feature, Level, Stroke, SvecImage, SvecObject } from './image';
import { SvecError, num } from './image';
import type { Refined, Topology } from './subdivide';
import { WASM, WASM_BYTES, WASM_SIZE } from './wasm-binary';

export { uniformIndices, type Refined, type Topology } from './subdivide';

interface Exports {
  memory: WebAssembly.Memory;
  __stack_pointer: WebAssembly.Global;
  reset(): void;
  alloc(bytes: number): number;
  topology(...args: number[]): number;
  refine(...args: number[]): number;
  adaptive(...args: number[]): number;
  compact(...args: number[]): number;
  xxh64(bytes: number, length: number): number;
  json(bytes: number, length: number): number;
  payload(bytes: number, length: number, version: number, flags: number): number;
  container(bytes: number, length: number): number;
}

let instance: Exports | null = null;
const MAX_KEPT = 64 * 2 ** 20; // an arena grown past this is dropped after the call

// The module's bytes (WASM_SIZE of them): base 116 (wasm/build: 7 characters, 1 to 126 without 7
// to 13, escape, ' and \, per 6 bytes, big-endian) of its zstd frame.
function unpack(): Uint8Array<ArrayBuffer> {
  const packed = new Uint8Array((WASM.length / 7) * 6);
  for (let i = 0, o = 0; i < WASM.length; o += 6) {
    let v = 0;
    for (const end = i + 7; i < end; i++) {
      const c = WASM.charCodeAt(i);
      v = v * 116 + c - (c > 13 ? 8 : 1) - +(c > 27) - +(c > 39) - +(c > 92);
    }
    for (let k = o + 6; k-- > o; v = Math.floor(v / 256)) packed[k] = v % 256;
  }
  const bytes = new Uint8Array(WASM_SIZE);
  let at = 0;
  new Decompress((part) => (bytes.set(part, at), (at += part.length))).push(packed.subarray(0, WASM_BYTES), true);
  return bytes;
}

// Compiled in the background from the moment the module is imported (a page fetches its file
// meanwhile); a call that comes first compiles it itself.
let compiled: WebAssembly.Module | null = null;
if (typeof WebAssembly === 'object')
  WebAssembly.compile(unpack()).then(
    (m) => (compiled = m),
    () => {}, // reported by the first call
  );

function module(): Exports {
  if (instance) return instance;
  const env = { cos: Math.cos, hypot: Math.hypot, atan2: Math.atan2, fail: failed, mean, exact, number, string };
  try {
    instance = new WebAssembly.Instance(compiled ?? new WebAssembly.Module(unpack()), { env }).exports as unknown as Exports;
  } catch (e) {
    // A Content-Security-Policy without 'wasm-unsafe-eval', or an engine without WebAssembly.
    throw new SvecError(`WebAssembly is not available here: ${e instanceof Error ? e.message : String(e)}`);
  }
  return instance;
}

type Typed = Int32Array | Uint32Array | Uint8Array | Float32Array | Float64Array;
type TypedClass<T extends Typed> = { new (buffer: ArrayBuffer, offset: number, length: number): T; BYTES_PER_ELEMENT: number };

// One call: the arena reset, `run` copying in with put() and calling (a function that returns a
// pointer returns 0 when the arena cannot grow), then the outputs read with get() (copies); the
// arena dropped when it grew large.
function call<R>(run: (put: (a: Typed) => number, m: Exports) => number, read: (at: number, get: <T extends Typed>(c: TypedClass<T>, at: number, n: number) => T, i32: (at: number) => number) => R): R {
  // A SvecError thrown from inside the module skips the C functions' epilogues: the stack
  // pointer is put back here, or each failed call would leave the stack lower.
  const m = module(), stack = m.__stack_pointer.value;
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
    m.__stack_pointer.value = stack;
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
      // The C struct Refined: seven 32-bit fields, then values[16] (offset 28) and sides[16] (92).
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

// strict: the module's messages are UTF-8 (keys the JSON reader decoded), and so must a file's strings be
const utf8 = new TextDecoder('utf-8', { fatal: true, ignoreBOM: true });

// A number as nlohmann's dump() writes it: 4.0, 0.5, 4e+38, 1e-05.
function dump(v: number): string {
  const [digits, exponent] = v.toExponential().split('e'), e = +exponent;
  if (e > 14 || e < -4) return `${digits}e${e < 0 ? '-' : '+'}${String(Math.abs(e)).padStart(2, '0')}`;
  return Number.isInteger(v) ? v.toFixed(1) : String(v);
}

// The module's message (wasm/message.h): UTF-8, with each number as a marker byte (0xfd: an
// integer, 0xfe: "%g", 0xff: dump()) and its 8 bytes.
function failed(at: number, n: number): never {
  const b = new Uint8Array(instance!.memory.buffer, at, n), d = new DataView(b.buffer, at, n);
  let s = '', from = 0;
  for (let i = 0; i < n; i++)
    if (b[i] > 0xfc) {
      s += utf8.decode(b.subarray(from, i)) + [String, num, dump][b[i] - 0xfd](d.getFloat64(i + 1, true));
      from = (i += 8) + 1;
    }
  throw new SvecError(s + utf8.decode(b.subarray(from)));
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

// ---------------------------------------------------------------------------------------------
// The JSON form (wasm/json.c).

// wasm/json.c's numerals and string literals (the literal's UTF-8 out, or -1 where JSON.parse
// refuses it, the bytes are not UTF-8 or it holds a lone surrogate).
const bytes = (at: number, n: number) => new Uint8Array(instance!.memory.buffer, at, n);
const number = (at: number, n: number) => Number(utf8.decode(bytes(at, n)));
function string(at: number, n: number, out: number): number {
  try {
    const s: string = JSON.parse(utf8.decode(bytes(at, n)));
    if (!/[\ud800-\udfff]/u.test(s)) return new TextEncoder().encodeInto(s, bytes(out, n)).written;
  } catch {}
  return -1;
}

type Get = <T extends Typed>(c: TypedClass<T>, at: number, n: number) => T;

// wasm/image.h's JsonImage, JsonLevel, JsonObject, JsonStroke, JsonEntry (32-bit fields; an
// Array is n, then a pointer), read back after wasm/validate.c has checked them.
function image(at: number, get: Get, i32: (at: number) => number): SvecImage {
  const f = (p: number, k: number) => i32(p + 4 * k);
  const ints = (p: number, k: number) => get(Int32Array, f(p, k + 1), f(p, k));
  const text = (p: number, k: number) => utf8.decode(get(Uint8Array, f(p, k), f(p, k + 1)));
  const mesh = (p: number): Level => {
    const nf = f(p, 14), saliency = get(Float64Array, f(p, 16), nf);
    return {
      positions: get(Float64Array, f(p, 1), f(p, 0)), colors: get(Float32Array, f(p, 3), f(p, 2)), triangles: ints(p, 4),
      triangleColors: ints(p, 6), creases: ints(p, 8),
      features: Array.from({ length: nf }, (_, k): Feature => ({ id: f(f(p, 15), k), saliency: saliency[k], vertices: ints(f(p, 17) + 8 * k, 0) })),
    };
  };
  const strokes = (p: number) => Array.from({ length: f(p, 0) }, (_, k): Stroke => {
    const s = f(p, 1) + 32 * k, v = get(Float32Array, s + 4, 5);
    return { level: f(s, 0), points: get(Float64Array, f(s, 7), f(s, 6)), width: v[0], color: [v[1], v[2], v[3]], taper: v[4] };
  });
  const levels = Array.from({ length: f(at, 2) }, (_, l) => mesh(f(at, 3) + 76 * l));
  const objects = Array.from({ length: f(at, 8) }, (_, k): SvecObject => {
    const p = f(at, 9) + 100 * k;
    return { level: f(p, 0), name: text(p, 2), visible: !!f(p, 1), mesh: mesh(p + 16), strokes: strokes(p + 92) };
  });
  const metadata = Array.from({ length: f(at, 6) }, (_, k): [string, string] => [text(f(at, 7) + 16 * k, 0), text(f(at, 7) + 16 * k, 2)]);
  return { width: f(at, 0), height: f(at, 1), levels, objects, strokes: strokes(at + 16), metadata };
}

/** A .svec.json file's image, validated, or a SvecError. */
export const readJson = (b: Uint8Array) => call((put, m) => m.json(put(b), b.length), image);

/** A .svec payload's image, validated, or a SvecError. `flags`: the header's (1: the payload
 * holds objects, 2: and their strokes). */
export const readPayload = (b: Uint8Array, version: number, flags: number) =>
  call((put, m) => m.payload(put(b), b.length, version, flags), image);

/** A .svec file's header and its zstd frame's header and blocks checked (wasm/json.c): the
 * payload's size, the frame's end, what a cut raw block gives, the frame descriptor, the version, the flags. */
export const container = (b: Uint8Array) => call((put, m) => m.container(put(b), b.length), (at, get) => get(Float64Array, at, 6));
