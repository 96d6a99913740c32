// Reading `.svec` (binary versions 1, 2 and 3) and `.svec.json` files (docs/format.md): a port of
// the C++ reader (src/io/svec.cpp, svec_binary.cpp, svec_compact.cpp, svec_range_p.h,
// svec_json.cpp) with the same checks in the same order and the same one-line messages, so that
// the viewer shows what the C++ renderer shows, numbered the same, or refuses what it refuses.
//
// Nothing is trusted: the zstd frame header is checked before fzstd allocates anything from it,
// every count is capped and checked against the bytes left before an array is sized from it
// (compact levels size theirs by what the stream can hold), every loop is bounded by the input,
// and whatever goes wrong inside surfaces as a SvecError. The hot loops are plain loops over
// typed arrays sized up front: a page decodes its file once, before anything is compiled.
import { Decompress } from 'fzstd';
import { SvecError, SvecImage } from './image';
import { checksum, container, readJson, readPayload } from './wasm';

const GIB = 2 ** 30; // largest file, and largest payload
const MAGIC = [0x53, 0x55, 0x42, 0x56, 0x45, 0x43, 0x00, 0x1a]; // "SUBVEC" NUL ^Z
const HEADER = 32;

const latin1 = (b: Uint8Array) => String.fromCharCode(...b);

function fail(message: string): never {
  throw new SvecError(message);
}

/** Control characters as \xNN, for one-line messages. */
const escape = (s: string) => s.replace(/[\x00-\x1f\x7f]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`);

// ---------------------------------------------------------------------------------------------
// zstd: one frame that must decompress to exactly `expected` bytes (fzstd, plus the checks
// libzstd makes that fzstd does not: window limit, dictionary, block sizes, checksum).

function unzstd(f: Uint8Array, expected: number, end: number, partial: number, d: number): Uint8Array {
  const out = new Uint8Array(expected);
  let produced = 0;
  try {
    new Decompress((part) => {
      if (produced + part.length > expected) fail(`zstd frame decompresses to more than the ${expected} bytes the header declares`);
      out.set(part, produced);
      produced += part.length;
    }).push(f.subarray(0, end), true);
  } catch (e) {
    if (e instanceof SvecError) throw e;
    if (end <= f.length || (e as { code?: number }).code !== 5) fail(`corrupt zstd frame: ${(e as Error).message}`);
  }
  if (end > f.length) fail(`truncated zstd frame: it ends after ${produced + partial} of ${expected} payload bytes`);
  if (d & 4 && new DataView(f.buffer, f.byteOffset + end - 4).getUint32(0, true) !== checksum(out.subarray(0, produced))) fail("corrupt zstd frame: Restored data doesn't match checksum");
  if (produced !== expected) fail(`zstd frame decompresses to ${produced} bytes but the header declares ${expected}`);
  if (end < f.length) fail(`${f.length - end} unexpected bytes after the zstd frame`);
  return out;
}

// ---------------------------------------------------------------------------------------------
// The binary form: the header and the zstd frame checked, the payload decompressed here, then
// read and validated in WebAssembly (wasm/json.c, validate.c).

function binary(b: Uint8Array): SvecImage {
  const [size, end, partial, d, version, flags] = container(b);
  return readPayload(unzstd(b.subarray(HEADER), size, end, partial, d), version, flags);
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
    if (b[i] === 123 || b[i] === 91) return readJson(b.subarray(bom));
    if (!b.length) fail('file is empty');
    const other = otherFormat(b, name);
    return other ? fail(other) : binary(b);
  } catch (e) {
    const message = e instanceof SvecError ? e.message : `internal error: ${e instanceof Error ? e.message : String(e)}`;
    throw new SvecError(escape(name ? `${name}: ${message}` : message));
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
    throw new SvecError(escape(`${name ? `${name}: ` : ''}${e instanceof Error ? e.message : String(e)}`));
  }
  return decode(bytes, name);
}
