// WebGL2 drawing of the refined limit mesh (Gouraud-shaded triangles with per-vertex colors, the
// tears as seams between GL vertices), strokes, and the overlays (control mesh, feature curves,
// the current selection). All geometry is in image pixels; one affine transform maps it to the
// canvas, so panning and zooming only change two uniforms.

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
  private meshIndex: WebGLBuffer;
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
  private triangleCount = 0;
  private tearCount = 0;
  private controlEdgeCount = 0;
  private highlightLineCount = 0;
  private highlightPointCount = 0;
  private controlPointCount = 0;  // drawn (all control points) while the points tool is on
  private selectedPointCount = 0;
  private strokeVertexCount = 0;
  // CPU copies, updated in place by deltas.
  positions = new Float32Array(0);
  colors = new Uint8Array(0);

  constructor(readonly canvas: HTMLCanvasElement, antialias: boolean) {
    const gl = canvas.getContext('webgl2', { antialias, premultipliedAlpha: false, depth: false, stencil: false });
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
    this.meshIndex = gl.createBuffer()!;
    this.tearIndex = gl.createBuffer()!;
    this.meshVao = vao(this.meshPos, this.meshColor, this.meshIndex);
    this.controlPos = gl.createBuffer()!;
    this.controlEdges = gl.createBuffer()!;
    this.highlightLines = gl.createBuffer()!;
    this.highlightPoints = gl.createBuffer()!;
    this.selectedPoints = gl.createBuffer()!;
    this.controlVao = vao(this.controlPos, null, this.controlEdges);
    this.strokePos = gl.createBuffer()!;
    this.strokeColor = gl.createBuffer()!;
    this.strokeVao = vao(this.strokePos, this.strokeColor, null);
  }

  setMesh(positions: Float32Array, colors: Uint8Array, triangles: Uint32Array, tears: Uint32Array) {
    const gl = this.gl;
    this.positions = new Float32Array(positions);
    this.colors = new Uint8Array(colors);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshPos);
    gl.bufferData(gl.ARRAY_BUFFER, this.positions, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshColor);
    gl.bufferData(gl.ARRAY_BUFFER, this.colors, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.meshIndex);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, triangles, gl.STATIC_DRAW);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.tearIndex);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, tears, gl.STATIC_DRAW);
    this.triangleCount = triangles.length;
    this.tearCount = tears.length;
  }

  // A delta from the server: dense arrays replace, sparse ones patch (indices + values).
  updatePositions(indices: Uint32Array | null, values: Float32Array) {
    if (indices === null) {
      if (values.length !== this.positions.length) return;
      this.positions.set(values);
    } else {
      for (let i = 0; i < indices.length; ++i) {
        const g = indices[i];
        this.positions[2 * g] = values[2 * i];
        this.positions[2 * g + 1] = values[2 * i + 1];
      }
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshPos);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, this.positions);
  }

  updateColors(indices: Uint32Array | null, values: Uint8Array) {
    if (indices === null) {
      if (values.length !== this.colors.length) return;
      this.colors.set(values);
    } else {
      for (let i = 0; i < indices.length; ++i) this.colors.set(values.subarray(4 * i, 4 * i + 4), 4 * indices[i]);
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.meshColor);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, this.colors);
  }

  private controlVertexCount = 0;
  setControl(positions: Float32Array, edges?: Uint32Array) {
    const gl = this.gl;
    this.controlVertexCount = positions.length / 2;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.controlPos);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    if (edges) {
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, edges, gl.STATIC_DRAW);
      this.controlEdgeCount = edges.length;
    }
  }

  // The selection: a feature chain (control vertex indices, drawn as a polyline over the control
  // positions) and the control vertices of a color region (drawn as points).
  setHighlight(chain: number[], region: number[]) {
    const gl = this.gl;
    const lines: number[] = [];
    for (let i = 0; i + 1 < chain.length; ++i) lines.push(chain[i], chain[i + 1]);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightLines);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(lines), gl.DYNAMIC_DRAW);
    this.highlightLineCount = lines.length;
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightPoints);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(region), gl.DYNAMIC_DRAW);
    this.highlightPointCount = region.length;
  }

  // The points tool's handles: every control point when `all`, and the selected ones.
  setPoints(all: boolean, selected: number[]) {
    const gl = this.gl;
    this.controlPointCount = all ? this.controlVertexCount : 0;
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.selectedPoints);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(selected), gl.DYNAMIC_DRAW);
    this.selectedPointCount = selected.length;
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
  }

  draw(t: Transform, overlays: Overlays) {
    const gl = this.gl;
    const w = this.canvas.width, h = this.canvas.height;
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.125, 0.129, 0.141, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.useProgram(this.program);
    gl.uniform2f(this.uScale, (2 * t.zoom) / w, (-2 * t.zoom) / h);
    gl.uniform2f(this.uOffset, (2 * t.panX) / w - 1, 1 - (2 * t.panY) / h);
    gl.uniform1f(this.uPoint, 5);
    gl.uniform4f(this.uTint, 0, 0, 0, 0);
    gl.bindVertexArray(this.meshVao);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.meshIndex);
    gl.drawElements(gl.TRIANGLES, this.triangleCount, gl.UNSIGNED_INT, 0);
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
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.meshIndex);
    }
    gl.bindVertexArray(this.controlVao);
    if (overlays.mesh && this.controlEdgeCount > 0) {
      gl.uniform4f(this.uTint, 0.1, 0.9, 1, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
      gl.drawElements(gl.LINES, this.controlEdgeCount, gl.UNSIGNED_INT, 0);
    }
    if (this.highlightLineCount > 0) {
      gl.uniform4f(this.uTint, 1, 0.2, 0.6, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightLines);
      gl.drawElements(gl.LINES, this.highlightLineCount, gl.UNSIGNED_INT, 0);
    }
    if (this.highlightPointCount > 0) {
      gl.uniform4f(this.uTint, 1, 1, 1, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.highlightPoints);
      gl.drawElements(gl.POINTS, this.highlightPointCount, gl.UNSIGNED_INT, 0);
    }
    if (this.controlPointCount > 0) {
      gl.uniform1f(this.uPoint, 4);
      gl.uniform4f(this.uTint, 0.1, 0.9, 1, 1);
      gl.drawArrays(gl.POINTS, 0, this.controlPointCount);
    }
    if (this.selectedPointCount > 0) {
      gl.uniform1f(this.uPoint, 8);
      gl.uniform4f(this.uTint, 1, 0.55, 0.05, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.selectedPoints);
      gl.drawElements(gl.POINTS, this.selectedPointCount, gl.UNSIGNED_INT, 0);
    }
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.controlEdges);
    gl.bindVertexArray(null);
  }

  // The canvas pixel at canvas coordinates (x, y), y down, read back right after a draw.
  readPixel(x: number, y: number): number[] {
    const out = new Uint8Array(4);
    const gl = this.gl;
    gl.readPixels(Math.floor(x), this.canvas.height - 1 - Math.floor(y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, out);
    return Array.from(out);
  }
}
