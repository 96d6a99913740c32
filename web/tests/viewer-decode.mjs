// The viewer's decoder (web/viewer/src/decode.ts) against the C++ reader (the `subvec` CLI).
//
//   node web/tests/viewer-decode.mjs BUILD/bin/subvec
//
// Bundles decode.ts for node with esbuild, then checks that
//  1. it rejects exactly the files of the bad-input corpora (tests/data/bad, fuzz/corpus) that
//     `subvec info` rejects, each with a SvecError of one non-empty line (both messages printed);
//  2. good files (the examples as JSON and as .svec versions 1, 2 and 3, a vectorized and a stylized
//     photograph, a hand-made image with strokes and metadata, files with objects made by
//     `subvec edit` in every version, with strokes on them by `subvec stylize --object`) decode
//     to what the C++ reader
//     gives, as `subvec convert X -o X.svec.json --lossless` writes it: same numbering, same
//     values (positions within 1e-9 relative, colors exact in float32);
//  3. the worked examples of docs/format.md (JSON, and the version 2 and 3 payloads) decode as the
//     document says;
//  4. small crafted inputs (JSON corner cases, huge counts in tiny payloads, objects and their
//     strokes good and bad in both forms) are accepted or rejected as by the C++ reader (bad objects with the C++
//     reader's message, word for word);
//  5. mutations of good files (truncations; flipped bytes of the file, and of the payload wrapped
//     in a fresh zstd frame) always give a SvecError or a valid image, quickly; accept/reject as
//     the C++ reader does;
//  6. the zstd content checksum (XXH64, in the viewer's WebAssembly) is the `zstd` command's, on
//     every length from 0 to 100 bytes (each tail of the hash) and on longer inputs.
// Exit 0 when all pass, 1 on a failure, 77 (SKIPPED) without web/node_modules or the CLI.
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const root = path.dirname(web);
const cli = process.argv[2] ? path.resolve(process.argv[2]) : '';
const skip = (reason) => {
  console.log(`SKIPPED: ${reason}`);
  process.exit(77);
};
if (!cli || !fs.existsSync(cli)) skip(`the subvec CLI ${cli ? `${cli} is missing` : 'is not given (node web/tests/viewer-decode.mjs BUILD/bin/subvec)'}`);
const require = createRequire(path.join(web, 'package.json'));
let esbuild, fzstd;
try {
  esbuild = require('esbuild');
  fzstd = require('fzstd');
} catch {
  skip('web/node_modules lacks esbuild or fzstd (npm ci in web/)');
}

const started = Date.now();
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'viewer-decode-'));
process.on('exit', () => fs.rmSync(tmp, { recursive: true, force: true }));
esbuild.buildSync({
  entryPoints: [path.join(web, 'viewer/src/decode.ts')],
  bundle: true,
  format: 'esm',
  platform: 'node',
  outfile: path.join(tmp, 'decode.mjs'),
  logLevel: 'error',
});
const { decode, load } = await import(pathToFileURL(path.join(tmp, 'decode.mjs')).href);

let passed = 0, failed = 0;
const check = (ok, what) => {
  if (ok) passed++;
  else {
    failed++;
    console.log(`FAIL: ${what}`);
  }
  return ok;
};

// The C++ reader: accepts or its message (without "subvec: PATH: "); `subvec info` on many files
// at once (starting the CLI is most of the test's time).
const subvec = (...args) => spawnSync(cli, args, { encoding: 'utf8' });
const verdict = (status, stderr, file) => ({
  ok: status === 0,
  message: (stderr.split('\n').find((l) => l.trim()) ?? '').replace(/^subvec: /, '').replace(`${file}: `, ''),
});
async function cppAll(files) {
  const out = [];
  let next = 0;
  const worker = async () => {
    for (let i; (i = next++) < files.length; )
      out[i] = await new Promise((resolve) => {
        const p = spawn(cli, ['info', files[i]], { stdio: ['ignore', 'ignore', 'pipe'] });
        let stderr = '';
        p.stderr.setEncoding('utf8').on('data', (d) => (stderr += d));
        p.on('close', (status) => resolve(verdict(status, stderr, files[i])));
      });
  };
  await Promise.all(Array.from({ length: Math.max(2, Math.min(8, os.cpus().length)) }, worker));
  return out;
}
// The viewer: the image, or the error (anything but a SvecError is a failure of its own).
function js(bytes) {
  const t = performance.now();
  try {
    return { ok: true, image: decode(bytes), ms: performance.now() - t };
  } catch (e) {
    return { ok: false, error: e, message: e?.message ?? String(e), ms: performance.now() - t };
  }
}
const wellFormed = (r) => r.ok || (r.error?.name === 'SvecError' && /^[^\n\r]+$/.test(r.message) && !r.message.startsWith('internal error'));

// ---------------------------------------------------------------------------------------------
console.log('== 1. bad-input corpora: accept/reject as the C++ reader, one-line SvecError');
const corpora = [path.join(root, 'tests/data/bad'), path.join(root, 'fuzz/corpus/svec_binary'), path.join(root, 'fuzz/corpus/svec_json')];
let same = 0, total = 0;
const corpus = corpora.filter((d) => fs.existsSync(d)).flatMap((d) => fs.readdirSync(d).sort().map((n) => path.join(d, n)));
const corpusVerdicts = await cppAll(corpus);
{
  for (const [k, file] of corpus.entries()) {
    const c = corpusVerdicts[k], j = js(fs.readFileSync(file));
    const label = path.relative(root, file);
    check(wellFormed(j), `${label}: not a one-line SvecError: ${j.error?.name}: ${j.message}`);
    if (!check(c.ok === j.ok, `${label}: C++ ${c.ok ? 'accepts' : 'rejects'} it, the viewer ${j.ok ? 'accepts' : 'rejects'} it`)) continue;
    total++;
    if (c.ok) console.log(`  ${label}: both accept`);
    else {
      same += c.message === j.message;
      console.log(`  ${label}:\n    C++:    ${c.message}\n    viewer: ${j.message}${c.message === j.message ? '  (same)' : ''}`);
    }
  }
}
console.log(`  ${total} files agree on accept/reject; ${same} messages identical`);

// ---------------------------------------------------------------------------------------------
// The C++ decode of a file, as JSON (exact: shortest round-trip numbers).
function reference(file) {
  const out = path.join(tmp, `ref-${path.basename(file)}.svec.json`);
  const r = subvec('convert', file, '-o', out, '--lossless');
  if (r.status !== 0) throw new Error(`subvec convert ${file}: ${r.stderr}`);
  return JSON.parse(fs.readFileSync(out, 'utf8'));
}
// Differences between a decoded image and the C++ one (as JSON); empty when equal.
function compare(image, ref) {
  const diffs = [];
  const eq = (a, b, what) => a !== b && !(Number.isNaN(a) && Number.isNaN(b)) && diffs.push(`${what}: ${a} != ${b}`);
  const close = (a, b, what) => Math.abs(a - b) > 1e-9 * Math.max(1, Math.abs(b)) && diffs.push(`${what}: ${a} != ${b}`);
  const flat = (rows) => (rows ?? []).flat();
  const array = (a, b, what, cmp = eq) => {
    eq(a.length, b.length, `${what} length`);
    for (let i = 0; i < Math.min(a.length, b.length) && diffs.length < 8; i++) cmp(a[i], b[i], `${what}[${i}]`);
  };
  eq(image.width, ref.width, 'width');
  eq(image.height, ref.height, 'height');
  eq(image.levels.length, ref.levels.length, 'levels');
  const mesh = (m, r, l) => {
    array(m.positions, flat(r.vertices), `${l} positions`, close);
    array(m.colors, flat(r.colors).map(Math.fround), `${l} colors`);
    array(m.triangles, flat(r.triangles), `${l} triangles`);
    array(m.triangleColors, flat(r.triangle_colors ?? r.triangles), `${l} triangle colors`);
    array(m.creases, flat(r.creases), `${l} creases`);
    eq(m.features.length, (r.features ?? []).length, `${l} features`);
    (r.features ?? []).forEach((f, i) => {
      const g = m.features[i];
      if (!g) return;
      eq(g.id, f.id, `${l} feature ${i} id`);
      close(g.saliency, f.saliency, `${l} feature ${i} saliency`);
      array(g.vertices, f.vertices, `${l} feature ${i} vertices`);
    });
  };
  const strokes = (mine, theirs = [], owner = '') => {
    eq(mine.length, theirs.length, `${owner}strokes`);
    theirs.forEach((s, i) => {
      const t = mine[i];
      if (!t) return;
      eq(t.level, s.level ?? 0, `${owner}stroke ${i} level`);
      array(t.points, flat(s.points), `${owner}stroke ${i} points`, close);
      eq(t.width, Math.fround(s.width), `${owner}stroke ${i} width`);
      array(t.color, s.color.map(Math.fround), `${owner}stroke ${i} color`);
      eq(t.taper, Math.fround(s.taper ?? 0.25), `${owner}stroke ${i} taper`);
    });
  };
  ref.levels.forEach((r, l) => image.levels[l] && mesh(image.levels[l], r, `level ${l}`));
  eq(image.objects.length, (ref.objects ?? []).length, 'objects');
  (ref.objects ?? []).forEach((o, i) => {
    const p = image.objects[i];
    if (!p) return;
    eq(p.level, o.level ?? 0, `object ${i} level`);
    eq(p.name, o.name ?? '', `object ${i} name`);
    eq(p.visible, o.visible ?? true, `object ${i} visible`);
    mesh(p.mesh, o.mesh, `object ${i}`);
    strokes(p.strokes, o.strokes, `object ${i} `);
  });
  strokes(image.strokes, ref.strokes);
  array(image.metadata.map((e) => e.join('\u0000')), Object.entries(ref.metadata ?? {}).map((e) => e.join('\u0000')), 'metadata');
  return diffs;
}
function same_as_cpp(file, label = path.relative(tmp, file)) {
  const j = js(fs.readFileSync(file));
  if (!check(j.ok, `${label}: the viewer rejects it: ${j.message}`)) return undefined;
  const diffs = compare(j.image, reference(file));
  const v = fs.readFileSync(file).subarray(0, 8).toString('latin1') === 'SUBVEC\0\x1a' ? `v${fs.readFileSync(file).readUInt32LE(8)}` : 'json';
  const size = (m) => `${m.positions.length / 2}/${m.triangles.length / 3}/${m.colors.length / 3}`;
  const sizes = j.image.levels.map(size).join(' ');
  const objects = j.image.objects.length ? `, objects ${j.image.objects.map((o) => `${size(o.mesh)}${o.visible ? '' : ' hidden'}${o.strokes.length ? ` +${o.strokes.length} strokes` : ''}`).join(' ')}` : '';
  if (check(!diffs.length, `${label}: differs from the C++ decode: ${diffs.join('; ')}`))
    console.log(`  ${label} (${v}, levels V/T/C ${sizes}${objects}, ${j.image.strokes.length} strokes, ${j.image.metadata.length} metadata): same as C++ (${j.ms.toFixed(1)} ms)`);
  return j.image;
}

console.log('== 2. good files decode to what the C++ reader gives');
const goods = [];
const make = (name, ...args) => {
  const out = path.join(tmp, name), r = subvec(...args.map((a) => (a === '@' ? out : a)));
  if (!check(r.status === 0, `subvec ${args.join(' ')}: ${r.stderr}`)) return;
  goods.push(out);
  return out;
};
for (const e of fs.readdirSync(path.join(root, 'examples')).filter((f) => f.endsWith('.svec.json')).sort()) {
  const src = path.join(root, 'examples', e), base = e.replace('.svec.json', '');
  goods.push(src);
  make(`${base}-v1.svec`, 'convert', src, '-o', '@', '--lossless');
  make(`${base}-v2.svec`, 'convert', src, '-o', '@', '--compact-version', '2');
  make(`${base}-v3.svec`, 'convert', src, '-o', '@');
}
// Strokes, metadata (with escapes and UTF-8), creases, two levels with a pyramid record.
const rich = JSON.parse(fs.readFileSync(path.join(root, 'examples/02-open-tear.svec.json'), 'utf8'));
rich.strokes = [
  { level: 0, points: [[1.5, 2.25], [30, 20.125], [59.9, 0.1]], width: 2.5, color: [10, 20.5, 30.25], taper: 0.1 },
  { points: [[0, 0], [60, 40]], width: 1, color: [0, 0, 0] },
];
rich.metadata = { title: 'rich "test" image', note: 'line one\nline two\ttab \\ backslash', unicode: 'café ✓ \u{1F600}' };
fs.writeFileSync(path.join(tmp, 'rich.svec.json'), JSON.stringify(rich));
goods.push(path.join(tmp, 'rich.svec.json'));
make('rich-v1.svec', 'convert', path.join(tmp, 'rich.svec.json'), '-o', '@', '--lossless');
make('rich-v3.svec', 'convert', path.join(tmp, 'rich.svec.json'), '-o', '@');
const rocketPng = path.join(root, 'examples/04-rocket.png');
const rocket = make('rocket.svec', 'vectorize', rocketPng, '-o', '@');
make('rocket-1.svec', 'vectorize', rocketPng, '-o', '@', '--levels', '1');
if (rocket) {
  make('rocket-v1.svec', 'convert', rocket, '-o', '@', '--lossless');
  make('rocket-v2.svec', 'convert', rocket, '-o', '@', '--compact-version', '2');
  make('rocket.svec.json', 'convert', rocket, '-o', '@');
  make('rocket-styled.svec', 'stylize', rocket, '-o', '@');
}
// Objects (docs/format.md, "Objects"): the disk made an object, moved, rotated, scaled, hidden and
// shown again (tests/bad-input/files/ops-objects.json), in every version; two objects, one hidden,
// over the second level of a pyramid, with strokes.
{
  const disk = path.join(root, 'examples/01-disk.svec.json'), ops = path.join(root, 'tests/bad-input/files/ops-objects.json');
  const object = make('disk-object.svec', 'edit', disk, '-o', '@', '--ops', ops);
  if (object) {
    make('disk-object-v1.svec', 'convert', object, '-o', '@', '--lossless');
    make('disk-object-v2.svec', 'convert', object, '-o', '@', '--compact-version', '2');
    make('disk-object.svec.json', 'convert', object, '-o', '@');
  }
  fs.writeFileSync(path.join(tmp, 'ops-two.json'), JSON.stringify([
    { op: 'make-object', at: [48, 48], name: 'first' }, { op: 'move-object', object: 0, translate: [-10, 8], scale: 0.5 },
    { op: 'make-object', at: [48, 48], name: 'second ✓' }, { op: 'hide-object', object: 0 },
  ]));
  const two = make('two-objects.svec', 'edit', disk, '-o', '@', '--ops', path.join(tmp, 'ops-two.json'));
  if (two) make('two-objects-v1.svec', 'convert', two, '-o', '@', '--lossless');
  // Strokes on an object (header flag 2; "strokes" in a JSON object): the disk object stylized,
  // in every version; the second of two objects stylized, and the image stylized over it.
  const styled = object && make('disk-object-styled.svec', 'stylize', object, '-o', '@', '--object', '0');
  if (styled) {
    make('disk-object-styled-v1.svec', 'convert', styled, '-o', '@', '--lossless');
    make('disk-object-styled-v2.svec', 'convert', styled, '-o', '@', '--compact-version', '2');
    make('disk-object-styled.svec.json', 'convert', styled, '-o', '@');
  }
  const twoStyled = two && make('two-objects-styled.svec', 'stylize', two, '-o', '@', '--object', '1');
  if (twoStyled) make('two-objects-styled-all.svec', 'stylize', twoStyled, '-o', '@');
}
for (const file of goods) same_as_cpp(file, path.relative(file.startsWith(tmp) ? tmp : root, file));

// ---------------------------------------------------------------------------------------------
console.log('== 3. the worked examples of docs/format.md');
const doc = fs.readFileSync(path.join(root, 'docs/format.md'), 'utf8');
const blocks = (tag) => [...doc.matchAll(new RegExp('```' + tag + '\\n([^]*?)```', 'g'))].map((m) => m[1]);
const hexBytes = (text) => Buffer.from(text.split('\n').map((l) => l.replace(/#.*/, '')).join(' ').trim().split(/\s+/).join(''), 'hex');
// A .svec file around a payload: the header and a zstd frame of raw blocks (content size, no checksum).
function svecFile(payload, version, flags = 0) {
  const frame = [Buffer.from([0x28, 0xb5, 0x2f, 0xfd, 0xe0]), Buffer.alloc(8)];
  frame[1].writeBigUInt64LE(BigInt(payload.length));
  for (let pos = 0; pos < payload.length || pos === 0; ) {
    const n = Math.min(payload.length - pos, 1 << 17), h = Buffer.alloc(3);
    h.writeUIntLE((n << 3) | (pos + n === payload.length ? 1 : 0), 0, 3);
    frame.push(h, payload.subarray(pos, (pos += n)));
    if (!n) break;
  }
  const f = Buffer.concat(frame), header = Buffer.alloc(32);
  header.write('SUBVEC\0\x1a', 'latin1');
  header.writeUInt32LE(version, 8);
  header.writeUInt32LE(flags, 12);
  header.writeBigUInt64LE(BigInt(payload.length), 16);
  header.writeBigUInt64LE(BigInt(f.length), 24);
  return Buffer.concat([header, f]);
}
const examples = blocks('json svec-example');
check(examples.length === 2, `docs/format.md has ${examples.length} json svec-example blocks, expected 2`);
examples.forEach((text, i) => {
  const file = path.join(tmp, `doc-example-${i + 1}.svec.json`);
  fs.writeFileSync(file, text);
  const image = same_as_cpp(file);
  if (!image) return;
  const m = image.levels[0];
  check(m.positions.join() === '0,0,4,0,4,4,0,4,2,2' && m.triangles.join() === '0,1,4,1,2,4,2,3,4,3,0,4', `doc example ${i + 1}: the square mesh`);
  if (i === 0) check(m.triangleColors.join() === m.triangles.join() && m.colors.join() === '255,0,0,255,0,0,0,0,255,0,0,255,127.5,0,127.5', 'doc example 1: colors per vertex');
  else
    check(
      m.triangleColors.join() === '0,1,4,1,2,4,2,3,4,3,5,4' && m.features.length === 1 && m.features[0].vertices.join() === '4,0' &&
        image.metadata[0]?.join('=') === 'title=a tear that ends in the middle',
      'doc example 2: the tear, its colors and the title',
    );
});
let compact;
for (const [tag, version] of [['text svec-compact-example', 2], ['text svec-coded-example', 3]]) {
  const [text] = blocks(tag);
  if (!check(text, `docs/format.md has no ${tag} block`)) continue;
  const file = path.join(tmp, `doc-v${version}.svec`);
  fs.writeFileSync(file, svecFile(hexBytes(text), version));
  goods.push(file);
  const image = same_as_cpp(file);
  if (!image) continue;
  const m = image.levels[0];
  check(
    m.positions.join() === '0,0,4,0,2,2,0,4,4,4' && m.triangles.join() === '0,1,2,3,0,2,3,2,4,4,2,1' &&
      m.colors.join() === '256,0,0,254,0,0,128,0,128,0,0,254,0,0,256',
    `doc version ${version} example: reads back as the document says`,
  );
  if (version === 3 && compact) check(!compare(image, { ...compact, levels: compact.levels }).length, 'doc version 3 example: same image as version 2');
  if (version === 2)
    compact = { width: 4, height: 4, levels: [{ vertices: [[0, 0], [4, 0], [2, 2], [0, 4], [4, 4]], colors: [[256, 0, 0], [254, 0, 0], [128, 0, 128], [0, 0, 254], [0, 0, 256]], triangles: [[0, 1, 2], [3, 0, 2], [3, 2, 4], [4, 2, 1]] }] };
}

// ---------------------------------------------------------------------------------------------
console.log('== 4. crafted inputs: accepted or rejected as by the C++ reader');
const square = (extra = '', level = '') =>
  `{"format": "subvec", "version": 1, "width": 4, "height": 4${extra}, "levels": [{"vertices": [[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]], ` +
  `"colors": [[255, 0, 0], [255, 0, 0], [0, 0, 255], [0, 0, 255], [127.5, 0, 127.5]], "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]${level}}]}`;
const deep = (n) => `{"format": "subvec", "version": 1, "metadata": {"a": ${'['.repeat(n)}${']'.repeat(n)}}}`;
const le = (...words) => Buffer.concat(words.map(([type, v]) => {
  if (type === 'bytes') return Buffer.from(v);
  const b = Buffer.alloc(type === 'f64' ? 8 : type === 'u8' ? 1 : 4);
  if (type === 'f64') b.writeDoubleLE(v);
  else if (type === 'f32') b.writeFloatLE(v);
  else if (type === 'u8') b.writeUInt8(v);
  else b.writeUInt32LE(v >>> 0);
  return b;
}));
// Objects over the 4 x 4 square: good, and each breaking one rule (JSON version 2, binary flag 1).
// A triangle is the smallest object: one boundary loop of three edges.
const triangle = { vertices: [[1, 1], [3, 1], [2, 3]], colors: [[0, 200, 0], [0, 200, 0], [0, 100, 0]], triangles: [[0, 1, 2]] };
function objectFiles() {
  const json = (objects, version = 2, extra = '') => square(`${extra}, "objects": ${JSON.stringify(objects)}`).replace('"version": 1', `"version": ${version}`);
  // The square twice: two levels (no pyramid record), for objects over level 1.
  const json2 = (objects) => json(objects).replace(/"levels": \[(\{.*\})\]/, '"levels": [$1, $1]');
  const stroke = { level: 0, points: [[0.5, 0.5], [2, 3.25], [3.5, 1]], width: 0.5, color: [255, 255, 0], taper: 0.1 };
  const with_ = (change) => [{ level: 0, name: 'tri', visible: true, mesh: { ...triangle, ...change } }];
  // Two triangles sharing vertex 0 only: a boundary pinched there (four boundary edges).
  const bowtie = { vertices: [[2, 2], [3, 1], [3, 3], [1, 3], [1, 1]], colors: Array(5).fill([9, 9, 9]), triangles: [[0, 1, 2], [0, 3, 4]] };
  // A fan of four triangles whose boundary vertex 0 is turned around once (a slit from 0 to 1 = 5).
  const slit = { vertices: [[2, 2], [3, 2], [2, 3], [1, 2], [2, 1], [3, 2]], colors: Array(6).fill([9, 9, 9]),
    triangles: [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]] };
  const files = {
    'object-json.svec.json': json(with_({})),
    'object-json-defaults.svec.json': json([{ mesh: triangle }, { mesh: triangle, level: 0, visible: false, name: 'é' }]),
    'object-json-version-1.svec.json': json(with_({}), 1),
    'object-json-version-3.svec.json': json(with_({}), 3),
    'object-json-no-objects-v2.svec.json': square().replace('"version": 1', '"version": 2'),
    'object-json-level-4.svec.json': json([{ level: 4, mesh: triangle }]),
    'object-json-level-negative.svec.json': json([{ level: -1, mesh: triangle }]),
    'object-json-visible-1.svec.json': json([{ visible: 1, mesh: triangle }]),
    'object-json-name-number.svec.json': json([{ name: 5, mesh: triangle }]),
    'object-json-unknown-key.svec.json': json([{ mesh: triangle, hidden: true }]),
    'object-json-no-mesh.svec.json': json([{ name: 'x' }]),
    'object-json-not-array.svec.json': json({ mesh: triangle }),
    'object-json-mesh-unknown-key.svec.json': json(with_({ tears: [] })),
    'object-json-parents.svec.json': json(with_({ parent_vertices: [0, 1, 2] })),
    'object-json-far.svec.json': json(with_({ vertices: [[2 ** 24 + 1, 1], [2 ** 24 + 3, 1], [2 ** 24 + 2, 3]] })),
    'object-json-outside.svec.json': json(with_({ vertices: [[-100, -50], [300, -50], [100, 1000]] })),
    'object-json-corner.svec.json': json(with_({ vertices: [[0, 0], [4, 0], [0, 4]] })),
    'object-json-flipped.svec.json': json(with_({ triangles: [[0, 2, 1]] })),
    'object-json-unused-vertex.svec.json': json(with_({ vertices: [...triangle.vertices, [2, 2]], colors: [...triangle.colors, [1, 1, 1]] })),
    'object-json-no-triangles.svec.json': json(with_({ vertices: [], colors: [], triangles: [] })),
    'object-json-pinched.svec.json': json(with_(bowtie)),
    'object-json-boundary-turn.svec.json': json(with_(slit)),
    'object-json-double-turn.svec.json': json(with_({ vertices: [[2, 2], [3, 2], [2, 3], [1, 2], [2, 1], [3, 2.0001], [2.0001, 3], [1, 2.0001], [2.0001, 1]],
      colors: Array(9).fill([9, 9, 9]), triangles: [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 6], [0, 6, 7], [0, 7, 8], [0, 8, 1]] })),
    'object-json-crease-on-boundary.svec.json': json(with_({ creases: [[0, 1]] })),
    'object-json-color-owner.svec.json': json(with_({ triangle_colors: [[0, 1, 1]] })),
    'object-json-unused-color.svec.json': json(with_({ colors: [...triangle.colors, [1, 1, 1]], triangle_colors: [[0, 1, 2]] })),
    'object-json-too-many.svec.json': json(Array(4097).fill({ mesh: triangle })),
    // Strokes on objects: the form of the image's strokes, each of its object's level.
    'object-json-strokes.svec.json': json([{ mesh: triangle, strokes: [stroke, { ...stroke, taper: 0 }] }, { mesh: triangle, visible: false, strokes: [stroke] }],
      2, `, "strokes": ${JSON.stringify([stroke])}`),
    'object-json-strokes-empty.svec.json': json([{ mesh: triangle, strokes: [] }]),
    'object-json-strokes-defaults.svec.json': json([{ mesh: triangle, strokes: [{ points: [[0, 0], [4, 4]], width: 1, color: [0, 0, 0] }] }]),
    'object-json-strokes-not-array.svec.json': json([{ mesh: triangle, strokes: stroke }]),
    'object-json-stroke-unknown-key.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, dash: 2 }] }]),
    'object-json-stroke-no-width.svec.json': json([{ mesh: triangle, strokes: [{ points: stroke.points, color: stroke.color }] }]),
    'object-json-stroke-color-string.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, color: 'red' }] }]),
    'object-json-stroke-level-out.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, level: 4 }] }]),
    'object-json-stroke-level-other.svec.json': json2([{ level: 1, mesh: triangle, strokes: [stroke, { ...stroke, level: 0 }] }]),
    'object-json-stroke-level-default.svec.json': json2([{ level: 1, mesh: triangle, strokes: [{ points: stroke.points, width: 1, color: [0, 0, 0] }] }]),
    'object-json-stroke-level-1.svec.json': json2([{ level: 1, mesh: triangle, strokes: [{ ...stroke, level: 1 }] }]),
    'object-json-stroke-one-point.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, points: [[1, 1]] }] }]),
    'object-json-stroke-width-0.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, width: 0 }] }]),
    'object-json-stroke-taper.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, taper: 0.75 }] }]),
    'object-json-stroke-second-object.svec.json': json([{ mesh: triangle, strokes: [stroke] }, { mesh: triangle, strokes: [stroke, { ...stroke, width: -2 }] }]),
    'object-json-stroke-bad-mesh-first.svec.json': json([{ mesh: { ...triangle, triangles: [[0, 2, 1]] }, strokes: [{ ...stroke, width: 0 }] }]),
    'object-json-stroke-and-image-stroke.svec.json': json([{ mesh: triangle, strokes: [{ ...stroke, level: 3 }] }], 2, `, "strokes": [${JSON.stringify({ ...stroke, level: 5 })}]`),
  };
  // Binary: the square in version 1, then the objects (flag 1).
  const mesh = (m) => le(['u32', m.vertices.length], ['u32', m.colors.length], ['u32', m.triangles.length], ['u32', 0], ['u32', 0],
    ...m.vertices.flat().map((v) => ['f64', v]), ...m.colors.flat().map((v) => ['f32', v]), ...m.triangles.flat().map((v) => ['u32', v]),
    ...m.triangles.flat().map((v) => ['u32', v]));
  const sq = { vertices: [[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]], colors: [[255, 0, 0], [255, 0, 0], [0, 0, 255], [0, 0, 255], [127.5, 0, 127.5]],
    triangles: [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]] };
  const object = ({ level = 0, visible = 1, name = [0x74], m = triangle } = {}) => le(['u32', level], ['u8', visible], ['u32', name.length], ['bytes', name], ['bytes', mesh(m)]);
  const payload = (objects, count = objects.length, objectStrokes = [], levels = 1) =>
    Buffer.concat([le(['u32', 4], ['u32', 4], ['u32', levels]), ...Array(levels).fill(mesh(sq)), le(['u32', count]), ...objects, ...objectStrokes, le(['u32', 0], ['u32', 0])]);
  // An object's strokes (flag 2): a count, then each stroke as the trailer's.
  const strokeBytes = ({ level = 0, width = 0.5, color = [255, 255, 0], taper = 0.1, points = [[0.5, 0.5], [2, 3.25], [3.5, 1]] } = {}) =>
    le(['u32', level], ['f32', width], ...color.map((c) => ['f32', c]), ['f32', taper], ['u32', points.length], ...points.flat().map((v) => ['f64', v]));
  const strokes = (...list) => Buffer.concat([le(['u32', list.length]), ...list.map(strokeBytes)]);
  const two = [object(), object({ visible: 0, name: [0xc3, 0xa9] })];
  const withStrokes = payload(two, 2, [strokes({}, { taper: 0 }), strokes({ width: 2 })]);
  const good = payload([object(), object({ visible: 0, name: [0xc3, 0xa9] })]);
  Object.assign(files, {
    'object-v1.svec': svecFile(good, 1, 1),
    'object-v1-no-flag.svec': svecFile(good, 1, 0),
    'object-v1-flags-2.svec': svecFile(good, 1, 2),
    'object-v1-flags-3.svec': svecFile(good, 1, 3),
    'object-v1-none.svec': svecFile(payload([]), 1, 1),
    'object-v1-visibility-2.svec': svecFile(payload([object({ visible: 2 })]), 1, 1),
    'object-v1-level-4.svec': svecFile(payload([object({ level: 4 })]), 1, 1),
    'object-v1-name-latin1.svec': svecFile(payload([object({ name: [0x63, 0x61, 0x66, 0xe9] })]), 1, 1),
    'object-v1-count-4097.svec': svecFile(payload([object()], 4097), 1, 1),
    'object-v1-count-3.svec': svecFile(payload([object()], 3), 1, 1),
    'object-v1-truncated.svec': svecFile(good.subarray(0, good.length - 40), 1, 1),
    'object-v1-huge-name.svec': svecFile(Buffer.concat([good.subarray(0, good.length - 8 - mesh(triangle).length - 6), le(['u32', 2 ** 26 + 1])]), 1, 1),
    'object-v1-far.svec': svecFile(payload([object({ m: { ...triangle, vertices: [[0, -(2 ** 25)], [2, -(2 ** 25)], [1, 2 - 2 ** 25]] } })]), 1, 1),
    'object-v1-flipped.svec': svecFile(payload([object({ m: { ...triangle, triangles: [[0, 2, 1]] } })]), 1, 1),
    'object-v1-bad-index.svec': svecFile(payload([object({ m: { ...triangle, triangles: [[0, 1, 7]] } })]), 1, 1),
    'object-v1-nan-color.svec': svecFile(payload([object({ m: { ...triangle, colors: [[0, 0, 0], [0, NaN, 0], [0, 0, 0]] } })]), 1, 1),
    // Strokes on objects (flag 2, only with flag 1): after the last object, each object's count
    // and strokes.
    'object-v1-strokes.svec': svecFile(withStrokes, 1, 3),
    'object-v1-strokes-none.svec': svecFile(payload(two, 2, [strokes(), strokes()]), 1, 3),
    'object-v1-strokes-flag-1.svec': svecFile(withStrokes, 1, 1),
    'object-v1-strokes-flag-2.svec': svecFile(withStrokes, 1, 2),
    'object-v1-strokes-flags-7.svec': svecFile(withStrokes, 1, 7),
    'object-v1-strokes-flags-6.svec': svecFile(withStrokes, 1, 6),
    'object-v1-strokes-no-objects.svec': svecFile(payload([], 0, []), 1, 3),
    'object-v1-strokes-truncated-count.svec': svecFile(withStrokes.subarray(0, withStrokes.length - 8 - strokeBytes({ width: 2 }).length - 2), 1, 3),
    'object-v1-strokes-truncated-points.svec': svecFile(withStrokes.subarray(0, withStrokes.length - 8 - 20), 1, 3),
    'object-v1-strokes-truncated-stroke.svec': svecFile(withStrokes.subarray(0, withStrokes.length - 8 - strokeBytes({ width: 2 }).length + 10), 1, 3),
    'object-v1-strokes-huge-count.svec': svecFile(payload(two, 2, [le(['u32', 2 ** 26 + 1])]), 1, 3),
    'object-v1-strokes-big-count.svec': svecFile(payload(two, 2, [le(['u32', 1000]), strokeBytes()]), 1, 3),
    'object-v1-strokes-huge-points.svec': svecFile(payload(two, 2, [le(['u32', 1], ['u32', 0], ['f32', 1], ['f32', 0], ['f32', 0], ['f32', 0], ['f32', 0], ['u32', 2 ** 26 + 1]), strokes()]), 1, 3),
    'object-v1-stroke-level-out.svec': svecFile(payload(two, 2, [strokes({ level: 9 }), strokes()]), 1, 3),
    'object-v1-stroke-level-other.svec': svecFile(payload([object({ level: 1 })], 1, [strokes({ level: 1 }, { level: 0 })], 2), 1, 3),
    'object-v1-stroke-level-negative.svec': svecFile(payload(two, 2, [strokes(), strokes({ level: -1 })]), 1, 3),
    'object-v1-stroke-nan-point.svec': svecFile(payload(two, 2, [strokes({ points: [[0, 0], [NaN, 1]] }), strokes()]), 1, 3),
    'object-v1-stroke-one-point.svec': svecFile(payload(two, 2, [strokes({ points: [[0, 0]] }), strokes()]), 1, 3),
    'object-v1-stroke-inf-color.svec': svecFile(payload(two, 2, [strokes(), strokes({ color: [0, Infinity, 0] })]), 1, 3),
    'object-v1-stroke-taper.svec': svecFile(payload(two, 2, [strokes({ taper: -0.5 }), strokes()]), 1, 3),
    'object-v1-stroke-width-nan.svec': svecFile(payload(two, 2, [strokes({ width: NaN }), strokes()]), 1, 3),
  });
  return files;
}
const crafted = {
  'json-float-width.svec.json': square().replace('"width": 4', '"width": 4.0'),
  'json-exponent-index.svec.json': square().replace('[0, 1, 4]', '[0, 1, 4e0]'),
  'json-negative-zero.svec.json': square().replace('"width": 4', '"width": -0'),
  'json-bom.svec.json': '\ufeff' + square(),
  'json-big-integer.svec.json': square().replace('"width": 4', '"width": 18446744073709551616'),
  'json-null-saliency.svec.json': square('', ', "features": [{"id": 0, "vertices": [4, 0], "saliency": null}], "triangle_colors": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 5, 4]]').replace('[127.5, 0, 127.5]]', '[127.5, 0, 127.5], [0, 0, 255]]'),
  'json-tear.svec.json': square('', ', "features": [{"id": 0, "vertices": [4, 0], "saliency": 1e-3}], "triangle_colors": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 5, 4]]').replace('[127.5, 0, 127.5]]', '[127.5, 0, 127.5], [0, 0, 255]]'),
  'json-duplicate-level-key.svec.json': square('', ', "creases": [], "creases": []'),
  'json-depth-32.svec.json': deep(30),
  'json-depth-33.svec.json': deep(31),
  'json-metadata-escapes.svec.json': square(', "metadata": {"k\\u00e9y": "v\\ud83d\\ude00\\n", "b": ""}'),
  'json-lone-surrogate.svec.json': square(', "metadata": {"k": "\\ud83d"}'),
  'json-invalid-utf8.svec.json': Buffer.from(square(', "metadata": {"k": "\u00c3("}'), 'latin1'),
  'json-control-char.svec.json': square(', "metadata": {"k": "a\tb"}'),
  'json-color-3e38.svec.json': square().replace('[127.5, 0, 127.5]', '[3e38, 0, 127.5]'),
  'json-color-4e38.svec.json': square().replace('[127.5, 0, 127.5]', '[4e38, 0, 127.5]'),
  'json-unterminated-string.svec.json': square().replace('"triangles": ', '"triangles ').repeat(4),
  'json-trailing-comma.svec.json': square().replace(']]}]}', ']],}]}'),
  'json-trailing-garbage.svec.json': square() + ' x',
  'json-stroke-taper.svec.json': square(', "strokes": [{"points": [[0, 0], [1, 1]], "width": 1, "color": [0, 0, 0], "taper": 0.5000001}]'),
  'json-pyramid-on-level-0.svec.json': square('', ', "parent_vertices": [0, 1, 2, 3, 4]'),
  'json-top-array.svec.json': '[1, 2]',
  'empty.svec': '',
  'png.svec': Buffer.from('89504e470d0a1a0a0000000d49484452', 'hex'),
  // 2^26 - 1 vertices declared in a tiny version 1 payload, and in a version 3 one.
  'v1-huge-count.svec': svecFile(le(['u32', 4], ['u32', 4], ['u32', 1], ['u32', 2 ** 26 - 1], ['u32', 0], ['u32', 0], ['u32', 0], ['u32', 0], ['f64', 0]), 1),
  'v3-huge-count.svec': svecFile(le(['u32', 4], ['u32', 4], ['u32', 1], ['u32', 2 ** 26], ['u32', 2 ** 26], ['u32', 2 ** 27], ['u32', 0], ['u32', 0], ['u8', 2], ['u8', 255], ['u32', 8], ['u32', 0x01020304], ['u32', 0x05060708]), 3),
  'v1-too-many-levels.svec': svecFile(le(['u32', 4], ['u32', 4], ['u32', 65]), 1),
  ...objectFiles(),
};
const craftedFiles = Object.entries(crafted).map(([name, content]) => (fs.writeFileSync(path.join(tmp, name), content), path.join(tmp, name)));
const craftedVerdicts = await cppAll(craftedFiles);
for (const [k, file] of craftedFiles.entries()) {
  const name = path.basename(file), c = craftedVerdicts[k], j = js(fs.readFileSync(file));
  check(wellFormed(j), `${name}: not a one-line SvecError: ${j.message}`);
  check(j.ms < 1000, `${name}: took ${j.ms.toFixed(0)} ms`);
  if (check(c.ok === j.ok, `${name}: C++ ${c.ok ? 'accepts' : `rejects (${c.message})`}, the viewer ${j.ok ? 'accepts' : `rejects (${j.message})`}`))
    console.log(`  ${name}: ${c.ok ? 'both accept' : `both reject\n    C++:    ${c.message}\n    viewer: ${j.message}`}`);
  // Objects are new: their messages are the C++ reader's, word for word.
  if (name.startsWith('object') && !c.ok && !j.ok) check(c.message === j.message, `${name}: the viewer's message differs from the C++ reader's`);
  if (c.ok && j.ok) check(!compare(j.image, reference(file)).length, `${name}: differs from the C++ decode`);
}
// load(): bytes, Blob, File, and failures as SvecError.
{
  const bytes = fs.readFileSync(goods[0]);
  const ok = await load(new Uint8Array(bytes)).then((i) => i.width > 0, () => false);
  const blob = await load(new Blob([bytes])).then((i) => i.width > 0, () => false);
  const file = await load(new File([Buffer.from('{"format": 1}')], 'bad.svec.json')).then(() => '', (e) => `${e.name}: ${e.message}`);
  const url = await load('http://127.0.0.1:9/none.svec').then(() => '', (e) => `${e.name}: ${e.message}`);
  const nourl = await load('not a url').then(() => '', (e) => e.name);
  check(ok && blob, 'load() of bytes and of a Blob');
  check(file === 'SvecError: bad.svec.json: format: expected "subvec", got 1 (this is not a subvec file)', `load() of a File names it: ${file}`);
  check(url.startsWith('SvecError: http://127.0.0.1:9/none.svec: '), `load() of an unreachable URL: ${url}`);
  check(nourl === 'SvecError', `load() of a bad URL: ${nourl}`);
  console.log(`  load(): bytes, Blob ok; File: ${file}; unreachable URL: ${url}`);
}

// ---------------------------------------------------------------------------------------------
console.log('== 5. mutations: a SvecError or a valid image, quickly; as the C++ reader decides');
let seed = 20261205;
const random = () => {
  seed = (seed + 0x6d2b79f5) | 0;
  let t = Math.imul(seed ^ (seed >>> 15), 1 | seed);
  t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
  return ((t ^ (t >>> 14)) >>> 0) / 2 ** 32;
};
const pick = (n) => Math.floor(random() * n);
const stats = { runs: 0, rejected: 0, valid: 0, agree: 0, slowest: 0 };
const mutants = [];
const mutant = (bytes, what) => mutants.push({ bytes, what, file: path.join(tmp, `mutant-${mutants.length}.svec`) });
function judge({ bytes, what, file }, c) {
  const j = js(bytes);
  stats.runs++;
  j.ok ? stats.valid++ : stats.rejected++;
  stats.slowest = Math.max(stats.slowest, j.ms);
  check(wellFormed(j), `${what}: ${j.error?.name}: ${j.message}`);
  check(j.ms < 2000, `${what}: took ${j.ms.toFixed(0)} ms`);
  if (check(c.ok === j.ok, `${what}: C++ ${c.ok ? 'accepts' : `rejects (${c.message})`}, the viewer ${j.ok ? 'accepts' : `rejects (${j.message})`}`)) stats.agree++;
  if (c.ok && j.ok) check(!compare(j.image, reference(file)).length, `${what}: differs from the C++ decode`);
}
const sources = ['rocket.svec', 'rocket-v1.svec', 'rocket-v2.svec', 'rich-v3.svec', 'doc-v2.svec', 'doc-v3.svec', 'disk-object-v1.svec', 'two-objects.svec',
  'disk-object-styled-v1.svec', 'two-objects-styled-all.svec'].map((n) => path.join(tmp, n)).filter((f) => fs.existsSync(f));
for (const file of sources) {
  const bytes = fs.readFileSync(file), label = path.basename(file), version = bytes.readUInt32LE(8);
  for (let k = 0; k < (label.startsWith('rocket') ? 20 : 8); k++) {
    const at = pick(bytes.length);
    mutant(bytes.subarray(0, at), `${label} cut at ${at}`);
  }
  for (let k = 0; k < 6; k++) {
    const b = Buffer.from(bytes), at = 32 + pick(b.length - 32);
    b[at] ^= 1 + pick(255);
    mutant(b, `${label} byte ${at} flipped`);
  }
  // The payload itself, flipped and wrapped in a fresh frame: reaches the payload decoders.
  const payload = Buffer.from(fzstd.decompress(bytes.subarray(32)));
  for (let k = 0; k < 12; k++) {
    const b = Buffer.from(payload), n = 1 + pick(3), where = [];
    for (let i = 0; i < n; i++) {
      const at = pick(b.length);
      b[at] ^= 1 << pick(8);
      where.push(at);
    }
    mutant(svecFile(b, version), `${label} payload bytes ${where.join(', ')} flipped`);
  }
}
for (const m of mutants) fs.writeFileSync(m.file, m.bytes);
const mutantVerdicts = await cppAll(mutants.map((m) => m.file));
mutants.forEach((m, k) => judge(m, mutantVerdicts[k]));
console.log(`  ${stats.runs} mutants: ${stats.rejected} rejected, ${stats.valid} valid; ${stats.agree} as C++; slowest ${stats.slowest.toFixed(1)} ms`);

console.log('== 6. the zstd checksum against the zstd command');
{
  esbuild.buildSync({ entryPoints: [path.join(web, 'viewer/src/wasm.ts')], bundle: true, format: 'esm', platform: 'node',
    outfile: path.join(tmp, 'wasm.mjs'), logLevel: 'error' });
  const { checksum } = await import(pathToFileURL(path.join(tmp, 'wasm.mjs')).href);
  const zstd = spawnSync('zstd', ['--version']).status === 0;
  if (check(zstd, 'the zstd command is missing (scripts/setup installs it)')) {
    let random = 12345, wrong = 0, lengths = 0;
    const next = () => (random = (Math.imul(random, 1103515245) + 12345) >>> 0) >>> 24;
    for (const n of [...Array(101).keys(), 127, 128, 129, 1000, 65537, 300001]) {
      const data = Buffer.from(Array.from({ length: n }, next));
      const frame = spawnSync('zstd', ['-q', '-c', '--check'], { input: data }).stdout;
      const expected = frame.readUInt32LE(frame.length - 4), got = checksum(new Uint8Array(data));
      if (got !== expected) wrong++, console.log(`  length ${n}: checksum ${got.toString(16)}, zstd ${expected.toString(16)}`);
      lengths++;
    }
    check(wrong === 0, `${wrong} of ${lengths} checksums differ from zstd's`);
    console.log(`  ${lengths} lengths: ${wrong} checksums differ from zstd's`);
  }
}

console.log(`(${((Date.now() - started) / 1000).toFixed(1)} s)`);
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
