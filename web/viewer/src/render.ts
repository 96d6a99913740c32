// Draws a vector image into a canvas with WebGL2, as `subvec render` draws it on the CPU
// (src/render/renderer.cpp): the same view plan (visible faces from ring boxes, the depth rule in
// output pixels), the same refinement (subdivide.ts), Gouraud-shaded limit triangles, then the
// level's visible objects (src/render/objects.cpp: each refined at the level's depth, its boundary
// a crease, drawn over the level in file order, each with its strokes over it), then the
// strokes. Tears, the image border and the
// objects' boundaries are anti-aliased by the canvas's 4x multisampling (the C++ rasterizer
// supersamples those pixels 4 x 4): an object drawn opaque over the level's samples composites
// with its coverage, as the C++ renderer's layer with alpha = coverage does; strokes by their
// coverage (strokes.ts).
// (Drawing each refined tear edge again as a band that mixes its two sides' colors by area was
// tried: no closer to the C++ renderer, because colors ramp steeply beside tears, and not faster.)
//
// A view reuses the last refinement when it needs the same level and depth and a subset of its
// faces: zooming in within one depth, and panning within the refined region, only redraw.
import { SvecError, type Stroke, type SvecImage } from './image';
import { adaptiveIndices, buildTopology, refine, uniformIndices, type Refined, type Topology } from './wasm';
import { strokeChords, type ViewTransform } from './strokes';

/** A region of the image, in image pixels. */
export interface ViewWindow {
  x0: number;
  y0: number;
  x1: number;
  y1: number;
}

export interface RenderStats {
  /** subdivision depth of the last frame */
  depth: number;
  /** triangles drawn */
  triangles: number;
  /** milliseconds spent refining for the last frame (0 when it reused the refinement) */
  refineMs: number;
  /** milliseconds spent issuing the draw calls */
  drawMs: number;
}

// The depth rule of src/render/renderer.cpp (choose_depth): the smallest k with mean refined edge
// <= maxEdgePixels * sqrt(zoom), at most 8, fewer while faces * 4^k is over the budget. The C++
// renderer refines to edges of 2.5 output pixels; the viewer by default to 5, one level less, a
// quarter of the triangles: the difference is a few tenths of a level (docs/viewer.md). The C++
// renderer allows 2^24 triangles; a browser gets 2^22.
export const DEFAULT_MAX_EDGE_PIXELS = 5;
const CPP_MAX_EDGE_PIXELS = 2.5;
const MAX_DEPTH = 8;
const MAX_TRIANGLES = 1 << 22;

export function chooseDepth(meanEdgePixels: number, maxEdgePixels: number, zoom: number, faces: number): number {
  const target = maxEdgePixels * Math.sqrt(Math.max(1, zoom));
  let k = 0;
  while (k < MAX_DEPTH && meanEdgePixels / 2 ** k > target) ++k;
  while (k > 0 && faces * 4 ** k > MAX_TRIANGLES) --k;
  return k;
}

// The shaders' text ships in the bundle, so it has no comments or indentation (and the build,
// vite.config.ts, takes out the rest of its blanks); compile() puts the version line first. view:
// the window's origin (image pixels) and output pixels per image pixel; size: the output in pixels.
const MESH_VS = `layout(location = 0) in vec2 position;
layout(location = 1) in vec3 color;
uniform vec4 view;
uniform vec2 size;
out vec3 shade;
void main() {
vec2 o = (position - view.xy) * view.zw;
gl_Position = vec4(2.0 * o.x / size.x - 1.0, 1.0 - 2.0 * o.y / size.y, 0.0, 1.0);
shade = color;
}`;
const MESH_FS = `precision highp float;
in vec3 shade;
out vec4 outColor;
void main() { outColor = vec4(clamp(shade / 255.0, 0.0, 1.0), 1.0); }`;

// One instanced quad per chord, covering the chord's capsule plus a pixel: ends x0, y0, x1, y1 and
// p, the pixel centre, in output pixels, y down.
const CHORD_VS = `layout(location = 0) in vec2 corner;
layout(location = 1) in vec4 ends;
layout(location = 2) in vec2 radii;
uniform vec2 size;
out vec4 vEnds;
out vec2 vRadii;
void main() {
float reach = max(radii.x, radii.y) + 1.0;
vec2 lo = min(ends.xy, ends.zw) - reach, hi = max(ends.xy, ends.zw) + reach;
vec2 o = mix(lo, hi, corner);
gl_Position = vec4(2.0 * o.x / size.x - 1.0, 1.0 - 2.0 * o.y / size.y, 0.0, 1.0);
vEnds = ends;
vRadii = radii;
}`;
const CHORD_FS = `precision highp float;
in vec4 vEnds;
in vec2 vRadii;
uniform vec2 size;
out vec4 coverage;
void main() {
vec2 p = vec2(gl_FragCoord.x, size.y - gl_FragCoord.y);
vec2 a = vEnds.xy, d = vEnds.zw - vEnds.xy;
float len2 = dot(d, d);
float u = len2 > 0.0 ? clamp(dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
float dist = length(p - (a + u * d)), r = mix(vRadii.x, vRadii.y, u);
coverage = vec4(clamp(min(dist + r, 0.5) - max(dist - r, -0.5), 0.0, 1.0));
}`;
// Source-over of one stroke's color with its coverage (premultiplied output).
const COMPOSITE_VS = `layout(location = 0) in vec2 corner;
void main() { gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0); }`;
const COMPOSITE_FS = `precision highp float;
uniform sampler2D coverage;
uniform vec3 color;
out vec4 outColor;
void main() {
float a = texelFetch(coverage, ivec2(gl_FragCoord.xy), 0).r;
outColor = vec4(clamp(color / 255.0, 0.0, 1.0) * a, a);
}`;

// Compiles and links without waiting: the GPU process works on it while the page goes on (the
// file is decoded meanwhile); `linked` asks for the result at first use.
function compile(gl: WebGL2RenderingContext, vs: string, fs: string): WebGLProgram {
  const program = gl.createProgram();
  for (const [type, source] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]] as const) {
    const shader = gl.createShader(type);
    if (!shader) throw new SvecError('WebGL2: cannot create a shader');
    gl.shaderSource(shader, `#version 300 es\n${source}`);
    gl.compileShader(shader);
    gl.attachShader(program, shader);
    gl.deleteShader(shader);
  }
  gl.linkProgram(program);
  return program;
}

function linked(gl: WebGL2RenderingContext, program: WebGLProgram): WebGLProgram {
  if (!gl.getProgramParameter(program, gl.LINK_STATUS) && !gl.isContextLost()) {
    throw new SvecError(`WebGL2: shader program failed: ${gl.getProgramInfoLog(program) || 'no log'}`);
  }
  return program;
}

/** Whether w is a window: finite, x0 < x1 and y0 < y1. */
export const validWindow = (w: ViewWindow): boolean => [w.x0, w.y0, w.x1, w.y1].every(Number.isFinite) && w.x0 < w.x1 && w.y0 < w.y1;

function checkWindow(w: ViewWindow): void {
  if (!validWindow(w)) throw new SvecError(`window ${w.x0},${w.y0},${w.x1},${w.y1} is empty or not finite (want x0 < x1, y0 < y1)`);
}

// The refinement of the last view of a mesh (the level's, or an object's), on the GPU.
interface Cache {
  level: number; // the level, or -1 - the object's index
  depth: number;
  faces: Int32Array | null; // ascending; null: all faces
  refined: Refined;
  scale: number; // the output pixels per image pixel the index buffer was chosen for
  numIndices: number;
  vao: WebGLVertexArrayObject;
  buffers: WebGLBuffer[];
}

// The faces of a mesh whose ring box meets the window, and the sum of their edges' lengths in
// output pixels.
function visibleFaces(topo: Topology, w: ViewWindow, view: ViewTransform): [number[], number] {
  const { triangles: tri, positions: p } = topo.level;
  const nf = tri.length / 3, boxes = topo.ringBoxes;
  const visible: number[] = [];
  let edges = 0;
  for (let f = 0; f < nf; ++f) {
    if (boxes[4 * f + 2] < w.x0 || boxes[4 * f] > w.x1 || boxes[4 * f + 3] < w.y0 || boxes[4 * f + 1] > w.y1) continue;
    visible.push(f);
    for (let k = 0; k < 3; ++k) {
      const a = tri[3 * f + k], b = tri[3 * f + ((k + 1) % 3)];
      edges += Math.hypot((p[2 * b] - p[2 * a]) * view.sx, (p[2 * b + 1] - p[2 * a + 1]) * view.sy);
    }
  }
  return [visible, edges];
}

// Whether the ascending list `want` (null: all) is within `have` (null: all).
function covers(have: Int32Array | null, want: Int32Array | null): boolean {
  if (!have) return true;
  if (!want || want.length > have.length) return false;
  let i = 0;
  for (const f of want) {
    while (i < have.length && have[i] < f) ++i;
    if (i === have.length || have[i] !== f) return false;
  }
  return true;
}

export class SubvecRenderer {
  readonly stats: RenderStats = { depth: 0, triangles: 0, refineMs: 0, drawMs: 0 };
  /** The depth rule's refined edge length at 1x, in output pixels: 2.5 draws what `subvec render` draws. */
  maxEdgePixels = DEFAULT_MAX_EDGE_PIXELS;
  /**
   * How far (in color levels) a control face's triangles may be from the next level's before it
   * is refined further, up to the depth rule's depth; 0 refines every face to that depth.
   */
  colorTolerance = 1;
  /** The same for tear and border curves, in output pixels. */
  positionTolerance = 0.25;
  readonly #gl: WebGL2RenderingContext;
  readonly #mesh: WebGLProgram;
  #meshLinked = false;
  #strokePrograms: { chord: WebGLProgram; composite: WebGLProgram; quad: WebGLBuffer } | null = null;
  #image: SvecImage | null = null;
  #level = 0;
  #topologies: Array<Topology | undefined> = [];
  #window: ViewWindow | null = null;
  #cache: Cache | null = null;
  #objectTopologies: Array<Topology | undefined> = [];
  #objectCaches: Array<Cache | undefined> = [];
  #objectDepth = 0;
  #coverage: { texture: WebGLTexture; framebuffer: WebGLFramebuffer; width: number; height: number } | null = null;

  constructor(readonly canvas: HTMLCanvasElement | OffscreenCanvas) {
    // preserveDrawingBuffer: the frame stays readable (toDataURL, drawImage) after it is shown.
    const gl = canvas.getContext('webgl2', { antialias: true, alpha: true, premultipliedAlpha: true, preserveDrawingBuffer: true });
    if (!gl) throw new SvecError('this browser cannot draw the image: WebGL2 is not available');
    this.#gl = gl as WebGL2RenderingContext;
    this.#mesh = compile(this.#gl, MESH_VS, MESH_FS);
    this.#warmUp();
  }

  // One empty draw in the mesh's state, so that the GPU process prepares its pipeline (software
  // GL compiles the shaders to machine code there) while the page decodes and refines the file.
  #warmUp(): void {
    const gl = this.#gl, mesh = this.#meshArrays(new Float32Array(15));
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array([0, 1, 2]), gl.STATIC_DRAW);
    gl.useProgram(this.#mesh);
    gl.drawElements(gl.TRIANGLES, 3, gl.UNSIGNED_INT, 0);  // a degenerate triangle: no pixels
    gl.bindVertexArray(null);
    this.#drop(mesh);
  }

  // A vertex array over `vertices` (x, y, r, g, b each) and an index buffer, left bound.
  #meshArrays(vertices: Float32Array): Pick<Cache, 'vao' | 'buffers'> {
    const gl = this.#gl;
    const vao = gl.createVertexArray()!, buffers = [gl.createBuffer()!, gl.createBuffer()!];
    gl.bindVertexArray(vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, buffers[0]);
    gl.bufferData(gl.ARRAY_BUFFER, vertices, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 20, 0);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 20, 8);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, buffers[1]);
    return { vao, buffers };
  }

  /** Shows `image` (already validated by decode/load) at `level`. */
  setImage(image: SvecImage, level = 0): void {
    this.#dropCache();
    this.#image = image;
    this.#topologies = [];
    this.#objectTopologies = [];
    this.#level = 0;
    this.setLevel(level);
  }

  setLevel(level: number): void {
    const count = this.#image ? this.#image.levels.length : 0;
    if (!Number.isInteger(level) || level < 0 || level >= count) {
      throw new SvecError(`level ${level} is out of range (${count} levels)`);
    }
    this.#level = level;
  }

  /** The region of the image mapped onto the whole canvas; null: the whole image. */
  setView(window: ViewWindow | null): void {
    if (window) checkWindow(window);
    this.#window = window ? { ...window } : null;
  }

  /** Draws at canvas.width x canvas.height device pixels; outside the image stays transparent. */
  render(): void {
    const gl = this.#gl;
    const width = this.canvas.width, height = this.canvas.height;
    gl.viewport(0, 0, width, height);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT);
    const image = this.#image;
    if (!image || width < 1 || height < 1) return;
    const w = this.#window ?? { x0: 0, y0: 0, x1: image.width, y1: image.height };
    const view: ViewTransform = { x0: w.x0, y0: w.y0, sx: width / (w.x1 - w.x0), sy: height / (w.y1 - w.y0), width, height };

    const t0 = performance.now();
    const cache = this.#plan(image, w, view), layers = this.#planObjects(image, w, view);
    const meshes = [cache, ...layers.map(([c]) => c)].filter((c): c is Cache => !!c);
    const t1 = performance.now();
    this.stats.refineMs = meshes.length ? t1 - t0 : 0;
    this.stats.triangles = meshes.reduce((n, c) => n + c.numIndices / 3, 0);
    // The level, then each object and its strokes, then the image's strokes. (The mesh program is
    // set again for each mesh: strokes between them use others.)
    const draw = (c: Cache | null) => {
      if (!c) return;
      if (!this.#meshLinked) this.#meshLinked = !!linked(gl, this.#mesh);
      gl.useProgram(this.#mesh);
      gl.uniform4f(gl.getUniformLocation(this.#mesh, 'view'), view.x0, view.y0, view.sx, view.sy);
      gl.uniform2f(gl.getUniformLocation(this.#mesh, 'size'), width, height);
      gl.bindVertexArray(c.vao);
      gl.drawElements(gl.TRIANGLES, c.numIndices, gl.UNSIGNED_INT, 0);
      gl.bindVertexArray(null);
    };
    draw(cache);
    for (const [c, strokes] of layers) draw(c), this.#drawStrokes(strokes, view);
    this.#drawStrokes(image.strokes, view);
    this.stats.drawMs = performance.now() - t1;
  }

  /** Frees the GPU resources; the renderer cannot draw afterwards. */
  dispose(): void {
    this.#dropCache();
    const gl = this.#gl;
    this.#dropCoverage();
    gl.deleteProgram(this.#mesh);
    if (this.#strokePrograms) {
      gl.deleteProgram(this.#strokePrograms.chord);
      gl.deleteProgram(this.#strokePrograms.composite);
      gl.deleteBuffer(this.#strokePrograms.quad);
      this.#strokePrograms = null;
    }
    this.#image = null;
  }

  // The view plan of src/render/renderer.cpp (plan_view): the faces whose ring box meets the
  // window, their mean edge in output pixels, the depth; then the refinement, reused if it can be.
  #plan(image: SvecImage, w: ViewWindow, view: ViewTransform): Cache | null {
    let topo = this.#topologies[this.#level];
    if (!topo) topo = this.#topologies[this.#level] = buildTopology(image.levels[this.#level], image.width, image.height);
    const [visible, edges] = visibleFaces(topo, w, view);
    this.stats.depth = this.#objectDepth = 0;
    if (visible.length === 0) return null;
    const mean = edges / (3 * visible.length), zoom = Math.min(view.sx, view.sy);
    const depth = (this.stats.depth = chooseDepth(mean, this.maxEdgePixels, zoom, visible.length));
    this.#objectDepth = chooseDepth(mean, Math.min(this.maxEdgePixels, CPP_MAX_EDGE_PIXELS), zoom, visible.length);
    return (this.#cache = this.#refined(this.#cache, this.#level, topo, visible, depth, view));
  }

  // The level's visible objects (draw_objects of src/render/objects.cpp), bottom to top: each
  // refined over its faces in view at the depth `subvec render` gives the level (its rule of
  // 2.5-pixel edges, fewer steps past the triangle budget): an object's boundary is drawn by its
  // chords, which the viewer's coarser depth for the level would show as facets; the adaptive
  // triangles keep only what the tolerances need. Their topology has no image corners (width and
  // height NaN): the boundary is all crease. Each with its strokes, also when none of its faces is
  // in view (null).
  #planObjects(image: SvecImage, w: ViewWindow, view: ViewTransform): Array<[Cache | null, Stroke[]]> {
    const out: Array<[Cache | null, Stroke[]]> = [];
    image.objects.forEach((object, i) => {
      if (object.level !== this.#level || !object.visible) return;
      const topo = (this.#objectTopologies[i] ??= buildTopology(object.mesh, NaN, NaN));
      const [visible] = visibleFaces(topo, w, view);
      let depth = this.#objectDepth;
      while (depth > 0 && visible.length * 4 ** depth > MAX_TRIANGLES) --depth;
      out.push([visible.length ? (this.#objectCaches[i] = this.#refined(this.#objectCaches[i], -1 - i, topo, visible, depth, view)) : null, object.strokes]);
    });
    return out;
  }

  // The refinement of `visible` faces of a mesh at `depth`: `cache` when it holds them (a subset
  // of its faces at the same depth), else a new one; and its triangles for the view's scale.
  #refined(cache: Cache | null | undefined, key: number, topo: Topology, visible: number[], depth: number, view: ViewTransform): Cache {
    const faces = visible.length === topo.level.triangles.length / 3 ? null : Int32Array.from(visible);
    if (!(cache && cache.level === key && cache.depth === depth && covers(cache.faces, faces))) {
      this.#drop(cache);
      cache = this.#upload(key, topo, faces, depth);
    }
    const scale = Math.min(view.sx, view.sy);
    if (cache.scale !== scale) this.#uploadIndices(cache, scale);
    return cache;
  }

  #upload(key: number, topo: Topology, faces: Int32Array | null, depth: number): Cache {
    const refined = refine(topo, faces, depth), mesh = this.#meshArrays(refined.vertices);
    this.#gl.bindVertexArray(null);
    return { level: key, depth, faces, refined, scale: NaN, numIndices: 0, ...mesh };
  }

  // The triangles to draw at this scale: each face as deep as it needs (the position tolerance is
  // in output pixels, so a zoom changes them), or all at the depth.
  #uploadIndices(cache: Cache, scale: number): void {
    const r = cache.refined;
    const indices = this.colorTolerance > 0 ? adaptiveIndices(r, scale, this.colorTolerance, this.positionTolerance) : uniformIndices(r);
    const gl = this.#gl;
    gl.bindVertexArray(cache.vao);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    cache.scale = scale;
    cache.numIndices = indices.length;
  }

  #drop(cache: Pick<Cache, 'vao' | 'buffers'> | null | undefined): void {
    if (!cache) return;
    this.#gl.deleteVertexArray(cache.vao);
    for (const b of cache.buffers) this.#gl.deleteBuffer(b);
  }

  #dropCache(): void {
    for (const c of [this.#cache, ...this.#objectCaches]) this.#drop(c);
    this.#cache = null;
    this.#objectCaches = [];
  }

  // Each of the strokes of the level (the image's, or an object's): its coverage (the maximum over
  // its chords) into a texture, then composited over the frame, in file order.
  #drawStrokes(all: Stroke[], view: ViewTransform): void {
    const strokes = all.filter((s) => s.level === this.#level && s.points.length >= 4);
    if (strokes.length === 0) return;
    const gl = this.#gl;
    const target = this.#coverageTarget(view.width, view.height);
    const { chord, composite, quad } = this.#strokeState();
    const chords = gl.createBuffer()!;
    const vao = gl.createVertexArray()!;
    gl.bindVertexArray(vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, quad);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, chords);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 4, gl.FLOAT, false, 24, 0);
    gl.vertexAttribDivisor(1, 1);
    gl.enableVertexAttribArray(2);
    gl.vertexAttribPointer(2, 2, gl.FLOAT, false, 24, 16);
    gl.vertexAttribDivisor(2, 1);
    gl.enable(gl.BLEND);
    for (const stroke of strokes) {
      const data = strokeChords(stroke, view);
      if (data.length === 0) continue;
      gl.bindFramebuffer(gl.FRAMEBUFFER, target.framebuffer);
      gl.clearColor(0, 0, 0, 0);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.blendEquation(gl.MAX);
      gl.useProgram(chord);
      gl.uniform2f(gl.getUniformLocation(chord, 'size'), view.width, view.height);
      gl.bindBuffer(gl.ARRAY_BUFFER, chords);
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STREAM_DRAW);
      gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, data.length / 6);

      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.blendEquation(gl.FUNC_ADD);
      gl.blendFunc(gl.ONE, gl.ONE_MINUS_SRC_ALPHA);
      gl.useProgram(composite);
      gl.bindTexture(gl.TEXTURE_2D, target.texture);
      gl.uniform1i(gl.getUniformLocation(composite, 'coverage'), 0);
      gl.uniform3f(gl.getUniformLocation(composite, 'color'), ...stroke.color);
      gl.vertexAttribDivisor(1, 0);
      gl.disableVertexAttribArray(1);
      gl.disableVertexAttribArray(2);
      gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
      gl.enableVertexAttribArray(1);
      gl.enableVertexAttribArray(2);
      gl.vertexAttribDivisor(1, 1);
    }
    gl.disable(gl.BLEND);
    gl.bindVertexArray(null);
    gl.deleteVertexArray(vao);
    gl.deleteBuffer(chords);
  }

  // The strokes' programs, made for the first image with strokes.
  #strokeState() {
    if (!this.#strokePrograms) {
      const gl = this.#gl, quad = gl.createBuffer()!;
      gl.bindBuffer(gl.ARRAY_BUFFER, quad);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([0, 0, 1, 0, 0, 1, 1, 1]), gl.STATIC_DRAW);
      const chord = compile(gl, CHORD_VS, CHORD_FS), composite = compile(gl, COMPOSITE_VS, COMPOSITE_FS);
      this.#strokePrograms = { chord: linked(gl, chord), composite: linked(gl, composite), quad };
    }
    return this.#strokePrograms;
  }

  #dropCoverage(): void {
    if (this.#coverage) {
      this.#gl.deleteTexture(this.#coverage.texture);
      this.#gl.deleteFramebuffer(this.#coverage.framebuffer);
    }
    this.#coverage = null;
  }

  #coverageTarget(width: number, height: number) {
    const gl = this.#gl;
    if (this.#coverage && this.#coverage.width === width && this.#coverage.height === height) return this.#coverage;
    this.#dropCoverage();
    const texture = gl.createTexture()!;
    gl.bindTexture(gl.TEXTURE_2D, texture);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.R8, width, height);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    const framebuffer = gl.createFramebuffer()!;
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, texture, 0);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    this.#coverage = { texture, framebuffer, width, height };
    return this.#coverage;
  }
}
