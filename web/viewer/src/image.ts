// The vector image as the viewer holds it: the content of a `.svec` / `.svec.json` file
// (docs/format.md), in typed arrays. Produced by decode.ts (read and checked in WebAssembly:
// wasm/json.c, validate.c), drawn by subdivide.ts + render.ts.

/** A tear feature: a chain of vertex indices (closed when the last repeats the first). */
export interface Feature {
  id: number;
  saliency: number;
  vertices: Int32Array;
}

/** One level: a control mesh over [0, W] x [0, H]. */
export interface Level {
  /** x, y per vertex (image pixels, y down). */
  positions: Float64Array;
  /** r, g, b per color value (0-255 sRGB scale, as stored). */
  colors: Float32Array;
  /** a, b, c per triangle (positive signed area). */
  triangles: Int32Array;
  /** the color value of each corner, 3 per triangle (always filled, also for JSON without it). */
  triangleColors: Int32Array;
  /** a, b per crease edge. */
  creases: Int32Array;
  features: Feature[];
}

/** A stroke: the clamped uniform cubic B-spline of its points (docs/format.md, Strokes). */
export interface Stroke {
  level: number;
  /** x, y per control point. */
  points: Float64Array;
  width: number;
  color: [number, number, number];
  taper: number;
}

/** An object (a layer, docs/format.md "Objects"): a control mesh of its own drawn over its level,
 * in file order from the bottom, when visible. Its mesh need not tile the image: its boundary
 * edges are creases, and what it covers is composited over the level. Its strokes (each of the
 * object's level) are drawn over it, under the objects above it. */
export interface SvecObject {
  level: number;
  name: string;
  visible: boolean;
  mesh: Level;
  strokes: Stroke[];
}

export interface SvecImage {
  width: number;
  height: number;
  levels: Level[];
  /** Drawn over their levels, bottom to top (empty for files without objects). */
  objects: SvecObject[];
  strokes: Stroke[];
  metadata: Array<[string, string]>;
}

/** v as printf's "%g" writes it (6 significant digits), as the C++ messages print numbers. */
export function num(v: number): string {
  if (!isFinite(v)) return isNaN(v) ? 'nan' : v < 0 ? '-inf' : 'inf';
  if (!v) return 1 / v < 0 ? '-0' : '0';
  const [mantissa, e] = v.toExponential(5).split('e'), exponent = +e;
  const trim = (s: string) => (s.includes('.') ? s.replace(/\.?0+$/, '') : s);
  if (exponent >= -4 && exponent < 6) return trim(v.toFixed(5 - exponent));
  return `${trim(mantissa)}e${exponent < 0 ? '-' : '+'}${String(Math.abs(exponent)).padStart(2, '0')}`;
}

/** Every problem with a file is reported as one of these: a one-line message naming it. */
export class SvecError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'SvecError';
  }
}
