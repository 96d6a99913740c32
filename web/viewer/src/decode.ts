// Reading `.svec` (binary versions 1, 2 and 3) and `.svec.json` files (docs/format.md): a port of
// the C++ reader (src/io/svec.cpp, svec_binary.cpp, svec_compact.cpp, svec_range_p.h,
// svec_json.cpp) with the same checks in the same order and the same one-line messages, so that
// the viewer shows what the C++ renderer shows, numbered the same, or refuses what it refuses.
//
// Nothing is trusted: the zstd frame header is checked before fzstd allocates anything from it,
// every count is capped and checked against the bytes left before an array is sized from it
// (compact levels grow their arrays as the traversal proves vertices), every loop is bounded by
// the input, and whatever goes wrong inside surfaces as a SvecError.
import { Decompress } from 'fzstd';
import { Feature, Level, Stroke, SvecError, SvecImage } from './image';
import { MAX_DIMENSION, MAX_ELEMENTS, MAX_LEVELS, PyramidRecord, fail, sortPairs, topology, validate, wedges } from './validate';

const GIB = 2 ** 30; // largest file, and largest payload
const MAGIC = [0x53, 0x55, 0x42, 0x56, 0x45, 0x43, 0x00, 0x1a]; // "SUBVEC" NUL ^Z
const HEADER = 32;
const utf8 = new TextDecoder('utf-8', { fatal: true, ignoreBOM: true });

const oneLine = (s: string) => s.replace(/[\x00-\x1f\x7f]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`);
const latin1 = (b: Uint8Array) => String.fromCharCode(...b);
const hex = (b: ArrayLike<number>) => Array.from(b, (x) => x.toString(16).padStart(2, '0')).join(' ');
const unzigzag = (v: number) => (v % 2 ? -(v + 1) / 2 : v / 2);

// Invalid UTF-8 gets a lone surrogate, which validate() reports in its place in the order.
function text(b: Uint8Array): string {
  try {
    return utf8.decode(b);
  } catch {
    return '\ud800';
  }
}

// ---------------------------------------------------------------------------------------------
// Bytes.

/** A bounds-checked little-endian cursor that names what it was reading when the bytes run out. */
class Cursor {
  pos = 0;
  what = 'the payload';
  private readonly d: DataView;
  constructor(readonly b: Uint8Array) {
    this.d = new DataView(b.buffer, b.byteOffset, b.length);
  }
  left() {
    return this.b.length - this.pos;
  }
  take(n: number): number {
    const p = this.pos;
    if (n > this.left()) fail(`truncated payload while reading ${this.what} (needs ${n} bytes at offset ${p}, ${this.left()} left)`);
    this.pos += n;
    return p;
  }
  bytes(n: number) {
    const p = this.take(n);
    return this.b.subarray(p, p + n);
  }
  u8() {
    return this.b[this.take(1)];
  }
  u32() {
    return this.d.getUint32(this.take(4), true);
  }
  i32() {
    return this.d.getInt32(this.take(4), true);
  }
  f32() {
    return this.d.getFloat32(this.take(4), true);
  }
  f64() {
    return this.d.getFloat64(this.take(8), true);
  }
  // Unsigned LEB128 of at most 64 bits; exact below 2^53, which every range check lies below.
  varint(): number {
    for (let v = 0, shift = 0; ; shift += 7) {
      const b = this.u8();
      if (shift === 63 && (b & 0x7e || b & 0x80)) fail(`malformed varint while reading ${this.what}`);
      v += (b & 0x7f) * 2 ** shift;
      if (!(b & 0x80)) return v;
    }
  }
  svarint() {
    return unzigzag(this.varint());
  }
  // An element count, capped by `max` and by the bytes left (each element takes `min` or more).
  count(what: string, min: number, max = MAX_ELEMENTS): number {
    this.what = `${what} count`;
    const n = this.u32();
    if (n > max) fail(`${what}: count ${n} is over the limit of ${max}`);
    this.what = what;
    if (n * min > this.left())
      fail(`truncated payload while reading ${what} (${n} declared, needing ${n * min} bytes at offset ${this.pos}, ${this.left()} left)`);
    return n;
  }
  string(what: string) {
    return text(this.bytes(this.count(what, 1)));
  }
}

// ---------------------------------------------------------------------------------------------
// zstd: one frame that must decompress to exactly `expected` bytes (fzstd, plus the checks
// libzstd makes that fzstd does not: window limit, dictionary, block sizes, checksum).

function unzstd(f: Uint8Array, expected: number): Uint8Array {
  const le = (at: number, n: number) => {
    let v = 0;
    for (let i = n; i--; ) v = v * 256 + f[at + i];
    return v;
  };
  const d = f[4], single = (d >> 5) & 1, dict = [0, 1, 2, 4][d & 3], sizeBytes = [single, 2, 4, 8][d >> 6];
  let end = 6 - single + dict + sizeBytes;
  if (f.length < end || le(0, 4) !== 0xfd2fb528 || d & 8) fail('corrupt zstd frame: bad frame header');
  const content = sizeBytes ? le(end - sizeBytes, sizeBytes) + (sizeBytes === 2 ? 256 : 0) : -1;
  if (content >= 0 && content !== expected) fail(`zstd frame holds ${content} bytes but the header declares ${expected}`);
  // fzstd allocates the window up front: libzstd's default limit (2^27) bounds it.
  const window = single ? content : 2 ** (10 + (f[5] >> 3)) * (1 + (f[5] & 7) / 8);
  if (window > 2 ** 27 + 1) fail('corrupt zstd frame: Frame requires too much memory for decoding');
  if (le(end - sizeBytes - dict, dict)) fail('corrupt zstd frame: Dictionary mismatch');
  // The blocks, to find the frame's end (trailing bytes, truncation). libzstd passes a raw block
  // through as far as it goes: `partial` is what a truncated one gives.
  let partial = 0;
  for (let last = 0; !last; ) {
    if (end + 3 > f.length) {
      end = Infinity;
      break;
    }
    const h = le(end, 3), type = (h >> 1) & 3, size = h >>> 3;
    if (type === 3 || size > Math.min(2 ** 17, window)) fail('corrupt zstd frame: Data corruption detected');
    last = h & 1;
    partial = type === 0 && f.length - end - 3 < size ? Math.max(0, f.length - end - 3) : 0;
    end += 3 + (type === 1 ? 1 : size);
  }
  if (d & 4) end += 4; // checksum
  const parts: Uint8Array[] = [];
  let produced = 0;
  try {
    new Decompress((part) => {
      produced += part.length;
      if (produced > expected) fail(`zstd frame decompresses to more than the ${expected} bytes the header declares`);
      parts.push(part);
    }).push(f.subarray(0, end), true);
  } catch (e) {
    if (e instanceof SvecError) throw e;
    if (end <= f.length || (e as { code?: number }).code !== 5) fail(`corrupt zstd frame: ${(e as Error).message}`);
  }
  if (end > f.length) fail(`truncated zstd frame: it ends after ${produced + partial} of ${expected} payload bytes`);
  const out = new Uint8Array(expected);
  parts.reduce((at, part) => (out.set(part, at), at + part.length), 0);
  if (d & 4 && le(end - 4, 4) !== xxh64(out.subarray(0, produced))) fail("corrupt zstd frame: Restored data doesn't match checksum");
  if (produced !== expected) fail(`zstd frame decompresses to ${produced} bytes but the header declares ${expected}`);
  if (end < f.length) fail(`${f.length - end} unexpected bytes after the zstd frame`);
  return out;
}

// The low 32 bits of XXH64 (seed 0): zstd's content checksum.
const M64 = 2n ** 64n - 1n, P1 = 11400714785074694791n, P2 = 14029467366897019727n;
const P3 = 1609587929392839161n, P4 = 9650029242287828579n, P5 = 2870177450012600261n;
const rotl = (x: bigint, r: bigint) => ((x << r) | (x >> (64n - r))) & M64;
const round = (acc: bigint, lane: bigint) => (rotl((acc + lane * P2) & M64, 31n) * P1) & M64;
function xxh64(b: Uint8Array): number {
  const d = new DataView(b.buffer, b.byteOffset, b.length), n = b.length;
  let i = 0, h = P5;
  if (n >= 32) {
    const v = [(P1 + P2) & M64, P2, 0n, M64 + 1n - P1];
    for (; i + 32 <= n; i += 32) for (let k = 0; k < 4; k++) v[k] = round(v[k], d.getBigUint64(i + 8 * k, true));
    h = (rotl(v[0], 1n) + rotl(v[1], 7n) + rotl(v[2], 12n) + rotl(v[3], 18n)) & M64;
    for (const x of v) h = ((h ^ round(0n, x)) * P1 + P4) & M64;
  }
  h = (h + BigInt(n)) & M64;
  for (; i + 8 <= n; i += 8) h = (rotl(h ^ round(0n, d.getBigUint64(i, true)), 27n) * P1 + P4) & M64;
  if (i + 4 <= n) (h = (rotl(h ^ ((BigInt(d.getUint32(i, true)) * P1) & M64), 23n) * P2 + P3) & M64), (i += 4);
  for (; i < n; i++) h = (rotl(h ^ ((BigInt(b[i]) * P5) & M64), 11n) * P1) & M64;
  h = ((h ^ (h >> 33n)) * P2) & M64;
  h = ((h ^ (h >> 29n)) * P3) & M64;
  return Number((h ^ (h >> 32n)) & 0xffffffffn);
}

// ---------------------------------------------------------------------------------------------
// The binary form: header, payload version 1 (lossless), trailer, pyramid records.

function binary(b: Uint8Array): SvecImage {
  const n = Math.min(b.length, 8);
  if (MAGIC.some((x, i) => b[i] !== x)) {
    if (n > 0 && n < 8 && MAGIC.slice(0, n).every((x, i) => b[i] === x))
      fail(`truncated .svec header: ${b.length} bytes, the header needs ${HEADER}`);
    fail(`not a .svec file: wrong magic bytes (${hex(b.subarray(0, n))}, expected ${hex(MAGIC)})`);
  }
  if (b.length < HEADER) fail(`truncated .svec header: ${b.length} bytes, the header needs ${HEADER}`);
  const h = new DataView(b.buffer, b.byteOffset, HEADER);
  const version = h.getUint32(8, true), flags = h.getUint32(12, true);
  const size = h.getBigUint64(16, true), frame = h.getBigUint64(24, true), available = BigInt(b.length - HEADER);
  if (version < 1 || version > 3) fail(`unsupported .svec version ${version} (this build reads 1, 2 and 3)`);
  if (flags) fail(`unsupported .svec flags ${flags} (this build knows none)`);
  if (size > GIB) fail(`declared payload of ${size} bytes is over the limit of ${GIB}`);
  if (frame > available) fail(`truncated .svec file: the header declares a ${frame}-byte zstd frame but only ${available} bytes follow`);
  if (frame < available) fail(`${available - frame} unexpected bytes after the zstd frame`);

  const c = new Cursor(unzstd(b.subarray(HEADER), Number(size)));
  c.what = 'image size';
  const width = c.i32(), height = c.i32(), levels: Level[] = [];
  const nl = c.count('levels', 20, MAX_LEVELS);
  if (version > 1 && (width < 1 || height < 1 || width > MAX_DIMENSION || height > MAX_DIMENSION))
    fail(`image size ${width} x ${height} is out of range (1 to ${MAX_DIMENSION} a side)`);
  for (let l = 0; l < nl; l++) levels.push(version > 1 ? compactLevel(c, l, width, height, version) : losslessLevel(c, l));

  const strokes: Stroke[] = [], metadata: Array<[string, string]> = [];
  for (let i = 0, n = c.count('strokes', 28); i < n; i++) {
    const what = (c.what = `stroke ${i}`);
    const level = c.i32(), width = c.f32(), color: [number, number, number] = [c.f32(), c.f32(), c.f32()], taper = c.f32();
    const points = new Float64Array(2 * c.count(`${what} points`, 16)).map(() => c.f64());
    strokes.push({ level, points, width, color, taper });
  }
  for (let i = 0, n = c.count('metadata entries', 8); i < n; i++)
    metadata.push([c.string(`metadata entry ${i} key`), c.string(`metadata entry ${i} value`)]);

  // Optional: the pyramid records of levels 1 and up (files written before them end here).
  const records: PyramidRecord[] = [];
  if (c.left() && c.left() < 4) fail(`${c.left()} unexpected bytes after the payload's metadata`);
  if (c.left()) {
    c.what = 'pyramid records';
    for (let i = 0, n = c.count('pyramid records', 3, MAX_LEVELS); i < n; i++) {
      const what = (c.what = `pyramid record ${i}`), l = c.u32(), old = records[l];
      if (l < 1 || l >= levels.length || (old && (old.parents.length || old.collapses.length)))
        fail(`${what}: level ${l} is out of range or named twice`);
      // base + delta as a vertex index; both are checked before they are added.
      const index = (base: number, code: number) => {
        const delta = unzigzag(code);
        if (Math.abs(delta) > 2 ** 32 || base + delta < 0 || base + delta > 2 ** 31 - 1) fail(`${what}: a vertex index is out of range`);
        return base + delta;
      };
      let previous = 0;
      const parents = new Int32Array(c.count(`${what} parent vertices`, 1)).map(() => (previous = index(previous, c.varint())));
      const collapses = new Int32Array(2 * c.count(`${what} collapses`, 2));
      for (let k = 0; k < collapses.length; k += 2) {
        collapses[k] = index(0, 2 * Math.min(c.varint(), 2 ** 40));
        collapses[k + 1] = index(collapses[k], c.varint());
      }
      records[l] = { parents, collapses };
    }
  }
  if (c.left()) fail(`${c.left()} unexpected bytes after the payload's pyramid records`);
  const image = { width, height, levels, strokes, metadata };
  validate(image, records);
  return image;
}

function losslessLevel(c: Cursor, l: number): Level {
  const at = `level ${l} `;
  c.what = `${at}counts`;
  const [nv, nc, nt, nr, nf] = ([['vertices', 16], ['colors', 12], ['triangles', 24], ['creases', 8], ['features', 16]] as const).map(
    ([what, min]) => c.count(at + what, min),
  );
  const read = <T extends Float64Array | Float32Array | Int32Array>(what: string, array: T, value: () => number) => {
    c.what = at + what;
    return array.map(value) as T;
  };
  const level: Level = {
    positions: read('vertices', new Float64Array(2 * nv), () => c.f64()),
    colors: read('colors', new Float32Array(3 * nc), () => c.f32()),
    triangles: read('triangles', new Int32Array(3 * nt), () => c.i32()),
    triangleColors: read('triangle colors', new Int32Array(3 * nt), () => c.i32()),
    creases: read('creases', new Int32Array(2 * nr), () => c.i32()),
    features: [],
  };
  for (let i = 0; i < nf; i++) {
    const what = (c.what = `${at}feature ${i}`), id = c.i32(), saliency = c.f64();
    level.features.push({ id, saliency, vertices: new Int32Array(c.count(`${what} vertices`, 4)).map(() => c.i32()) });
  }
  return level;
}

// ---------------------------------------------------------------------------------------------
// Compact levels (versions 2 and 3): the symbols of six kinds, from varint sections (version 2)
// or one range-coded stream (version 3); the traversal, predictions and canonical colors decode
// them alike.

const SECTIONS = ['connectivity', 'split offsets', 'positions', 'features', 'feature steps', 'colors'];
const CONNECTIVITY = 0, SPLITS = 1, POSITIONS = 2, FEATURES = 3, STEPS = 4, COLORS = 5;
const C = 0, L = 1, R = 2, E = 3; // and S = 4

interface Source {
  begin(section: number): void;
  end(section: number): void;
  virtual(): number;
  op(triangle: boolean, fanU: number, fanW: number): number;
  split(): number;
  position(k: number): number;
  vertex(): number;
  step(first: boolean): number;
  id(what: string): number;
  saliency(what: string): number;
  length(what: string): number;
  color(channel: number, activity: number): number;
  finish(): void;
}

function varintSource(c: Cursor, name: string, nv: number): Source {
  const s: Cursor[] = [];
  let ops = 0, packed = 0;
  return {
    begin(k) {
      const label = name + SECTIONS[k], n = c.count(label, 1, MAX_ELEMENTS * 64);
      c.what = label;
      (s[k] = new Cursor(c.bytes(n))).what = label;
      const expected = Math.ceil((2 * nv - 3) / 3);
      if (k === CONNECTIVITY && n !== expected) fail(`${name}connectivity: ${n} bytes for ${nv} vertices (expected ${expected})`);
    },
    end(k) {
      if (s[k].left()) fail(`${s[k].left()} unexpected bytes at the end of ${name}${SECTIONS[k]}`);
    },
    virtual: () => s[SPLITS].varint(),
    op() {
      if (ops % 3 === 0 && (packed = s[CONNECTIVITY].u8()) >= 125) fail(`${name}connectivity: byte ${ops / 3} is not three operations`);
      ops++;
      const op = packed % 5;
      packed = (packed / 5) | 0;
      return op;
    },
    split: () => s[SPLITS].varint(),
    position: () => s[POSITIONS].svarint(),
    vertex: () => s[FEATURES].varint(),
    step: () => s[STEPS].varint(),
    id(what) {
      s[FEATURES].what = name + what;
      return s[FEATURES].svarint();
    },
    saliency(what) {
      const f = s[FEATURES], tag = f.u8();
      if (tag === 1) return f.f32();
      if (tag === 2) return f.f64();
      return tag ? fail(`${name}${what}: unknown saliency tag ${tag}`) : 0;
    },
    length(what) {
      const n = s[FEATURES].varint();
      if (n > s[STEPS].left()) fail(`${name}${what}: ${n + 2} vertices, too few bytes`);
      return n;
    },
    color: () => s[COLORS].svarint(),
    finish() {},
  };
}

// Contexts of version 3 (docs/format.md, "Payload, version 3"), in one array: the operations, 23
// number models, the saliency's.
const OP_C = 1, OP_R = 9, OP_L = 17; // context 0: C or E on a loop of 3; then 8 fans each
const NUMBER = (model: number) => 25 + 170 * model; // zero, sign, prefix[56], suffix[56][2]
const VIRTUAL = 0, SPLIT = 1, X = 2, STEP_FIRST = 4, STEP_NEXT = 5, ID = 6, LENGTH = 7, COLOR = 8; // + 5 channel + activity
const SALIENCY = NUMBER(23); // nonzero, wide, then top[2][4096], then mantissa[2][4]
const CONTEXTS = SALIENCY + 2 + 8192 + 8;

function rangeSource(bytes: Uint8Array, name: string, nv: number): Source {
  const what = `${name}stream`, vertexBits = 32 - Math.clz32(nv - 1);
  const p = new Uint16Array(CONTEXTS).fill(2048), seen = new Uint8Array(CONTEXTS);
  let range = 0xffffffff, code = 0, pos = 0, overread = 0, context = 'header';
  const next = () => {
    if (pos < bytes.length) return bytes[pos++];
    if (++overread > 4) fail(`${what} ${context}: the coded data ends early (${bytes.length} bytes)`);
    return 0;
  };
  const normalize = () => {
    while (range < 2 ** 24) (range = (range << 8) >>> 0), (code = ((code << 8) | next()) >>> 0);
  };
  // A decision in context i; p adapts by 1/2^shift, shift = min(n + 2, 5) after n updates.
  const bit = (i: number) => {
    const bound = (range >>> 12) * p[i], shift = Math.min(seen[i] + 2, 5);
    if (seen[i] < 3) seen[i]++;
    const b = +(code >= bound);
    if (b) (code -= bound), (range -= bound), (p[i] -= p[i] >> shift);
    else (range = bound), (p[i] += (4096 - p[i]) >> shift);
    normalize();
    return b;
  };
  const direct = (n: number) => {
    let v = 0;
    while (n--) {
      range >>>= 1;
      const b = +(code >= range);
      if (b) code -= range;
      v = v * 2 + b;
      normalize();
    }
    return v;
  };
  // Exp-Golomb over decisions: k ones then a zero (prefix[i]), then the k low bits of n + 1,
  // the top two in suffix[k][j], the rest equiprobable.
  const unsigned = (model: number) => {
    const m = NUMBER(model);
    let k = 0, v = 1;
    while (bit(m + 2 + k)) if (++k === 56) fail(`${what} ${context}: a number of more than 56 bits`);
    for (let j = 0; j < k; j++) v = v * 2 + (j < 2 ? bit(m + 58 + 2 * k + j) : direct(1));
    return v - 1;
  };
  const signed = (model: number) => {
    if (!bit(NUMBER(model))) return 0;
    const negative = bit(NUMBER(model) + 1), magnitude = unsigned(model) + 1;
    return negative ? -magnitude : magnitude;
  };
  for (let i = 0; i < 4; i++) code = ((code << 8) | next()) >>> 0;
  if (code >= range) fail(`${what}: corrupt coded data (bad first bytes)`);
  return {
    begin(k) {
      context = SECTIONS[k];
    },
    end() {},
    virtual: () => unsigned(VIRTUAL),
    op(triangle, fanU, fanW) {
      if (triangle) return bit(0) ? E : C;
      if (!bit(OP_C + fanW)) return C;
      if (!bit(OP_R + fanW)) return R;
      return bit(OP_L + fanU) ? 4 : L;
    },
    split: () => unsigned(SPLIT),
    position: (k) => signed(X + k),
    vertex: () => direct(vertexBits),
    step: (first) => unsigned(first ? STEP_FIRST : STEP_NEXT),
    id: () => signed(ID),
    // A bit tree over sign and exponent (node 1 first, node 2i + bit after i), four modeled
    // mantissa bits, the rest equiprobable; f32 or f64.
    saliency() {
      if (!bit(SALIENCY)) return 0;
      const wide = bit(SALIENCY + 1), top = wide ? 12 : 9, view = new DataView(new ArrayBuffer(8));
      let node = 1;
      for (let i = 0; i < top; i++) node = 2 * node + bit(SALIENCY + 2 + 4096 * wide + node);
      let high = node - 2 ** top;
      for (let k = 0; k < 4; k++) high = 2 * high + bit(SALIENCY + 8194 + 4 * wide + k);
      if (!wide) return view.setUint32(0, high * 2 ** 19 + direct(19)), view.getFloat32(0);
      view.setUint32(0, high * 2 ** 16 + direct(16));
      view.setUint32(4, direct(32));
      return view.getFloat64(0);
    },
    length: () => unsigned(LENGTH),
    color: (channel, activity) => signed(COLOR + 5 * channel + activity),
    finish() {
      if (pos < bytes.length) fail(`${bytes.length - pos} unexpected bytes at the end of ${what}`);
      if (code >= range) fail(`${what}: corrupt coded data (the code leaves its interval)`);
    },
  };
}

// ⌊(2·s + n) / (2·n)⌋, the rounded mean of n integers summing to s; BigInt where doubles could
// round.
function mean(terms: number[]): number {
  const n = terms.length;
  let s = 0, bound = 0;
  for (const t of terms) (s += t), (bound += Math.abs(t));
  if (bound < 2 ** 50) return Math.floor((2 * s + n) / (2 * n));
  const num = 2n * terms.reduce((a, t) => a + BigInt(t), 0n) + BigInt(n), den = BigInt(2 * n), q = num / den;
  return Number(num % den && num < 0n ? q - 1n : q);
}

// a·b + c·d for integers, rounded once to a double (as C++ converts an exact int64).
const exact = (a: number, b: number, c: number, d: number) =>
  Math.abs(a * b) + Math.abs(c * d) < 2 ** 53 ? a * b + c * d : Number(BigInt(a) * BigInt(b) + BigInt(c) * BigInt(d));

// The neighbors of each of n vertices in increasing order (CSR), from triangles, 3 per face.
function neighbors(t: Int32Array, n: number): [Int32Array, Int32Array] {
  const a = new Int32Array(2 * t.length), b = new Int32Array(2 * t.length);
  t.forEach((x, h) => {
    const y = t[h - (h % 3) + ((h + 1) % 3)];
    (a[2 * h] = b[2 * h + 1] = x), (b[2 * h] = a[2 * h + 1] = y);
  });
  const [order, start] = sortPairs(a, b, n), offsets = new Int32Array(n + 1), list: number[] = [];
  for (let v = 0; v < n; v++) {
    for (let i = start[v]; i < start[v + 1]; i++) {
      const y = b[order[i]];
      if (list.length === offsets[v] || list[list.length - 1] !== y) list.push(y);
    }
    offsets[v + 1] = list.length;
  }
  return [offsets, Int32Array.from(list)];
}

function compactLevel(c: Cursor, l: number, width: number, height: number, version: number): Level {
  const name = `level ${l} `;
  c.what = `${name}counts`;
  const [nv, ncolors, ntriangles, ncreases, nfeatures] = ['vertices', 'colors', 'triangles', 'creases', 'features'].map((w) => c.count(name + w, 0));
  c.what = `${name}precision`;
  const pb = c.u8(), cb = (c.u8() << 24) >> 24;
  if (pb > 12 || cb < -4 || cb > 12) fail(`${name}precision: position bits ${pb}, color bits ${cb} (expected 0 to 12 and -4 to 12)`);
  if (nv < 3) fail(`${name}vertices: ${nv} (a level has at least 3)`);
  let src: Source;
  if (version === 2) src = varintSource(c, name, nv);
  else {
    const label = `${name}stream`, n = c.count(label, 1, MAX_ELEMENTS * 64);
    c.what = label;
    src = rangeSource(c.bytes(n), name, nv);
  }

  // 1-2. Connectivity: the traversal of the mesh closed by the virtual vertex, 2V - 3 operations
  // after the seed (0, 1, 2). Vertices get decode numbers as C meets them.
  const corrupt = (message: string): never => fail(`${name}connectivity: ${message}`);
  src.begin(CONNECTIVITY);
  src.begin(SPLITS);
  const virt = src.virtual();
  if (virt < 3 || virt > nv) corrupt(`virtual vertex ${virt} out of range`);
  const basis = [-1, -1, -1, -1, -1, -1, -1, -1, -1]; // per decode number: gate u, w and apex when met
  const faces = [0, 1, 2], visits = [1, 1, 1];
  const fan = (v: number) => (v === virt ? 7 : Math.min(visits[v], 6));
  // The frontier: cyclic lists of entries, each the edge to the next one, with the apex (third
  // vertex) of the visited triangle across it; the current loop starts at its gate, the others
  // wait on the stack (gate, size). At the start the loop is 1, 0, 2.
  const vertex = [1, 0, 2], next = [1, 2, 0], prev = [2, 0, 1], apex = [2, 1, 0], stack: number[] = [];
  let gate = 0, size = 3, done = false;
  const entry = (v: number, n: number, p: number, a: number) => {
    next[p] = prev[n] = vertex.length;
    next.push(n), prev.push(p), apex.push(a);
    return vertex.push(v) - 1;
  };
  const unlink = (k: number) => {
    next[prev[k]] = next[k];
    prev[next[k]] = prev[k];
    size--;
  };
  for (let i = 0; i < 2 * nv - 3; i++) {
    if (done) corrupt('the traversal ends before the last operation');
    const g = gate, n = next[g], u = vertex[g], w = vertex[n], op = src.op(size === 3, fan(u), fan(w));
    let x: number;
    if (op === C) {
      // x new, between u and w
      if (visits.length > nv) corrupt(`more vertices than the ${nv} declared`);
      basis.push(u, w, apex[g]);
      x = visits.push(0) - 1;
      apex[g] = w;
      gate = entry(x, n, g, u);
      size++;
    } else if (op === E) {
      // the loop is u, w, x: done; continue with the one on top of the stack
      if (size !== 3) corrupt(`operation ${i} closes a loop of ${size} edges`);
      x = vertex[next[n]];
      if (!(done = !stack.length)) (size = stack.pop()!), (gate = stack.pop()!);
    } else if (op === R || op === L) {
      // x after w (w leaves the loop), or before u (u leaves)
      if (size <= 3) corrupt(`operation ${i} on a loop of 3 edges`);
      const p = prev[g];
      x = vertex[op === R ? next[n] : p];
      op === R ? ((apex[g] = w), unlink(n)) : ((apex[p] = u), unlink(g), (gate = p));
    } else {
      // x pos entries on: the loop splits into x, w, ... (current) and u, x, ... (put aside)
      const code = src.split(), half = Math.floor(code / 2), pos = code % 2 ? size - 2 - half : half + 3;
      if (pos < 3 || pos > size - 2) corrupt('split offset out of range');
      let at = g;
      if (pos <= size / 2) for (let k = 0; k < pos; k++) at = next[at];
      else for (let k = pos; k < size; k++) at = prev[at];
      x = vertex[at];
      gate = entry(x, n, prev[at], u);
      next[g] = at;
      prev[at] = g;
      apex[g] = w;
      stack.push(g, size - pos + 1);
      size = pos;
    }
    if (x === u || x === w) corrupt(`operation ${i} makes a degenerate triangle`);
    visits[u]++, visits[w]++, visits[x]++;
    faces.push(u, w, x);
  }
  if (!done) corrupt('the traversal leaves triangles unvisited');
  if (visits.length !== nv + 1) corrupt(`${visits.length - 1} vertices, but ${nv} are declared`);
  src.end(CONNECTIVITY);
  src.end(SPLITS);

  // The level's vertices are the decode numbers without the virtual one; its triangles the
  // visited ones without it, in visit order.
  const nd = nv + 1, vertexOf = (d: number) => (d < virt ? d : d - 1), decodeOf = (v: number) => (v < virt ? v : v + 1);
  const real: number[] = [];
  for (let f = 0; f < faces.length; f += 3) if (faces[f] !== virt && faces[f + 1] !== virt && faces[f + 2] !== virt) real.push(f / 3);
  if (real.length !== ntriangles) corrupt(`${real.length} triangles, but ${ntriangles} are declared`);
  const triangles = new Int32Array(3 * real.length);
  real.forEach((f, i) => triangles.set(faces.slice(3 * f, 3 * f + 3).map(vertexOf), 3 * i));

  // 3. Positions on the 2^-p grid by decode number, each predicted from those before it: the
  // mean of the parallelograms a + b - c over triangles (x, a, b) and (b, a, c), else from the
  // gate it was met across; clamped to the image.
  src.begin(POSITIONS);
  const px = new Float64Array(nd), py = new Float64Array(nd), ha = new Int32Array(3 * real.length), hb = new Int32Array(3 * real.length);
  real.forEach((f, i) => {
    for (let k = 0; k < 3; k++) (ha[3 * i + k] = faces[3 * f + k]), (hb[3 * i + k] = faces[3 * f + ((k + 1) % 3)]);
  });
  // Half-edges by (from, to): the faces around a vertex (its outgoing half-edges) and the face
  // holding a given half-edge.
  const [order, start] = sortPairs(ha, hb, nd);
  const face = (a: number, b: number) => {
    for (let i = start[a]; i < start[a + 1]; i++) if (hb[order[i]] === b) return real[(order[i] / 3) | 0];
    return -1;
  };
  const maxX = width * 2 ** pb, maxY = height * 2 ** pb, tx: number[] = [], ty: number[] = [];
  let previousX = 0, previousY = 0;
  for (let d = 0; d < nd; d++) {
    if (d === virt) continue;
    tx.length = ty.length = 0;
    for (let i = start[d]; i < start[d + 1]; i++) {
      const a = hb[order[i]], f = real[(order[i] / 3) | 0], b = faces.slice(3 * f, 3 * f + 3).find((v) => v !== d && v !== a)!;
      if (a > d || b > d) continue;
      const o = face(b, a);
      if (o < 0) continue;
      const third = faces.slice(3 * o, 3 * o + 3).find((v) => v !== a && v !== b)!;
      if (third > d) continue;
      tx.push(px[a] + px[b] - px[third]), ty.push(py[a] + py[b] - py[third]);
    }
    let qx: number, qy: number;
    const [u, w, a] = basis.slice(3 * d, 3 * d + 3);
    if (tx.length) (qx = mean(tx)), (qy = mean(ty));
    else if (u < 0) (qx = previousX), (qy = previousY);
    else if (u === virt) (qx = px[w]), (qy = py[w]);
    else if (w === virt) (qx = px[u]), (qy = py[u]);
    else if (a === virt) {
      // Across a border edge: the apex of an equilateral triangle on its inner side.
      qx = Math.floor((px[u] + px[w]) / 2) - Math.floor(((py[w] - py[u]) * 7) / 8);
      qy = Math.floor((py[u] + py[w]) / 2) + Math.floor(((px[w] - px[u]) * 7) / 8);
    } else (qx = px[u] + px[w] - px[a]), (qy = py[u] + py[w] - py[a]);
    const rx = src.position(0), ry = src.position(1);
    if (Math.abs(rx) > 2 ** 40 || Math.abs(ry) > 2 ** 40) fail(`${name}positions: residual out of range`);
    previousX = px[d] = Math.min(Math.max(qx, 0), maxX) + rx;
    previousY = py[d] = Math.min(Math.max(qy, 0), maxY) + ry;
  }
  src.end(POSITIONS);
  const fx = new Float64Array(nv).map((_, v) => px[decodeOf(v)]), fy = new Float64Array(nv).map((_, v) => py[decodeOf(v)]);
  const positions = new Float64Array(2 * nv).map((_, i) => (i % 2 ? fy : fx)[i >> 1] * 2 ** -pb);

  // 4. Creases and features: a first vertex, then each next one as its rank among the current
  // vertex's neighbors, by number for the first step, after that straightest first (exact
  // integer dot products, one rounding, as in C++).
  src.begin(FEATURES);
  src.begin(STEPS);
  const [offsets, list] = neighbors(triangles, nv);
  const checked = (v: number, what: string) => (v >= nv ? fail(`${name}${what}: vertex ${v} out of range`) : v);
  const step = (from: number, at: number, first: boolean, what: string) => {
    let ranked = Array.from(list.subarray(offsets[at], offsets[at + 1]));
    if (from >= 0) {
      const dx = fx[at] - fx[from], dy = fy[at] - fy[from];
      ranked = ranked
        .map((q) => {
          const ex = fx[q] - fx[at], ey = fy[q] - fy[at], len = Math.sqrt(exact(ex, ex, ey, ey));
          return [len > 0 ? -exact(dx, ex, dy, ey) / len : 0, q];
        })
        .sort((s, t) => s[0] - t[0] || s[1] - t[1])
        .map((k) => k[1]);
    }
    const r = src.step(first);
    return r >= ranked.length ? fail(`${name}${what}: step ${r} out of range`) : ranked[r];
  };
  const creases: number[] = [], features: Feature[] = [];
  for (let i = 0; i < ncreases; i++) {
    const a = checked(src.vertex(), `crease ${i}`);
    creases.push(a, step(-1, a, true, `crease ${i}`));
  }
  for (let i = 0, previous = -1; i < nfeatures; i++) {
    const what = `feature ${i}`, id = (previous += 1 + src.id(what));
    if (id < -(2 ** 31) || id > 2 ** 31 - 1) fail(`${name}${what}: id out of range`);
    const saliency = src.saliency(what), n = src.length(what);
    if (n > nv) fail(`${name}${what}: ${n + 2} vertices, more than the level has`);
    const v = [checked(src.vertex(), what)];
    for (let k = 0; k <= n; k++) v.push(step(v.length >= 2 ? v[v.length - 2] : -1, v[v.length - 1], k === 0, what));
    features.push({ id, saliency, vertices: Int32Array.from(v) });
  }
  src.end(FEATURES);
  src.end(STEPS);

  // 5. Colors: one value per wedge (the tears are known now), numbered canonically; each
  // predicted by the rounded mean of the known values it shares a triangle with (else the
  // previous one), coded as d_G, d_R - d_G, d_B - d_G in contexts of the neighbors' residuals.
  src.begin(COLORS);
  const level: Level = { positions, colors: new Float32Array(0), triangles, triangleColors: triangles, creases: Int32Array.from(creases), features };
  const [triangleColors, nc] = wedges(level, topology(level, nv));
  if (nc !== ncolors) fail(`${name}colors: the tears give ${nc} color values, but ${ncolors} are declared`);
  const [coffsets, clist] = neighbors(triangleColors, nc);
  const rgb = new Float64Array(3 * nc), activity = new Float64Array(3 * nc), known = new Uint8Array(nc);
  const mid = Math.round(128 * 2 ** cb), last = [mid, mid, mid];
  for (let ci = 0; ci < nc; ci++) {
    const adjacent = Array.from(clist.subarray(coffsets[ci], coffsets[ci + 1])).filter((j) => known[j]), n = adjacent.length;
    const q = [0, 1, 2].map((ch) => (n ? mean(adjacent.map((j) => rgb[3 * j + ch])) : last[ch]));
    const d = [0, 1, 2].map((ch) => {
      const mean = Math.floor(adjacent.reduce((s, j) => s + activity[3 * j + ch], 0) / n);
      return src.color(ch, n ? Math.min((33 - Math.clz32(mean)) >> 1, 4) : 0);
    });
    d.forEach((r, ch) => {
      if (Math.abs(r) > 2 ** 48) fail(`${name}colors: residual out of range`);
      activity[3 * ci + ch] = Math.min(Math.abs(r), 65535);
    });
    [d[1] + d[0], d[0], d[2] + d[0]].forEach((r, ch) => {
      if (Math.abs(q[ch]) > 2 ** 48) fail(`${name}colors: value out of range`);
      last[ch] = rgb[3 * ci + ch] = q[ch] + r;
    });
    known[ci] = 1;
  }
  src.end(COLORS);
  src.finish();
  return { ...level, colors: Float32Array.from(rgb, (v) => v * 2 ** -cb), triangleColors };
}

// ---------------------------------------------------------------------------------------------
// The JSON form: a small exact tokenizer (duplicate keys, integers vs numbers, depth 32, UTF-8),
// then a walk with the C++ reader's checks and messages ("levels[0].triangles[12][1]: ...").

/** A number written with a fraction or exponent whose value is an integer (3.0, 1e2). */
class Fraction {
  constructor(readonly value: number) {}
}
type Json = number | Fraction | string | boolean | null | Json[] | Map<string, Json>;

// Token patterns, on the text read one character per byte.
const SPACE = /[ \t\n\r]*/y, NUMERAL = /-?(0|[1-9]\d*)(\.\d+)?([eE][+-]?\d+)?/y, LITERAL = /true|false|null/y;

function parseJson(b: Uint8Array): Json {
  const text = new TextDecoder('latin1').decode(b);
  let i = 0;
  const token = (pattern: RegExp) => {
    pattern.lastIndex = i;
    const m = pattern.exec(text);
    if (m) i = pattern.lastIndex;
    return m;
  };
  const frames: Array<{ key?: string; index: number }> = []; // open containers, for the paths
  const path = (withTopKey: boolean) =>
    frames.reduce(
      (s, f, k) =>
        f.key === undefined ? (f.index >= 0 ? `${s}[${f.index}]` : s) : f.key && (withTopKey || k + 1 < frames.length) ? (s ? `${s}.${f.key}` : f.key) : s,
      '',
    ) || '(top level)';
  const syntax = (what: string): never => {
    const line = text.slice(0, i).split('\n');
    return fail(`invalid JSON near ${path(true)} (byte ${i + 1}): parse error at line ${line.length}, column ${line[line.length - 1].length + 1}: syntax error - ${what}`);
  };
  // Escapes are JSON.parse's; the bytes must be UTF-8 and the escapes make no lone surrogate.
  const string = (): string => {
    const from = i++;
    while (i < b.length && b[i] !== 34) i += b[i] === 92 ? 2 : 1;
    if (i++ >= b.length) syntax('invalid string: missing closing quote');
    try {
      const s: string = JSON.parse(utf8.decode(b.subarray(from, i)));
      if (!/[\ud800-\udfff]/u.test(s)) return s;
    } catch {}
    return syntax('invalid string');
  };
  const value = (): Json => {
    token(SPACE);
    const c = text[i];
    if (c === '{' || c === '[') {
      if (frames.length >= 32) fail(`${path(true)}: JSON nested deeper than 32 levels`);
      const close = c === '{' ? '}' : ']', out: Json = c === '{' ? new Map<string, Json>() : [];
      const frame = { key: out instanceof Map ? '' : undefined, index: -1 };
      frames.push(frame);
      i++;
      token(SPACE);
      if (text[i] === close) i++;
      else
        for (;;) {
          if (out instanceof Map) {
            token(SPACE);
            if (text[i] !== '"') syntax('expected string literal');
            const key = (frame.key = string());
            if (out.has(key)) fail(`${path(false)}: duplicate key "${key}"`);
            token(SPACE);
            if (text[i++] !== ':') syntax("expected ':'");
            out.set(key, value());
          } else frame.index++, out.push(value());
          token(SPACE);
          const d = text[i++];
          if (d === close) break;
          if (d !== ',') syntax(`expected ',' or '${close}'`);
        }
      frames.pop();
      return out;
    }
    if (c === '"') return string();
    const number = token(NUMERAL), literal = !number && token(LITERAL);
    if (number) {
      const v = Number(number[0]);
      if (!isFinite(v)) fail(`invalid JSON at ${path(true)}: number overflow parsing '${number[0]}'`);
      // An integer token is an integer where it fits 64 bits (nlohmann: int64 or uint64).
      if (!number[2] && !number[3] && v >= -(2 ** 63) && v < 2 ** 64) return v + 0;
      return Number.isInteger(v) ? new Fraction(v) : v;
    }
    if (literal) return literal[0] === 'null' ? null : literal[0] === 'true';
    return syntax(c === undefined ? 'unexpected end of input' : 'invalid literal');
  };
  const root = value();
  token(SPACE);
  if (i < b.length) syntax('unexpected character after the value; expected end of input');
  return root;
}

const TOP = '(top level)';
const at = (p: string, k: string | number) => (typeof k === 'number' ? `${p === TOP ? '' : p}[${k}]` : p === TOP ? k : `${p}.${k}`);
const bad = (p: string, message: string): never => fail(`${p}: ${message}`);
const typeName = (j: Json) =>
  j === null
    ? 'null'
    : typeof j === 'number'
    ? Number.isInteger(j) ? 'an integer' : 'a number with a fraction or exponent'
    : j instanceof Fraction
    ? 'a number with a fraction or exponent'
    : typeof j === 'string'
    ? 'a string'
    : typeof j === 'boolean'
    ? 'a boolean'
    : Array.isArray(j)
    ? 'an array'
    : 'an object';

// A number as nlohmann's dump() writes it: 4.0, 0.5, 4e+38, 1e-05.
function dump(v: number): string {
  const [digits, exponent] = v.toExponential().split('e'), e = +exponent;
  if (e > 14 || e < -4) return `${digits}e${e < 0 ? '-' : '+'}${String(Math.abs(e)).padStart(2, '0')}`;
  return Number.isInteger(v) ? v.toFixed(1) : String(v);
}
const number = (j: Json, p: string) => (typeof j === 'number' ? j : j instanceof Fraction ? j.value : bad(p, `expected a number, got ${typeName(j)}`));
function float(j: Json, p: string): number {
  const v = number(j, p);
  return Math.abs(v) > 3.4028234663852886e38 ? bad(p, `number ${dump(v)} is out of range for a 32-bit float`) : Math.fround(v);
}
function int(j: Json, p: string): number {
  if (typeof j !== 'number' || !Number.isInteger(j))
    return bad(p, `expected an integer, got ${typeName(j)}${typeof j === 'number' || j instanceof Fraction ? ` (${dump(number(j, p))})` : ''}`);
  return j < -(2 ** 31) || j > 2 ** 31 - 1 ? bad(p, `integer ${j} is out of the 32-bit range`) : j;
}
function object(j: Json, p: string): Map<string, Json> {
  return j instanceof Map ? j : bad(p, `expected an object, got ${typeName(j)}`);
}
// Rejects keys outside `allowed`, naming the first unknown one in key order (as std::map has them).
function known(m: Map<string, Json>, p: string, allowed: string[]) {
  const unknown = [...m.keys()].sort().find((k) => !allowed.includes(k));
  if (unknown !== undefined) bad(p, `unknown key "${unknown}" (expected one of: ${allowed.join(', ')})`);
  return m;
}
const need = (m: Map<string, Json>, p: string, key: string) => (m.has(key) ? m.get(key)! : bad(p, `missing key "${key}"`));
function list(j: Json, p: string): Json[] {
  if (!Array.isArray(j)) return bad(p, `expected an array, got ${typeName(j)}`);
  return j.length > MAX_ELEMENTS ? bad(p, `${j.length} elements is over the limit of ${MAX_ELEMENTS}`) : j;
}
type Read = (j: Json, p: string) => number;
// A fixed-size array such as [x, y] or [a, b, c].
function tuple(j: Json, p: string, n: number, shape: string, read: Read): number[] {
  if (!Array.isArray(j) || j.length !== n) bad(p, `expected ${shape}, got ${Array.isArray(j) ? `an array of ${j.length} elements` : typeName(j)}`);
  return (j as Json[]).map((x, k) => read(x, at(p, k)));
}
// A list of them into a typed array.
function tuples<T extends Float64Array | Float32Array | Int32Array>(array: new (n: number) => T, j: Json, p: string, n: number, shape: string, read: Read): T {
  const items = list(j, p), out = new array(n * items.length);
  items.forEach((t, i) => out.set(tuple(t, at(p, i), n, shape, read), n * i));
  return out;
}
const ints = (j: Json, p: string) => Int32Array.from(list(j, p), (x, i) => int(x, at(p, i)));
const TRIANGLE = '[a, b, c] (three integers)';

function json(b: Uint8Array): SvecImage {
  const root = parseJson(b);
  if (!(root instanceof Map)) return bad(TOP, `expected a JSON object, got ${typeName(root)}`);
  const top = root;
  const format = need(top, TOP, 'format');
  if (format !== 'subvec') bad('format', `expected "subvec", got ${JSON.stringify(format instanceof Fraction ? format.value : format)} (this is not a subvec file)`);
  const version = int(need(top, TOP, 'version'), 'version');
  if (version !== 1) bad('version', `unsupported .svec.json version ${version} (this build reads 1)`);
  known(top, TOP, ['format', 'version', 'width', 'height', 'levels', 'strokes', 'metadata']);
  const width = int(need(top, TOP, 'width'), 'width'), height = int(need(top, TOP, 'height'), 'height');
  const items = list(need(top, TOP, 'levels'), 'levels'), records: PyramidRecord[] = [];
  if (items.length > MAX_LEVELS) bad('levels', `${items.length} levels is over the limit of ${MAX_LEVELS}`);
  const levels = items.map((j, l): Level => {
    const p = at('levels', l), m = known(object(j, p), p, ['vertices', 'colors', 'triangles', 'triangle_colors', 'creases', 'features', 'parent_vertices', 'collapses']);
    const positions = tuples(Float64Array, need(m, p, 'vertices'), at(p, 'vertices'), 2, '[x, y]', number);
    const colors = tuples(Float32Array, need(m, p, 'colors'), at(p, 'colors'), 3, '[r, g, b]', float);
    const triangles = tuples(Int32Array, need(m, p, 'triangles'), at(p, 'triangles'), 3, TRIANGLE, int);
    let triangleColors = triangles.slice();
    if (m.has('triangle_colors')) {
      const q = at(p, 'triangle_colors');
      triangleColors = tuples(Int32Array, m.get('triangle_colors')!, q, 3, TRIANGLE, int);
      if (triangleColors.length !== triangles.length)
        bad(q, `${triangleColors.length / 3} entries but there are ${triangles.length / 3} triangles (one entry per triangle)`);
    } else if (colors.length / 3 !== positions.length / 2) {
      bad(p, `"triangle_colors" is absent, so color i belongs to vertex i, but there are ${positions.length / 2} vertices and ${colors.length / 3} colors`);
    }
    const optional = <T>(key: string, read: (j: Json, p: string) => T, otherwise: T) => (m.has(key) ? read(m.get(key)!, at(p, key)) : otherwise);
    const creases = optional('creases', (j, q) => tuples(Int32Array, j, q, 2, '[a, b] (two vertex indices)', int), new Int32Array(0));
    const features = optional('features', (j, q) => list(j, q).map((f, i): Feature => {
      const r = at(q, i), o = known(object(f, r), r, ['id', 'vertices', 'saliency']);
      const id = int(need(o, r, 'id'), at(r, 'id')), vertices = ints(need(o, r, 'vertices'), at(r, 'vertices'));
      return { id, vertices, saliency: o.has('saliency') ? number(o.get('saliency')!, at(r, 'saliency')) : 0 };
    }), []);
    records[l] = {
      parents: optional('parent_vertices', ints, new Int32Array(0)),
      collapses: optional('collapses', (j, q) => tuples(Int32Array, j, q, 2, '[removed, kept] (two vertex indices)', int), new Int32Array(0)),
    };
    return { positions, colors, triangles, triangleColors, creases, features };
  });
  const strokes = top.has('strokes')
    ? list(top.get('strokes')!, 'strokes').map((j, i): Stroke => {
        const p = at('strokes', i), m = known(object(j, p), p, ['level', 'points', 'width', 'color', 'taper']);
        const level = m.has('level') ? int(m.get('level')!, at(p, 'level')) : 0;
        const points = tuples(Float64Array, need(m, p, 'points'), at(p, 'points'), 2, '[x, y]', number);
        const width = float(need(m, p, 'width'), at(p, 'width'));
        const color = tuple(need(m, p, 'color'), at(p, 'color'), 3, '[r, g, b]', float) as [number, number, number];
        return { level, points, width, color, taper: m.has('taper') ? float(m.get('taper')!, at(p, 'taper')) : 0.25 };
      })
    : [];
  const metadata: Array<[string, string]> = [];
  if (top.has('metadata'))
    for (const [key, v] of object(top.get('metadata')!, 'metadata'))
      metadata.push([key, typeof v === 'string' ? v : bad(at('metadata', key), `expected a string, got ${typeName(v)}`)]);
  const image = { width, height, levels, strokes, metadata };
  validate(image, records);
  return image;
}

// ---------------------------------------------------------------------------------------------
// Entry points.

// Another image format, named (docs/format.md, "Error messages"), with what to do where there is
// something to do.
const FORMATS: Array<[string, RegExp]> = [
  ['PNG', /^\x89PNG\r\n\x1a\n/], ['JPEG', /^\xff\xd8\xff/], ['WebP', /^RIFF[^]{4}WEBP/], ['TIFF', /^(II[*+]\0|MM\0[*+])/],
  ['BMP', /^BM/], ['GIF', /^GIF8[^]{2}/], ['PDF', /^%PDF-/], ['SVG', /^[ \t\r\n\xef\xbb\xbf]*(?=<)[^]*<svg/],
];
function otherFormat(b: Uint8Array, name = 'image'): string | undefined {
  const head = latin1(b.subarray(0, 4096)), format = FORMATS.find(([, pattern]) => pattern.test(head))?.[0];
  if (!format) return undefined;
  const vector = format === 'PDF' || format === 'SVG';
  return `${format === 'SVG' ? 'an' : 'a'} ${format} ${vector ? 'file' : 'image'}, not a .svec or .svec.json file${
    vector ? `; subvec writes ${format} (render -o out.${format.toLowerCase()}) but cannot read it`
    : format === 'GIF' ? '' : `; vectorize it first: subvec vectorize ${name} -o ${name.replace(/(\.[^./\\]*)?$/, '.svec')}`}`;
}

/** Decodes and validates a .svec (binary versions 1, 2, 3) or .svec.json file from its bytes.
 * Throws SvecError with a one-line message (prefixed with `name` when given). */
export function decode(bytes: Uint8Array | ArrayBuffer, name?: string): SvecImage {
  try {
    const b = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
    if (b.length > GIB) fail(`file is ${b.length} bytes, over the limit of ${GIB}`);
    if (MAGIC.every((x, i) => b[i] === x)) return binary(b);
    // The form is chosen by content: JSON starts with { or [ (after a byte order mark, blanks).
    const bom = b[0] === 0xef && b[1] === 0xbb && b[2] === 0xbf ? 3 : 0;
    let i = bom;
    while (b[i] === 32 || b[i] === 9 || b[i] === 10 || b[i] === 13) i++;
    if (b[i] === 123 || b[i] === 91) return json(b.subarray(bom));
    if (!b.length) fail('file is empty');
    const other = otherFormat(b, name);
    return other ? fail(other) : binary(b);
  } catch (e) {
    const message = e instanceof SvecError ? e.message : `internal error: ${e instanceof Error ? e.message : String(e)}`;
    throw new SvecError(oneLine(name ? `${name}: ${message}` : message));
  }
}

/** fetch()es a URL (or reads a Blob/File, or takes an ArrayBuffer/Uint8Array) and decodes it.
 * Rejects with SvecError (HTTP status, network failure, or decode error), never anything else. */
export async function load(source: string | URL | Blob | ArrayBuffer | Uint8Array, init?: RequestInit): Promise<SvecImage> {
  let name: string | undefined, bytes: ArrayBuffer | Uint8Array;
  try {
    const tooLarge = (n: number) => n > GIB && fail(`file is ${n} bytes, over the limit of ${GIB}`);
    if (typeof source === 'string' || source instanceof URL) {
      name = String(source);
      const response = await fetch(source, init);
      if (!response.ok) fail(`HTTP ${response.status} ${response.statusText}`.trim());
      tooLarge(Number(response.headers.get('content-length')));
      bytes = await response.arrayBuffer();
    } else if (source instanceof Blob) {
      name = (source as File).name || undefined;
      tooLarge(source.size);
      bytes = await source.arrayBuffer();
    } else bytes = source;
  } catch (e) {
    throw new SvecError(oneLine(`${name ? `${name}: ` : ''}${e instanceof Error ? e.message : String(e)}`));
  }
  return decode(bytes, name);
}
