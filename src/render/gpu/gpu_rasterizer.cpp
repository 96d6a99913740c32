// The GPU path of the renderer through OpenGL 4.3 core in a headless EGL context; the design note
// is in gpu_p.h. This is the only translation unit of the library that includes GL or EGL headers.
//
// Order of a frame: (on a new refinement) upload the CSR limit stencils, the corner index pairs
// and the tear / border edges; (on an edit) upload control values and run the stencil compute
// shader; then per tile: draw every refined triangle at the pixel centres and (with tears to
// anti-alias) at 4x4 subsamples into integer targets, mark the pixels the tears cross, resolve
// into packed RGB(A) bytes with a compute shader and read them back into the output rows.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "render/gpu/gpu_p.h"
#include "subvec/core/error.h"

namespace subvec::detail {
namespace {

// ---- Shaders ------------------------------------------------------------------------------------

// Limit values = stencils x control values, one CSR row per invocation; rows [u_first_row,
// u_end_row) of this dispatch. indices[] / weights[] are bound from entry u_base on (a buffer range
// of at most GL_MAX_SHADER_STORAGE_BLOCK_SIZE bytes). Accumulated in double, as the CPU does.
constexpr const char* kStencilShader = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Offsets { int offsets[]; };
layout(std430, binding = 1) readonly buffer Indices { int indices[]; };
layout(std430, binding = 2) readonly buffer Weights { double weights[]; };
layout(std430, binding = 3) readonly buffer Control { double control[]; };
layout(std430, binding = 4) writeonly buffer Limit { float limit[]; };
uniform int u_first_row;
uniform int u_end_row;
uniform int u_base;
void main() {
  int row = u_first_row + int(gl_GlobalInvocationID.x);
  if (row >= u_end_row) return;
  double acc[N];
  for (int c = 0; c < N; ++c) acc[c] = 0.0lf;
  int end = offsets[row + 1] - u_base;
  for (int k = offsets[row] - u_base; k < end; ++k) {
    double w = weights[k];
    int j = indices[k] * N;
    for (int c = 0; c < N; ++c) acc[c] += w * control[j + c];
  }
  for (int c = 0; c < N; ++c) limit[row * N + c] = float(acc[c]);
}
)";

// Vertex pulling: each corner is a (refined vertex, refined color value) pair, so the two sides of
// a tear share positions but not colors. The vertex is snapped to the CPU's 24.8 fixed point in
// output pixels (round half up, within the +-2^21 pixel guard band) in double precision; the
// tile origin is an integer and u_to_ndc = 2 * factor / viewport a power of two, so the window
// coordinates the rasterizer gets are the CPU's fixed-point values times the factor, exactly.
// The picture is mirrored in x (the resolve reads it back mirrored): GL's top-left fill rule
// gives a sample on a shared edge or vertex to the triangle on its right, the CPU's rule (raster.cpp,
// a nudge of the sample by (-e, e^2)) to the one on its left, and mirroring swaps the two. Rows
// are not flipped: GL's rule for horizontal edges already agrees with the CPU's.
constexpr const char* kDrawVertexShader = R"(
layout(location = 0) in ivec2 a_corner;
layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Colors { float colors[]; };
uniform dvec2 u_origin;
uniform dvec2 u_scale;
uniform dvec2 u_tile;
uniform double u_to_ndc;
noperspective out vec3 v_color;
void main() {
  int v = 2 * a_corner.x, c = 3 * a_corner.y;
  dvec2 p = dvec2(positions[v], positions[v + 1]);
  dvec2 o = clamp((p - u_origin) * u_scale * 256.0lf, dvec2(-536870912.0lf), dvec2(536870912.0lf));
  o = floor(o + 0.5lf) / 256.0lf;
  dvec2 ndc = (o - u_tile) * u_to_ndc - 1.0lf;
  ndc.x = -ndc.x;
  gl_Position = vec4(vec2(ndc), 0.0, 1.0);
  v_color = vec3(colors[c], colors[c + 1], colors[c + 2]);
}
)";

// One subsample: the Gouraud color rounded as the CPU's shader rounds (c + 0.5 clamped to
// [0, 255.25], truncated); alpha 1 marks the subsample covered.
constexpr const char* kDrawFragmentShader = R"(
noperspective in vec3 v_color;
layout(location = 0) out uvec4 o_color;
void main() {
  vec3 v = min(max(v_color + 0.5, vec3(0.0)), vec3(255.25));
  o_color = uvec4(uvec3(v), 1u);
}
)";

// Marks the pixels that tear (and, when asked, border) edges cross, exactly as the CPU does
// (MarkTiles::mark_segment in raster.cpp: per pixel row, the columns the segment spans there,
// widened by one subpixel unit), one edge per invocation, as bits of the tile's pixels.
constexpr const char* kMarkShader = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Edges { int edges[]; };
layout(std430, binding = 2) buffer Marks { uint marks[]; };
uniform dvec2 u_origin;
uniform dvec2 u_scale;
uniform int u_edges;
uniform ivec2 u_tile;
uniform ivec2 u_size;
uniform int u_output_width;
ivec2 fixed_point(int v) {
  dvec2 p = dvec2(positions[2 * v], positions[2 * v + 1]);
  dvec2 o = clamp((p - u_origin) * u_scale * 256.0lf, dvec2(-536870912.0lf), dvec2(536870912.0lf));
  return ivec2(floor(o + 0.5lf));
}
void main() {
  int e = int(gl_GlobalInvocationID.x);
  if (e >= u_edges) return;
  ivec2 a = fixed_point(edges[2 * e]), b = fixed_point(edges[2 * e + 1]);
  if (a.y > b.y) { ivec2 t = a; a = b; b = t; }
  if (max(a.x, b.x) < 0 || (min(a.x, b.x) >> 8) >= u_output_width) return;
  int r0 = max(a.y >> 8, u_tile.y), r1 = min(b.y >> 8, u_tile.y + u_size.y - 1);
  double dy = double(b.y) - double(a.y);
  for (int r = r0; r <= r1; ++r) {
    double ya = max(double(a.y), double(r) * 256.0lf);
    double yb = min(double(b.y), double(r + 1) * 256.0lf);
    double xa = double(a.x), xb = double(b.x);
    if (dy > 0.0lf) {
      xa = double(a.x) + (double(b.x) - double(a.x)) * (ya - double(a.y)) / dy;
      xb = double(a.x) + (double(b.x) - double(a.x)) * (yb - double(a.y)) / dy;
    }
    int c0 = max(int(floor((min(xa, xb) - 1.0lf) / 256.0lf)), max(0, u_tile.x));
    int c1 = min(int(floor((max(xa, xb) + 1.0lf) / 256.0lf)),
                 min(u_output_width, u_tile.x + u_size.x) - 1);
    for (int c = c0; c <= c1; ++c) {
      int i = (r - u_tile.y) * u_size.x + (c - u_tile.x);
      atomicOr(marks[i >> 5], 1u << uint(i & 31));
    }
  }
}
)";

// Resolve, as the CPU resolves: a marked pixel is the mean of its covered subsamples, rounded as
// the CPU rounds ((sum + count / 2) / count), with alpha the covered fraction (none covered: 0, 0,
// 0, 0); any other pixel is its centre sample (alpha 255, or 0, 0, 0, 0 uncovered). Each
// invocation resolves 4 consecutive pixels of the tile (row-major) and writes them packed, 3 or 4
// bytes a pixel, so the buffer holds exactly the rows of the output image.
constexpr const char* kResolveShader = R"(
layout(local_size_x = 64) in;
layout(binding = 0) uniform usampler2D u_samples;
layout(binding = 1) uniform usampler2D u_centres;
layout(std430, binding = 0) writeonly buffer Packed { uint words[]; };
layout(std430, binding = 1) readonly buffer Marks { uint marks[]; };
uniform int u_width;
uniform int u_pixels;
uniform int u_antialias;
uniform int u_channels;
uvec4 resolve(int p) {
  if (p >= u_pixels) return uvec4(0u);
  ivec2 xy = ivec2(p % u_width, p / u_width);
  ivec2 cxy = ivec2(u_width - 1 - xy.x, xy.y);  // the targets are mirrored in x
  if (u_antialias == 0 || (marks[p >> 5] & (1u << uint(p & 31))) == 0u) {
    uvec4 s = texelFetch(u_centres, cxy, 0);
    return s.a != 0u ? uvec4(s.rgb, 255u) : uvec4(0u);
  }
  uvec3 sum = uvec3(0u);
  uint count = 0u;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      uvec4 s = texelFetch(u_samples, ivec2(4 * (u_width - xy.x) - 1 - i, 4 * xy.y + j), 0);
      if (s.a != 0u) { sum += s.rgb; ++count; }
    }
  }
  if (count == 0u) return uvec4(0u);
  return uvec4((sum + count / 2u) / count, (count * 255u + 8u) / 16u);
}
void main() {
  int g = int(gl_GlobalInvocationID.x);
  if (4 * g >= u_pixels) return;
  uvec4 px[4];
  for (int k = 0; k < 4; ++k) px[k] = resolve(4 * g + k);
  if (u_channels == 4) {
    for (int k = 0; k < 4; ++k) {
      words[4 * g + k] = px[k].r | (px[k].g << 8) | (px[k].b << 16) | (px[k].a << 24);
    }
  } else {
    words[3 * g] = px[0].r | (px[0].g << 8) | (px[0].b << 16) | (px[1].r << 24);
    words[3 * g + 1] = px[1].g | (px[1].b << 8) | (px[2].r << 16) | (px[2].g << 24);
    words[3 * g + 2] = px[2].b | (px[3].r << 8) | (px[3].g << 16) | (px[3].b << 24);
  }
}
)";

// ---- EGL -----------------------------------------------------------------------------------------

std::string hex(unsigned v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04x", v);
  return buf;
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// An OpenGL 4.3 core context without a surface on an initialized display, or EGL_NO_CONTEXT.
EGLContext create_context(EGLDisplay display, std::string& error) {
  if (!eglBindAPI(EGL_OPENGL_API)) {
    error = "EGL has no desktop OpenGL";
    return EGL_NO_CONTEXT;
  }
  const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                               4,
                               EGL_CONTEXT_MINOR_VERSION,
                               3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                               EGL_NONE};
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_no_config_context")) {
    const EGLint wanted[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    if (!eglChooseConfig(display, wanted, &config, 1, &count) || count < 1) {
      error = "no EGL config for desktop OpenGL";
      return EGL_NO_CONTEXT;
    }
  }
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
  if (context == EGL_NO_CONTEXT) {
    error = "no OpenGL 4.3 core context (EGL error " + hex(unsigned(eglGetError())) + ")";
  }
  return context;
}

// The process's EGL display: hardware devices first (EGL_EXT_platform_device), then Mesa's
// software device, then the surfaceless platform. Initialized once and kept (never terminated:
// contexts of other renderers may live until exit).
struct DisplayChoice {
  EGLDisplay display = EGL_NO_DISPLAY;  // one on which a 4.3 core context can be created
  std::string error;
  bool initialized_any = false;  // some display initialized (the failure is then the context)
};

DisplayChoice open_display() {
  const auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  const auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  const auto device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  if (!get_display) return {EGL_NO_DISPLAY, "EGL has no eglGetPlatformDisplayEXT (no EGL driver?)"};
  std::vector<EGLDisplay> candidates;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (query_devices && has_extension(client, "EGL_EXT_platform_device")) {
    EGLint count = 0;
    if (query_devices(0, nullptr, &count) && count > 0) {
      std::vector<EGLDeviceEXT> devices(static_cast<size_t>(count));
      query_devices(count, devices.data(), &count);
      std::vector<EGLDisplay> software;
      for (EGLint i = 0; i < count; ++i) {
        const char* ext = device_string ? device_string(devices[i], EGL_EXTENSIONS) : nullptr;
        EGLDisplay d = get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d == EGL_NO_DISPLAY) continue;
        (has_extension(ext, "EGL_MESA_device_software") ? software : candidates).push_back(d);
      }
      candidates.insert(candidates.end(), software.begin(), software.end());
    }
  }
  if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY) candidates.push_back(d);
  }
  if (candidates.empty()) return {EGL_NO_DISPLAY, "no EGL device or surfaceless display"};
  std::string error = "no EGL display could be initialized";
  bool initialized = false;
  for (EGLDisplay d : candidates) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(d, &major, &minor)) continue;
    initialized = true;
    EGLContext context = create_context(d, error);
    if (context == EGL_NO_CONTEXT) continue;
    eglDestroyContext(d, context);
    return {d, "", true};
  }
  return {EGL_NO_DISPLAY, error, initialized};
}

const DisplayChoice& display() {
  static const DisplayChoice choice = open_display();
  return choice;
}

// ---- GL helpers ---------------------------------------------------------------------------------

void check_gl(const char* what) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return;
  if (e == GL_OUT_OF_MEMORY) {
    throw Error(ErrorCode::kLimit, std::string("GPU: out of memory in ") + what);
  }
  throw Error(ErrorCode::kIo, std::string("GPU: OpenGL error ") + hex(e) + " in " + what);
}

// The first line of a shader's or program's info log (glGetShaderInfoLog / glGetProgramInfoLog).
template <class GetLog>
std::string first_log_line(GLuint object, GetLog get_log) {
  char log[512] = {};
  get_log(object, sizeof log, nullptr, log);
  const std::string text(log);
  return text.substr(0, text.find('\n'));
}

GLuint compile(GLenum type, const std::string& source, const char* name) {
  const GLuint shader = glCreateShader(type);
  const std::string text = "#version 430 core\n" + source;
  const char* p = text.c_str();
  glShaderSource(shader, 1, &p, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string line = first_log_line(shader, glGetShaderInfoLog);
    glDeleteShader(shader);
    throw Error(ErrorCode::kIo, std::string("GPU: the ") + name + " shader does not compile: " + line);
  }
  return shader;
}

GLuint link(std::initializer_list<GLuint> shaders, const char* name) {
  const GLuint program = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(program, s);
  glLinkProgram(program);
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string line = first_log_line(program, glGetProgramInfoLog);
    glDeleteProgram(program);
    throw Error(ErrorCode::kIo, std::string("GPU: the ") + name + " program does not link: " + line);
  }
  return program;
}

GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

// ---- Profiling (gpu_p.h: GpuPassTimes) ----------------------------------------------------------

std::atomic<bool> profiling{false};
std::mutex last_pass_times_mutex;
GpuPassTimes last_pass_times;

double milliseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// GL_TIME_ELAPSED queries around the passes of a frame (one at a time: they do not nest), summed
// per pass by add_to(), which waits for the results. A pass cannot take longer on the GPU than the
// wall time since it was issued; a result over that is the driver's error (llvmpipe leaves the
// start of a frame's first query unset), and that pass's time is NaN.
class PassClock {
 public:
  void start() {
    used_ = 0;
    passes_.clear();
    started_ = std::chrono::steady_clock::now();
  }
  void begin(double GpuPassTimes::*pass) {
    if (used_ == queries_.size()) {
      queries_.push_back(0);
      glGenQueries(1, &queries_.back());
    }
    passes_.push_back(pass);
    glBeginQuery(GL_TIME_ELAPSED, queries_[used_++]);
  }
  void end() { glEndQuery(GL_TIME_ELAPSED); }
  void add_to(GpuPassTimes& times) {
    std::vector<GLuint64> ns(used_);
    for (size_t i = 0; i < used_; ++i) glGetQueryObjectui64v(queries_[i], GL_QUERY_RESULT, &ns[i]);
    const double bound = milliseconds_since(started_);
    for (size_t i = 0; i < used_; ++i) {
      const double ms = double(ns[i]) * 1e-6;
      times.*passes_[i] += ms <= bound ? ms : std::numeric_limits<double>::quiet_NaN();
    }
  }
  void release() {
    glDeleteQueries(GLsizei(queries_.size()), queries_.data());
    queries_.clear();
  }

 private:
  std::vector<GLuint> queries_;
  size_t used_ = 0;
  std::vector<double GpuPassTimes::*> passes_;
  std::chrono::steady_clock::time_point started_;
};

// Times the GL commands issued during its lifetime as one pass of `clock`; does nothing when
// profiling is off.
class PassScope {
 public:
  PassScope(PassClock& clock, bool profile, double GpuPassTimes::*pass)
      : clock_(profile ? &clock : nullptr) {
    if (clock_) clock_->begin(pass);
  }
  ~PassScope() {
    if (clock_) clock_->end();
  }
  PassScope(const PassScope&) = delete;
  PassScope& operator=(const PassScope&) = delete;

 private:
  PassClock* clock_;
};

// Rows of one stencil matrix on the GPU, applied in dispatches whose index / weight ranges fit
// one shader storage binding.
struct StencilBuffers {
  GLuint offsets = 0, indices = 0, weights = 0;
  int rows = 0;
  struct Chunk {
    int first_row, end_row;
    int64_t base, count;  // entries [base, base + count) of indices / weights
  };
  std::vector<Chunk> chunks;
};

class GlRasterizer final : public GpuRasterizer {
 public:
  GlRasterizer(EGLDisplay display, EGLContext context) : display_(display), context_(context) {}

  ~GlRasterizer() override {
    if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      release_refinement();
      const GLuint buffers[] = {control_positions_, control_colors_, resolved_, marks_};
      glDeleteBuffers(4, buffers);
      for (Target* t : {&centres_, &samples_}) {
        glDeleteTextures(1, &t->texture);
        glDeleteFramebuffers(1, &t->framebuffer);
      }
      glDeleteVertexArrays(1, &vao_);
      clock_.release();
      for (GLuint p : {stencil2_, stencil3_, draw_, resolve_, mark_}) glDeleteProgram(p);
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(display_, context_);
  }

  // Compiles the programs and reads the limits; throws Error on failure.
  void init() {
    Current current(*this);
    const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    int major = 0, minor = 0;
    if (!version || std::sscanf(version, "%d.%d", &major, &minor) != 2 ||
        major * 10 + minor < 43) {
      throw Error(ErrorCode::kIo, std::string("GPU: OpenGL ") + (version ? version : "?") +
                                      " is older than 4.3 (compute shaders)");
    }
    const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    renderer_ = name ? name : "";
    stencil2_ = link({compile(GL_COMPUTE_SHADER, "#define N 2\n" + std::string(kStencilShader),
                              "stencil")},
                     "stencil");
    stencil3_ = link({compile(GL_COMPUTE_SHADER, "#define N 3\n" + std::string(kStencilShader),
                              "stencil")},
                     "stencil");
    draw_ = link({compile(GL_VERTEX_SHADER, kDrawVertexShader, "vertex"),
                  compile(GL_FRAGMENT_SHADER, kDrawFragmentShader, "fragment")},
                 "draw");
    resolve_ = link({compile(GL_COMPUTE_SHADER, kResolveShader, "resolve")}, "resolve");
    mark_ = link({compile(GL_COMPUTE_SHADER, kMarkShader, "mark")}, "mark");
    GLint64 block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
    max_block_ = std::min<int64_t>(block, int64_t{1} << 31);
    GLint align = 0;
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &align);
    align_entries_ = std::max<int64_t>(1, (align + 3) / 4);
    GLint tex = 0, dims[2] = {0, 0};
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &tex);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, dims);
    const int side = std::min({tex, dims[0], dims[1], 16384});
    max_side_ = 1;
    while (max_side_ * 2 <= side) max_side_ *= 2;
    glGenVertexArrays(1, &vao_);
    GLuint buffers[4];
    glGenBuffers(4, buffers);
    control_positions_ = buffers[0], control_colors_ = buffers[1], resolved_ = buffers[2];
    marks_ = buffers[3];
    check_gl("setup");
  }

  void set_refinement(const Subdivision& subdivision) override {
    const SparseMatrix& ps = subdivision.position_stencils();
    const SparseMatrix& cs = subdivision.color_stencils();
    const RefinedMesh& topology = subdivision.topology();
    Current current(*this);
    release_refinement();
    upload_stencils(ps, positions_);
    upload_stencils(cs, colors_);
    num_vertices_ = subdivision.num_vertices();
    num_colors_ = subdivision.num_colors();
    limit_positions_ = new_buffer(int64_t(num_vertices_) * 2 * 4, "the limit positions");
    limit_colors_ = new_buffer(int64_t(num_colors_) * 3 * 4, "the limit colors");

    // Corners: (vertex, color value) per triangle corner, drawn as a plain triangle list.
    const int64_t num_triangles = topology.num_triangles();
    std::vector<int32_t> corners(size_t(num_triangles) * 6);
    for (int64_t t = 0; t < num_triangles; ++t) {
      for (int k = 0; k < 3; ++k) {
        corners[size_t(t) * 6 + 2 * k] = topology.triangles[t][k];
        corners[size_t(t) * 6 + 2 * k + 1] = topology.triangle_colors[t][k];
      }
    }
    num_corners_ = num_triangles * 3;
    glGenBuffers(1, &corners_);
    glBindBuffer(GL_ARRAY_BUFFER, corners_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(corners.size() * 4), corners.data(), GL_STATIC_DRAW);
    glBindVertexArray(vao_);
    glEnableVertexAttribArray(0);
    glVertexAttribIPointer(0, 2, GL_INT, 8, nullptr);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    // Edges whose pixels are supersampled: the tears, then the border.
    std::vector<int32_t> edges;
    edges.reserve((topology.tear_edges.size() + topology.border_edges.size()) * 2);
    for (const auto* list : {&topology.tear_edges, &topology.border_edges}) {
      for (const EdgeVerts& e : *list) edges.insert(edges.end(), {e[0], e[1]});
    }
    num_tear_edges_ = static_cast<int>(topology.tear_edges.size());
    num_border_edges_ = static_cast<int>(topology.border_edges.size());
    mark_edges_ = new_buffer(int64_t(edges.size()) * 4, "the tear and border edges");
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(edges.size() * 4), edges.data());
    check_gl("uploading the refined triangles");
  }

  void set_positions(std::span<const Vec2> positions) override {
    Current current(*this);
    std::vector<double> values(positions.size() * 2);
    for (size_t i = 0; i < positions.size(); ++i) {
      values[2 * i] = positions[i].x;
      values[2 * i + 1] = positions[i].y;
    }
    evaluate(stencil2_, positions_, control_positions_, values, limit_positions_);
  }

  void set_colors(std::span<const Color> colors) override {
    Current current(*this);
    std::vector<double> values(colors.size() * 3);
    for (size_t i = 0; i < colors.size(); ++i) {
      values[3 * i] = colors[i].r;
      values[3 * i + 1] = colors[i].g;
      values[3 * i + 2] = colors[i].b;
    }
    evaluate(stencil3_, colors_, control_colors_, values, limit_colors_);
  }

  void draw(const ViewTransform& view, int channels, bool antialias, Image8& out) override {
    const int width = view.width, height = view.height;
    if (out.width != width || out.height != height || out.channels != channels) {
      out = Image8(width, height, channels);
    }
    Current current(*this);
    const bool profile = profiling.load(std::memory_order_relaxed);
    const auto start = std::chrono::steady_clock::now();
    // Pixels to supersample: those crossed by tears, and by the border when the window leaves the
    // image (RGBA), as on the CPU.
    const int mark_edges = antialias ? num_tear_edges_ + (channels == 4 ? num_border_edges_ : 0) : 0;
    const bool supersample = mark_edges > 0;
    // Tiles: at most max_side_ subsamples a side and 2^22 output pixels (2^26 subsamples).
    const int tile_w = std::min(width, max_side_ / 4);
    const int tile_h = std::min({height, max_side_ / 4, std::max(1, (1 << 22) / tile_w)});
    ensure_target(centres_, tile_w, tile_h);
    if (supersample) ensure_target(samples_, tile_w * 4, tile_h * 4);
    const int64_t tile_pixels = int64_t(tile_w) * tile_h;
    const int64_t tile_bytes = (tile_pixels + 3) / 4 * 4 * channels;
    if (resolved_size_ < tile_bytes) {
      glBindBuffer(GL_SHADER_STORAGE_BUFFER, resolved_);
      glBufferData(GL_SHADER_STORAGE_BUFFER, tile_bytes, nullptr, GL_STREAM_READ);
      resolved_size_ = tile_bytes;
    }
    const int64_t mark_bytes = (tile_pixels + 31) / 32 * 4;
    if (marks_size_ < mark_bytes) {
      glBindBuffer(GL_SHADER_STORAGE_BUFFER, marks_);
      glBufferData(GL_SHADER_STORAGE_BUFFER, mark_bytes, nullptr, GL_DYNAMIC_COPY);
      marks_size_ = mark_bytes;
    }
    glEnable(GL_CULL_FACE);  // the CPU draws no back-facing (folded) triangle either
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    if (profile) clock_.start();
    for (int ty = 0; ty < height; ty += tile_h) {
      for (int tx = 0; tx < width; tx += tile_w) {
        const int w = std::min(tile_w, width - tx), h = std::min(tile_h, height - ty);
        {
          const PassScope pass(clock_, profile, &GpuPassTimes::centres);
          draw_triangles(centres_, view, tx, ty, w, h, 1);
        }
        if (supersample) {
          {
            const PassScope pass(clock_, profile, &GpuPassTimes::samples);
            draw_triangles(samples_, view, tx, ty, w, h, 4);
          }
          const PassScope pass(clock_, profile, &GpuPassTimes::mark);
          mark(view, tx, ty, w, h, mark_edges);
        }
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        const int pixels = w * h;
        {  // Resolve.
          const PassScope pass(clock_, profile, &GpuPassTimes::resolve);
          glUseProgram(resolve_);
          glActiveTexture(GL_TEXTURE0);
          glBindTexture(GL_TEXTURE_2D, samples_.texture);
          glActiveTexture(GL_TEXTURE1);
          glBindTexture(GL_TEXTURE_2D, centres_.texture);
          glUniform1i(uniform(resolve_, "u_samples"), 0);
          glUniform1i(uniform(resolve_, "u_centres"), 1);
          glUniform1i(uniform(resolve_, "u_width"), w);
          glUniform1i(uniform(resolve_, "u_pixels"), pixels);
          glUniform1i(uniform(resolve_, "u_antialias"), supersample ? 1 : 0);
          glUniform1i(uniform(resolve_, "u_channels"), channels);
          glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, resolved_);
          glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, marks_);
          glDispatchCompute(GLuint((pixels + 255) / 256), 1, 1);
          glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        }
        std::chrono::steady_clock::time_point read_start;
        if (profile) {
          glFinish();
          read_start = std::chrono::steady_clock::now();
        }
        // Read back: straight into the output when the tile spans whole rows.
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, resolved_);
        const size_t tile_row = size_t(w) * channels;
        if (w == width) {
          glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(tile_row * h), out.row(ty));
        } else {
          staging_.resize(tile_row * h);
          glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(staging_.size()),
                             staging_.data());
          for (int y = 0; y < h; ++y) {
            std::memcpy(out.row(ty + y) + size_t(tx) * channels, staging_.data() + y * tile_row,
                        tile_row);
          }
        }
        check_gl("drawing a frame");
        if (profile) {
          pending_.read_back += milliseconds_since(read_start);
          ++pending_.tiles;
        }
      }
    }
    if (profile) {
      clock_.add_to(pending_);
      pending_.frame = milliseconds_since(start);
      const std::lock_guard<std::mutex> lock(last_pass_times_mutex);
      last_pass_times = pending_;
    }
    pending_ = GpuPassTimes{};
  }

  void read_positions(std::vector<float>& out) override {
    Current current(*this);
    read(limit_positions_, size_t(num_vertices_) * 2, out);
  }
  void read_colors(std::vector<float>& out) override {
    Current current(*this);
    read(limit_colors_, size_t(num_colors_) * 3, out);
  }

 private:
  // Makes the context current on this thread for the scope of a call, and releases it after, so
  // that the renderer may be used from another thread next time.
  struct Current {
    explicit Current(GlRasterizer& r) : r_(r) {
      if (!eglMakeCurrent(r.display_, EGL_NO_SURFACE, EGL_NO_SURFACE, r.context_)) {
        throw Error(ErrorCode::kIo,
                    "GPU: the EGL context cannot be made current (EGL error " +
                        hex(unsigned(eglGetError())) + ")");
      }
    }
    ~Current() { eglMakeCurrent(r_.display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT); }
    Current(const Current&) = delete;
    Current& operator=(const Current&) = delete;
    GlRasterizer& r_;
  };

  GLuint new_buffer(int64_t bytes, const char* what) {
    if (bytes > max_block_) {
      throw Error(ErrorCode::kLimit, std::string("GPU: ") + what + " need " +
                                         std::to_string(bytes >> 20) +
                                         " MiB in one buffer, over the driver's limit of " +
                                         std::to_string(max_block_ >> 20) + " MiB");
    }
    GLuint b = 0;
    glGenBuffers(1, &b);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glBufferData(GL_SHADER_STORAGE_BUFFER, std::max<int64_t>(bytes, 4), nullptr, GL_DYNAMIC_COPY);
    check_gl(what);
    return b;
  }

  void upload_stencils(const SparseMatrix& s, StencilBuffers& b) {
    b.rows = static_cast<int>(s.rows());
    // CSR offsets (the matrix may be uncompressed: rebuild them from the row sizes).
    std::vector<int32_t> offsets(size_t(b.rows) + 1, 0);
    std::vector<int32_t> indices;
    std::vector<double> weights;
    indices.reserve(size_t(s.nonZeros()));
    weights.reserve(size_t(s.nonZeros()));
    for (int r = 0; r < b.rows; ++r) {
      for (SparseMatrix::InnerIterator it(s, r); it; ++it) {
        indices.push_back(static_cast<int32_t>(it.col()));
        weights.push_back(it.value());
      }
      offsets[size_t(r) + 1] = static_cast<int32_t>(indices.size());
    }
    b.offsets = new_buffer(int64_t(offsets.size()) * 4, "the stencil offsets");
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(offsets.size() * 4), offsets.data());
    glGenBuffers(1, &b.indices);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b.indices);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<size_t>(indices.size(), 1) * 4),
                 indices.data(), GL_STATIC_DRAW);
    glGenBuffers(1, &b.weights);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b.weights);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<size_t>(weights.size(), 1) * 8),
                 weights.data(), GL_STATIC_DRAW);
    check_gl("uploading the stencils");
    // Dispatch chunks: at most 65535 work groups of 64 rows, entries within one binding.
    const int64_t max_entries = max_block_ / 8 - align_entries_;
    constexpr int kMaxRows = 65535 * 64;
    b.chunks.clear();
    for (int first = 0; first < b.rows;) {
      const int64_t base = offsets[first] / align_entries_ * align_entries_;
      int end = first + 1;
      if (offsets[end] - base > max_entries) {
        throw Error(ErrorCode::kLimit, "GPU: a stencil row is over the storage buffer limit");
      }
      // The last row end with offsets[end] - base <= max_entries, and at most kMaxRows rows.
      int lo = end, hi = std::min(b.rows, first + kMaxRows);
      while (lo < hi) {
        const int mid = lo + (hi - lo + 1) / 2;
        if (offsets[mid] - base <= max_entries) lo = mid; else hi = mid - 1;
      }
      end = lo;
      b.chunks.push_back({first, end, base, std::max<int64_t>(offsets[end] - base, 1)});
      first = end;
    }
  }

  void evaluate(GLuint program, const StencilBuffers& b, GLuint control,
                const std::vector<double>& values, GLuint limit) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, control);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<size_t>(values.size(), 1) * 8),
                 values.data(), GL_DYNAMIC_DRAW);
    const bool profile = profiling.load(std::memory_order_relaxed);
    if (profile) clock_.start();
    {
      const PassScope pass(clock_, profile, &GpuPassTimes::stencils);
      glUseProgram(program);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, b.offsets);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, control);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, limit);
      for (const StencilBuffers::Chunk& c : b.chunks) {
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 1, b.indices, GLintptr(c.base * 4),
                          GLsizeiptr(c.count * 4));
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 2, b.weights, GLintptr(c.base * 8),
                          GLsizeiptr(c.count * 8));
        glUniform1i(uniform(program, "u_first_row"), c.first_row);
        glUniform1i(uniform(program, "u_end_row"), c.end_row);
        glUniform1i(uniform(program, "u_base"), static_cast<GLint>(c.base));
        glDispatchCompute(GLuint((c.end_row - c.first_row + 63) / 64), 1, 1);
      }
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
    if (profile) clock_.add_to(pending_);
    check_gl("evaluating the stencils");
  }

  void read(GLuint buffer, size_t count, std::vector<float>& out) {
    out.resize(count);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(count * 4), out.data());
    check_gl("reading limit values");
  }

  // A render target: an RGBA8UI texture (one texel per sample) and its framebuffer.
  struct Target {
    GLuint texture = 0, framebuffer = 0;
    int width = 0, height = 0;
  };

  void ensure_target(Target& t, int w, int h) {
    if (t.texture && t.width >= w && t.height >= h) return;
    if (t.texture) glDeleteTextures(1, &t.texture);
    if (!t.framebuffer) glGenFramebuffers(1, &t.framebuffer);
    t.width = std::max(w, t.width);
    t.height = std::max(h, t.height);
    glGenTextures(1, &t.texture);
    glBindTexture(GL_TEXTURE_2D, t.texture);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8UI, t.width, t.height);
    // An integer texture with a filtering (the default) filter is incomplete and reads as 0.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, t.framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.texture, 0);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("allocating a render target");
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      throw Error(ErrorCode::kIo, "GPU: a render target is incomplete (" + hex(status) + ")");
    }
  }

  // Draws every refined triangle into `t` for the output tile at (tx, ty), w x h pixels, with
  // factor x factor samples per pixel (1: the pixel centres; 4: the 4x4 subsample grid).
  void draw_triangles(const Target& t, const ViewTransform& view, int tx, int ty, int w, int h,
                      int factor) {
    int viewport = 1;
    while (viewport < std::max(w, h) * factor) viewport *= 2;
    glBindFramebuffer(GL_FRAMEBUFFER, t.framebuffer);
    // Mirrored in x (see the vertex shader): window x = w * factor - output x * factor.
    glViewport(-(viewport - w * factor), 0, viewport, viewport);
    glFrontFace(GL_CW);
    const GLuint zero[4] = {0, 0, 0, 0};
    glClearBufferuiv(GL_COLOR, 0, zero);
    glUseProgram(draw_);
    glUniform2d(uniform(draw_, "u_origin"), view.x0, view.y0);
    glUniform2d(uniform(draw_, "u_scale"), view.sx, view.sy);
    glUniform2d(uniform(draw_, "u_tile"), double(tx), double(ty));
    glUniform1d(uniform(draw_, "u_to_ndc"), 2.0 * factor / viewport);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, limit_positions_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, limit_colors_);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(num_corners_));
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  // Clears the marks of the tile and marks the pixels the first `edges` mark edges cross.
  void mark(const ViewTransform& view, int tx, int ty, int w, int h, int edges) {
    const GLuint zero = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, marks_);
    glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glUseProgram(mark_);
    glUniform2d(uniform(mark_, "u_origin"), view.x0, view.y0);
    glUniform2d(uniform(mark_, "u_scale"), view.sx, view.sy);
    glUniform1i(uniform(mark_, "u_edges"), edges);
    glUniform2i(uniform(mark_, "u_tile"), tx, ty);
    glUniform2i(uniform(mark_, "u_size"), w, h);
    glUniform1i(uniform(mark_, "u_output_width"), view.width);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, limit_positions_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, mark_edges_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, marks_);
    glDispatchCompute(GLuint((edges + 63) / 64), 1, 1);
  }

  void release_refinement() {
    for (StencilBuffers* b : {&positions_, &colors_}) {
      const GLuint buffers[] = {b->offsets, b->indices, b->weights};
      glDeleteBuffers(3, buffers);
      *b = StencilBuffers{};
    }
    const GLuint buffers[] = {limit_positions_, limit_colors_, corners_, mark_edges_};
    glDeleteBuffers(4, buffers);
    limit_positions_ = limit_colors_ = corners_ = mark_edges_ = 0;
    num_corners_ = 0;
    num_tear_edges_ = num_border_edges_ = 0;
  }

  EGLDisplay display_;
  EGLContext context_;
  GLuint stencil2_ = 0, stencil3_ = 0, draw_ = 0, resolve_ = 0;
  GLuint mark_ = 0, vao_ = 0;
  Target centres_, samples_;  // the pixel centres, and the 4x4 subsamples, of one tile
  int max_side_ = 1;
  int64_t max_block_ = 0, align_entries_ = 1;
  StencilBuffers positions_, colors_;
  GLuint control_positions_ = 0, control_colors_ = 0, limit_positions_ = 0, limit_colors_ = 0;
  GLuint corners_ = 0, resolved_ = 0, marks_ = 0;
  GLuint mark_edges_ = 0;  // refined tear edges, then border edges (vertex index pairs)
  int num_tear_edges_ = 0, num_border_edges_ = 0;
  int64_t num_corners_ = 0, resolved_size_ = 0, marks_size_ = 0;
  int num_vertices_ = 0, num_colors_ = 0;
  std::vector<uint8_t> staging_;
  std::string renderer_;
  PassClock clock_;        // profiling only
  GpuPassTimes pending_;   // the times of the frame being drawn (and of the edits before it)

 public:
  std::string renderer() const override { return renderer_; }
};

}  // namespace

std::unique_ptr<GpuRasterizer> GpuRasterizer::create(std::string& error) {
  const DisplayChoice& d = display();
  if (d.display == EGL_NO_DISPLAY) {
    error = d.error;
    return nullptr;
  }
  EGLContext context = create_context(d.display, error);
  if (context == EGL_NO_CONTEXT) return nullptr;
  auto r = std::make_unique<GlRasterizer>(d.display, context);
  try {
    r->init();
  } catch (const Error& e) {
    error = e.what();
    return nullptr;
  }
  return r;
}

namespace {

// The probe's answer: the reason ("" when a context was created) and that context's renderer.
const std::pair<std::string, std::string>& probe() {
  static const std::pair<std::string, std::string> answer = [] {
    std::string error;
    const std::unique_ptr<GpuRasterizer> r = GpuRasterizer::create(error);
    return r ? std::pair<std::string, std::string>{std::string(), r->renderer()}
             : std::pair<std::string, std::string>{error, std::string()};
  }();
  return answer;
}

}  // namespace

std::string gpu_probe(bool* no_display) {
  if (no_display) *no_display = !display().initialized_any;
  return probe().first;
}

std::string gpu_probe_renderer() { return probe().second; }

void set_gpu_profiling(bool on) { profiling.store(on, std::memory_order_relaxed); }

GpuPassTimes gpu_pass_times() {
  const std::lock_guard<std::mutex> lock(last_pass_times_mutex);
  return last_pass_times;
}

}  // namespace subvec::detail
