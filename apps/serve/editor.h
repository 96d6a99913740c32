// The editing state behind `subvec serve` (docs/serve.md), independent of HTTP.
//
// Design note. One Editor holds one *versioned document*: the vector image the user named, an
// undo and a redo stack of whole images, and a version number that every change increments.
// Browser tabs are *sessions*: a session owns what only its page needs (the refined mesh it draws,
// at the depth and over the window its zoom asks for, and the state of a drag in progress), never
// the document. Every request that changes the document names the version the page shows; a
// request made from a stale version is refused (Conflict), so two tabs can never overwrite each
// other's edits unseen: the refused tab reloads and the user sees the other tab's work. The
// version is also what a tab polls to notice a change made elsewhere.
//
// Edits go through the library exactly as `subvec edit` does (apply_edit_ops with one EditOp), so a
// session's history is also a valid ops file. A drag is previewed with the same calls
// (drag_feature / drag_vertex / move_feature, then ShapeEditor::deform with the factorization
// cached for the drag's handle set) and committed with apply_edit_ops when the mouse is released.
//
// Redraw data. A view is the control faces of one level that the renderer would draw for the
// page's window and scale, refined to the renderer's depth and pushed to the limit
// (subvec::view_mesh, render/renderer.h), unwelded into "GL vertices" (one per refined vertex and
// color value pair, so a tear is a seam), with RGBA8 colors and float positions in image pixels. After an edit
// a session answers with a Delta: the GL vertices whose position or color changed (sparse when few
// changed, dense otherwise), never the topology again.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "subvec/edit/ops.h"
#include "subvec/edit/shape.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec_serve {

using subvec::Color;
using subvec::ControlMesh;
using subvec::Vec2;
using subvec::VectorImage;

// A refused request: `status` is the HTTP status the server answers with.
class RequestError : public std::runtime_error {
 public:
  RequestError(int status, const std::string& message)
      : std::runtime_error(message), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

// Status codes used by the editor (RFC 9110 names).
inline constexpr int kBadRequest = 400, kNotFound = 404, kConflict = 409, kUnprocessable = 422,
                     kUnavailable = 503;

// A view as the renderer plans it (render/renderer.h, view_mesh): the faces whose limit surface
// may touch the window, refined to the renderer's depth for `scale` and `max_edge_pixels`, or to
// `depth` when it is given.
struct ViewRequest {
  int level = 0;
  int depth = -1;  // -1: the renderer's depth rule; else 0..8
  // Image-space window the page shows (with a margin); empty (x1 <= x0): the whole image.
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double scale = 1;              // canvas pixels per image pixel
  double max_edge_pixels = subvec::RenderOptions{}.max_edge_pixels;  // the depth rule's target
  int64_t have = 0;              // the view the page holds (ViewMesh::id; 0: none)
};

// The refined mesh a session draws, unwelded for WebGL.
struct ViewMesh {
  int64_t id = 0;
  int level = 0;
  int depth = 0;
  bool partial = false;             // only the faces near the window were refined
  // The view the page holds (ViewRequest::have) is the session's and covers the request (same
  // level, depth and document version, and every face it needs): nothing to send, the arrays are
  // empty and `id` is the held view's.
  bool unchanged = false;
  std::vector<float> positions;     // #G x 2, image pixels
  std::vector<uint8_t> colors;      // #G x 4, RGBA8 (alpha 255)
  std::vector<uint32_t> triangles;  // #T x 3 GL vertex indices
  std::vector<uint32_t> coarse_triangles;  // the view one level coarser, same GL vertices (RefinedMesh)
  std::vector<uint32_t> tear_lines; // pairs of GL vertex indices along the feature curves
  // The visible objects of the level (subvec::object_views), drawn over it bottom to top: one GL
  // vertex per triangle corner, three per triangle, object after object. Not changed by deltas:
  // an edit of an object reloads the view.
  struct ObjectRange {
    int object = 0;          // index in VectorImage::objects
    uint32_t first = 0;      // first GL vertex (of object_positions / 2)
    uint32_t count = 0;      // GL vertices (3 per triangle)
  };
  std::vector<ObjectRange> objects;
  std::vector<float> object_positions;  // x, y per GL vertex
  std::vector<uint8_t> object_colors;   // RGBA8 per GL vertex
  int num_gl_vertices() const { return static_cast<int>(positions.size() / 2); }
};

// What changed in a view after an edit. Sparse: the indices and the new values of the changed GL
// vertices; dense (`dense_*` true): every GL vertex, in order, `*_indices` empty.
struct Delta {
  int64_t view_id = 0;
  bool dense_positions = false, dense_colors = false;
  std::vector<uint32_t> position_indices;
  std::vector<float> positions;
  std::vector<uint32_t> color_indices;
  std::vector<uint8_t> colors;
  std::vector<float> control_positions;  // #V x 2 of the view's level (for the overlay)
  bool strokes_changed = false;
  // The level's topology changed (a feature added or deleted, or the undo of one): the view is
  // gone, and the page fetches a new one and the control mesh. Nothing else is set.
  bool reload = false;
  // A drag preview sends moves instead (a third of the bytes): `moved` has a bit per GL vertex
  // (bit g % 8 of byte g / 8), and `offsets` an (x, y) int16 pair per set bit, in steps of
  // 2^-offset_shift image pixels, to add to the position the page holds. The sum is exact in
  // double and then rounded to float, so the page and the server agree bit for bit. The same for
  // the control positions (`control_moved`, `control_offsets`; `control_positions` is then empty).
  bool moves = false;  // false: positions are absolute, as above
  int offset_shift = 0;
  std::vector<uint8_t> moved, control_moved;
  std::vector<int16_t> offsets, control_offsets;
};

// A stroke as the page draws it: a polyline with a half-width per point.
struct StrokeGeometry {
  std::vector<float> points;  // #P x 2
  std::vector<float> half_widths;
  Color color;
};

// A filter of the level pyramid's detail bands (pyramid/pyramid.h, as `subvec filter`): eta per
// band, finest first (a short list repeats its last value), applied to the positions and/or the
// colors.
struct FilterRequest {
  std::vector<double> eta;
  bool geometry = false, color = true;
  std::optional<int> object;  // filter this object alone (FilterOptions::object)
};

struct DocumentInfo {
  int64_t version = 0;
  int width = 0, height = 0;
  struct Level {
    int vertices = 0, triangles = 0, colors = 0, features = 0;
    double mean_edge = 0;  // mean control edge length, pixels
  };
  std::vector<Level> levels;
  struct ObjectEntry {
    int level = 0;
    std::string name;
    bool visible = true;
    int vertices = 0;
    int strokes = 0;  // its own (Object::strokes)
  };
  std::vector<ObjectEntry> objects;  // bottom to top
  int undo = 0, redo = 0;
  int strokes = 0;
  int bands = 0;  // detail bands of the level pyramid (0: no pyramid, nothing to filter)
  // The filter the document shows, while the last change was a filter (the page's sliders).
  std::optional<FilterRequest> filter;
};

// One drag in progress (drag tool or move-feature tool).
struct DragStart {
  int level = 0;
  bool move_feature = false;             // else: a drag
  subvec::EditSelect select = subvec::EditSelect::kFeature;
  Vec2 at;
  double sigma = 20;
  double region = 0;
  // Left to the editor ("auto"): subvec::suggested_drag_extent for what is grabbed.
  bool auto_sigma = false, auto_region = false;
  // Not empty: a move of these control vertices (the points tool's selection), by the mouse's
  // displacement from `at`.
  std::vector<int32_t> vertices;
};

struct SelectRequest {
  int level = 0;
  subvec::EditSelect select = subvec::EditSelect::kVertex;
  Vec2 at;
  double radius = 0;
  double tolerance = subvec::kDefaultRegionTolerance;  // a region's
};

struct SelectResult {
  int vertex = -1, feature = -1;
  double distance = 0;
  std::vector<int32_t> chain;       // control vertices of the feature (empty for a vertex)
  std::vector<int32_t> region;      // control vertices whose color values the region holds
  int colors = 0;                   // color values in the region
  double drag_sigma = 0, drag_region = 0;  // a drag's extent, as resolved ("auto" or asked)
};

class Editor {
 public:
  // Limits that keep one request bounded in time and memory.
  static constexpr int kMaxSessions = 32;
  static constexpr int kMaxUndo = 200;

  explicit Editor(VectorImage image);
  ~Editor();
  Editor(const Editor&) = delete;
  Editor& operator=(const Editor&) = delete;

  // `session`: undo and redo count that session's tab's steps (empty: every step).
  DocumentInfo info(const std::string& session = "") const;
  int64_t version() const;
  // A copy of the document (for saving and exporting) and its version.
  std::pair<VectorImage, int64_t> snapshot() const;

  // Sessions: a new one per tab; unknown ids throw RequestError(404).
  // `tab`: the browser tab the session serves (the page keeps one id per tab across reloads);
  // undo and redo take back that tab's edits only. Empty: the session is its own tab.
  std::string new_session(const std::string& tab = "");

  // Control mesh of a level for the overlay: positions, unique edges, feature chains.
  struct ControlData {
    std::vector<float> positions;
    std::vector<uint32_t> edges;
    std::vector<std::vector<int32_t>> features;
  };
  ControlData control(int level) const;

  // Builds the session's view and returns it (the session keeps it for deltas).
  ViewMesh view(const std::string& session, const ViewRequest& request);
  std::vector<StrokeGeometry> strokes(int level) const;

  SelectResult select(const SelectRequest& request) const;

  // Drag: start (picks the handle; version must be current), move (preview, changes nothing in
  // the document), end (commits through apply_edit_ops; returns the log line).
  SelectResult drag_start(const std::string& session, int64_t version, const DragStart& start);
  Delta drag_move(const std::string& session, Vec2 to, double rotate);
  Delta drag_end(const std::string& session, int64_t version, Vec2 to, double rotate,
                 std::string& log);
  void drag_cancel(const std::string& session);

  // A color edit (op.kind == kColor), a nudge of control points (kMoveVertices) or a feature
  // added or deleted (kAddFeature, kDeleteFeature: the delta then says reload) through
  // apply_edit_ops; the delta for the session's view, and `log`, the page's line: "color blend at
  // (50, 46): 34 control colors moved toward (0, 255, 0)", "moved 3 control points by (1, 0) px".
  Delta apply(const std::string& session, int64_t version, const subvec::EditOp& op,
              std::string& log);
  // The deformation's extent local to a selection of control vertices (suggested_drag_extent).
  double suggested_region(int level, const std::vector<int32_t>& vertices) const;
  // Stylizes `level`, or `object`'s own features (apply_stylize).
  Delta stylize(const std::string& session, int64_t version, int level, std::optional<int> object,
                std::optional<double> threshold, uint64_t seed, double probability, std::string& log);
  // Filters the pyramid (subvec::filter). The sliders are absolute: a filter that directly follows
  // another (no edit, undo or redo between them) replaces it, i.e. filters the image the first one
  // started from, so eta = 1 everywhere gives that image back exactly. Each one is an undo step.
  Delta filter(const std::string& session, int64_t version, const FilterRequest& request,
               std::string& log);
  // `label` gets the edit undone or redone.
  Delta undo(const std::string& session, int64_t version, std::string& label);
  Delta redo(const std::string& session, int64_t version, std::string& label);

 private:
  struct Session;
  struct View;
  Session& session_locked(const std::string& id);
  void check_version_locked(int64_t version) const;
  void check_level_locked(int level) const;
  void commit_locked(VectorImage image, std::string label, const Session& by);
  Delta drag_move_locked(Session& session, Vec2 to, double rotate);
  Delta delta_locked(Session& session, const std::vector<Vec2>* preview, bool strokes_changed);
  // An undo or redo step: the image on the other side of it, and the edit it is ("color blend at
  // (223, 262)"), which the page shows as "undid: ...".
  struct HistoryStep {
    VectorImage image;
    std::string label;
    std::string tab;  // the tab that made the edit: only it may undo or redo it
  };
  Delta step_history(const std::string& session, int64_t version, std::vector<HistoryStep>& from,
                     std::vector<HistoryStep>& to, const char* verb, std::string& label);

  mutable std::mutex mutex_;
  VectorImage image_;
  int64_t version_ = 1;
  std::vector<HistoryStep> undo_, redo_;
  // The image the current run of filters started from, valid while version_ == filter_version_.
  VectorImage filter_base_;
  int64_t filter_version_ = 0;
  FilterRequest filter_;  // the filter that made version filter_version_
  std::vector<std::unique_ptr<Session>> sessions_;  // most recently used first
  int64_t next_session_ = 1, next_view_ = 1;
};

}  // namespace subvec_serve
