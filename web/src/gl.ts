// WebGL2 drawing of the refined limit mesh (Gouraud-shaded triangles with per-vertex colors, the
// tears as seams between GL vertices), strokes, and the overlays (control mesh, feature curves,
// the current selection). All geometry is in image pixels; one affine transform maps it to the
// canvas, so panning and zooming only change two uniforms.
//
// Partial redraws. The drawing buffer is preserved between frames, and the renderer remembers what
// it shows. A change to some GL vertices (a drag preview, a color edit) marks the rectangle around
// their triangles, before and after; a change to control points or highlights, the overlay points
// and lines on them. When the view and the overlays are those shown, the next frame clears and
// draws only the rectangle around all that (scissored), and of the triangles only the chunks that
// meet it: the triangles are sorted along a Hilbert curve once per view, so that a chunk of CHUNK
// consecutive ones is a compact patch with a bounding box. Pixels outside the rectangle are those
// a full draw would give, so the frame is exact (web/tests/e2e-input.mjs compares it with a full
// redraw). Anything else (a new view, zoom, pan, overlay switches, resize, strokes) draws
// everything.

const VERTEX = `#version 300 es
in vec2 a_pos;
in vec4 a_color;
uniform vec2 u_scale, u_offset;
uniform float u_point;
out vec4 v_color;
void main() {
  gl_Position = vec4(a_pos * u_scale + u_offset, 0.0, 1.0);
  gl_PointSize = u_point;
  v_color = a_color;
}`;

const FRAGMENT = `#version 300 es
precision mediump float;
in vec4 v_color;
uniform vec4 u_tint;   // alpha 0: the vertex color; else this color
out vec4 o_color;
void main() { o_color = u_tint.a > 0.0 ? u_tint : v_color; }`;

export interface Transform {
  zoom: number;  // canvas pixels per image pixel
  panX: number;  // canvas position of image (0, 0)
  panY: number;
}

export interface Overlays {
  mesh: boolean;
  features: boolean;
}

// Whether WebGL draws on the CPU (SwiftShader, llvmpipe): such a renderer pays per triangle and
// per multisample, so the page refines less and turns MSAA off there (docs/serve.md).
export function softwareWebGL(): boolean {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return false;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

function compile(gl: WebGL2RenderingContext, type: number, source: string): WebGLShader {
  const shader = gl.createShader(type)!;
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    throw new Error('shader: ' + gl.getShaderInfoLog(shader));
  }
  return shader;
}

const CHUNK = 256;        // triangles per culling chunk
const MARGIN = 6;         // canvas pixels around a dirty rectangle: the widest point is 8 px
const PARTIAL_SHARE = 0.9; // a dirty rectangle over this share of the canvas: draw everything

// Index along a Hilbert curve of a point on a 1024 x 1024 grid: consecutive indices are
// neighbours, so a run of triangles sorted by it is a compact patch.
function hilbert(x: number, y: number): number {
  let d = 0;
  for (let s = 512; s > 0; s >>= 1) {
    const rx = (x & s) > 0 ? 1 : 0, ry = (y & s) > 0 ? 1 : 0;
    d += s * s * ((3 * rx) ^ ry);
    if (ry === 0) {
      if (rx === 1) {
        x = 1023 - x;
        y = 1023 - y;
      }
      const t = x;
      x = y;
      y = t;
    }
  }
  return d;
}

// Grows box b (x0, y0, x1, y1) to hold (x, y).
function grow(b: number[] | Float32Array, x: number, y: number) {
  if (x < b[0]) b[0] = x;
  if (y < b[1]) b[1] = y;
  if (x > b[2]) b[2] = x;
  if (y > b[3]) b[3] = y;
}

// What a frame showed: a partial redraw needs the same canvas size, transform and overlays.
interface Shown {
  w: number; h: number; zoom: number; panX: number; panY: number; mesh: boolean; features: boolean;
}

// A triangle list as drawn: sorted along a Hilbert curve of the centroids (so a chunk of CHUNK
// consecutive triangles is a compact patch), the chunks' bounding boxes in image pixels (the
// `stale` ones are recomputed before use), and per GL vertex the chunks it is in and its
// neighbours along the triangles' edges (CSR; an inner edge appears twice).
class TriangleSet {
  readonly buffer: WebGLBuffer;
  readonly triangles: Uint32Array;
  readonly chunkBox: Float32Array;
  private chunkStale: Uint8Array;
  private staleChunks: number[];
  private vertexChunkOffset: Uint32Array;
  private vertexChunks: Uint32Array;
  private neighbourOffset: Uint32Array;
  private neighbours: Uint32Array;

  // `bounds`: the box of the positions p, which the curve's grid spans.
  constructor(gl: WebGL2RenderingContext, p: Float32Array, bounds: number[], triangles: Uint32Array) {
    const nt = triangles.length / 3, nv = p.length / 2;
    const [x0, y0, x1, y1] = bounds;
    const sx = 1023 / Math.max(x1 - x0, 1e-6), sy = 1023 / Math.max(y1 - y0, 1e-6);
    // key * 2^22 + index, sorted as doubles (exact below 2^53): a stable order by key.
    const keys = new Float64Array(nt);
    for (let t = 0; t < nt; ++t) {
      const a = 2 * triangles[3 * t], b = 2 * triangles[3 * t + 1], c = 2 * triangles[3 * t + 2];
      const cx = (p[a] + p[b] + p[c]) / 3, cy = (p[a + 1] + p[b + 1] + p[c + 1]) / 3;
      keys[t] = hilbert(Math.round((cx - x0) * sx), Math.round((cy - y0) * sy)) * 4194304 + t;
    }
    keys.sort();
    const sorted = new Uint32Array(3 * nt);
    for (let j = 0; j < nt; ++j) {
      const t = keys[j] % 4194304;
      sorted[3 * j] = triangles[3 * t];
      sorted[3 * j + 1] = triangles[3 * t + 1];
      sorted[3 * j + 2] = triangles[3 * t + 2];
    }
    this.triangles = sorted;
    // Each vertex's chunks, once each: chunk ids come in increasing order along the triangles.
    const last = new Int32Array(nv).fill(-1);
    const offset = new Uint32Array(nv + 1);
    for (let k = 0; k < sorted.length; ++k) {
      const v = sorted[k], c = (k / (3 * CHUNK)) | 0;
      if (last[v] !== c) {
        last[v] = c;
        offset[v + 1]++;
      }
    }
    for (let v = 0; v < nv; ++v) offset[v + 1] += offset[v];
    const fill = offset.slice(0, nv);
    const list = new Uint32Array(offset[nv]);
    last.fill(-1);
    for (let k = 0; k < sorted.length; ++k) {
      const v = sorted[k], c = (k / (3 * CHUNK)) | 0;
      if (last[v] !== c) {
        last[v] = c;
        list[fill[v]++] = c;
      }
    }
    this.vertexChunkOffset = offset;
    this.vertexChunks = list;
    const around = new Uint32Array(nv + 1);
    for (let k = 0; k < sorted.length; ++k) around[sorted[k] + 1] += 2;
    for (let v = 0; v < nv; ++v) around[v + 1] += around[v];
    const at = around.slice(0, nv);
    const neighbours = new Uint32Array(around[nv]);
    for (let t = 0; t < nt; ++t) {
      for (let c = 0; c < 3; ++c) {
        const v = sorted[3 * t + c];
        neighbours[at[v]++] = sorted[3 * t + ((c + 1) % 3)];
        neighbours[at[v]++] = sorted[3 * t + ((c + 2) % 3)];
      }
    }
    this.neighbourOffset = around;
    this.neighbours = neighbours;
    const chunks = Math.ceil(nt / CHUNK);
    this.chunkBox = new Float32Array(4 * chunks);
    this.chunkStale = new Uint8Array(chunks);
    this.staleChunks = [];
    this.restale();
    this.buffer = gl.createBuffer()!;
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.buffer);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, sorted, gl.STATIC_DRAW);
  }

  get count() { return this.triangles.length; }

  // Every chunk's box is recomputed before its next use.
  restale() {
    this.chunkStale.fill(1);
    this.staleChunks = Array.from({ length: this.chunkStale.length }, (_, c) => c);
  }

  // Grows `d` (x0, y0, x1, y1) by GL vertex g's triangles as they are now, and marks their chunks
  // stale. Called before a change of g (and the caller adds g's own new place after a move: a
  // neighbour that moves adds its own old and new places).
  touch(g: number, p: Float32Array, d: number[]) {
    for (let k = this.neighbourOffset[g], end = this.neighbourOffset[g + 1]; k < end; ++k) {
      const n = this.neighbours[k];
      grow(d, p[2 * n], p[2 * n + 1]);
    }
    for (let k = this.vertexChunkOffset[g], end = this.vertexChunkOffset[g + 1]; k < end; ++k) {
      const c = this.vertexChunks[k];
      if (this.chunkStale[c]) continue;
      this.chunkStale[c] = 1;
      this.staleChunks.push(c);
    }
  }

  // Recomputes the bounding boxes of the stale chunks.
  refresh(p: Float32Array) {
    const tri = this.triangles, box = this.chunkBox, nt = tri.length / 3;
    for (const c of this.staleChunks) {
      const b = box.subarray(4 * c, 4 * c + 4);
      b.set([Infinity, Infinity, -Infinity, -Infinity]);
      for (let k = 3 * c * CHUNK, end = 3 * Math.min(nt, (c + 1) * CHUNK); k < end; ++k) grow(b, p[2 * tri[k]], p[2 * tri[k] + 1]);
      this.chunkStale[c] = 0;
    }
    this.staleChunks = [];
  }
}

export class Renderer {
  readonly gl: WebGL2RenderingContext;
  private program: WebGLProgram;
  private uScale: WebGLUniformLocation;
  private uOffset: WebGLUniformLocation;
  private uTint: WebGLUniformLocation;
  private uPoint: WebGLUniformLocation;
  private meshVao: WebGLVertexArrayObject;
  private meshPos: WebGLBuffer;
  private meshColor: WebGLBuffer;
  private tearIndex: WebGLBuffer;
  private controlVao: WebGLVertexArrayObject;
  private controlPos: WebGLBuffer;
  private controlEdges: WebGLBuffer;
  private highlightLines: WebGLBuffer;
  private highlightPoints: WebGLBuffer;
  private selectedPoints: WebGLBuffer;
  private strokeVao: WebGLVertexArrayObject;
  private strokePos: WebGLBuffer;
  private strokeColor: WebGLBuffer;
  private objectVao: WebGLVertexArrayObject;
  private objectPos: WebGLBuffer;
  private objectColor: WebGLBuffer;
  /** The objects over the level: one vertex per triangle corner, object after object (CPU copy). */
  objectPositions = new Float32Array(0);
  private tearCount = 0;
  private allPoints = false;  // every control point drawn (the points tool is on)
  private strokeVertexCount = 0;
  // CPU copies, updated in place by deltas.
  positions = new Float32Array(0);
  colors = new Uint8Array(0);
  // The view's triangles, the same surface one level coarser (drag previews on software WebGL; null
  // when the view has no coarser level), and the set drawn.
  private fine: TriangleSet | null = null;
  private coarse: TriangleSet | null = null;
  private active: TriangleSet | null = null;
  // Overlay geometry on the control points (CPU copies, for dirty rectangles).
  private control = new Float32Array(0);
  private controlEdgeList = new Uint32Array(0);
  private highlightChain = new Uint32Array(0);   // pairs of control vertices
  private highlightRegion = new Uint32Array(0);
  private selectedList = new Uint32Array(0);
  // What the drawing buffer shows (null: nothing trustworthy, the next frame draws everything) and
  // the image-space rectangle changed since (x0, y0, x1, y1; empty while x0 > x1).
  private shown: Shown | null = null;
  private dirty = [Infinity, Infinity, -Infinity, -Infinity];
  /** Frames drawn in full and in part (for tests and the benchmark). */
  frames = { full: 0, partial: 0, skipped: 0, partialShare: 0, triangleShare: 0 };  // shares: summed over partial frames

  constructor(readonly canvas: HTMLCanvasElement, antialias: boolean) {
    // Opaque (the compositor neither blends nor converts it), no depth or stencil buffer, and
    // preserved between frames for partial redraws.
    const gl = canvas.getContext('webgl2', {
      antialias, alpha: false, depth: false, stencil: false, preserveDrawingBuffer: true,
    });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    const program = gl.createProgram()!;
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT));
    gl.bindAttribLocation(program, 0, 'a_pos');
    gl.bindAttribLocation(program, 1, 'a_color');
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) {
      throw new Error('program: ' + gl.getProgramInfoLog(program));
    }
    this.program = program;
    this.uScale = gl.getUniformLocation(program, 'u_scale')!;
    this.uOffset = gl.getUniformLocation(program, 'u_offset')!;
    this.uTint = gl.getUniformLocation(program, 'u_tint')!;
    this.uPoint = gl.getUniformLocation(program, 'u_point')!;

    const vao = (pos: WebGLBuffer, color: WebGLBuffer | null, index: WebGLBuffer | null) => {
      const v = gl.createVertexArray()!;
      gl.bindVertexArray(v);
      gl.bindBuffer(gl.ARRAY_BUFFER, pos);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
      if (color) {
        gl.bindBuffer(gl.ARRAY_BUFFER, color);
        gl.enableVertexAttribArray(1);
        gl.vertexAttribPointer(1, 4, gl.UNSIGNED_BYTE, true, 0, 0);
      } else {
        gl.disableVertexAttribArray(1);
        gl.vertexAttrib4f(1, 0, 0, 0, 1);
      }
      if (index) gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, index);
      gl.bindVertexArray(null);
      return v;
    };
    this.meshPos = gl.createBuffer()!;
    this.meshColor = gl.createBuffer()!;
    this.tearIndex = gl.createBuffer()!;
    this.meshVao = vao(this.meshPos, this.meshColor, null);
    this.controlPos = gl.createBuffer()!;
    this.controlEdges = gl.createBuffer()!;
    this.highlightLines = gl.createBuffer()!;
    this.highlightPoints = gl.createBuffer()!;
    this.selectedPoints = gl.createBuffer()!;
    this.controlVao = vao(this.controlPos, null, this.controlEdges);
    this.strokePos = gl.createBuffer()!;
    this.strokeColor = gl.createBuffer()!;
    this.strokeVao = vao(this.strokePos, this.strokeColor, null);
    this.objectPos = gl.createBuffer()!;
    this.objectColor = gl.createBuffer()!;
    this.objectVao = vao(this.objectPos, this.objectColor, null);
  }

  // The objects drawn over the level (subvec serve's view: three vertices per triangle).
  setObjects(positions: Float32Array, colors: Uint8Array) {
    const gl = this.gl;
    this.objectPositions = new Float32Array(positions);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.objectPos);
    gl.bufferData(gl.ARRAY_BUFFER, this.objectPositions, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.objectColor);
    gl.bufferData(gl.ARRAY_BUFFER, colors, gl.STATIC_DRAW);
    this.shown = null;
  }

  // Shows vertices [first, first + count) of the objects as `rest` scaled by s and turned by
  // `degrees` (clockwise on screen) about `pivot`, then moved by (dx, dy): a move's preview.
  offsetObject(rest: Float32Array, first: number, count: number, dx: number, dy: number,
               pivot: [number, number] = [0, 0], degrees = 0, s = 1) {
    const a = (degrees * Math.PI) / 180, c = s * Math.cos(a), sn = s * Math.sin(a);
    for (let g = first; g < first + count; ++g) {
      const x = rest[2 * g] - pivot[0], y = rest[2 * g + 1] - pivot[1];
      this.objectPositions[2 * g] = pivot[0] + c * x - sn * y + dx;
      this.objectPositions[2 * g + 1] = pivot[1] + sn * x + c * y + dy;
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.objectPos);
    gl.bufferData(gl.ARRAY_BUFFER, this.objectPositions, gl.DYNAMIC_DRAW);
    this.shown = null;
  }

  // A new view: GL vertex positions and colors, its triangles and, when it has a coarser level,
  // that level's triangles over the same vertices (`coarse`, else empty), and the tear lines.
  setMesh(positions: Float32Array, colors: Uint8Array, triangles: Uint32Array, coarse: Uint32Array, tears: Uint32Array) {
    const gl = this.gl;
    this.positions = new Float32Array(positions);
    this.colors = new Uint8Array(colors);
    for (const set of [this.fine, this.coarse]) if (set) gl.deleteBuffer(set.buffer);
    const bounds = [Infinity, Infinity, -Infinity, -Infinity];
    for (let i = 0; i < positions.length; i += 2) grow(bounds, positions[i], positions[i + 1]);
    this.fine = new TriangleSet(gl, this.positions, bounds, triangles);
    this.coarse = coarse.length > 0 ? new TriangleSet(gl, this.positions, bounds, coarse) : null;
    this.active = this.fine;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshPos);
    gl.bufferData(gl.ARRAY_BUFFER, this.positions, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshColor);
    gl.bufferData(gl.ARRAY_BUFFER, this.colors, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.tearIndex);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, tears, gl.STATIC_DRAW);
    this.tearCount = tears.length;
    this.shown = null;
  }

  // Draws the coarser triangles (when the view has them) instead of the view's, or back. A drag
  // preview on software WebGL: a quarter of the triangles.
  coarsePreview(on: boolean) {
    const want = on && this.coarse ? this.coarse : this.fine;
    if (want === this.active || !want) return;
    this.active = want;
    want.restale();  // the vertices moved while it was not drawn
    this.shown = null;
  }

  /** Triangles a frame draws now (for tests). */
  get drawnTriangles() { return this.active ? this.active.count / 3 : 0; }

  // Grows the dirty rectangle by GL vertex g's triangles, as drawn now.
  private touchVertex(g: number) {
    this.active?.touch(g, this.positions, this.dirty);
    this.touchPoint(g);
  }

  private touchPoint(g: number) {
    grow(this.dirty, this.positions[2 * g], this.positions[2 * g + 1]);
  }

  // Grows the dirty rectangle by a control point, at its current position.
  private touchControl(v: number) {
    grow(this.dirty, this.control[2 * v], this.control[2 * v + 1]);
  }

  // Grows the dirty rectangle by the overlay points and lines on the control points flagged in
  // `changed` (current positions; call before and after a move).
  private touchControlOverlays(changed: Uint8Array) {
    const touchLines = (pairs: Uint32Array) => {
      for (let i = 0; i + 1 < pairs.length; i += 2) {
        if (changed[pairs[i]] || changed[pairs[i + 1]]) {
          this.touchControl(pairs[i]);
          this.touchControl(pairs[i + 1]);
        }
      }
    };
    if (this.shown?.mesh) touchLines(this.controlEdgeList);
    touchLines(this.highlightChain);
    for (let v = 0; v < changed.length; ++v) if (changed[v]) this.touchControl(v);
  }

  // Uploads GL vertices lo..hi (inclusive) of `data` (`per` values each) into `buffer`.
  private uploadRange(buffer: WebGLBuffer, data: Float32Array | Uint8Array, per: number, lo: number, hi: number) {
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    if (hi < lo) return;
    gl.bufferSubData(gl.ARRAY_BUFFER, lo * per * data.BYTES_PER_ELEMENT, data, lo * per, (hi - lo + 1) * per);
  }

  // A delta from the server: dense arrays replace, sparse ones patch (indices + values).
  updatePositions(indices: Uint32Array | null, values: Float32Array) {
    const p = this.positions;
    if (indices === null) {
      if (values.length !== p.length) return;
      // Dense: the vertices that moved, as if the delta were sparse.
      const moved: number[] = [];
      for (let g = 0; g < p.length / 2; ++g) {
        if (p[2 * g] !== values[2 * g] || p[2 * g + 1] !== values[2 * g + 1]) moved.push(g);
      }
      this.movePositions(new Uint32Array(moved), (_, g) => {
        p[2 * g] = values[2 * g];
        p[2 * g + 1] = values[2 * g + 1];
      });
      return;
    }
    this.movePositions(indices, (i, g) => {
      p[2 * g] = values[2 * i];
      p[2 * g + 1] = values[2 * i + 1];
    });
  }

  // Moves GL vertices `indices` (set(i, g) writes vertex g = indices[i]), marking where their
  // triangles were and are dirty, and uploads the range they span.
  private movePositions(indices: Uint32Array, set: (i: number, g: number) => void) {
    let lo = Infinity, hi = -1;
    for (let i = 0; i < indices.length; ++i) {
      const g = indices[i];
      this.touchVertex(g);
      set(i, g);
      this.touchPoint(g);
      if (g < lo) lo = g;
      if (g > hi) hi = g;
    }
    this.uploadRange(this.meshPos, this.positions, 2, lo, hi);
  }

  updateColors(indices: Uint32Array | null, values: Uint8Array) {
    if (indices === null) {
      if (values.length !== this.colors.length) return;
      this.colors.set(values);
      this.shown = null;
      this.uploadRange(this.meshColor, this.colors, 4, 0, this.colors.length / 4 - 1);
      return;
    }
    let lo = Infinity, hi = -1;
    for (let i = 0; i < indices.length; ++i) {
      const g = indices[i];
      this.colors.set(values.subarray(4 * i, 4 * i + 4), 4 * g);
      this.touchVertex(g);
      if (g < lo) lo = g;
      if (g > hi) hi = g;
    }
    this.uploadRange(this.meshColor, this.colors, 4, lo, hi);
  }

  setControl(positions: Float32Array, edges?: Uint32Array) {
    const gl = this.gl;
    const n = positions.length / 2;
    const changed = new Uint8Array(n);
    if (edges || n !== this.control.length / 2) {
      this.shown = null;
    } else {
      let any = false;
      for (let v = 0; v < n; ++v) {
        if (positions[2 * v] !== this.control[2 * v] || positions[2 * v + 1] !== this.control[2 * v + 1]) {
          changed[v] = 1;
          any = true;
        }
      }
      if (!any) return;
      this.touchControlOverlays(changed);  // where they were
    }
    this.control = new Float32Array(positions);
    if (this.shown) this.touchControlOverlays(changed);  // where they are
    gl.bindBuffer(gl.ARRAY_BUFFER, this.controlPos);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    if (edges) {
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, edges, gl.STATIC_DRAW);
      this.controlEdgeList = new Uint32Array(edges);
    }
  }

  // The selection: a feature chain (control vertex indices, drawn as a polyline over the control
  // positions) and the control vertices of a color region (drawn as points).
  setHighlight(chain: number[], region: number[]) {
    const gl = this.gl;
    const lines: number[] = [];
    for (let i = 0; i + 1 < chain.length; ++i) lines.push(chain[i], chain[i + 1]);
    // What was highlighted and what will be: both are redrawn.
    for (const v of this.highlightChain) this.touchControl(v);
    for (const v of this.highlightRegion) this.touchControl(v);
    this.highlightChain = new Uint32Array(lines);
    this.highlightRegion = new Uint32Array(region);
    for (const v of this.highlightChain) this.touchControl(v);
    for (const v of this.highlightRegion) this.touchControl(v);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightLines);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, this.highlightChain, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightPoints);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, this.highlightRegion, gl.DYNAMIC_DRAW);
  }

  // The points tool's handles: every control point when `all`, and the selected ones.
  setPoints(all: boolean, selected: number[]) {
    const gl = this.gl;
    if (all !== this.allPoints) this.shown = null;
    this.allPoints = all;
    for (const v of this.selectedList) this.touchControl(v);
    this.selectedList = new Uint32Array(selected);
    for (const v of this.selectedList) this.touchControl(v);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.selectedPoints);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, this.selectedList, gl.DYNAMIC_DRAW);
  }

  // Strokes as triangle strips turned into triangles: each polyline point offset by its
  // half-width along the normal.
  setStrokes(strokes: { points: number[]; half_widths: number[]; color: number[] }[]) {
    const pos: number[] = [];
    const col: number[] = [];
    for (const s of strokes) {
      const n = s.points.length / 2;
      const rgba = [s.color[0], s.color[1], s.color[2], 255].map((c) => Math.max(0, Math.min(255, Math.round(c))));
      const side: number[][] = [];
      for (let i = 0; i < n; ++i) {
        const a = Math.max(0, i - 1), b = Math.min(n - 1, i + 1);
        let tx = s.points[2 * b] - s.points[2 * a], ty = s.points[2 * b + 1] - s.points[2 * a + 1];
        const len = Math.hypot(tx, ty) || 1;
        tx /= len; ty /= len;
        const w = s.half_widths[i];
        const x = s.points[2 * i], y = s.points[2 * i + 1];
        side.push([x - ty * w, y + tx * w, x + ty * w, y - tx * w]);
      }
      for (let i = 0; i + 1 < n; ++i) {
        const p = side[i], q = side[i + 1];
        pos.push(p[0], p[1], p[2], p[3], q[0], q[1], q[0], q[1], p[2], p[3], q[2], q[3]);
        for (let k = 0; k < 6; ++k) col.push(...rgba);
      }
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.strokePos);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(pos), gl.STATIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.strokeColor);
    gl.bufferData(gl.ARRAY_BUFFER, new Uint8Array(col), gl.STATIC_DRAW);
    this.strokeVertexCount = pos.length / 2;
    this.shown = null;
  }

  // Draws the frame: only the dirty rectangle when the buffer shows this view with these overlays
  // (see the top of this file), everything otherwise or when `full`.
  draw(t: Transform, overlays: Overlays, full = false) {
    const gl = this.gl;
    const w = this.canvas.width, h = this.canvas.height;
    const s = this.shown, d = this.dirty;
    const same = s !== null && s.w === w && s.h === h && s.zoom === t.zoom && s.panX === t.panX &&
      s.panY === t.panY && s.mesh === overlays.mesh && s.features === overlays.features;
    let scissor: number[] | null = null;
    if (same && !full) {
      if (d[0] > d[2]) {
        this.frames.skipped++;
        return;  // nothing changed
      }
      // The rectangle in canvas pixels (y down), with a margin for lines and points.
      const x0 = Math.max(0, Math.floor(d[0] * t.zoom + t.panX) - MARGIN);
      const y0 = Math.max(0, Math.floor(d[1] * t.zoom + t.panY) - MARGIN);
      const x1 = Math.min(w, Math.ceil(d[2] * t.zoom + t.panX) + MARGIN);
      const y1 = Math.min(h, Math.ceil(d[3] * t.zoom + t.panY) + MARGIN);
      if (x1 <= x0 || y1 <= y0) {
        this.frames.skipped++;
        this.dirty = [Infinity, Infinity, -Infinity, -Infinity];
        return;  // all of it off the canvas
      }
      if ((x1 - x0) * (y1 - y0) <= PARTIAL_SHARE * w * h) scissor = [x0, y0, x1, y1];
    }
    this.dirty = [Infinity, Infinity, -Infinity, -Infinity];
    gl.viewport(0, 0, w, h);
    gl.disable(gl.DITHER);  // of no use on an 8-bit target, and a partial frame must match a full one
    if (scissor) {
      gl.enable(gl.SCISSOR_TEST);
      gl.scissor(scissor[0], h - scissor[3], scissor[2] - scissor[0], scissor[3] - scissor[1]);
      this.frames.partial++;
      this.frames.partialShare += ((scissor[2] - scissor[0]) * (scissor[3] - scissor[1])) / (w * h);
    } else {
      this.frames.full++;
    }
    gl.clearColor(0.125, 0.129, 0.141, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.useProgram(this.program);
    gl.uniform2f(this.uScale, (2 * t.zoom) / w, (-2 * t.zoom) / h);
    gl.uniform2f(this.uOffset, (2 * t.panX) / w - 1, 1 - (2 * t.panY) / h);
    gl.uniform1f(this.uPoint, 5);
    gl.uniform4f(this.uTint, 0, 0, 0, 0);
    gl.bindVertexArray(this.meshVao);
    const set = this.active;
    if (set) gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, set.buffer);
    if (set && scissor) {
      // The chunks that meet the rectangle (in image pixels), consecutive ones in one call.
      set.refresh(this.positions);
      const rx0 = (scissor[0] - t.panX) / t.zoom, ry0 = (scissor[1] - t.panY) / t.zoom;
      const rx1 = (scissor[2] - t.panX) / t.zoom, ry1 = (scissor[3] - t.panY) / t.zoom;
      const box = set.chunkBox, chunks = box.length / 4, nt = set.count / 3;
      let run = -1;
      for (let c = 0; c <= chunks; ++c) {
        const meets = c < chunks && box[4 * c] <= rx1 && box[4 * c + 2] >= rx0 && box[4 * c + 1] <= ry1 && box[4 * c + 3] >= ry0;
        if (meets && run < 0) run = c;
        if (!meets && run >= 0) {
          const first = run * CHUNK, last = Math.min(nt, c * CHUNK);
          gl.drawElements(gl.TRIANGLES, 3 * (last - first), gl.UNSIGNED_INT, 12 * first);
          this.frames.triangleShare += (last - first) / nt;
          run = -1;
        }
      }
    } else if (set) {
      gl.drawElements(gl.TRIANGLES, set.count, gl.UNSIGNED_INT, 0);
    }
    if (this.objectPositions.length > 0) {
      gl.bindVertexArray(this.objectVao);
      gl.drawArrays(gl.TRIANGLES, 0, this.objectPositions.length / 2);
    }
    if (this.strokeVertexCount > 0) {
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
      gl.bindVertexArray(this.strokeVao);
      gl.drawArrays(gl.TRIANGLES, 0, this.strokeVertexCount);
      gl.disable(gl.BLEND);
    }
    if (overlays.features && this.tearCount > 0) {
      gl.bindVertexArray(this.meshVao);
      gl.uniform4f(this.uTint, 1, 0.85, 0.1, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.tearIndex);
      gl.drawElements(gl.LINES, this.tearCount, gl.UNSIGNED_INT, 0);
    }
    gl.bindVertexArray(this.controlVao);
    if (overlays.mesh && this.controlEdgeList.length > 0) {
      gl.uniform4f(this.uTint, 0.1, 0.9, 1, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
      gl.drawElements(gl.LINES, this.controlEdgeList.length, gl.UNSIGNED_INT, 0);
    }
    if (this.highlightChain.length > 0) {
      gl.uniform4f(this.uTint, 1, 0.2, 0.6, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightLines);
      gl.drawElements(gl.LINES, this.highlightChain.length, gl.UNSIGNED_INT, 0);
    }
    if (this.highlightRegion.length > 0) {
      gl.uniform4f(this.uTint, 1, 1, 1, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightPoints);
      gl.drawElements(gl.POINTS, this.highlightRegion.length, gl.UNSIGNED_INT, 0);
    }
    if (this.allPoints && this.control.length > 0) {
      gl.uniform1f(this.uPoint, 4);
      gl.uniform4f(this.uTint, 0.1, 0.9, 1, 1);
      gl.drawArrays(gl.POINTS, 0, this.control.length / 2);
    }
    if (this.selectedList.length > 0) {
      gl.uniform1f(this.uPoint, 8);
      gl.uniform4f(this.uTint, 1, 0.55, 0.05, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.selectedPoints);
      gl.drawElements(gl.POINTS, this.selectedList.length, gl.UNSIGNED_INT, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
    gl.bindVertexArray(null);
    if (scissor) gl.disable(gl.SCISSOR_TEST);
    this.shown = { w, h, zoom: t.zoom, panX: t.panX, panY: t.panY, mesh: overlays.mesh, features: overlays.features };
  }

  // The next frame draws everything (the canvas was resized or cleared).
  invalidate() {
    this.shown = null;
  }



  // The whole canvas, RGBA rows bottom up (tests compare a partial frame with a full one).
  readAll(): Uint8Array {
    const gl = this.gl;
    const out = new Uint8Array(4 * this.canvas.width * this.canvas.height);
    gl.readPixels(0, 0, this.canvas.width, this.canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, out);
    return out;
  }

  // The canvas pixel at canvas coordinates (x, y), y down, read back right after a draw.
  readPixel(x: number, y: number): number[] {
    const out = new Uint8Array(4);
    const gl = this.gl;
    gl.readPixels(Math.floor(x), this.canvas.height - 1 - Math.floor(y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, out);
    return Array.from(out);
  }
}
