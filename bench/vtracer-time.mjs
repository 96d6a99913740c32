// Times vtracer's `hi` preset (npm @neplex/vectorizer 0.1.0: vtracer's Rust code, native) on one
// image, in-process and without the PNG decoding: prints `{"image", "seconds": [..], "svg_bytes"}`.
// It loads the package's native binding, @neplex/vectorizer-linux-x64-gnu (an optional dependency
// of web/, docs/performance.md says why), which exports the same functions and enums.
// Used by `scripts/bench-vectorize --vtracer`, which runs subvec beside it (issue 24).
// Usage: node bench/vtracer-time.mjs IMAGE RUNS
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import path from 'node:path';

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(path.join(here, '..', 'web', 'package.json'));
const vtracer = require('@neplex/vectorizer-linux-x64-gnu');

// The `hi` preset as the issue fixes it (vtracer's web demo and CLI call it "photo, high").
const hi = {
  colorMode: vtracer.ColorMode.Color,
  hierarchical: vtracer.Hierarchical.Stacked,
  filterSpeckle: 1,
  colorPrecision: 8,
  layerDifference: 8,
  mode: vtracer.PathSimplifyMode.Spline,
  cornerThreshold: 60,
  lengthThreshold: 4,
  maxIterations: 10,
  spliceThreshold: 45,
  pathPrecision: 2,
};

const [image, runsArg] = process.argv.slice(2);
if (!image) {
  console.error('usage: node bench/vtracer-time.mjs IMAGE [RUNS]');
  process.exit(2);
}
const runs = Number(runsArg ?? 3);
const decoded = vtracer.readImageSync(readFileSync(image));
const size = { width: decoded.width, height: decoded.height };
const seconds = [];
let svg = '';
for (let i = 0; i < runs; ++i) {
  const t0 = process.hrtime.bigint();
  svg = vtracer.vectorizeRawSync(decoded.pixels, size, hi);
  seconds.push(Number(process.hrtime.bigint() - t0) / 1e9);
}
console.log(JSON.stringify({ image: path.basename(image), width: size.width, height: size.height,
                             seconds, svg_bytes: Buffer.byteLength(svg) }));
