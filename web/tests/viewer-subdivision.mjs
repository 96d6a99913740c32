// The viewer's Loop subdivision (web/viewer/src/subdivide.ts) against the C++ library's
// (OpenSubdiv, through the Python module's _subdivide): the same limit triangles, positions and
// colors, on the examples (tears, an open tear, a junction), a crease made from a tear, and the
// bundled photograph, at depths 0 to 3, the whole mesh and a window's faces. A change to the
// subdivision rules on either side that the other does not follow fails here. The WebAssembly
// refinement the viewer draws with (web/viewer/wasm/subdivide.c, through src/wasm.ts) must give
// subdivide.ts's results to the bit: topology, refinement, uniform and adaptive triangles.
//
//   node web/tests/viewer-subdivision.mjs PYTHON BUILD/python
//
// Exit 0: all passed; 1: a mismatch; 77: skipped (no web/node_modules or no Python module).
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const [python, pythonPath] = process.argv.slice(2);
const esbuild = join(here, '..', 'node_modules', 'esbuild', 'lib', 'main.js');
if (!existsSync(esbuild)) {
  console.log('SKIPPED: web/node_modules is missing (run: cd web && npm ci)');
  process.exit(77);
}
if (!python || !pythonPath || !existsSync(join(pythonPath, 'subvec'))) {
  console.log(`SKIPPED: no Python module at ${pythonPath}`);
  process.exit(77);
}

const tmp = mkdtempSync(join(tmpdir(), 'subvec-subdiv-'));
let passed = 0, failed = 0;
try {
  const { build } = await import(esbuild);
  await build({ entryPoints: [join(root, 'web/viewer/src/subdivide.ts')], bundle: true, format: 'esm',
    outfile: join(tmp, 'subdivide.mjs'), logLevel: 'error' });
  const { buildTopology, refine, uniformIndices, adaptiveIndices } = await import(join(tmp, 'subdivide.mjs'));
  await build({ entryPoints: [join(root, 'web/viewer/src/wasm.ts')], bundle: true, format: 'esm',
    outfile: join(tmp, 'wasm.mjs'), logLevel: 'error' });
  const wasm = await import(join(tmp, 'wasm.mjs'));
  // Every field of two results equal to the bit (typed arrays compared as bytes).
  const same = (a, b, path = '') => {
    if (ArrayBuffer.isView(a) || ArrayBuffer.isView(b)) {
      if (!ArrayBuffer.isView(a) || !ArrayBuffer.isView(b) || a.constructor !== b.constructor) return `${path}: types differ`;
      const x = new Uint8Array(a.buffer, a.byteOffset, a.byteLength), y = new Uint8Array(b.buffer, b.byteOffset, b.byteLength);
      if (x.length !== y.length) return `${path}: ${a.length} against ${b.length} elements`;
      const i = x.findIndex((v, k) => v !== y[k]);
      return i < 0 ? null : `${path}[${Math.floor(i / a.BYTES_PER_ELEMENT)}]: ${a[Math.floor(i / a.BYTES_PER_ELEMENT)]} against ${b[Math.floor(i / a.BYTES_PER_ELEMENT)]}`;
    }
    if (typeof a === 'object' && a && b) {
      if (path.endsWith('.level')) return null; // the level itself, shared
      for (const k of new Set([...Object.keys(a), ...Object.keys(b)])) {
        const d = same(a[k], b[k], `${path}.${k}`);
        if (d) return d;
      }
      return null;
    }
    return Object.is(a, b) ? null : `${path}: ${a} against ${b}`;
  };
  const bitwise = (label, fromJs, fromWasm) => {
    const d = same(fromJs, fromWasm);
    console.log(`${d ? 'FAIL' : 'PASS'} ${label}: WebAssembly and subdivide.ts agree to the bit${d ? `: first difference ${d}` : ''}`);
    d ? failed++ : passed++;
  };

  const toLevel = (L) => ({
    positions: Float64Array.from(L.vertices.flat()), colors: Float32Array.from(L.colors.flat()),
    triangles: Int32Array.from(L.triangles.flat()),
    triangleColors: Int32Array.from((L.triangle_colors ?? L.triangles).flat()),
    creases: Int32Array.from((L.creases ?? []).flat()),
    features: (L.features ?? []).map((f) => ({ id: f.id, saliency: f.saliency ?? 0, vertices: Int32Array.from(f.vertices) })),
  });
  // A crease where the open tear was: the feature's edges listed as creases, one color per vertex.
  const crease = JSON.parse(readFileSync(join(root, 'examples/02-open-tear.svec.json'), 'utf8'));
  {
    const L = crease.levels[0];
    const first = new Map();
    L.triangles.forEach((t, f) => t.forEach((v, k) => { if (!first.has(v)) first.set(v, L.colors[(L.triangle_colors ?? L.triangles)[f][k]]); }));
    L.colors = L.vertices.map((_, v) => first.get(v));
    L.creases = L.features.flatMap((f) => f.vertices.slice(1).map((v, k) => [f.vertices[k], v]));
    delete L.triangle_colors;
    delete L.features;
    writeFileSync(join(tmp, 'crease.svec.json'), JSON.stringify(crease));
  }
  const rocket = join(tmp, 'rocket.svec.json');
  execFileSync(python, ['-c', `import subvec; subvec.load(${JSON.stringify(join(root, 'web/viewer/demo/rocket.svec'))}).save(${JSON.stringify(rocket)})`],
    { env: { ...process.env, PYTHONPATH: pythonPath } });
  const cases = [
    ['01-disk', join(root, 'examples/01-disk.svec.json'), [0, 1, 3]],
    ['02-open-tear', join(root, 'examples/02-open-tear.svec.json'), [0, 2, 3]],
    ['03-junction', join(root, 'examples/03-junction.svec.json'), [0, 1, 3]],
    ['crease', join(tmp, 'crease.svec.json'), [0, 1, 3]],
    ['rocket', rocket, [2]],
  ];

  // C++: float32 triangles (x, y, r, g, b per corner) per case and depth, in one Python run.
  const script = `
import sys, numpy as np, subvec
for path, depth, out in zip(sys.argv[1::3], sys.argv[2::3], sys.argv[3::3]):
    d = subvec.load(path).subdivide(level=0, depth=int(depth), limit=True)
    P, C = d['positions'], d['colors']
    np.concatenate([P[d['triangles']], C[d['triangle_colors']]], axis=2).astype(np.float32).tofile(out)
`;
  const args = [];
  for (const [name, path, depths] of cases) for (const d of depths) args.push(path, String(d), join(tmp, `${name}-${d}.bin`));
  execFileSync(python, ['-c', script, ...args], { env: { ...process.env, PYTHONPATH: pythonPath } });

  // Corners keyed by rounded position; triangles keyed by their three sorted corner keys.
  const key = (x, y) => `${Math.round(x * 256)},${Math.round(y * 256)}`;
  const triangles = (data, count, get) => {
    const map = new Map();
    for (let t = 0; t < count; ++t) {
      const corners = [0, 1, 2].map((k) => get(t, k)).sort((a, b) => (a.key < b.key ? -1 : 1));
      map.set(corners.map((c) => c.key).join(' '), corners);
    }
    return map;
  };
  const compare = (label, cpp, ts, faces) => {
    let missing = 0, worstPos = 0, worstColor = 0;
    for (const [k, corners] of ts) {
      const other = cpp.get(k);
      if (!other) { missing++; continue; }
      corners.forEach((c, i) => {
        worstPos = Math.max(worstPos, Math.abs(c.x - other[i].x), Math.abs(c.y - other[i].y));
        for (let j = 0; j < 3; ++j) worstColor = Math.max(worstColor, Math.abs(c.rgb[j] - other[i].rgb[j]));
      });
    }
    const ok = missing === 0 && (faces || ts.size === cpp.size) && worstPos < 1e-3 && worstColor < 1e-2;
    console.log(`${ok ? 'PASS' : 'FAIL'} ${label}: ${ts.size} triangles (C++ ${cpp.size}), ${missing} unmatched, ` +
      `position error ${worstPos.toExponential(1)} px, color error ${worstColor.toExponential(1)}`);
    ok ? passed++ : failed++;
  };
  // Faces refined only as deep as they need: a closed mesh over the image (every edge inside the
  // image has its twin, running the other way: no cracks, no T-junctions), no flipped triangle,
  // fewer triangles than the uniform refinement, and more of them at a tighter tolerance.
  const adaptive = (label, r, width, height) => {
    const V = r.vertices, uniform = uniformIndices(r).length / 3;
    const counts = [];
    let uniformFlipped = -1;
    for (const tolerance of [0, 4, 1, 0.25]) {
      const I = tolerance > 0 ? adaptiveIndices(r, 1, tolerance, 0.25) : uniformIndices(r);
      const edges = new Map();
      let flipped = 0, area = 0;
      for (let t = 0; t < I.length / 3; ++t) {
        const p = [0, 1, 2].map((k) => [V[5 * I[3 * t + k]], V[5 * I[3 * t + k] + 1]]);
        const a = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        if (a < -1e-9) flipped++;
        area += a / 2;
        for (let k = 0; k < 3; ++k) {
          const from = key(...p[k]), to = key(...p[(k + 1) % 3]);
          edges.set(`${from} ${to}`, (edges.get(`${from} ${to}`) ?? 0) + 1);
        }
      }
      const onBorder = (k) => k.split(' ').every((c) => { const [x, y] = c.split(',').map((v) => v / 256); return x === 0 || y === 0 || x === width || y === height; });
      let open = 0;
      for (const [k, n] of edges) {
        const [from, to] = k.split(' ');
        if (n !== 1 || (!edges.has(`${to} ${from}`) && !onBorder(k))) open++;
      }
      // The limit mesh itself may fold a few thin triangles by tears; none is added.
      if (tolerance === 0) uniformFlipped = flipped;
      const ok = open === 0 && flipped <= uniformFlipped && Math.abs(area - width * height) < 1e-3 * width * height && I.length / 3 <= uniform &&
        (counts.length < 2 || I.length / 3 >= counts[counts.length - 1]);
      counts.push(I.length / 3);
      console.log(`${ok ? 'PASS' : 'FAIL'} ${label}, ${tolerance ? `adaptive at ${tolerance} levels` : 'uniform'}: ${I.length / 3} triangles of ${uniform}, ` +
        `${open} open or repeated edges, ${flipped} flipped, area ${area.toFixed(2)} of ${width * height}`);
      ok ? passed++ : failed++;
    }
  };
  for (const [name, path, depths] of cases) {
    const j = JSON.parse(readFileSync(path, 'utf8'));
    const level = toLevel(j.levels[0]);
    const topo = buildTopology(level, j.width, j.height);
    bitwise(`${name} topology`, topo, wasm.buildTopology(level, j.width, j.height));
    for (const depth of depths) {
      const raw = new Float32Array(readFileSync(join(tmp, `${name}-${depth}.bin`)).buffer.slice(0));
      const cpp = triangles(raw, raw.length / 15, (t, k) => {
        const o = 15 * t + 5 * k;
        return { key: key(raw[o], raw[o + 1]), x: raw[o], y: raw[o + 1], rgb: [raw[o + 2], raw[o + 3], raw[o + 4]] };
      });
      const fromViewer = (r, indices = uniformIndices(r)) => triangles(r.vertices, indices.length / 3, (t, k) => {
        const v = 5 * indices[3 * t + k], V = r.vertices;
        return { key: key(V[v], V[v + 1]), x: V[v], y: V[v + 1], rgb: [V[v + 2], V[v + 3], V[v + 4]] };
      });
      const whole = refine(topo, null, depth);
      compare(`${name} depth ${depth}`, cpp, fromViewer(whole), false);
      bitwise(`${name} depth ${depth}`, whole, wasm.refine(topo, null, depth));
      // A window's faces with their one-ring: the children of those faces are exact too.
      const some = Int32Array.from({ length: Math.ceil(topo.ringBoxes.length / 4 / 7) }, (_, i) => 7 * i);
      const part = refine(topo, some, depth);
      compare(`${name} depth ${depth}, every 7th face`, cpp, fromViewer(part), true);
      bitwise(`${name} depth ${depth}, every 7th face`, part, wasm.refine(topo, some, depth));
      for (const [scale, tolerance] of [[1, 0.5], [4, 0.25], [0.5, 2]]) {
        for (const r of [whole, part]) {
          bitwise(`${name} depth ${depth}, ${r === whole ? 'whole' : 'every 7th face'}, adaptive at scale ${scale}, tolerance ${tolerance}`,
            adaptiveIndices(r, scale, tolerance, 0.25), wasm.adaptiveIndices(r, scale, tolerance, 0.25));
        }
      }
      if (depth >= 2) adaptive(`${name} depth ${depth}`, refine(topo, null, depth), j.width, j.height);
    }
  }
} finally {
  rmSync(tmp, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 ? 0 : 1);
