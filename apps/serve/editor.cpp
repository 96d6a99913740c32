// The editing state behind `subvec serve`: see editor.h for the design.
#include "editor.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "subvec/core/error.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/stylize.h"
#include "subvec/mesh/curves.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/pyramid/pyramid.h"
#include "subvec/render/renderer.h"

namespace subvec_serve {

using subvec::EditOp;
using subvec::EditSelect;
using subvec::Error;
using subvec::ErrorCode;
using subvec::MeshTopology;

struct Editor::View {
  ViewMesh mesh;
  subvec::ViewMesh limit;  // the library's view mesh: faces, depth, subdivision, limit values
  std::vector<int32_t> gl_vertex, gl_color;  // #G: refined vertex and color value of each GL vertex
  int num_control_vertices = 0;
  int64_t version = 0;     // the document version it shows
  bool preview = false;    // it holds a drag preview's positions, not the document's
  double scale = 1;        // canvas pixels per image pixel (ViewRequest::scale)
  uint64_t topology = 0;   // topology_key() of the level it refines
  uint64_t objects = 0;    // objects_key() of the level's objects it draws
};

struct Editor::Session {
  std::string id;
  std::string tab;
  std::unique_ptr<View> view;
  struct Drag {
    DragStart start;
    int64_t version = 0;
    int vertex = -1, feature = -1;
    subvec::Feature chain;  // the feature or crease chain grabbed (edit/selection.h)
    std::unique_ptr<subvec::ShapeEditor> shape;
    std::vector<Vec2> preview;
    // The control positions the page holds (the drag's start, then each preview's moves).
    std::vector<float> control_shown;
    // The last target the preview accepted (it starts at the press point): a release the mesh
    // cannot take commits this one instead.
    Vec2 last_to;
    double last_rotate = 0;
  };
  std::unique_ptr<Drag> drag;
};

namespace {

// Whether any object carries strokes (the page then reloads the strokes after object edits).
bool has_object_strokes(const VectorImage& image) {
  return std::any_of(image.objects.begin(), image.objects.end(),
                     [](const subvec::Object& o) { return !o.strokes.empty(); });
}

uint8_t to_byte(float v) {
  if (!(v > 0)) return 0;
  if (v >= 255) return 255;
  return static_cast<uint8_t>(std::lround(v));
}

// Positions as the page holds them: x, y floats.
std::vector<float> as_floats(const std::vector<Vec2>& positions) {
  std::vector<float> out;
  out.reserve(2 * positions.size());
  for (const Vec2& p : positions) {
    out.push_back(static_cast<float>(p.x));
    out.push_back(static_cast<float>(p.y));
  }
  return out;
}

// Delta::moved and Delta::offsets for points `indices` (of `count`) going from `shown` to `to`,
// in steps of 2^-shift; `shown` takes the positions the page will hold. False, with nothing
// changed, when a move is over 32767 steps.
bool encode_moves(const std::vector<uint32_t>& indices, const std::vector<float>& to, int shift,
                  size_t count, std::vector<float>& shown, std::vector<uint8_t>& mask,
                  std::vector<int16_t>& offsets) {
  const double step = std::ldexp(1.0, -shift);
  offsets.resize(to.size());
  for (size_t k = 0; k < to.size(); ++k) {
    const double o = std::round((static_cast<double>(to[k]) - shown[2 * indices[k / 2] + k % 2]) / step);
    if (!(std::abs(o) <= 32767)) return false;
    offsets[k] = static_cast<int16_t>(o);
  }
  mask.assign((count + 7) / 8, 0);
  for (size_t i = 0; i < indices.size(); ++i) {
    const uint32_t g = indices[i];
    mask[g / 8] = static_cast<uint8_t>(mask[g / 8] | (1u << (g % 8)));
    // Exact in double (an int16 times a power of two plus a float), then one rounding to float:
    // the page computes the same.
    for (int c = 0; c < 2; ++c) {
      shown[2 * g + c] = static_cast<float>(static_cast<double>(shown[2 * g + c]) + offsets[2 * i + c] * step);
    }
  }
  return true;
}

// A library error raised by a request's content: 422 (the request was well formed, the edit is
// impossible on this image), except for errors that are ours.
[[noreturn]] void refuse_edit(const Error& e) {
  const int status = e.code() == ErrorCode::kInvalidArgument ? kUnprocessable : 500;
  throw RequestError(status, e.what());
}

// A hash of what a view's refinement depends on besides positions and colors: the triangles,
// their color corners, the creases and the feature chains. An edit that changes it (a feature
// added or deleted, or the undo of one) makes the page fetch a new view.
// A hash of the objects drawn over `level` (what an ObjectRange shows): their order, visibility,
// positions, colors and triangles. An edit that changes it makes the page fetch a new view.
uint64_t objects_key(const VectorImage& image, int level) {
  uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](uint64_t v) { h = (h ^ v) * 1099511628211ull; };
  for (size_t o = 0; o < image.objects.size(); ++o) {
    const subvec::Object& object = image.objects[o];
    if (object.level != level) continue;
    mix(o), mix(object.visible);
    for (const Vec2& p : object.mesh.positions) mix(std::bit_cast<uint64_t>(p.x)), mix(std::bit_cast<uint64_t>(p.y));
    for (const Color& c : object.mesh.colors)
      mix(std::bit_cast<uint32_t>(c.r)), mix(std::bit_cast<uint32_t>(c.g)), mix(std::bit_cast<uint32_t>(c.b));
    for (const subvec::Tri& t : object.mesh.triangles) mix(uint64_t(t[0])), mix(uint64_t(t[1])), mix(uint64_t(t[2]));
  }
  return h;
}

uint64_t topology_key(const ControlMesh& mesh) {
  uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](int64_t v) { h = (h ^ static_cast<uint64_t>(v)) * 1099511628211ull; };
  mix(mesh.num_vertices());
  for (const subvec::Tri& t : mesh.triangles) mix(t[0]), mix(t[1]), mix(t[2]);
  for (const subvec::Tri& t : mesh.triangle_colors) mix(t[0]), mix(t[1]), mix(t[2]);
  for (const subvec::EdgeVerts& e : mesh.creases) mix(e[0]), mix(e[1]);
  for (const subvec::Feature& f : mesh.features) {
    mix(-1);
    for (const int32_t v : f.vertices) mix(v);
  }
  return h;
}

// What an edit was, for the undo and redo messages: "color blend at (223, 262)".
std::string edit_label(const EditOp& op) {
  const auto at = [](Vec2 p) {
    return " at (" + std::to_string(std::lround(p.x)) + ", " + std::to_string(std::lround(p.y)) + ")";
  };
  const auto points = [](size_t n) {
    return " of " + std::to_string(n) + (n == 1 ? " control point" : " control points");
  };
  switch (op.kind) {
    case EditOp::Kind::kDrag: return "drag" + at(op.from);
    case EditOp::Kind::kMoveFeature: return "feature move" + at(op.at);
    case EditOp::Kind::kColor:
      return op.name() + (op.select == EditSelect::kVertices ? points(op.vertices.size()) : at(op.at));
    case EditOp::Kind::kMoveVertices: return "move" + points(op.vertices.size());
    case EditOp::Kind::kAddFeature: return "new feature" + at(op.points.front());
    case EditOp::Kind::kDeleteFeature: return "feature deleted" + at(op.at);
    case EditOp::Kind::kMakeObject: return "new object" + at(op.at);
    case EditOp::Kind::kMoveObject: return "object " + std::to_string(op.object) + " moved";
    case EditOp::Kind::kHideObject: return "object " + std::to_string(op.object) + " hidden";
    case EditOp::Kind::kShowObject: return "object " + std::to_string(op.object) + " shown";
    case EditOp::Kind::kOrderObject: return "object " + std::to_string(op.object) + " reordered";
  }
  return op.name();
}

// apply_edit_ops names the operation of its ops file ("ops[0] (drag): ..."); the page applies one
// operation at a time, so the prefix says nothing there.
std::string without_op_prefix(const std::string& line) {
  if (line.rfind("ops[0] (", 0) != 0) return line;
  const size_t end = line.find("): ");
  return end == std::string::npos ? line : line.substr(end + 3);
}

Vec2 clamp_to_image(Vec2 p, int width, int height) {
  return {std::clamp(p.x, 0.0, double(width)), std::clamp(p.y, 0.0, double(height))};
}

bool is_image_corner(Vec2 p, int width, int height) {
  return (p.x == 0 || p.x == width) && (p.y == 0 || p.y == height);
}

}  // namespace

Editor::Editor(VectorImage image) : image_(std::move(image)) {
  if (image_.levels.empty()) throw Error(ErrorCode::kInvalidArgument, "the image has no level");
}

Editor::~Editor() = default;

int64_t Editor::version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

std::pair<VectorImage, int64_t> Editor::snapshot() const {
  std::lock_guard lock(mutex_);
  return {image_, version_};
}

DocumentInfo Editor::info(const std::string& session) const {
  std::lock_guard lock(mutex_);
  DocumentInfo info;
  info.version = version_;
  info.width = image_.width;
  info.height = image_.height;
  for (const ControlMesh& mesh : image_.levels) {
    DocumentInfo::Level level;
    level.vertices = mesh.num_vertices();
    level.triangles = mesh.num_triangles();
    level.colors = mesh.num_colors();
    level.features = static_cast<int>(mesh.features.size());
    double sum = 0;
    for (const subvec::Tri& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const Vec2 a = mesh.positions[t[k]], b = mesh.positions[t[(k + 1) % 3]];
        sum += std::hypot(b.x - a.x, b.y - a.y);
      }
    }
    level.mean_edge = mesh.triangles.empty() ? 0 : sum / (3.0 * mesh.num_triangles());
    info.levels.push_back(level);
  }
  for (const subvec::Object& o : image_.objects) {
    info.objects.push_back({o.level, o.name, o.visible, o.mesh.num_vertices(), static_cast<int>(o.strokes.size())});
  }
  // A session's tab counts its own steps (an unknown session: none of them).
  const auto mine = [&](const std::vector<HistoryStep>& steps) {
    if (session.empty()) return static_cast<int>(steps.size());
    std::string tab = "\n";  // matches no step
    for (const auto& s : sessions_) {
      if (s->id == session) tab = s->tab;
    }
    return static_cast<int>(std::count_if(steps.begin(), steps.end(),
                                          [&](const HistoryStep& h) { return h.tab == tab; }));
  };
  info.undo = mine(undo_);
  info.redo = mine(redo_);
  info.strokes = static_cast<int>(image_.strokes.size());
  info.bands = subvec::filter_bands(image_);  // 0 for one level
  if (filter_version_ == version_) info.filter = filter_;
  return info;
}

std::string Editor::new_session(const std::string& tab) {
  std::lock_guard lock(mutex_);
  auto session = std::make_unique<Session>();
  session->id = "s" + std::to_string(next_session_++);
  session->tab = tab.empty() ? session->id : tab;
  std::string id = session->id;
  sessions_.insert(sessions_.begin(), std::move(session));
  // The least recently used session goes when there are too many: its tab then gets 404 and
  // opens a new one (the document is not affected).
  if (static_cast<int>(sessions_.size()) > kMaxSessions) sessions_.pop_back();
  return id;
}

Editor::Session& Editor::session_locked(const std::string& id) {
  auto it = std::find_if(sessions_.begin(), sessions_.end(),
                         [&](const auto& s) { return s->id == id; });
  if (it == sessions_.end()) {
    throw RequestError(kNotFound, "unknown session '" + id + "' (reload the page)");
  }
  std::rotate(sessions_.begin(), it, it + 1);  // most recently used first
  return *sessions_.front();
}

void Editor::check_version_locked(int64_t version) const {
  if (version != version_) {
    throw RequestError(kConflict, "the document changed in another tab (now version " +
                                      std::to_string(version_) + ", this page showed " +
                                      std::to_string(version) + "): reloaded, try again");
  }
}

void Editor::check_level_locked(int level) const {
  const int n = static_cast<int>(image_.levels.size());
  if (level < 0 || level >= n) {
    throw RequestError(kBadRequest, "level " + std::to_string(level) +
                                        " is out of range (the image has " + std::to_string(n) +
                                        (n == 1 ? " level)" : " levels)"));
  }
}

Editor::ControlData Editor::control(int level) const {
  std::lock_guard lock(mutex_);
  check_level_locked(level);
  const ControlMesh& mesh = image_.levels[level];
  ControlData data;
  data.positions = as_floats(mesh.positions);
  // Each interior edge appears in two triangles with opposite directions: keep a < b once, and
  // border edges (one triangle) whichever way they come.
  std::vector<std::pair<int32_t, int32_t>> edges;
  for (const subvec::Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = t[k], b = t[(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const auto& [a, b] : edges) {
    data.edges.push_back(static_cast<uint32_t>(a));
    data.edges.push_back(static_cast<uint32_t>(b));
  }
  for (const subvec::Feature& f : mesh.features) data.features.push_back(f.vertices);
  return data;
}

ViewMesh Editor::view(const std::string& session_id, const ViewRequest& request) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_level_locked(request.level);
  if (request.depth < -1 || request.depth > 8) {
    throw RequestError(kBadRequest, "depth " + std::to_string(request.depth) +
                                        " is out of range (-1 to 8; -1: from the scale)");
  }
  const ControlMesh& mesh = image_.levels[request.level];

  // The renderer's view of the window at the page's scale (render/renderer.h): its visible faces
  // and its depth rule, or the depth the request names.
  subvec::RenderOptions options;
  options.level = request.level;
  if (request.x1 > request.x0 && request.y1 > request.y0) {
    options.window = subvec::Window{request.x0, request.y0, request.x1, request.y1};
  }
  options.scale = request.scale;
  options.depth = request.depth;
  options.max_edge_pixels = request.max_edge_pixels;
  options.max_pixels = subvec::kMaxRenderPixels;  // nothing is rasterized: the size is the scale
  auto v = std::make_unique<View>();
  try {
    if (session.view && request.have == session.view->mesh.id &&
        session.view->version == version_ && !session.view->preview &&
        session.view->limit.covers(subvec::view_faces(image_, options))) {
      // The view the page holds already has every face this one needs at its depth.
      const ViewMesh& held = session.view->mesh;
      ViewMesh same;
      same.id = held.id;
      same.level = held.level;
      same.depth = held.depth;
      same.partial = held.partial;
      same.unchanged = true;
      return same;
    }
    v->limit = subvec::view_mesh(image_, options);
    v->topology = topology_key(image_.levels[request.level]);
    v->objects = objects_key(image_, request.level);
    // The objects over the level, unwelded per corner.
    for (const subvec::ObjectView& o : subvec::object_views(image_, options)) {
      const subvec::RefinedMesh& r = o.refined;
      ViewMesh::ObjectRange range;
      range.object = o.object;
      range.first = static_cast<uint32_t>(v->mesh.object_positions.size() / 2);
      for (size_t t = 0; t < r.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
          const size_t rv = static_cast<size_t>(r.triangles[t][k]), rc = static_cast<size_t>(r.triangle_colors[t][k]);
          v->mesh.object_positions.push_back(r.positions[2 * rv]);
          v->mesh.object_positions.push_back(r.positions[2 * rv + 1]);
          for (int c = 0; c < 3; ++c) v->mesh.object_colors.push_back(to_byte(r.colors[3 * rc + c]));
          v->mesh.object_colors.push_back(255);
        }
      }
      range.count = static_cast<uint32_t>(v->mesh.object_positions.size() / 2) - range.first;
      v->mesh.objects.push_back(range);
    }
  } catch (const Error& e) {
    const ErrorCode code = e.code();
    throw RequestError(code == ErrorCode::kInvalidArgument ? kBadRequest
                       : code == ErrorCode::kLimit         ? kUnprocessable
                                                           : 500,
                       e.what());
  }
  subvec::RefinedMesh& refined = v->limit.refined;
  const int nr = refined.num_vertices();

  // Unweld: GL vertex = (refined vertex, color value). The first color seen at a vertex takes
  // the vertex's slot; the other sides of a tear get extra GL vertices.
  std::vector<int32_t> first_color(nr, -1), vertex_gl(nr, -1);
  std::unordered_map<int64_t, uint32_t> seam;
  const auto gl_of = [&](int32_t rv, int32_t rc) -> uint32_t {
    if (first_color[rv] < 0) {
      first_color[rv] = rc;
      vertex_gl[rv] = static_cast<int32_t>(v->gl_vertex.size());
      v->gl_vertex.push_back(rv);
      v->gl_color.push_back(rc);
      return static_cast<uint32_t>(vertex_gl[rv]);
    }
    if (first_color[rv] == rc) return static_cast<uint32_t>(vertex_gl[rv]);
    const int64_t key = (int64_t{rv} << 32) | static_cast<uint32_t>(rc);
    auto [it, fresh] = seam.try_emplace(key, static_cast<uint32_t>(v->gl_vertex.size()));
    if (fresh) {
      v->gl_vertex.push_back(rv);
      v->gl_color.push_back(rc);
    }
    return it->second;
  };
  std::vector<uint32_t>& tris = v->mesh.triangles;
  tris.reserve(refined.triangles.size() * 3);
  for (size_t i = 0; i < refined.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) tris.push_back(gl_of(refined.triangles[i][k], refined.triangle_colors[i][k]));
  }
  // The same surface one level coarser on the same GL vertices (their limit points are that
  // level's): the page draws drag previews with it on software WebGL.
  v->mesh.coarse_triangles.reserve(refined.coarse_triangles.size() * 3);
  for (size_t i = 0; i < refined.coarse_triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      v->mesh.coarse_triangles.push_back(gl_of(refined.coarse_triangles[i][k], refined.coarse_triangle_colors[i][k]));
    }
  }
  for (const subvec::EdgeVerts& e : refined.tear_edges) {
    if (vertex_gl[e[0]] < 0 || vertex_gl[e[1]] < 0) continue;
    v->mesh.tear_lines.push_back(static_cast<uint32_t>(vertex_gl[e[0]]));
    v->mesh.tear_lines.push_back(static_cast<uint32_t>(vertex_gl[e[1]]));
  }

  // Limit values, gathered per GL vertex.
  const size_t ng = v->gl_vertex.size();
  v->mesh.positions.resize(ng * 2);
  v->mesh.colors.resize(ng * 4);
  for (size_t g = 0; g < ng; ++g) {
    const size_t rv = static_cast<size_t>(v->gl_vertex[g]), rc = static_cast<size_t>(v->gl_color[g]);
    v->mesh.positions[2 * g] = refined.positions[2 * rv];
    v->mesh.positions[2 * g + 1] = refined.positions[2 * rv + 1];
    for (int c = 0; c < 3; ++c) v->mesh.colors[4 * g + c] = to_byte(refined.colors[3 * rc + c]);
    v->mesh.colors[4 * g + 3] = 255;
  }
  // Deltas need only the limit values; the topology lives on in the subdivision and the GL arrays.
  refined.triangles = {};
  refined.triangle_colors = {};
  refined.triangle_parent = {};
  refined.crease_edges = {};
  refined.border_edges = {};
  refined.tear_edges = {};
  v->scale = request.scale > 0 && std::isfinite(request.scale) ? request.scale : 1;
  v->mesh.id = next_view_++;
  v->mesh.level = request.level;
  v->mesh.depth = v->limit.faces.depth;
  v->mesh.partial = !v->limit.faces.all_faces;
  v->num_control_vertices = mesh.num_vertices();
  v->version = version_;
  session.view = std::move(v);
  return session.view->mesh;
}

Delta Editor::delta_locked(Session& session, const std::vector<Vec2>* preview,
                           bool strokes_changed) {
  // A drag preview moves positions only: its colors are those the view already holds.
  const bool colors = preview == nullptr;
  Delta delta;
  delta.strokes_changed = strokes_changed;
  if (!session.view) return delta;
  View& v = *session.view;
  const ControlMesh& mesh = image_.levels[v.mesh.level];
  if (v.topology != topology_key(mesh) || v.objects != objects_key(image_, v.mesh.level)) {
    // The view refines another mesh, or its objects changed: the page fetches a new view and the
    // control mesh.
    delta.view_id = v.mesh.id;
    delta.reload = true;
    session.view.reset();
    return delta;
  }
  const std::vector<Vec2>& positions = preview ? *preview : mesh.positions;
  delta.view_id = v.mesh.id;
  v.version = version_;
  v.preview = preview != nullptr;
  subvec::RefinedMesh& refined = v.limit.refined;
  if (v.limit.subdivision) {
    v.limit.subdivision->evaluate_positions(positions, refined.positions);
    if (colors) v.limit.subdivision->evaluate_colors(mesh.colors, refined.colors);
  }
  const size_t ng = v.gl_vertex.size();
  // A preview leaves out the vertices that moved less than 1/32 of a canvas pixel from what the
  // page shows (v.mesh.positions is that): no one sees it, and a drag's smooth falloff moves most
  // of the region by less. They go as soon as their drift reaches it, and the drag's end sends
  // every change exactly.
  const float slack = preview ? static_cast<float>(1 / (32 * v.scale)) : 0.0f;
  std::vector<uint32_t> moved;
  std::vector<float> to;  // their new positions
  for (size_t g = 0; g < ng; ++g) {
    const size_t rv = static_cast<size_t>(v.gl_vertex[g]);
    const float x = refined.positions[2 * rv], y = refined.positions[2 * rv + 1];
    const float dx = std::abs(x - v.mesh.positions[2 * g]), dy = std::abs(y - v.mesh.positions[2 * g + 1]);
    if (preview ? (dx > slack || dy > slack) : (dx != 0 || dy != 0)) {
      moved.push_back(static_cast<uint32_t>(g));
      to.push_back(x);
      to.push_back(y);
    }
    if (!colors) continue;
    const size_t rc = static_cast<size_t>(v.gl_color[g]);
    bool changed = false;
    for (int c = 0; c < 3; ++c) {
      const uint8_t b = to_byte(refined.colors[3 * rc + c]);
      changed |= b != v.mesh.colors[4 * g + c];
      v.mesh.colors[4 * g + c] = b;
    }
    if (changed) delta.color_indices.push_back(static_cast<uint32_t>(g));
  }
  if (preview) {
    // Moves in steps of 2^-shift image pixels, at most 1/64 of a canvas pixel (half the slack, so
    // every move sent is at least one step).
    const int shift = std::clamp(static_cast<int>(std::ceil(std::log2(64 * v.scale))), -8, 24);
    std::vector<float>& control_shown = session.drag->control_shown;
    const std::vector<float> control = as_floats(positions);
    std::vector<uint32_t> control_moved;
    std::vector<float> control_to;
    for (size_t i = 0; i < positions.size(); ++i) {
      const float x = control[2 * i], y = control[2 * i + 1];
      if (std::abs(x - control_shown[2 * i]) > slack || std::abs(y - control_shown[2 * i + 1]) > slack) {
        control_moved.push_back(static_cast<uint32_t>(i));
        control_to.push_back(x);
        control_to.push_back(y);
      }
    }
    if (encode_moves(moved, to, shift, ng, v.mesh.positions, delta.moved, delta.offsets) &&
        encode_moves(control_moved, control_to, shift, positions.size(), control_shown,
                     delta.control_moved, delta.control_offsets)) {
      delta.moves = true;
      delta.offset_shift = shift;
      return delta;
    }
    // A move too long for int16 steps: absolute positions (below).
    delta.moved.clear();
    delta.offsets.clear();
    delta.control_moved.clear();
    delta.control_offsets.clear();
    control_shown = control;
  }
  for (size_t i = 0; i < moved.size(); ++i) {
    v.mesh.positions[2 * moved[i]] = to[2 * i];
    v.mesh.positions[2 * moved[i] + 1] = to[2 * i + 1];
  }
  // Sparse while it is smaller: an index (4 bytes) per changed value against 8 / 4 bytes each.
  if (moved.size() * 2 > ng) {
    delta.dense_positions = true;
    delta.positions = v.mesh.positions;
  } else {
    delta.position_indices = std::move(moved);
    delta.positions = std::move(to);
  }
  if (delta.color_indices.size() * 2 > ng) {
    delta.dense_colors = true;
    delta.color_indices.clear();
    delta.colors = v.mesh.colors;
  } else {
    for (uint32_t g : delta.color_indices) {
      delta.colors.insert(delta.colors.end(), v.mesh.colors.begin() + 4 * g,
                          v.mesh.colors.begin() + 4 * g + 4);
    }
  }
  delta.control_positions = as_floats(positions);
  return delta;
}

std::vector<StrokeGeometry> Editor::strokes(int level) const {
  std::lock_guard lock(mutex_);
  check_level_locked(level);
  std::vector<StrokeGeometry> out;
  // The visible objects' strokes (bottom to top), then the level's, which the renderer draws
  // last. (Where objects overlap, the renderer draws an object's strokes under the objects above
  // it; the page draws every stroke over every object.)
  std::vector<const subvec::Stroke*> strokes;
  for (const subvec::Object& o : image_.objects)
    if (o.level == level && o.visible)
      for (const subvec::Stroke& s : o.strokes) strokes.push_back(&s);
  for (const subvec::Stroke& s : image_.strokes) strokes.push_back(&s);
  for (const subvec::Stroke* stroke : strokes) {
    const subvec::Stroke& s = *stroke;
    if (s.level != level || s.points.size() < 2) continue;
    const std::vector<Vec2> line = subvec::sample_bspline(s.points, false, 8);
    std::vector<double> at(line.size(), 0);
    for (size_t i = 1; i < line.size(); ++i) {
      at[i] = at[i - 1] + std::hypot(line[i].x - line[i - 1].x, line[i].y - line[i - 1].y);
    }
    // The renderer's taper (render/strokes.cpp): half * min(1, s / (taper L), (L - s) / (taper L)).
    const double length = at.back(), ramp = s.taper * length;
    StrokeGeometry g;
    g.color = s.color;
    for (size_t i = 0; i < line.size(); ++i) {
      double f = 1;
      if (ramp > 0) f = std::min({1.0, at[i] / ramp, (length - at[i]) / ramp});
      g.points.push_back(static_cast<float>(line[i].x));
      g.points.push_back(static_cast<float>(line[i].y));
      g.half_widths.push_back(static_cast<float>(0.5 * s.width * std::max(f, 0.0)));
    }
    out.push_back(std::move(g));
  }
  return out;
}

SelectResult Editor::select(const SelectRequest& request) const {
  std::lock_guard lock(mutex_);
  check_level_locked(request.level);
  const ControlMesh& mesh = image_.levels[request.level];
  const MeshTopology topology = MeshTopology::build(mesh, image_.width, image_.height);
  SelectResult result;
  try {
    if (request.select == EditSelect::kVertex) {
      result.vertex = subvec::nearest_vertex(mesh, request.at);
      const Vec2 p = mesh.positions[result.vertex];
      result.distance = std::hypot(p.x - request.at.x, p.y - request.at.y);
    } else if (request.select == EditSelect::kFeature) {
      const std::vector<subvec::Feature> chains = subvec::editable_chains(mesh, topology);
      const subvec::FeaturePick pick = subvec::nearest_feature(chains, mesh, topology, request.at);
      if (pick.feature < 0) {
        throw RequestError(kUnprocessable, "nothing to select: level " +
                                               std::to_string(request.level) + " has no features");
      }
      result.feature = pick.feature;
      result.distance = pick.distance;
      result.chain = chains[pick.feature].vertices;
    }
    const subvec::ColorSelection colors = subvec::select_colors(
        mesh, topology, request.select, request.at, request.radius, request.tolerance);
    result.colors = static_cast<int>(colors.colors.size());
    std::vector<char> in(mesh.num_colors(), 0);
    for (int32_t c : colors.colors) in[c] = 1;
    std::vector<char> vin(mesh.num_vertices(), 0);
    for (int f = 0; f < mesh.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (in[mesh.triangle_colors[f][k]]) vin[mesh.triangles[f][k]] = 1;
      }
    }
    for (int i = 0; i < mesh.num_vertices(); ++i) {
      if (vin[i]) result.region.push_back(i);
    }
  } catch (const Error& e) {
    refuse_edit(e);
  }
  return result;
}

SelectResult Editor::drag_start(const std::string& session_id, int64_t version,
                                const DragStart& start) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_version_locked(version);
  check_level_locked(start.level);
  const ControlMesh& mesh = image_.levels[start.level];
  auto drag = std::make_unique<Session::Drag>();
  drag->start = start;
  drag->start.at = clamp_to_image(start.at, image_.width, image_.height);
  drag->last_to = drag->start.at;
  drag->version = version;
  SelectResult result;
  const bool points = !start.vertices.empty();
  if (points) {
    try {
      (void)subvec::move_vertices(mesh, start.vertices, {0, 0});  // checks the list
    } catch (const Error& e) {
      refuse_edit(e);
    }
  } else if (!start.move_feature && start.select == EditSelect::kVertex) {
    drag->vertex = subvec::nearest_vertex(mesh, drag->start.at);
    if (is_image_corner(mesh.positions[drag->vertex], image_.width, image_.height)) {
      throw RequestError(kUnprocessable, "nothing to drag: the nearest control vertex is an image "
                                         "corner, which stays fixed");
    }
    result.vertex = drag->vertex;
  } else {
    const MeshTopology topology = MeshTopology::build(mesh, image_.width, image_.height);
    const std::vector<subvec::Feature> chains = subvec::editable_chains(mesh, topology);
    const subvec::FeaturePick pick = subvec::nearest_feature(chains, mesh, topology, drag->start.at);
    if (pick.feature < 0) {
      throw RequestError(kUnprocessable, "nothing to select: level " +
                                             std::to_string(start.level) + " has no features");
    }
    drag->feature = pick.feature;
    drag->chain = chains[pick.feature];
    result.feature = pick.feature;
    result.distance = pick.distance;
    result.chain = drag->chain.vertices;
  }
  // What the user left to the editor: an extent local to what was grabbed.
  if (start.auto_sigma || start.auto_region) {
    const subvec::DragExtent e = points              ? subvec::suggested_drag_extent(mesh, start.vertices)
                                 : drag->vertex >= 0 ? subvec::suggested_drag_extent(mesh, -1, drag->vertex)
                                                     : subvec::suggested_drag_extent(mesh, drag->chain);
    if (start.auto_sigma) drag->start.sigma = e.sigma;
    if (start.auto_region) drag->start.region = e.region;
  }
  if (!(drag->start.sigma > 0) || !std::isfinite(drag->start.sigma)) {
    throw RequestError(kBadRequest, "sigma must be a positive number of pixels");
  }
  if (!(drag->start.region >= 0) || !std::isfinite(drag->start.region)) {
    throw RequestError(kBadRequest, "region must be a non-negative number of pixels");
  }
  result.drag_sigma = drag->start.sigma;
  result.drag_region = drag->start.region;
  try {
    drag->shape = std::make_unique<subvec::ShapeEditor>(mesh, image_.width, image_.height);
  } catch (const Error& e) {
    refuse_edit(e);
  }
  // The page holds the document's control positions: previews send moves from there.
  drag->control_shown = as_floats(mesh.positions);
  session.drag = std::move(drag);
  // Factor the ARAP systems for this handle set now (a zero move), so that every move of the
  // drag only back-substitutes.
  (void)drag_move_locked(session, session.drag->start.at, 0);
  return result;
}

Delta Editor::drag_move(const std::string& session_id, Vec2 to, double rotate) {
  std::lock_guard lock(mutex_);
  return drag_move_locked(session_locked(session_id), to, rotate);
}

Delta Editor::drag_move_locked(Session& session, Vec2 to, double rotate) {
  if (!session.drag) throw RequestError(kConflict, "no drag in progress");
  Session::Drag& drag = *session.drag;
  // Another tab edited while this drag went on: the drag goes on over the edited document (the
  // topology never changes, so its handle is still valid), and its end applies to that.
  if (drag.version != version_) {
    drag.shape = std::make_unique<subvec::ShapeEditor>(image_.levels[drag.start.level],
                                                       image_.width, image_.height);
    drag.version = version_;
  }
  if (!std::isfinite(to.x) || !std::isfinite(to.y) || !std::isfinite(rotate)) {
    throw RequestError(kBadRequest, "drag target must be finite");
  }
  to = clamp_to_image(to, image_.width, image_.height);
  const ControlMesh& mesh = image_.levels[drag.start.level];
  const Vec2 d{to.x - drag.start.at.x, to.y - drag.start.at.y};
  subvec::Handles handles;
  if (!drag.start.vertices.empty()) {
    handles = subvec::move_vertices(mesh, drag.start.vertices, d);
  } else if (drag.start.move_feature) {
    handles = subvec::move_feature(mesh, drag.chain, d, rotate);
  } else if (drag.vertex >= 0) {
    handles = subvec::drag_vertex(mesh, drag.vertex, d);
  } else {
    handles = subvec::drag_feature(mesh, drag.chain, drag.start.at, d, drag.start.sigma);
  }
  handles.region = drag.start.region;
  try {
    drag.shape->deform(handles, drag.preview);
  } catch (const Error& e) {
    refuse_edit(e);
  }
  drag.last_to = to;
  drag.last_rotate = rotate;
  if (!session.view || session.view->mesh.level != drag.start.level) {
    Delta none;
    return none;
  }
  return delta_locked(session, &drag.preview, false);
}

Delta Editor::drag_end(const std::string& session_id, int64_t version, Vec2 to, double rotate,
                       std::string& log) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  if (!session.drag) throw RequestError(kConflict, "no drag in progress");
  std::unique_ptr<Session::Drag> drag = std::move(session.drag);
  // The page's version may be behind by another tab's edit made during the drag: the drag applies
  // to the document as it is now, over that edit, instead of being thrown away.
  (void)version;
  drag->version = version_;
  if (!std::isfinite(to.x) || !std::isfinite(to.y) || !std::isfinite(rotate)) {
    throw RequestError(kBadRequest, "drag target must be finite");
  }
  to = clamp_to_image(to, image_.width, image_.height);
  const auto op_to = [&](Vec2 target, double angle) {
    EditOp op;
    op.level = drag->start.level;
    op.region = drag->start.region;
    if (!drag->start.vertices.empty()) {
      op.kind = EditOp::Kind::kMoveVertices;
      op.vertices = drag->start.vertices;
      op.translate = {target.x - drag->start.at.x, target.y - drag->start.at.y};
    } else if (drag->start.move_feature) {
      op.kind = EditOp::Kind::kMoveFeature;
      op.at = drag->start.at;
      op.translate = {target.x - drag->start.at.x, target.y - drag->start.at.y};
      op.rotate = angle;
    } else {
      op.kind = EditOp::Kind::kDrag;
      op.select = drag->vertex >= 0 ? EditSelect::kVertex : EditSelect::kFeature;
      op.from = drag->start.at;
      op.to = target;
      op.sigma = drag->start.sigma;
    }
    return op;
  };
  // The release position, or else the last one the preview took: a drag that cannot go all the
  // way stops where it last could (issue 29), and says so. The page's message is plain: what
  // moved and by how much (the library's line names vertex counts and solver figures).
  const auto said = [&](Vec2 target, double angle) {
    const auto px = [](double v) {
      std::string t = std::to_string(static_cast<double>(std::lround(v * 10)) / 10);
      t.erase(t.find_last_not_of('0') + 1);
      if (t.back() == '.') t.pop_back();
      return t == "-0" ? std::string("0") : t;
    };
    const std::string by =
        "(" + px(target.x - drag->start.at.x) + ", " + px(target.y - drag->start.at.y) + ") px";
    if (const size_t n = drag->start.vertices.size()) {
      return "moved " + std::to_string(n) + (n == 1 ? " control point" : " control points") + " by " + by;
    }
    if (!drag->start.move_feature) return "dragged by " + by;
    return "moved by " + by + (angle != 0 ? ", rotated by " + px(angle) + "°" : std::string());
  };
  VectorImage edited = image_;
  EditOp op = op_to(to, rotate);
  try {
    const std::vector<std::string> lines = subvec::apply_edit_ops(edited, std::span(&op, 1));
    // The fold-free path stopped short (issue 25): the frame or a crossing holds the drag.
    const bool stopped = !lines.empty() && lines.front().find("; stopped at ") != std::string::npos;
    log = (stopped ? "stopped at the last position the mesh could take: " : "") + said(to, rotate);
  } catch (const Error& e) {
    const bool moved = drag->last_to.x != drag->start.at.x || drag->last_to.y != drag->start.at.y ||
                       drag->last_rotate != 0;
    if (e.code() != ErrorCode::kInvalidArgument || !moved) {
      refuse_edit(Error(e.code(), without_op_prefix(e.what())));
    }
    edited = image_;
    op = op_to(drag->last_to, drag->last_rotate);
    try {
      subvec::apply_edit_ops(edited, std::span(&op, 1));
      log = "stopped at the last position the mesh could take: " +
            said(drag->last_to, drag->last_rotate);
    } catch (const Error&) {
      refuse_edit(Error(e.code(), without_op_prefix(e.what())));
    }
  }
  // The level's strokes (or the object's) moved with it (apply_edit_ops carries them along).
  const bool strokes_moved = op.in_object ? !edited.objects[op.object].strokes.empty()
                                          : std::any_of(edited.strokes.begin(), edited.strokes.end(),
                                                        [&](const subvec::Stroke& s) { return s.level == op.level; });
  commit_locked(std::move(edited), edit_label(op), session);
  return delta_locked(session, nullptr, strokes_moved);
}

void Editor::drag_cancel(const std::string& session_id) {
  std::lock_guard lock(mutex_);
  session_locked(session_id).drag.reset();
}

void Editor::commit_locked(VectorImage image, std::string label, const Session& by) {
  undo_.push_back({std::move(image_), std::move(label), by.tab});
  if (static_cast<int>(undo_.size()) > kMaxUndo) undo_.erase(undo_.begin());
  redo_.clear();
  image_ = std::move(image);
  ++version_;
}

Delta Editor::apply(const std::string& session_id, int64_t version, const EditOp& op,
                    std::string& log) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_version_locked(version);
  check_level_locked(op.level);
  using K = EditOp::Kind;
  const bool object_edit = op.kind == K::kMakeObject || op.kind == K::kMoveObject ||
                           op.kind == K::kHideObject || op.kind == K::kShowObject ||
                           op.kind == K::kOrderObject;
  if (op.kind != K::kColor && op.kind != K::kMoveVertices && op.kind != K::kAddFeature &&
      op.kind != K::kDeleteFeature && !object_edit) {
    throw RequestError(kBadRequest, "not a color edit, a move of control points, a feature edit or an object edit");
  }
  VectorImage edited = image_;
  std::vector<std::string> lines;
  try {
    lines = subvec::apply_edit_ops(edited, std::span(&op, 1));
  } catch (const Error& e) {
    refuse_edit(Error(e.code(), without_op_prefix(e.what())));
  }
  if (op.kind == EditOp::Kind::kAddFeature || op.kind == EditOp::Kind::kDeleteFeature || object_edit) {
    log = lines.empty() ? edit_label(op) : without_op_prefix(lines.front());
    session.drag.reset();
    // An object's strokes move, hide and reorder with it (and making one takes the level's).
    const bool strokes_changed = object_edit && (has_object_strokes(image_) || has_object_strokes(edited));
    commit_locked(std::move(edited), edit_label(op), session);
    return delta_locked(session, nullptr, strokes_changed);
  }
  if (op.kind == EditOp::Kind::kMoveVertices) {  // an arrow-key nudge
    const auto px = [](double v) { return std::to_string(std::lround(v)); };
    log = "moved " + std::to_string(op.vertices.size()) +
          (op.vertices.size() == 1 ? " control point" : " control points") + " by (" +
          px(op.translate.x) + ", " + px(op.translate.y) + ") px";
    const bool strokes_moved = std::any_of(edited.strokes.begin(), edited.strokes.end(),
                                           [&](const subvec::Stroke& s) { return s.level == op.level; });
    commit_locked(std::move(edited), edit_label(op), session);
    return delta_locked(session, nullptr, strokes_moved);
  }
  // The page's line, in plain words: what changed and how much (the library's line names the
  // seed vertex and its color value).
  const std::vector<subvec::Color>& before = image_.levels[op.level].colors;
  const std::vector<subvec::Color>& after = edited.levels[op.level].colors;
  int changed = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    changed += before[i].r != after[i].r || before[i].g != after[i].g || before[i].b != after[i].b;
  }
  const auto rgb = [](subvec::Color c) {
    return "(" + std::to_string(std::lround(c.r)) + ", " + std::to_string(std::lround(c.g)) + ", " +
           std::to_string(std::lround(c.b)) + ")";
  };
  log = edit_label(op) + ": " + std::to_string(changed) + " control colors " +
        (op.mode == subvec::ColorMode::kBlend ? "moved toward " : "mapped onto ") + rgb(op.color);
  commit_locked(std::move(edited), edit_label(op), session);
  return delta_locked(session, nullptr, false);
}

double Editor::suggested_region(int level, const std::vector<int32_t>& vertices) const {
  std::lock_guard lock(mutex_);
  check_level_locked(level);
  try {
    return subvec::suggested_drag_extent(image_.levels[level], vertices).region;
  } catch (const Error& e) {
    refuse_edit(e);
  }
}

Delta Editor::stylize(const std::string& session_id, int64_t version, int level,
                      std::optional<int> object, std::optional<double> threshold, uint64_t seed,
                      double probability, std::string& log) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_version_locked(version);
  check_level_locked(level);
  subvec::StylizeOptions options;
  options.level = level;
  options.object = object;
  options.threshold = threshold;
  options.seed = seed;
  options.probability = probability;
  subvec::StylizeReport report;
  VectorImage edited = image_;
  try {
    report = subvec::apply_stylize(edited, options);
  } catch (const Error& e) {
    refuse_edit(e);
  }
  log = std::to_string(report.strokes) + " strokes on " +
        std::to_string(report.above + report.chosen) + " of " + std::to_string(report.in_region) +
        " features (saliency threshold " + std::to_string(std::lround(report.threshold)) + ")" +
        (report.replaced > 0 ? ", replacing the " + std::to_string(report.replaced) + " before"
                             : std::string());
  commit_locked(std::move(edited), "stylize", session);
  return delta_locked(session, nullptr, true);
}

Delta Editor::filter(const std::string& session_id, int64_t version, const FilterRequest& request,
                     std::string& log) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_version_locked(version);
  // A slider's next value filters the image it started from, while it filters the same thing.
  const bool continues = filter_version_ == version_ && filter_.object == request.object;
  const VectorImage& base = continues ? filter_base_ : image_;
  if (request.object && (*request.object < 0 || *request.object >= static_cast<int>(base.objects.size()))) {
    throw RequestError(kBadRequest, "\"object\" " + std::to_string(*request.object) + " is out of range (" +
                                        std::to_string(base.objects.size()) + " objects)");
  }
  if (!request.object && base.levels.size() < 2) {
    throw RequestError(kUnprocessable, "this image has no level pyramid to filter (make one with "
                                       "subvec vectorize --levels 2 or more)");
  }
  const int bands = subvec::filter_bands(base, request.object);
  if (request.eta.empty() || static_cast<int>(request.eta.size()) > bands) {
    throw RequestError(kBadRequest, "\"eta\" must have 1 to " + std::to_string(bands) +
                                        " values (one per band)");
  }
  for (double eta : request.eta) {
    if (!std::isfinite(eta) || eta < 0 || eta > 4) {
      throw RequestError(kBadRequest, "\"eta\" values must be 0 to 4");
    }
  }
  const bool identity = (!request.geometry && !request.color) ||
                        std::all_of(request.eta.begin(), request.eta.end(),
                                    [](double eta) { return eta == 1; });
  VectorImage filtered;
  subvec::FilterReport report;
  if (identity) {
    filtered = base;
  } else {
    subvec::FilterOptions options;
    options.object = request.object;
    if (request.geometry) options.geometry_eta = request.eta;
    if (request.color) options.color_eta = request.eta;
    try {
      filtered = subvec::filter(base, options, &report);
    } catch (const Error& e) {
      refuse_edit(e);
    }
  }
  VectorImage start = continues ? std::move(filter_base_) : image_;
  commit_locked(std::move(filtered), identity ? "filter off" : "filter", session);
  filter_base_ = std::move(start);
  filter_version_ = version_;
  filter_ = request;
  session.drag.reset();
  log = identity ? "filter off: the image before filtering"
                 : "filtered " + std::to_string(bands) + (bands == 1 ? " band" : " bands") +
                       (request.object ? " of object " + std::to_string(*request.object) : std::string()) + " on " +
                       (request.geometry && request.color ? "geometry and color"
                        : request.geometry              ? "geometry"
                                                        : "color") +
                       (report.restored_vertices > 0 ? ", held back where it would fold"
                                                     : std::string());
  return delta_locked(session, nullptr, false);
}

Delta Editor::undo(const std::string& session_id, int64_t version, std::string& label) {
  return step_history(session_id, version, undo_, redo_, "undo", label);
}

Delta Editor::redo(const std::string& session_id, int64_t version, std::string& label) {
  return step_history(session_id, version, redo_, undo_, "redo", label);
}

// Undo takes from the undo stack and keeps the current image on the redo stack; redo the reverse.
Delta Editor::step_history(const std::string& session_id, int64_t version,
                           std::vector<HistoryStep>& from, std::vector<HistoryStep>& to,
                           const char* verb, std::string& label) {
  std::lock_guard lock(mutex_);
  Session& session = session_locked(session_id);
  check_version_locked(version);
  // A tab takes back its own edits only (docs/serve.md, "Two tabs"): the step on top must be its.
  const bool any = std::any_of(from.begin(), from.end(),
                               [&](const HistoryStep& h) { return h.tab == session.tab; });
  if (!any) throw RequestError(kConflict, std::string("nothing to ") + verb + " in this tab");
  if (from.back().tab != session.tab) {
    throw RequestError(kConflict, std::string(verb) +
                                      " waits: the last edit was made in another window, which can undo it");
  }
  // Strokes move with shape edits, so any may differ: the page reloads them when there are any.
  const bool strokes_changed = !from.back().image.strokes.empty() || !image_.strokes.empty() ||
                               has_object_strokes(from.back().image) || has_object_strokes(image_);
  label = from.back().label;
  to.push_back({std::move(image_), label, session.tab});
  image_ = std::move(from.back().image);
  from.pop_back();
  ++version_;
  session.drag.reset();
  return delta_locked(session, nullptr, strokes_changed);
}

}  // namespace subvec_serve
