// `subvec serve`: the editor's versioned document and its HTTP boundary (apps/serve).
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "editor.h"
#include "subvec/core/error.h"
#include "server.h"
#include "subvec/edit/ops.h"
#include "subvec/io/svec.h"
#include "subvec/pyramid/pyramid.h"
#include "../pyramid/pyramid_test_util.h"

// After the library headers: <httplib.h> brings <resolv.h>, whose _res macro breaks Eigen.
#include <httplib.h>

namespace subvec_serve {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

VectorImage disk() {
  return subvec::read_svec(fs::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json");
}

subvec::EditOp color_op(Vec2 at, Color color) {
  subvec::EditOp op;
  op.kind = subvec::EditOp::Kind::kColor;
  op.select = subvec::EditSelect::kFeature;
  op.at = at;
  op.radius = 40;
  op.color = color;
  op.amount = 1;
  return op;
}

// What `subvec edit` makes of a feature drag from (76, 48) to (to_x, 48), sigma 30: the reference
// a committed drag of the page must equal.
VectorImage dragged(VectorImage image, double to_x) {
  subvec::EditOp op;
  op.kind = subvec::EditOp::Kind::kDrag;
  op.select = subvec::EditSelect::kFeature;
  op.from = {76, 48};
  op.to = {to_x, 48};
  op.sigma = 30;
  subvec::apply_edit_ops(image, std::span(&op, 1));
  return image;
}

int status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const RequestError& e) {
    return e.status();
  }
  return 0;
}

TEST(ServeEditor, StaleVersionIsRefusedAndNothingChanges) {
  Editor editor(disk());
  const std::string a = editor.new_session(), b = editor.new_session();
  std::string log;
  editor.apply(a, 1, color_op({48, 48}, {0, 255, 0}), log);
  EXPECT_EQ(editor.version(), 2);
  const VectorImage after_a = editor.snapshot().first;
  // Tab b still shows version 1: its edit must not overwrite a's.
  EXPECT_EQ(status_of([&] { editor.apply(b, 1, color_op({48, 48}, {255, 0, 0}), log); }), kConflict);
  EXPECT_EQ(editor.version(), 2);
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, after_a.levels[0].colors);
  std::string label;
  EXPECT_EQ(status_of([&] { editor.undo(b, 1, label); }), kConflict);
  EXPECT_EQ(status_of([&] { editor.apply("nope", 2, color_op({48, 48}, {}), log); }), kNotFound);
}

TEST(ServeEditor, UndoRedoRestoreExactly) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  std::string log;
  editor.apply(s, 1, color_op({48, 48}, {0, 0, 255}), log);
  EXPECT_EQ(log.rfind("color blend at (48, 48): ", 0), 0u) << log;
  EXPECT_NE(log.find(" control colors moved toward (0, 0, 255)"), std::string::npos) << log;
  const VectorImage edited = editor.snapshot().first;
  ASSERT_NE(edited.levels[0].colors, original.levels[0].colors);
  std::string label;
  editor.undo(s, 2, label);
  EXPECT_EQ(label, "color blend at (48, 48)");  // what the page says: "undid: color blend ..."
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, original.levels[0].colors);
  EXPECT_EQ(editor.info().redo, 1);
  editor.redo(s, 3, label);
  EXPECT_EQ(label, "color blend at (48, 48)");
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, edited.levels[0].colors);
  EXPECT_EQ(status_of([&] { editor.redo(s, 4, label); }), kConflict);  // nothing to redo
}

// Undo is per tab: a tab takes back its own edits, and waits while another tab's edit is on top;
// a reload (a new session for the same tab) keeps them.
TEST(ServeEditor, UndoTakesBackThisTabsEditsOnly) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string a = editor.new_session("tab-a"), b = editor.new_session("tab-b");
  std::string log, label;
  editor.apply(a, 1, color_op({48, 48}, {0, 255, 0}), log);   // inside the disk
  const VectorImage after_a = editor.snapshot().first;
  editor.apply(b, 2, color_op({8, 8}, {255, 0, 0}), log);     // outside it
  EXPECT_EQ(editor.info(a).undo, 1);
  EXPECT_EQ(editor.info(b).undo, 1);
  EXPECT_EQ(editor.info().undo, 2);
  int status = 0;
  try {
    editor.undo(a, 3, label);
  } catch (const RequestError& e) {
    status = e.status();
    EXPECT_STREQ(e.what(), "undo waits: the last edit was made in another window, which can undo it");
  }
  EXPECT_EQ(status, kConflict);
  EXPECT_EQ(editor.version(), 3);
  editor.undo(b, 3, label);  // b's own edit
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, after_a.levels[0].colors);
  const std::string a2 = editor.new_session("tab-a");  // tab a reloaded
  editor.undo(a2, 4, label);
  EXPECT_EQ(label, "color blend at (48, 48)");
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, original.levels[0].colors);
  EXPECT_EQ(status_of([&] { editor.undo(a2, 5, label); }), kConflict);  // nothing to undo in this tab
  EXPECT_EQ(editor.info(b).redo, 1);
}

// Another tab's edit during a drag: the drag goes on over the edited document and lands on top of
// that edit instead of being thrown away.
TEST(ServeEditor, ADragOutlivesAnotherTabsEdit) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string a = editor.new_session("tab-a"), b = editor.new_session("tab-b");
  DragStart start;
  start.at = {76, 48};
  start.sigma = 30;
  editor.drag_start(a, 1, start);
  editor.drag_move(a, {80, 48}, 0);
  std::string log;
  editor.apply(b, 1, color_op({8, 8}, {255, 0, 0}), log);
  const VectorImage after_b = editor.snapshot().first;
  editor.drag_move(a, {84, 48}, 0);
  editor.drag_end(a, 1, {84, 48}, 0, log);  // the page still shows version 1
  EXPECT_EQ(editor.version(), 3);
  const VectorImage expected = dragged(after_b, 84);
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected.levels[0].positions);
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, after_b.levels[0].colors);  // b's edit kept
}

// The committed drag is exactly what `subvec edit` makes of the same operation. The previews
// send moves (int16 steps of 2^-offset_shift px) and leave out moves under 1/32 of a canvas pixel
// (scale 1 here), so the last one the page drew is that result within 1/32 px, and the commit's
// delta brings the page's positions to it exactly.
TEST(ServeEditor, DragCommitMatchesSubvecEditAndLastPreview) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  const ViewMesh view = editor.view(s, {0, 2});
  std::vector<float> page = view.positions;  // what the page draws, delta by delta
  std::vector<float> control;                // the page's control positions
  for (const Vec2& p : original.levels[0].positions) {
    control.push_back(static_cast<float>(p.x));
    control.push_back(static_cast<float>(p.y));
  }
  size_t move_bytes = 0, absolute_bytes = 0;  // the previews' positions, as sent and as they were
  const auto apply = [&](const Delta& d) {
    if (d.moves) {
      // As the page does it (web/src/main.ts): in double, then rounded to float.
      const double step = std::ldexp(1.0, -d.offset_shift);
      const auto patch = [&](std::vector<float>& out, const std::vector<uint8_t>& mask,
                             const std::vector<int16_t>& offsets) {
        ASSERT_EQ(mask.size(), (out.size() / 2 + 7) / 8);
        size_t i = 0;
        for (size_t g = 0; g < out.size() / 2; ++g) {
          if (!((mask[g / 8] >> (g % 8)) & 1)) continue;
          ASSERT_LT(2 * i + 1, offsets.size());
          for (size_t c = 0; c < 2; ++c) {
            out[2 * g + c] = static_cast<float>(static_cast<double>(out[2 * g + c]) + offsets[2 * i + c] * step);
          }
          ++i;
        }
        EXPECT_EQ(2 * i, offsets.size());
        move_bytes += mask.size() + 2 * offsets.size();
        absolute_bytes += std::min(4 * out.size(), 6 * offsets.size());
      };
      patch(page, d.moved, d.offsets);
      absolute_bytes += 4 * control.size();  // sent whole before
      patch(control, d.control_moved, d.control_offsets);
      absolute_bytes -= std::min(4 * control.size(), 6 * d.control_offsets.size());
      return;
    }
    if (!d.control_positions.empty()) control = d.control_positions;
    if (d.dense_positions) {
      page = d.positions;
      return;
    }
    for (size_t i = 0; i < d.position_indices.size(); ++i) {
      page[2 * d.position_indices[i]] = d.positions[2 * i];
      page[2 * d.position_indices[i] + 1] = d.positions[2 * i + 1];
    }
  };
  DragStart start;
  start.at = {76, 48};
  start.sigma = 30;
  const SelectResult picked = editor.drag_start(s, 1, start);
  EXPECT_EQ(picked.feature, 0);
  Delta preview;
  size_t sent = 0;
  for (int i = 1; i <= 8; ++i) {
    preview = editor.drag_move(s, {76.0 + i, 48}, 0);
    EXPECT_TRUE(preview.moves);
    EXPECT_EQ(preview.offset_shift, 6);  // steps of 1/64 px at scale 1
    apply(preview);
    sent += preview.offsets.size() / 2;
  }
  EXPECT_EQ(preview.view_id, view.id);
  EXPECT_GT(sent, page.size() / 2);  // an ARAP drag moves much of the mesh
  EXPECT_TRUE(preview.color_indices.empty());
  EXPECT_LT(2 * move_bytes, absolute_bytes) << move_bytes << " bytes of moves";
  const VectorImage previewed = dragged(original, 84);
  float control_drift = 0;
  for (size_t i = 0; i < control.size(); ++i) {
    const Vec2& p = previewed.levels[0].positions[i / 2];
    control_drift = std::max(control_drift, std::abs(control[i] - static_cast<float>(i % 2 ? p.y : p.x)));
  }
  EXPECT_LE(control_drift, 1.0f / 32 + 1e-5f);
  std::string log;
  const std::vector<float> last_preview = page;
  const Delta commit = editor.drag_end(s, 1, {84, 48}, 0, log);
  EXPECT_NE(log.find("dragged"), std::string::npos) << log;
  EXPECT_FALSE(commit.moves);
  apply(commit);
  const std::string fresh_session = editor.new_session();
  const ViewMesh fresh = editor.view(fresh_session, {0, 2});
  EXPECT_EQ(page, fresh.positions);
  float drift = 0;
  for (size_t i = 0; i < page.size(); ++i) drift = std::max(drift, std::abs(last_preview[i] - page[i]));
  EXPECT_GT(drift, 0);  // some moves were too small to send
  EXPECT_LE(drift, 1.0f / 32 + 1e-5f);

  const VectorImage expected = dragged(original, 84);
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected.levels[0].positions);
  EXPECT_EQ(commit.control_positions.size(), expected.levels[0].positions.size() * 2);
}

// The view's coarse triangles (the page's drag previews on software WebGL) are the view one
// level coarser: the same positions and colors, tears included, on the same GL vertices.
TEST(ServeEditor, CoarseTrianglesAreTheViewOneLevelCoarser) {
  Editor editor(disk());
  const std::string s = editor.new_session();
  const ViewMesh fine = editor.view(s, {0, 2});
  const std::string s1 = editor.new_session();
  const ViewMesh coarse = editor.view(s1, {0, 1});
  ASSERT_EQ(fine.coarse_triangles.size(), coarse.triangles.size());
  const auto corners = [](const ViewMesh& m, const std::vector<uint32_t>& tris) {
    std::vector<std::array<std::array<long, 6>, 3>> out(tris.size() / 3);
    for (size_t i = 0; i < tris.size(); ++i) {
      const uint32_t g = tris[i];
      out[i / 3][i % 3] = {std::lround(m.positions[2 * g] * 1024), std::lround(m.positions[2 * g + 1] * 1024),
                           m.colors[4 * g], m.colors[4 * g + 1], m.colors[4 * g + 2], m.colors[4 * g + 3]};
    }
    for (auto& t : out) std::sort(t.begin(), t.end());
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(corners(fine, fine.coarse_triangles), corners(coarse, coarse.triangles));
  for (uint32_t g : fine.coarse_triangles) EXPECT_LT(g, static_cast<uint32_t>(fine.num_gl_vertices()));
  EXPECT_TRUE(editor.view(editor.new_session(), {0, 0}).coarse_triangles.empty());
}

// A drag that would fold the mesh (issue 25) stops at the last fold-free position, in the preview
// and in the commit, which is `subvec edit`'s result and says it stopped.
TEST(ServeEditor, ADragThatWouldFoldStopsAndSaysSo) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  DragStart start;
  start.at = {76, 48};
  start.sigma = 30;
  editor.drag_start(s, 1, start);
  editor.drag_move(s, {80, 48}, 0);
  // Through the disk and out of its other side: the outline would cross itself.
  const Vec2 far{4, 48};
  editor.drag_move(s, far, 0);
  std::string log;
  editor.drag_end(s, 1, far, 0, log);
  EXPECT_EQ(log.rfind("stopped at the last position the mesh could take: dragged by (-72, 0) px", 0), 0u) << log;
  EXPECT_EQ(editor.version(), 2);
  subvec::EditOp op;
  op.kind = subvec::EditOp::Kind::kDrag;
  op.select = subvec::EditSelect::kFeature;
  op.from = start.at;
  op.to = far;
  op.sigma = 30;
  VectorImage expected = original;
  const std::vector<std::string> lines = subvec::apply_edit_ops(expected, std::span(&op, 1));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("% of the way"), std::string::npos) << lines[0];
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected.levels[0].positions);
  EXPECT_NE(expected.levels[0].positions, original.levels[0].positions);
}

// The move tool: translate and rotate a whole feature, committed as `subvec edit`'s move-feature.
TEST(ServeEditor, MoveFeatureCommitMatchesSubvecEdit) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  DragStart start;
  start.move_feature = true;
  start.at = {76, 48};
  editor.drag_start(s, 1, start);
  editor.drag_move(s, {72, 50}, 15);
  std::string log;
  editor.drag_end(s, 1, {72, 50}, 15, log);
  EXPECT_NE(log.find("rotated by 15"), std::string::npos) << log;
  EXPECT_EQ(log.rfind("ops[", 0), std::string::npos) << log;  // no ops-file prefix on the page

  subvec::EditOp op;
  op.kind = subvec::EditOp::Kind::kMoveFeature;
  op.at = {76, 48};
  op.translate = {-4, 2};
  op.rotate = 15;
  VectorImage expected = original;
  subvec::apply_edit_ops(expected, std::span(&op, 1));
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected.levels[0].positions);
  EXPECT_NE(expected.levels[0].positions, original.levels[0].positions);
  // A drag that ended is over: another move is refused.
  EXPECT_EQ(status_of([&] { editor.drag_move(s, {70, 50}, 0); }), kConflict);
}

TEST(ServeEditor, ViewIsUnweldedAtTearsAndColorDeltasAreSparse) {
  Editor editor(disk());
  const std::string s = editor.new_session();
  const ViewMesh view = editor.view(s, {0, 3});
  ASSERT_GT(view.triangles.size(), 0u);
  ASSERT_GT(view.tear_lines.size(), 0u);
  const int ng = view.num_gl_vertices();
  for (uint32_t i : view.triangles) ASSERT_LT(i, static_cast<uint32_t>(ng));
  // The closed tear gives seam copies: two GL vertices at one position with different colors.
  int seams = 0;
  for (size_t k = 0; k < view.tear_lines.size(); ++k) {
    const uint32_t g = view.tear_lines[k];
    for (int h = 0; h < ng; ++h) {
      if (static_cast<uint32_t>(h) != g && view.positions[2 * h] == view.positions[2 * g] &&
          view.positions[2 * h + 1] == view.positions[2 * g + 1]) {
        ++seams;
        break;
      }
    }
  }
  EXPECT_EQ(seams, static_cast<int>(view.tear_lines.size()));

  // A color edit inside the disk changes colors inside only: sparse, no positions.
  std::string log;
  const Delta d = editor.apply(s, 1, color_op({48, 48}, {0, 255, 0}), log);
  EXPECT_FALSE(d.dense_colors);
  EXPECT_GT(d.color_indices.size(), 0u);
  EXPECT_LT(d.color_indices.size(), static_cast<size_t>(ng) / 2);
  EXPECT_TRUE(d.position_indices.empty() && !d.dense_positions);
  for (uint32_t g : d.color_indices) {
    const double x = view.positions[2 * g] - 48, y = view.positions[2 * g + 1] - 48;
    EXPECT_LT(std::hypot(x, y), 29.0);  // inside the tear (control radius 28)
  }
}

// The pen tool's edits (issue 25): a feature added and deleted through the editor equals `subvec
// edit`'s, each changes the topology, so the delta tells the page to fetch a new view, and undo
// and redo across them do the same.
// Objects (issue 26): each object edit reloads the view, which carries the objects' triangles;
// a level edit afterwards is a plain delta again; undo takes an object edit back.
TEST(ServeEditor, ObjectEditsReloadTheViewWithTheObjects) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  EXPECT_TRUE(editor.view(s, {0, 2}).objects.empty());
  subvec::EditOp make;
  make.kind = subvec::EditOp::Kind::kMakeObject;
  make.rect = std::array<int, 4>{12, 12, 72, 72};
  std::string log;
  Delta d = editor.apply(s, 1, make, log);
  EXPECT_TRUE(d.reload);
  EXPECT_NE(log.find("object 0 made of what [12, 12, 72, 72] frames"), std::string::npos) << log;
  ViewMesh v = editor.view(s, {0, 2});
  ASSERT_EQ(v.objects.size(), 1u);
  EXPECT_EQ(v.objects[0].first, 0u);
  EXPECT_EQ(v.objects[0].count * 2, v.object_positions.size());
  EXPECT_EQ(v.object_colors.size(), 2 * v.object_positions.size());
  d = editor.apply(s, 2, color_op({5, 5}, {0, 255, 0}), log);  // the background: a plain delta
  EXPECT_FALSE(d.reload);
  subvec::EditOp move;
  move.kind = subvec::EditOp::Kind::kMoveObject;
  move.object = 0;
  move.translate = {10, 0};
  d = editor.apply(s, 3, move, log);
  EXPECT_TRUE(d.reload);
  v = editor.view(s, {0, 2});
  subvec::EditOp hide;
  hide.kind = subvec::EditOp::Kind::kHideObject;
  hide.object = 0;
  d = editor.apply(s, 4, hide, log);
  EXPECT_TRUE(d.reload);
  EXPECT_TRUE(editor.view(s, {0, 2}).objects.empty());
  std::string label;
  d = editor.undo(s, 5, label);
  EXPECT_TRUE(d.reload);
  EXPECT_EQ(label, "object 0 hidden");
  EXPECT_EQ(editor.view(s, {0, 2}).objects.size(), 1u);
  // A move of an object that is not there is refused by name.
  move.object = 3;
  try {
    editor.apply(s, 6, move, log);
    ADD_FAILURE() << "no error";
  } catch (const RequestError& e) {
    EXPECT_EQ(e.status(), kUnprocessable);
    EXPECT_NE(std::string(e.what()).find("object 3 is out of range (the image has 1 object)"), std::string::npos) << e.what();
  }
}

TEST(ServeEditor, FeatureEditsReloadTheViewAndUndo) {
  const VectorImage original = disk();
  Editor editor(original);
  const std::string s = editor.new_session();
  editor.view(s, {0, 2});
  subvec::EditOp add;
  add.kind = subvec::EditOp::Kind::kAddFeature;
  for (int i = 0; i <= 30; ++i) add.points.push_back({8 + 0.2 * i, 20 + 2.0 * i});  // left of the disk
  std::string log;
  Delta d = editor.apply(s, 1, add, log);
  EXPECT_TRUE(d.reload);
  EXPECT_NE(log.find("tear feature 1 (id 1) added"), std::string::npos) << log;
  VectorImage reference = original;
  subvec::apply_edit_ops(reference, std::span(&add, 1));
  const VectorImage added = editor.snapshot().first;
  EXPECT_EQ(added.levels[0].triangles, reference.levels[0].triangles);
  EXPECT_EQ(added.levels[0].colors, reference.levels[0].colors);
  ASSERT_EQ(added.levels[0].features.size(), 2u);
  // A color edit on the fresh view is a plain delta again.
  editor.view(s, {0, 2});
  d = editor.apply(s, 2, color_op({48, 48}, {0, 255, 0}), log);
  EXPECT_FALSE(d.reload);
  EXPECT_GT(d.color_indices.size(), 0u);
  subvec::EditOp del;
  del.kind = subvec::EditOp::Kind::kDeleteFeature;
  del.at = {10, 50};
  d = editor.apply(s, 3, del, log);
  EXPECT_TRUE(d.reload);
  EXPECT_NE(log.find("feature 1 (id 1)"), std::string::npos) << log;
  EXPECT_EQ(editor.snapshot().first.levels[0].features.size(), 1u);
  std::string label;
  editor.view(s, {0, 2});
  d = editor.undo(s, 4, label);
  EXPECT_TRUE(d.reload);
  EXPECT_EQ(label, "feature deleted at (10, 50)");
  EXPECT_EQ(editor.snapshot().first.levels[0].features.size(), 2u);
  editor.undo(s, 5, label);  // the color edit: same topology, but the view went with the reload
  editor.view(s, {0, 2});
  d = editor.undo(s, 6, label);
  EXPECT_TRUE(d.reload);
  EXPECT_EQ(label, "new feature at (8, 20)");
  EXPECT_EQ(editor.snapshot().first.levels[0].triangles, original.levels[0].triangles);
  editor.view(s, {0, 2});
  d = editor.redo(s, 7, label);
  EXPECT_TRUE(d.reload);
  EXPECT_EQ(editor.snapshot().first.levels[0].triangles, reference.levels[0].triangles);
  // A curve that crosses itself is refused, and nothing changes.
  subvec::EditOp twisted = add;
  twisted.points = {{20, 20}, {40, 40}, {40, 20}, {20, 40}};
  EXPECT_EQ(status_of([&] { editor.apply(s, 8, twisted, log); }), kUnprocessable);
  EXPECT_EQ(editor.version(), 8);
  // One across the disk, through two of its control vertices (y = 48), joins it there.
  subvec::EditOp across = add;
  across.points = {{10, 48}, {90, 48}};
  editor.view(s, {0, 2});
  d = editor.apply(s, 8, across, log);
  EXPECT_TRUE(d.reload);
  EXPECT_NE(log.find("junctions with existing features"), std::string::npos) << log;
}

TEST(ServeEditor, WindowedViewRefinesFewerFaces) {
  Editor editor(disk());
  const std::string s = editor.new_session();
  const ViewMesh whole = editor.view(s, {0, 3});
  ViewRequest zoomed{0, 3, 0, 0, 20, 20};
  // The page holds the whole view, which covers the window at that depth: nothing to send again.
  zoomed.have = whole.id;
  const ViewMesh same = editor.view(s, zoomed);
  EXPECT_TRUE(same.unchanged);
  EXPECT_EQ(same.id, whole.id);
  EXPECT_TRUE(same.triangles.empty());
  zoomed.have = 0;  // a page that holds no view gets one
  EXPECT_FALSE(editor.view(s, zoomed).unchanged);
  const ViewMesh part = editor.view(editor.new_session(), zoomed);
  EXPECT_FALSE(whole.partial);
  EXPECT_FALSE(whole.unchanged);
  EXPECT_TRUE(part.partial);
  EXPECT_LT(part.triangles.size(), whole.triangles.size() / 2);
  // Without a depth, the renderer's rule for the scale: 4x larger is 1 level deeper (edges twice
  // as long in output pixels as at 1x: the deviation from the limit, ~h^2 / s, stays the same).
  ViewRequest fit{0, -1, 0, 0, 0, 0, 1, 2.5};
  const ViewMesh at1 = editor.view(editor.new_session(), fit);
  fit.scale = 4;
  const ViewMesh at4 = editor.view(editor.new_session(), fit);
  EXPECT_EQ(at4.depth, at1.depth + 1);
  EXPECT_EQ(status_of([&] { editor.view(s, {0, 9}); }), kBadRequest);
  EXPECT_EQ(status_of([&] { editor.view(s, {5, 2}); }), kBadRequest);
}

// A small three-level pyramid of the synthetic shapes photograph (tests/unit/pyramid).
const VectorImage& pyramid_image() {
  static const VectorImage image =
      subvec::test::shapes_levels(subvec::test::shapes_image(128, 96));
  return image;
}

TEST(ServeEditor, FilterIsAbsoluteUndoableAndVersioned) {
  const VectorImage& original = pyramid_image();
  ASSERT_TRUE(subvec::has_pyramid(original));
  Editor editor(original);
  EXPECT_EQ(editor.info().bands, 2);
  const std::string s = editor.new_session();
  const ViewMesh view = editor.view(s, {0, 1});
  std::string log;
  FilterRequest smooth;
  smooth.eta = {0.2};
  const Delta d = editor.filter(s, 1, smooth, log);
  EXPECT_EQ(d.view_id, view.id);
  EXPECT_FALSE(d.colors.empty());
  subvec::FilterOptions options;
  options.color_eta = {0.2};
  const VectorImage expected = subvec::filter(original, options);
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, expected.levels[0].colors);
  EXPECT_NE(expected.levels[0].colors, original.levels[0].colors);
  // A second filter right after replaces the first: it filters the original, not the result.
  FilterRequest both;
  both.eta = {0.5, 1.5};
  both.geometry = true;
  editor.filter(s, 2, both, log);
  options.color_eta = options.geometry_eta = {0.5, 1.5};
  const VectorImage expected2 = subvec::filter(original, options);
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected2.levels[0].positions);
  EXPECT_EQ(editor.snapshot().first.levels[1].colors, expected2.levels[1].colors);
  // eta = 1 gives the original back exactly; each filter was one undo step.
  FilterRequest off;
  off.eta = {1};
  editor.filter(s, 3, off, log);
  EXPECT_EQ(editor.snapshot().first.levels[0].colors, original.levels[0].colors);
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, original.levels[0].positions);
  EXPECT_EQ(editor.info().undo, 3);
  std::string label;
  editor.undo(s, 4, label);
  EXPECT_EQ(label, "filter off");
  EXPECT_EQ(editor.snapshot().first.levels[0].positions, expected2.levels[0].positions);
  // Stale versions, bad eta lists and images without a pyramid are refused.
  EXPECT_EQ(status_of([&] { editor.filter(s, 4, smooth, log); }), kConflict);
  FilterRequest bad;
  bad.eta = {0.5, 0.5, 0.5};
  EXPECT_EQ(status_of([&] { editor.filter(s, 5, bad, log); }), kBadRequest);
  bad.eta = {-1};
  EXPECT_EQ(status_of([&] { editor.filter(s, 5, bad, log); }), kBadRequest);
  Editor flat(disk());
  EXPECT_EQ(flat.info().bands, 0);
  EXPECT_EQ(status_of([&] { flat.filter(flat.new_session(), 1, smooth, log); }), kUnprocessable);
}

// ---- HTTP ----------------------------------------------------------------------------------

class ServeHttp : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("subvec-serve-test-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    ServeOptions options;
    options.input = fs::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json";
    options.output = dir_ / "out.svec";
    options.port = 0;
    server_ = std::make_unique<EditorServer>(options);
    server_->start();
    thread_ = std::thread([this] { server_->run(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->port());
    for (int i = 0; i < 200 && !client_->Get("/api/status"); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  void TearDown() override {
    server_->stop();
    thread_.join();
    fs::remove_all(dir_);
  }
  static json body(const httplib::Result& r) { return json::parse(r->body, nullptr, false); }

  fs::path dir_;
  std::unique_ptr<EditorServer> server_;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(ServeHttp, ServesThePageAndTheDocument) {
  auto page = client_->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<canvas"), std::string::npos);
  auto doc = client_->Get("/api/document");
  ASSERT_TRUE(doc);
  const json j = body(doc);
  EXPECT_EQ(j["width"], 96);
  EXPECT_EQ(j["levels"].size(), 1u);
  EXPECT_EQ(j["filter"]["available"], false);
}

TEST_F(ServeHttp, ErrorsAreJsonWithStatus) {
  auto expect_error = [&](const httplib::Result& r, int status) {
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, status) << r->body;
    const json j = body(r);
    ASSERT_TRUE(j.is_object()) << r->body;
    EXPECT_TRUE(j["error"].is_string());
    EXPECT_EQ(j["status"], status);
  };
  expect_error(client_->Get("/no/such/page"), 404);
  expect_error(client_->Get("/api/control?level=7"), 400);
  expect_error(client_->Get("/api/control?level=x"), 400);
  expect_error(client_->Post("/api/select", "{\"at\": [1]}", "application/json"), 400);
  expect_error(client_->Post("/api/select", "not json", "application/json"), 400);
  expect_error(client_->Post("/api/select", "{\"at\": [1, 2]}", "text/plain"), 415);
  expect_error(client_->Post("/api/view", "{\"session\": \"s99\"}", "application/json"), 404);
  expect_error(client_->Post("/api/filter", "{\"eta\": [0.5], \"version\": 1}", "application/json"), 400);
  expect_error(client_->Get("/api/download?format=exe"), 400);
  const std::string big(100 * 1024, ' ');
  expect_error(client_->Post("/api/select", big, "application/json"), 413);
  httplib::Headers foreign = {{"Host", "evil.example:80"}};
  expect_error(client_->Get("/api/status", foreign), 403);
}

// The region fill over HTTP: /api/select with "select": "region" reports the values a color
// edit with the same fields changes (the disk's closed tear bounds it), and a tolerance is the
// region's only.
TEST_F(ServeHttp, RegionSelectAndColorAgree) {
  const json pick = {{"select", "region"}, {"at", {48, 48}}, {"tolerance", 100}};
  auto sel = client_->Post("/api/select", pick.dump(), "application/json");
  ASSERT_TRUE(sel);
  ASSERT_EQ(sel->status, 200) << sel->body;
  const json s = body(sel);
  const VectorImage original = disk();
  const int inside = s["colors"].get<int>();
  EXPECT_GT(inside, 1);
  EXPECT_LT(inside, original.levels[0].num_colors());  // the tear stops it
  EXPECT_EQ(s["vertex"], -1);
  EXPECT_EQ(s["feature"], -1);
  auto session = client_->Post("/api/session", "{}", "application/json");
  ASSERT_TRUE(session);
  json edit = pick;
  edit.update({{"session", body(session)["session"]}, {"version", 1}, {"color", {0, 255, 0}}, {"amount", 1}});
  auto r = client_->Post("/api/color", edit.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find(std::to_string(inside) + " control colors"), std::string::npos) << r->body.substr(0, 300);
  auto bad = client_->Post("/api/select", json{{"select", "vertex"}, {"at", {48, 48}}, {"tolerance", 5}}.dump(), "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(bad->body.find("applies to \\\"select\\\": \\\"region\\\" only"), std::string::npos) << bad->body;
  auto drag = client_->Post("/api/drag/start", json{{"session", "s1"}, {"version", 2}, {"select", "region"}, {"at", {48, 48}}}.dump(), "application/json");
  ASSERT_TRUE(drag);
  EXPECT_EQ(drag->status, 400) << drag->body;
}

// The points tool over HTTP: a nudge (/api/points/move) and a drag of a selection ("tool":
// "points") move exactly the listed vertices by the asked amount, color per control point takes
// "select": "vertices", and bad lists are 400 or 422.
TEST_F(ServeHttp, PointsMoveNudgeAndRecolor) {
  auto session = client_->Post("/api/session", "{}", "application/json");
  ASSERT_TRUE(session);
  const std::string id = body(session)["session"];
  const VectorImage original = disk();
  const ControlMesh& m = original.levels[0];
  std::vector<int32_t> inner;
  for (int v = 0; v < m.num_vertices() && inner.size() < 2; ++v)
    if (m.positions[v].x > 30 && m.positions[v].x < 66 && m.positions[v].y > 30 && m.positions[v].y < 66) inner.push_back(v);
  ASSERT_EQ(inner.size(), 2u);
  const auto positions = [&] {
    auto c = client_->Get("/api/control?level=0");
    return body(c)["positions"].get<std::vector<double>>();
  };
  auto post = [&](const char* path, const json& j) { return client_->Post(path, j.dump(), "application/json"); };
  auto r = post("/api/points/move", {{"session", id}, {"version", 1}, {"vertices", inner}, {"translate", {2, 1}}, {"region", "auto"}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find("moved 2 control points by (2, 1) px"), std::string::npos);
  std::vector<double> p = positions();
  for (const int32_t v : inner) {
    EXPECT_NEAR(p[2 * v], m.positions[v].x + 2, 1e-4);
    EXPECT_NEAR(p[2 * v + 1], m.positions[v].y + 1, 1e-4);
  }
  const Vec2 grab{p[2 * inner[0]], p[2 * inner[0] + 1]};
  r = post("/api/drag/start", {{"session", id}, {"version", 2}, {"tool", "points"}, {"vertices", inner}, {"at", {grab.x, grab.y}}, {"region", "auto"}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  r = post("/api/drag/end", {{"session", id}, {"version", 2}, {"to", {grab.x - 3, grab.y}}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find("moved 2 control points by (-3, 0) px"), std::string::npos);
  p = positions();
  EXPECT_NEAR(p[2 * inner[1]], m.positions[inner[1]].x - 1, 1e-4);
  r = post("/api/color", {{"session", id}, {"version", 3}, {"select", "vertices"}, {"vertices", inner}, {"color", {0, 0, 255}}, {"amount", 1}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find("color blend of 2 control points"), std::string::npos);
  r = post("/api/points/move", {{"session", id}, {"version", 4}, {"vertices", json::array()}, {"translate", {1, 1}}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  r = post("/api/points/move", {{"session", id}, {"version", 4}, {"vertices", {100000}}, {"translate", {1, 1}}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 422) << r->body;
  EXPECT_NE(r->body.find("out of range"), std::string::npos);
}

TEST_F(ServeHttp, SaveWritesOnlyTheNamedFile) {
  const fs::path out = dir_ / "out.svec";
  EXPECT_FALSE(fs::exists(out));
  auto session = client_->Post("/api/session", "{}", "application/json");
  ASSERT_TRUE(session);
  const std::string id = body(session)["session"];
  const json edit = {{"session", id}, {"version", 1},   {"at", {48, 48}},
                     {"color", {0, 255, 0}}, {"amount", 1}, {"radius", 40}};
  auto r = client_->Post("/api/color", edit.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body.substr(0, 4), "SVB1");
  EXPECT_FALSE(fs::exists(out));  // nothing written before Save
  auto save = client_->Post("/api/save", json{{"version", 2}}.dump(), "application/json");
  ASSERT_TRUE(save);
  ASSERT_EQ(save->status, 200) << save->body;
  const VectorImage saved = subvec::read_svec(out);
  const VectorImage original = disk();
  EXPECT_NE(saved.levels[0].colors, original.levels[0].colors);
  // Only out.svec in the folder (no temporary left over), the input untouched.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 1);
  auto stale = client_->Post("/api/save", json{{"version", 1}}.dump(), "application/json");
  ASSERT_TRUE(stale);
  EXPECT_EQ(stale->status, 409);
}

TEST_F(ServeHttp, APortInUseIsRefused) {
  ServeOptions options;
  options.input = fs::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json";
  options.port = server_->port();
  EditorServer second(options);
  EXPECT_THROW(second.start(), subvec::Error);
}

TEST_F(ServeHttp, DownloadsAreBuiltInMemory) {
  auto png = client_->Get("/api/download?format=png");
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200);
  EXPECT_EQ(png->body.substr(1, 3), "PNG");
  EXPECT_NE(png->get_header_value("Content-Disposition").find("01-disk-v1.png"), std::string::npos);
  auto svec = client_->Get("/api/download?format=svec");
  ASSERT_TRUE(svec);
  EXPECT_EQ(svec->body.substr(0, 6), "SUBVEC");
  auto pdf = client_->Get("/api/download?format=pdf");
  ASSERT_TRUE(pdf);
  EXPECT_EQ(pdf->body.substr(0, 5), "%PDF-");
  EXPECT_FALSE(fs::exists(dir_ / "out.svec"));
}

// The endpoint gives what `subvec filter` gives on the same file, byte for byte once saved.
TEST(ServeHttpFilter, SavedFilterEqualsTheFilterCommand) {
  const fs::path dir = fs::temp_directory_path() / ("subvec-serve-filter-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path input = dir / "in.svec", saved = dir / "saved.svec", cli = dir / "cli.svec";
  subvec::write_svec(input, pyramid_image());
  const std::string command = std::string("'") + SUBVEC_CLI + "' filter '" + input.string() + "' -o '" +
                              cli.string() + "' --eta-levels 0.3,1.6 --geometry-eta --color-eta >/dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  ServeOptions options;
  options.input = input;
  options.output = saved;
  options.port = 0;
  EditorServer server(options);
  server.start();
  std::thread thread([&] { server.run(); });
  httplib::Client client("127.0.0.1", server.port());
  for (int i = 0; i < 200 && !client.Get("/api/status"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  auto doc = client.Get("/api/document");
  ASSERT_TRUE(doc);
  const json info = json::parse(doc->body, nullptr, false);
  EXPECT_EQ(info["filter"]["available"], true);
  EXPECT_EQ(info["filter"]["bands"], 2);
  auto session = client.Post("/api/session", "{}", "application/json");
  ASSERT_TRUE(session);
  const std::string id = json::parse(session->body)["session"];
  const json request = {{"session", id},      {"version", 1},    {"eta", {0.3, 1.6}},
                        {"geometry", true}, {"color", true}};
  auto r = client.Post("/api/filter", request.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body.substr(0, 4), "SVB1");
  auto wrong = client.Post("/api/filter", json{{"session", id}, {"version", 2}, {"eta", 0.5}}.dump(),
                           "application/json");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 400);
  auto save = client.Post("/api/save", json{{"version", 2}}.dump(), "application/json");
  ASSERT_TRUE(save);
  ASSERT_EQ(save->status, 200) << save->body;
  server.stop();
  thread.join();
  const std::string a = file_bytes(saved), b = file_bytes(cli);
  EXPECT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "saved " << a.size() << " bytes, subvec filter " << b.size();
  fs::remove_all(dir);
}

// `subvec serve photo.png` vectorizes as `subvec vectorize photo.png` does, levels included: with
// the same options, Save writes the same bytes. (Options through the struct the CLI's flags fill,
// vectorize_options.h; here a few set away from their defaults, as the flags would.)
TEST(ServeHttpVectorize, SavedDocumentEqualsTheVectorizeCommand) {
  const fs::path dir = fs::temp_directory_path() / ("subvec-serve-vectorize-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path photo = fs::path(SUBVEC_SOURCE_DIR) / "examples" / "04-rocket.png";
  const fs::path saved = dir / "saved.svec", cli = dir / "cli.svec";
  const std::string command = std::string("'") + SUBVEC_CLI + "' vectorize '" + photo.string() + "' -o '" +
                              cli.string() + "' --ratio 0.02 --refine 4 --level-reduction 0.6 >/dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  ServeOptions options;
  options.input = photo;
  options.output = saved;
  options.port = 0;
  options.vectorize.ratio = 0.02;
  options.vectorize.refine.rounds = 4;
  options.vectorize.levels.reduction = 0.6;
  EditorServer server(options);
  server.start();
  std::thread thread([&] { server.run(); });
  httplib::Client client("127.0.0.1", server.port());
  json status;
  for (int i = 0; i < 6000; ++i) {  // until vectorized (at most a minute)
    if (auto r = client.Get("/api/status")) {
      status = json::parse(r->body, nullptr, false);
      if (status["state"] != "vectorizing") break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(status["state"], "ready") << status.dump();
  auto doc = client.Get("/api/document");
  ASSERT_TRUE(doc);
  EXPECT_EQ(json::parse(doc->body)["levels"].size(), static_cast<size_t>(subvec::LevelOptions{}.levels));
  auto save = client.Post("/api/save", "{}", "application/json");
  ASSERT_TRUE(save);
  ASSERT_EQ(save->status, 200) << save->body;
  server.stop();
  thread.join();
  const std::string a = file_bytes(saved), b = file_bytes(cli);
  EXPECT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "saved " << a.size() << " bytes, subvec vectorize " << b.size();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace subvec_serve
