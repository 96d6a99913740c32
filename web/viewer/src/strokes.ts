// Strokes as the C++ renderer draws them (src/render/strokes.cpp): the clamped uniform cubic
// B-spline of the points, flattened in output pixels into chords of at most about 2 pixels (at
// most 256 per span), each chord a capsule whose radius follows the taper linearly. The coverage
// of a pixel is the maximum over the stroke's chords of the box-filtered band coverage
// clamp(min(d + r, 1/2) - max(d - r, -1/2), 0, 1); render.ts evaluates it per pixel on the GPU.
import type { Stroke } from './image';

/** Maps image pixels to output pixels. */
export interface ViewTransform {
  x0: number;
  y0: number;
  sx: number;
  sy: number;
  width: number;
  height: number;
}

// Point i of the sequence extended by a phantom point past each end (2 P0 - P1, 2 Pn - Pn-1).
function control(p: Float64Array, i: number, c: number): number {
  const n = p.length / 2;
  if (i < 0) return 2 * p[c] - p[2 + c];
  if (i >= n) return 2 * p[2 * (n - 1) + c] - p[2 * (n - 2) + c];
  return p[2 * i + c];
}

/** 6 floats per chord (x0, y0, x1, y1, r0, r1) in output pixels; empty when it misses the view. */
export function strokeChords(stroke: Stroke, view: ViewTransform): Float32Array {
  const n = stroke.points.length / 2;
  const half = 0.5 * stroke.width * Math.sqrt(view.sx * view.sy);
  const p = new Float64Array(2 * n);
  let bx0 = Infinity, by0 = Infinity, bx1 = -Infinity, by1 = -Infinity, longest = 0;
  for (let i = 0; i < n; ++i) {
    const x = (stroke.points[2 * i] - view.x0) * view.sx, y = (stroke.points[2 * i + 1] - view.y0) * view.sy;
    p[2 * i] = x;
    p[2 * i + 1] = y;
    bx0 = Math.min(bx0, x), by0 = Math.min(by0, y), bx1 = Math.max(bx1, x), by1 = Math.max(by1, y);
    if (i > 0) longest = Math.max(longest, Math.hypot(x - p[2 * i - 2], y - p[2 * i - 1]));
  }
  const reach = longest + half + 1; // the phantom points reach one span past the ends
  if (!(bx1 + reach >= 0 && by1 + reach >= 0 && bx0 - reach <= view.width && by0 - reach <= view.height)) {
    return new Float32Array(0);
  }
  const perSpan = Math.min(256, Math.max(1, Math.ceil(longest / 2)));
  const line: number[] = [];
  for (let s = 0; s < n - 1; ++s) {
    for (let k = 0; k < perSpan; ++k) {
      const t = k / perSpan, u = 1 - t, t2 = t * t, t3 = t2 * t;
      const w0 = (u * u * u) / 6, w1 = (3 * t3 - 6 * t2 + 4) / 6, w2 = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, w3 = t3 / 6;
      for (let c = 0; c < 2; ++c) {
        line.push(w0 * control(p, s - 1, c) + w1 * control(p, s, c) + w2 * control(p, s + 1, c) + w3 * control(p, s + 2, c));
      }
    }
  }
  line.push(p[2 * n - 2], p[2 * n - 1]);
  // Arc length, then the radius: half * min(1, s / (taper L), (L - s) / (taper L)).
  const m = line.length / 2;
  const at = new Float64Array(m);
  for (let i = 1; i < m; ++i) at[i] = at[i - 1] + Math.hypot(line[2 * i] - line[2 * i - 2], line[2 * i + 1] - line[2 * i - 1]);
  const length = at[m - 1], ramp = stroke.taper * length;
  const radius = (s: number) => Math.max(0, ramp <= 0 ? half : half * Math.min(1, s / ramp, (length - s) / ramp));
  const chords = new Float32Array(6 * (m - 1));
  for (let i = 0; i + 1 < m; ++i) {
    chords.set([line[2 * i], line[2 * i + 1], line[2 * i + 2], line[2 * i + 3], radius(at[i]), radius(at[i + 1])], 6 * i);
  }
  return chords;
}
